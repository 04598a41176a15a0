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
The one-bit bound (throwmap.funnel_bound) against the model it claims to bound.

* The continuum argument, checked by simulation: on the triangle (40 cm arm, speeds up to
  600 deg/s), thousands of starts (log-spaced above each edge's lowest start, so the front's
  neighbourhood stays dense however much the jog spreads it) are thrown by random policies that
  use any speed safe for every start still on its edge and unseen (all-zero bits); none finds
  a speed safe before the throw the bound says it is first usable, and some held-back speed
  becomes safe exactly at that throw (the bound is tight there).
* The per-start search against brute force: every speed sequence enumerated without merging.
* An edge whose jog is not checked increasing and jump-free gives no constraint, said in the
  notes.
The bound against every policy, start by start, is in test_funnel.py (its planned fixture).
"""

import itertools
import math

import numpy as np
import pytest
from throwmap import funnel as F
from throwmap import funnel_bound as B
from throwmap.scene import load_scene
from throwmap.sensor import sees
from throwmap_testing import SCENES

SPEEDS_DEG = '300,340,380,440,520,600'


@pytest.fixture(scope='module')
def setup():
    scene, _ = F.arm_scene(load_scene(str(SCENES / 'triangle.yaml')), 0.40)
    speeds = F.parse_speeds(SPEEDS_DEG)
    system = F.build_system(scene, speeds, 0.005, 200, 5)
    thrower = F.Thrower(scene, system)
    models = [thrower.model(k) for k in range(len(speeds))]
    starts = F.start_grid(scene)
    return scene, system, models, starts


def _starts_near_the_front(system, models, starts, per_edge=3000):
    """Start states log-spaced above each edge's lowest start, up to its window (all read 0)."""
    edges, radii = starts
    u_max = models[0].part.U.max(axis=1)
    E, R = [], []
    for e in sorted({int(v) for v in edges}):
        lo = float(radii[edges == e].min())
        top = min(float(radii[edges == e].max()),
                  system.sensor_radius - system.footprint - u_max[e]) - 1e-9
        r = lo + np.concatenate([[0.0], np.geomspace(1e-9, top - lo, per_edge - 1)])
        E.append(np.full(r.size, e))
        R.append(r)
    return np.concatenate(E), np.concatenate(R)


def test_no_policy_finds_a_speed_safe_before_the_bound_says(setup):
    _, system, models, starts = setup
    first, constraining, notes = B.first_use(system, models, starts)
    assert not notes and constraining == sorted(set(starts[0].tolist()))
    part = models[0].part
    E0, R0 = _starts_near_the_front(system, models, starts)
    early, found = [], {}
    for seed in range(6):
        rng = np.random.default_rng(seed)
        E, R, home = E0.copy(), R0.copy(), E0.copy()
        for t in range(1, 100):
            outs = [m.f_batch(E, R) for m in models]
            safe = [k for k, o in enumerate(outs) if np.all((o['status'] == 0) & (o['edge'] >= 0))]
            early += [(seed, t, k) for k in safe if first[k] > t]
            for k in safe:
                found[k] = min(found.get(k, t), t)
            # Mostly the fastest safe speed (the one that could beat the bound), else any.
            k = max(safe) if rng.random() < 0.6 else int(rng.choice(safe))
            E, R = outs[k]['edge'].astype(int), outs[k]['R']
            # The continuum: the starts still on their edge that the sensor has not seen (a 0
            # rules those out).
            keep = (E == home) & ~sees(part, E, R, system.sensor_radius, system.footprint)
            E, R, home = E[keep], R[keep], home[keep]
            if not E.size:
                break
    assert not early, f'(seed, throw, speed) safe before the bound allows them: {early[:10]}'
    # The check bites: speeds the bound holds back do become safe, some at the bound's throw.
    gated = {k: t for k, t in found.items() if first[k] > 1}
    assert gated, f'no held-back speed ever became safe: {found}'
    assert any(t == first[k] for k, t in gated.items()), (gated, first)


def test_the_search_is_brute_force_over_every_sequence(setup):
    # With bins of 1e-9 m the search is brute force's point search; with the default bins it
    # may only be lower (each bin stands for all of its states), never higher.
    _, system, models, starts = setup
    dist = B.full_knowledge_bound(system)
    first = np.array([1, 1, 2, 3, 1, 5], dtype=float)     # gated speeds, as first_use gives
    part = models[0].part
    edges, radii = starts
    checked = 0
    for e0, r0 in zip(edges, radii):
        bound = B.throws_to_first_ready(system, models, int(e0), float(r0), first, dist,
                                        step=1e-9, max_throws=6)
        if bound > 4:
            continue
        assert B.throws_to_first_ready(system, models, int(e0), float(r0), first,
                                       dist) <= bound
        best = math.inf
        for depth in range(1, int(bound) + 1):
            for seq in itertools.product(range(len(models)), repeat=depth):
                if any(first[k] > t + 1 for t, k in enumerate(seq)):
                    continue
                e, r = np.array([int(e0)]), np.array([float(r0)])
                for t, k in enumerate(seq, start=1):
                    res = models[k].f_batch(e, r)
                    if res['status'][0] != 0 or res['edge'][0] < 0:
                        break
                    e, r = res['edge'].astype(int), res['R']
                    if sees(part, e, r, system.sensor_radius, system.footprint)[0]:
                        c = system.cell(int(e[0]), float(r[0]))
                        extra = 0 if e[0] == system.goal_edge or c < 0 else dist[c]
                        best = min(best, t + extra)
                        break
        assert best == bound, (e0, r0)
        checked += 1
    assert checked >= 10


def test_an_edge_the_argument_does_not_hold_for_gives_no_constraint(setup, monkeypatch):
    _, system, models, starts = setup
    monkeypatch.setattr(B, 'JUMP_STEPS', 0)
    first, constraining, notes = B.first_use(system, models, starts)
    assert constraining == [] and np.all(first == 1)
    assert len(notes) == len(set(starts[0].tolist()))
    assert all('gives no constraint' in n for n in notes)


def test_merging_never_loses_the_fastest_sequence():
    # Two speeds 0.003 deg/s apart (320 and the triangle's own 320.003) keep their states
    # within a bin for many throws; merging them to one point took the slower one's path: 28
    # throws from edge 0 at 8.96 cm, where 320.003 deg/s alone is seen on edge 1 after 27.
    scene, _ = F.arm_scene(load_scene(str(SCENES / 'triangle.yaml')), 0.40)
    speeds = np.sort(np.append(F.parse_speeds('320'), float(scene.model.w)))
    system = F.build_system(scene, speeds, 0.005, 200, 5)
    thrower = F.Thrower(scene, system)
    models = [thrower.model(k) for k in range(len(speeds))]
    starts = F.start_grid(scene)
    dist = B.full_knowledge_bound(system)
    part = scene.model.part
    for i in (5, 0, 40):
        e0, r0 = int(starts[0][i]), float(starts[1][i])
        alone = []
        for k in range(len(speeds)):
            e, r = e0, r0
            for t in range(1, 200):
                e, r = thrower.throw(k, e, r)
                if sees(part, e, r, system.sensor_radius, system.footprint):
                    c = system.cell(e, r)
                    alone.append(t + (0 if e == system.goal_edge else dist[c]))
                    break
        both = B.throws_to_first_ready(system, models, e0, r0, np.ones(len(speeds)), dist)
        assert both <= min(alone), (i, both, alone)
