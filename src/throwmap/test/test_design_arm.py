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
Design search on the arm the feeder has (issue 21 item 2, the arm's length).

The paper's feeder has "a 40 cm long horizontal arm". A scene says so with ``arm.length_cm``
and effect ``finite_arm``; the design kernel then throws with that length (base_map.off_arm,
the effect's own rule) and a design whose Z, grid starts or limit set put the part past the
arm's end is not eligible, and its sensor must fit on the arm. Checked against the effect
itself: the kernel's throws equal EffectModel's with finite_arm state by state, and the chosen
design keeps every grid start on the arm for 10,000 throws.
"""

import io
import json
import math

import numpy as np
import pytest
from throwmap import design as D
from throwmap import Scene
from throwmap.base_map import throw_one
from throwmap.basins import default_grid
from throwmap.cli import main
from throwmap.status import LOST, OK, REC_COLS
from throwmap_testing import PAPER_W, TRIANGLE_VERTICES

ARM = 0.40
# The design an endless-arm search chose by readies per second (issue 21): sensor at 43.9 cm.
ENDLESS_CHOICE = (-0.009846153846153848, 4.153023076923076)


def triangle(arm=ARM, h=-0.005, w=PAPER_W):
    data = {'name': 'triangle_arm', 'part': {'vertices': TRIANGLE_VERTICES},
            'arm': {'offset': h}, 'throw': {'release_speed': w}, 'gravity': -9.66,
            'sensor': {'goal_edge': 1}, 'start': {'edge': 1, 'R': 0.12}}
    if arm is not None:
        data['arm']['length'] = arm
        data['effects'] = ['finite_arm']
    return Scene(data)


@pytest.fixture(scope='module')
def on_arm():
    return triangle()


def test_the_kernel_loses_a_part_exactly_where_effect_finite_arm_does(on_arm):
    model = on_arm.model                      # EffectModel: the pipeline with finite_arm
    rng = np.random.default_rng(11)
    edges = rng.choice(model.part.stable_edges, 600)
    radii = np.array([model.r_min(e) for e in edges]) * 1.01 + rng.uniform(0.0, 0.45, 600)
    ref = model.f_batch(edges, radii)
    rec = np.empty((0, REC_COLS))
    got = [throw_one(int(e), float(r), model.w, model.g, model.h, model.r_grasp,
                     model.part.arrays, model._knobs, rec, ARM)[:3] for e, r in zip(edges, radii)]
    status = np.array([g[0] for g in got])
    np.testing.assert_array_equal(status, ref['status'])
    assert 50 < int(np.sum(status == LOST)) < 550 and set(status.tolist()) <= {OK, LOST}
    ok = status == OK
    np.testing.assert_array_equal(np.array([g[1] for g in got])[ok], ref['edge'][ok])
    np.testing.assert_array_equal(np.array([g[2] for g in got])[ok], ref['R'][ok])
    # Without the arm argument (inf) the kernel is the base model: nothing is lost.
    assert all(throw_one(int(e), float(r), model.w, model.g, model.h, model.r_grasp,
                         model.part.arrays, model._knobs, rec)[0] == OK
               for e, r in zip(edges[:100], radii[:100]))


def test_a_design_that_throws_the_part_off_the_arm_is_not_eligible():
    h, w = ENDLESS_CHOICE
    endless = triangle(arm=None, h=h, w=w)
    res = D.evaluate_grid(endless, [h], [w], options=D.eval_options(endless))
    assert res.design[0, D.D_STATUS] == D.ST_OK
    assert res.sensor[0, 0, 0, D.S_FITS]          # an endless arm holds any sensor
    arm = triangle(h=h, w=w)
    res = D.evaluate_grid(arm, [h], [w], options=D.eval_options(arm))
    assert res.design[0, D.D_STATUS] == D.ST_OFF_ARM
    assert 'past the arm' in D.STATUS_TEXT[D.ST_OFF_ARM]
    # The paper's design fits its arm.
    paper = triangle()
    res = D.evaluate_grid(paper, [paper.h], [paper.release_speed],
                          options=D.eval_options(paper))
    assert res.design[0, D.D_STATUS] == D.ST_OK and res.design[0, D.D_R_HI] < ARM


def test_the_search_on_a_40_cm_arm_chooses_a_design_that_keeps_the_part(tmp_path):
    path = tmp_path / 'triangle_arm.yaml'
    path.write_text(json.dumps({
        'name': 'triangle_arm', 'part': {'vertices': TRIANGLE_VERTICES},
        'arm': {'offset': -0.005, 'length_cm': 40}, 'throw': {'release_speed': PAPER_W},
        'gravity': -9.66, 'sensor': {'goal_edge': 1}, 'start': {'edge': 1, 'R': 0.12},
        'effects': ['finite_arm']}))
    out = io.StringIO()
    # ready-rate: the ranking whose endless-arm choice put the sensor at 43.9 cm and lost parts
    code = main(['design-search', str(path), '--grid', '20x20', '--objective', 'ready-rate',
                 '--json', '--quiet'], out=out)
    result = json.loads(out.getvalue())
    assert code == 0 and result['chosen'] is not None
    assert not any(n.startswith('the arm is taken as endless') for n in result['notes'])
    f = result['chosen']['figures']
    assert f['sensor_radius'] + triangle().sensor_footprint <= ARM and f['r_hi'] <= ARM
    chosen = triangle(h=result['chosen']['h'], w=result['chosen']['release_speed'])
    model = chosen.model
    edges, radii = default_grid(model)
    status, done = model.orbits(edges, radii, 10_000)[3:]
    assert not np.any(status == LOST), f'{int(np.sum(status == LOST))} grid starts lost'
    assert np.all(status == OK) and np.all(done == 10_000)
    assert math.isfinite(model.arm_length) and model.arm_length == ARM
