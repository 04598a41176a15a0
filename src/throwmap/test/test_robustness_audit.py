# Copyright 2026 The feeder authors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
The robustness cell map's audit: random samples of cell x box against the map.

The audit gives the sampled robustness verdict its stated confidence (docs/design.md section
3). Checked here: on the paper's design it finds no miss; on a map with every successor range
cut by one cell it finds misses, and sample by sample it agrees with f through the public
ThrowModel (not the compiled throw the audit uses).
"""

import math

import numpy as np
import pytest
from throwmap import design as D
from throwmap import load_scene
from throwmap import robustness as RB
from throwmap import search as S
from throwmap.model import ThrowModel
from throwmap.status import REC_COLS
from throwmap_testing import SCENES

PAPER = (-0.005, 5.5851)
SMALL = {'radii_per_edge': 8, 'throws': 90, 'ref_throws': 600}
S_ROBUST = 0.005        # inside what the graph proves for the paper's design (test_design)


@pytest.fixture(scope='module')
def setting():
    tri = load_scene(str(SCENES / 'triangle.yaml'))
    opt = D.eval_options(tri, **SMALL)
    res = D.evaluate_grid(tri, [PAPER[0]], [PAPER[1]], goals=[1], options=opt, workers=1)
    cand = S.Candidate(PAPER[0], PAPER[1], 1, 0.25, S._figures(res, 0, 0, 0))
    spec = S.limit_spec(tri, cand, opt)
    part = tri.part
    h, w = PAPER
    dh, dw = S_ROBUST * part.d_min, S_ROBUST * w
    verdict, cmap = RB.robust_check(tri.model, h, w, dh, dw, spec, with_map=True)
    assert verdict.ok, verdict.reason
    return tri, (h, w, dh, dw), cmap


def _cut(cmap):
    lo, hi, succ_lo, succ_hi, escape, progress = cmap
    return lo, hi, succ_lo, np.where(succ_hi > succ_lo, succ_hi - 1, succ_hi), escape, progress


def test_audit_finds_no_miss_where_the_graph_proves_robustness(setting):
    tri, (h, w, dh, dw), cmap = setting
    a = RB.audit(tri.model, h, w, dh, dw, cmap, 20000, seed=3)
    assert a.samples + a.skipped == 20000 and a.samples > 19000
    assert a.misses == 0
    # Rule of three: no miss in N samples bounds the missed fraction by about 3 / N.
    assert a.miss_bound_95 == pytest.approx(1 - 0.05 ** (1 / a.samples))
    assert a.miss_bound_95 < 3.1 / a.samples


def test_audit_finds_the_misses_of_a_cut_map_sample_by_sample(setting):
    tri, (h, w, dh, dw), cmap = setting
    part, g = tri.part, tri.model.g
    cut = _cut(cmap)
    assert RB.audit(tri.model, h, w, dh, dw, cut, 5000).misses > 100
    lo, hi, succ_lo, succ_hi, escape, progress = cut
    m = escape.shape[1]
    rng = np.random.default_rng(5)
    out = np.zeros(3, dtype=np.int64)
    agree = misses = 0
    for _ in range(200):
        e = int(rng.choice([i for i in range(part.n) if part.stable[i]]))
        c = int(rng.integers(0, m))
        if escape[e, c]:
            continue
        u_r, u_w, u_h = rng.random(), rng.uniform(-1, 1), rng.uniform(-1, 1)
        tri.model.composed.audit_cells(h, w, dh, dw, tri.model.ctx, tri.model.prm,
                                       np.empty((0, REC_COLS)), lo, hi, succ_lo, succ_hi,
                                       escape, progress, np.array([e]), np.array([c]),
                                       np.array([u_r]), np.array([u_w]), np.array([u_h]),
                                       np.empty(part.n), out)
        model = ThrowModel(part, h + dh * u_h, w + dw * u_w, g)
        R = lo[e] + (c + u_r) * (hi[e] - lo[e]) / m
        if R < model.r_min(e):
            assert out[2] == 1
            continue
        j, r1, kind = model.f(e, R)
        cell = math.floor((r1 - lo[j]) / ((hi[j] - lo[j]) / m))
        inside = lo[j] <= r1 <= hi[j] and succ_lo[e, c, j] <= cell <= succ_hi[e, c, j]
        # A cell taken as jogging outwards must not keep a throw that does not move out.
        stalled = j == e and cell == c and progress[e, c] > 0 and not (kind == 'jog' and r1 > R)
        inside = inside and not stalled
        assert out[1] == (0 if inside else 1), (e, c, R, j, r1)
        agree += 1
        misses += not inside
    assert agree > 150 and misses > 10
