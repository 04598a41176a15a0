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
The feed rate a cell sees (issue 21 item 7): seconds per part, the objectives, the arrival.

The seconds from a part's arrival to its first proven ready are checked against orbits
iterated with the public ThrowModel; the default ranking against the grid's own columns; the
ready-rate objective against the choice the search made before it had objectives.
"""

import io
import json
import math

import numpy as np
import pytest
from throwmap import design as D
from throwmap import search as S
from throwmap.cli import main
from throwmap.errors import InputError
from throwmap.model import ThrowModel
from throwmap.sensor import sees
from throwmap_testing import SCENES, shipped_scene

PAPER = (-0.005, 5.5851)
# Small but long enough that every start of the paper's design gets a first ready.
SMALL = {'radii_per_edge': 8, 'throws': 120, 'ref_throws': 600}
# A 4 x 4 grid on which the two objectives choose different designs.
GRID = {'h_range': (-0.012, -0.004), 'w_range': (4.0, 6.5), 'n_h': 4, 'n_w': 4, 'goals': [1]}


@pytest.fixture(scope='module')
def triangle():
    # The objectives on the paper's triangle with an endless arm, as they were introduced.
    return shipped_scene('triangle', endless=True)


def _seconds_by_orbits(triangle, opt, row, starts, first_rows):
    """Mean and p95 seconds per part from ThrowModel orbits: the kernel's rule, redone."""
    part, g = triangle.part, triangle.model.g
    h, w = PAPER
    model = ThrowModel(part, h, w, g)
    x, goal, T = row['sensor_radius'], 1, opt.throws
    orbits = [model.orbit_arrays(int(e), float(r), T)[:2] for e, r in starts]
    # Warm-up: after it no start ever shows another edge to the sensor.
    warmup = max([k + 1 for e, r in orbits for k in range(len(e))
                  if e[k] != goal and sees(part, e[k], r[k], x, opt.footprint)], default=0)
    assert warmup == row['warmup']
    firsts = []
    for e, r in orbits[first_rows]:
        k = next(k for k in range(warmup, len(e)) if e[k] == goal
                 and sees(part, e[k], r[k], x, opt.footprint))
        firsts.append(k)
    # The cycle: the limit set's mean flight (second half of the reference orbit) + settle +
    # reset.
    ref_e, ref_r, _ = model.orbit_arrays(goal, 1.5 * model.r_min(goal), opt.ref_throws)
    tail = slice(opt.ref_throws // 2, opt.ref_throws)
    flight = model.f_batch(ref_e[tail], ref_r[tail])['flight_time'].mean()
    cycle = flight + opt.settle_time + opt.reset_time
    p95 = sorted(firsts)[math.ceil(0.95 * len(firsts)) - 1]
    return np.mean(firsts) * cycle, p95 * cycle


def test_seconds_per_part_are_throws_to_the_first_ready_times_the_mean_cycle(triangle):
    opt = D.eval_options(triangle, **SMALL)
    res = D.evaluate_grid(triangle, [PAPER[0]], [PAPER[1]], goals=[1], options=opt, workers=1)
    row = dict(zip(D.S_COLS, res.sensor[0, 0, 0]))
    assert row['never_ready'] == 0
    mean, p95 = _seconds_by_orbits(triangle, opt, row, res.starts[0], slice(None))
    assert row['part_seconds_mean'] == pytest.approx(mean, rel=1e-9)
    assert row['part_seconds_p95'] == pytest.approx(p95, rel=1e-9)
    assert row['parts_per_minute'] == pytest.approx(60 / mean, rel=1e-9)


def test_an_arrival_gives_the_first_readies_of_its_own_starts(triangle):
    """A chute on edge 1, R uniform in [10, 14] cm: midpoints of equal bins, after the grid."""
    opt = D.eval_options(triangle, **SMALL, arrival=(1, 0.10, 0.14), arrival_starts=10)
    res = D.evaluate_grid(triangle, [PAPER[0]], [PAPER[1]], goals=[1], options=opt, workers=1)
    grid = 3 * SMALL['radii_per_edge']
    assert res.starts.shape == (1, grid + 10, 2) and res.arrival == (1, 0.10, 0.14, 10)
    np.testing.assert_array_equal(res.starts[0, grid:, 0], 1)
    np.testing.assert_allclose(res.starts[0, grid:, 1], 0.10 + (np.arange(10) + 0.5) * 0.004,
                               rtol=0, atol=1e-15)
    row = dict(zip(D.S_COLS, res.sensor[0, 0, 0]))
    mean, p95 = _seconds_by_orbits(triangle, opt, row, res.starts[0], slice(grid, None))
    assert row['part_seconds_mean'] == pytest.approx(mean, rel=1e-9)
    assert row['part_seconds_p95'] == pytest.approx(p95, rel=1e-9)
    # The grid's figures differ: the arrival is what was measured.
    plain = D.evaluate_grid(triangle, [PAPER[0]], [PAPER[1]], goals=[1],
                            options=D.eval_options(triangle, **SMALL), workers=1)
    assert plain.sensor[0, 0, 0, D.S_PART_MEAN] != row['part_seconds_mean']


def test_an_arrival_below_the_domain_of_f_is_refused_or_makes_the_design_ineligible(triangle):
    # Edge 1's domain starts at the toe stub (5.47 cm) at every h: refused, the domain named.
    with pytest.raises(InputError, match=r'R_min of edge 1 is 0\.054667 m \(R_grasp'):
        D.evaluate_grid(triangle, [PAPER[0]], [PAPER[1]], goals=[1], workers=1,
                        options=D.eval_options(triangle, **SMALL, arrival=(1, 0.03, 0.2)))
    # Edge 2's R_min is R_grasp, which grows with h (4.3 cm at h -1.5 cm, 6.2 at -0.1 cm):
    # over a range of h the designs whose R_min lies above 5 cm are not eligible, with why.
    opt = D.eval_options(triangle, **SMALL, arrival=(2, 0.05, 0.2))
    hs = np.array([-0.014, -0.012, -0.004, -0.002])
    res = D.evaluate_grid(triangle, hs, [4.5] * 4, goals=[1], options=opt, workers=1)
    status = res.design[:, D.D_STATUS]
    assert (status[2:] == D.ST_ARRIVAL_OUTSIDE).all() and (status[:2] != D.ST_ARRIVAL_OUTSIDE
                                                           ).all()
    assert 'R_min' in D.STATUS_TEXT[D.ST_ARRIVAL_OUTSIDE]
    assert not S.eligible(res)[2:].any()
    # Still evaluated (limit set, sensor, rates), only without first readies.
    assert np.isfinite(res.sensor[2:, 0, 0, D.S_PER_SECOND]).all()
    assert np.isnan(res.sensor[2:, 0, 0, D.S_PART_MEAN]).all()
    # The search's own scene design there is marked, not refused.
    with pytest.raises(InputError, match='R_min of edge 2 is 0.056667 m'):
        D.evaluate_grid(triangle, [PAPER[0]], [PAPER[1]], goals=[1], options=opt, workers=1)
    own = D.evaluate_grid(triangle, [PAPER[0]], [PAPER[1]], goals=[1], options=opt, workers=1,
                          refuse_arrival_outside=False)
    assert own.design[0, D.D_STATUS] == D.ST_ARRIVAL_OUTSIDE
    for bad, message in (((0, 0.05, 0.2, 1), 'expected'), ((5, 0.1, 0.2), 'not a stable'),
                         ((1, 0.2, 0.1), 'RMIN <= RMAX'), ((1, math.nan, 0.2), 'RMIN <= RMAX')):
        with pytest.raises(InputError, match=message):
            D.eval_options(triangle, arrival=bad)


def _eligible_by_columns(res, opt):
    """Return the eligibility rule and the seconds per part from the grid's raw columns."""
    d, s = res.design, res.sensor
    ok = ((d[:, D.D_STATUS] == D.ST_OK) & (d[:, D.D_SHARE] == 1) & (d[:, D.D_ATTRACTORS] == 1))
    ok = ok[:, None, None] & (s[..., D.S_FEASIBLE] == 1) & (s[..., D.S_FITS] == 1) & (
        s[..., D.S_NEVER] == 0)
    cycle = d[:, D.D_FLIGHT] + opt.settle_time + opt.reset_time
    mean = s[..., D.S_READY_MEAN] * cycle[:, None, None]
    p95 = s[..., D.S_READY_P95] * cycle[:, None, None]
    return ok, mean, p95


def test_the_default_objective_ranks_first_the_fewest_seconds_per_part(triangle):
    opt = D.eval_options(triangle, **SMALL)
    res = S.search(triangle, **GRID, top=2, spread=0, refine=0, options=opt, workers=1)
    assert res.objective == 'part_time'
    ok, mean, p95 = _eligible_by_columns(res.grid, opt)
    assert ok.sum() >= 3
    best = min(zip(mean[ok], p95[ok], np.argwhere(ok)), key=lambda t: (t[0], t[1]))
    k = best[2][0]
    first = res.candidates[0]
    assert (first.h, first.w) == (res.grid.h[k], res.grid.w[k])
    assert first.figures['part_seconds_mean'] == pytest.approx(best[0], rel=1e-12)
    # Chosen (floor 0): the fewest seconds per part of the assessed ones and the scene's.
    pool = [c for c in res.candidates + [res.reference] if c.figures['never_ready'] == 0]
    assert res.chosen.figures['part_seconds_mean'] == min(c.figures['part_seconds_mean']
                                                          for c in pool)
    # ... which is not the design with the most readies per second on this grid.
    most = np.argmax(np.where(ok, res.grid.sensor[..., D.S_PER_SECOND], -1).ravel())
    assert (res.chosen.h, res.chosen.w) != (res.grid.h[most], res.grid.w[most])
    # The front is ordered by the objective: fewer seconds first.
    front = [c.figures['part_seconds_mean'] for c in res.pareto]
    assert front == sorted(front)


def test_the_ready_rate_objective_reproduces_the_choice_before_objectives(triangle):
    opt = D.eval_options(triangle, **SMALL)
    res = S.search(triangle, **GRID, top=3, options=opt, workers=1, objective='ready_rate')
    ok, _, _ = _eligible_by_columns(res.grid, opt)
    rate = np.where(ok, res.grid.sensor[..., D.S_PER_SECOND], -1)
    k = np.unravel_index(np.argmax(rate), rate.shape)[0]
    assert (res.candidates[0].h, res.candidates[0].w) == (res.grid.h[k], res.grid.w[k])
    # What `search` chose on this grid before it had objectives (commit f56a59b): the
    # refinement's (h -1.0667 cm, 4.0 rad/s).
    assert res.chosen.stage == 'refined'
    assert res.chosen.h == pytest.approx(-0.032 / 3, abs=1e-15) and res.chosen.w == 4.0
    rates = [c.feed() for c in res.candidates + [res.reference]
             if c.figures['never_ready'] == 0]
    assert res.chosen.feed() == max(rates)
    with pytest.raises(InputError, match='part_time, ready_rate'):
        S.search(triangle, **GRID, options=opt, objective='fast')


def test_cli_says_which_objective_ranked_and_shows_both_figures(capsys):
    scene = str(SCENES / 'triangle.yaml')
    args = ['design-search', scene, '--grid', '3x3', '--h=-0.012:-0.004', '--speed',
            '4:6.5', '--top', '1', '--quiet']
    out = io.StringIO()
    assert main(args + ['--objective', 'ready-rate', '--json'], out=out) == 0
    result = json.loads(out.getvalue())
    assert result['objective'] == 'ready_rate'
    assert result['first_ready_from'] == 'grid of starts'
    for cand in [result['chosen'], result['scene_design']] + result['pareto']:
        for name in ('part_seconds_mean', 'part_seconds_p95', 'parts_per_minute',
                     'readies_per_second'):
            assert name in cand['figures']
    out = io.StringIO()
    assert main(args + ['--arrival', '1:0.10:0.14'], out=out) == 0
    text = out.getvalue()
    assert 'ranked by mean seconds from arrival to first proven ready' in text
    assert '--objective part-time' in text and 'arrivals on edge 1' in text
    assert 's/part mean/p95' in text and 'parts/min' in text and 'readies/s' in text


@pytest.mark.parametrize('option, message', [
    (['--objective', 'fast'], '--objective: expected one of part-time, ready-rate'),
    (['--objective', 'part_time'], '--objective: expected one of part-time, ready-rate'),
    (['--arrival', '1:0.1'], '--arrival: expected EDGE:RMIN:RMAX'),
    (['--arrival', 'a:0.1:0.2'], '--arrival: expected EDGE:RMIN:RMAX'),
    (['--arrival', '1:0.2:0.1'], '--arrival: need finite RMIN <= RMAX'),
    (['--arrival', '1:nan:0.1'], '--arrival: need finite RMIN <= RMAX'),
    (['--arrival', '5:0.1:0.2'], 'arrival: edge 5 is not a stable edge'),
    (['--arrival', '1:0.01:0.2'], 'lies outside the domain of f: R_min of edge 1 is 0.054667 m'),
])
def test_design_search_refuses_a_bad_objective_or_arrival(option, message, capsys):
    assert main(['design-search', str(SCENES / 'triangle.yaml'), '--grid', '3x3', '--quiet',
                 *option]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count('\n') == 1
