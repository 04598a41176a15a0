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

"""The paper's own numbers and figures (section V) as acceptance tests."""

import math

import numpy as np
import pytest
from throwmap import (analyse, basin, default_grid, design_radii, limit_set, orbit, Part, sees,
                      ThrowModel)


def test_triangle_mass_properties_are_the_uniform_6_8_10_lamina(triangle):
    part = triangle.part
    assert part.cm == pytest.approx([0.04, 0.08 / 3], abs=1e-15)
    # rho^2 of a right triangle with legs a, b about its centroid: (a^2 + b^2) / 18.
    assert part.rho2 == pytest.approx((0.06 ** 2 + 0.08 ** 2) / 18, rel=1e-12)
    # Heights of the CM over E0 (8 cm leg), E1 (hypotenuse), E2 (6 cm leg): 2, 1.6, 8/3 cm.
    assert part.d == pytest.approx([0.02, 0.016, 0.08 / 3], rel=1e-12)
    assert part.stable.all()
    assert part.r == pytest.approx(math.hypot(0.02, 0.08 - 0.08 / 3), rel=1e-12)   # V1


def test_triangle_grasp_matches_paper(triangle):
    rows, r_grasp, mu_min = triangle.grasp_table()
    # Paper, section V.A: "a dynamic grasp is guaranteed for all edges ... for R >= 5.68 cm and
    # mu >= 0.382". The reconstruction gives 17/3 cm exactly (bound (3) on E2).
    assert r_grasp == pytest.approx(0.17 / 3, rel=1e-12)
    assert r_grasp == pytest.approx(0.0568, abs=0.0002)
    assert round(mu_min, 3) == 0.382
    e2 = rows[2]
    assert e2.R_grasp == pytest.approx(r_grasp) and e2.binding == 3


def test_bracket_placeholder_matches_printed_grasp_numbers():
    from throwmap import load_scene
    from throwmap_testing import SCENES
    scene = load_scene(str(SCENES / 'bracket.yaml'))
    rows, r_grasp, mu_min = scene.model.grasp_table()
    assert [g.stable for g in rows] == [True, True, False, True, True]   # "edge 2 unstable"
    assert r_grasp == pytest.approx(0.1383, abs=0.00005)
    assert mu_min == pytest.approx(0.177, abs=0.0015)


def test_bracket_cycle_is_figure_8():
    from throwmap import load_scene
    from throwmap_testing import SCENES
    scene = load_scene(str(SCENES / 'bracket.yaml'))
    ls = limit_set(scene.model, *scene.default_start(), throws=4000)
    # Figure 8: jogs on E4, flip to E3, jogs on E3, flip to E1, flip to E0, flip to E4.
    rotated = ls.pattern[ls.pattern.index(4):] + ls.pattern[:ls.pattern.index(4)]
    assert rotated == (4, 3, 1, 0)
    assert ls.jogs[4][0] >= 1 and ls.jogs[3][0] >= 1


def test_figure_5_sequence_from_1_12cm(triangle):
    orb = orbit(triangle, 1, 0.12, 60)
    e, kinds = list(orb.edges), list(orb.kinds)
    # Jogs on edge 1 first, outward (Prop. IV.4) ...
    first_flip = kinds.index('flip')
    assert first_flip >= 3
    assert all(e[k] == 1 for k in range(first_flip))
    assert np.all(np.diff(orb.radii[:first_flip]) > 0)
    # ... then a flip to edge 0, a flip to edge 2, zero to three jogs on edge 2, back to edge 1.
    assert e[first_flip] == 0
    assert e[first_flip + 1] == 2 and kinds[first_flip + 1] == 'flip'
    k = first_flip + 2
    jogs_on_2 = 0
    while e[k] == 2:
        assert kinds[k] == 'jog'
        jogs_on_2 += 1
        k += 1
    assert 0 <= jogs_on_2 <= 3
    assert e[k] == 1 and kinds[k] == 'flip'


def test_figure_7_every_start_converges_to_the_same_cycle(triangle):
    ref = limit_set(triangle, 1, 0.12, 10_000)
    assert ref.pattern == (0, 2, 1)
    starts_e, starts_r = default_grid(triangle, radii_per_edge=50)
    assert len(starts_e) == 150
    bas = basin(triangle, starts_e, starts_r, throws=1000, reference=ref)
    assert set(bas.signatures) == {'0-2-1'}
    assert np.all(bas.status == 0)


def test_only_edge_1_beyond_the_sensor_radius(triangle_scene):
    an = analyse(triangle_scene)
    sensor = an.sensor
    assert sensor.goal_edge == 1 and sensor.feasible
    # Paper, section V.B: "by placing the sensor at a radius greater than 25 cm, we can be
    # certain that when the part is detected, it must lie on edge 1".
    assert 0.24 < sensor.guarantee_radius < 0.27
    model = triangle_scene.model
    # Independent check on fresh orbits from many starts, after the computed warm-up.
    starts_e, starts_r = default_grid(model, radii_per_edge=20)
    e, r, _, status, _ = model.orbits(starts_e, starts_r, 600)
    assert np.all(status == 0)
    after = np.s_[:, sensor.warmup_throws:]
    seen = sees(triangle_scene.part, e[after], r[after], sensor.radius, sensor.footprint)
    assert seen.any()
    assert set(np.unique(e[after][seen])) == {1}
    # A sensor inside the guarantee radius would be fooled by another edge.
    inside = sensor.guarantee_radius - 0.01
    seen_inside = sees(triangle_scene.part, e[after], r[after], inside, 0.0)
    assert set(np.unique(e[after][seen_inside])) - {1}


def test_design_radii_ordering_prop_iv4(triangle):
    d = design_radii(triangle)
    assert d['invariant']
    for row in d['edges']:
        assert row['R_grasp'] <= row['R_min'] < row['R_flip'] <= row['R_max']
        i = row['edge']
        # R_min adds the toe-stub bound: the left vertex must start right of the pivot.
        assert row['R_min'] == pytest.approx(max(row['R_grasp'], -triangle.part.u_l[i]))
        # Below R_flip a throw jogs outward; at R_flip it flips.
        for R in np.linspace(row['R_min'] * 1.0001, row['R_flip'] * 0.999, 15):
            e1, r1, kind = triangle.f(i, R)
            assert kind == 'jog' and r1 > R
        assert triangle.f(i, row['R_flip'])[2] == 'flip'


def test_first_stable_rule_gives_same_cycle_on_triangle():
    model = ThrowModel(Part([[0.06, 0.0], [0.06, 0.08], [0.0, 0.0]]), -0.005,
                       math.radians(320), -9.66, settle_rule='first_stable')
    ls = limit_set(model, 1, 0.12, 4000)
    assert ls.pattern == (0, 2, 1)


def test_sensor_design_when_only_the_goal_edge_recurs():
    """A limit set on the goal edge alone: every spot its shadow covers proves the goal edge."""
    from throwmap import load_scene
    from throwmap_testing import SCENES
    scene = load_scene(str(SCENES / 'hard' / 'slow_release.yaml'))
    an = analyse(scene)
    assert set(an.limit_set.bands) == {an.sensor.goal_edge}
    assert an.sensor.guarantee_radius == float('-inf') and an.sensor.feasible
    assert math.isfinite(an.sensor.radius) and an.sensor.radius < an.sensor.reach_radius
    assert an.sensor.detection_rate > 0


def test_a_lost_part_is_never_seen(triangle_scene):
    assert not triangle_scene.sense(-1, 0.24, x=0.25)
    assert triangle_scene.sense(1, 0.24, x=0.25)


def test_figure_7_with_the_papers_100_throws_labels_every_start(triangle):
    """100 throws per start, as in Figure 7: slow starts enter late but follow the cycle."""
    ref = limit_set(triangle, 1, 0.12, 10_000)
    starts_e, starts_r = default_grid(triangle, radii_per_edge=50)
    bas = basin(triangle, starts_e, starts_r, throws=100, reference=ref)
    assert bas.summary() == {'0-2-1': 150}
    assert bas.transients.max() > 50          # some starts take most of the 100 throws
    short = basin(triangle, starts_e, starts_r, throws=10, reference=ref)
    assert short.summary().get('not converged', 0) > 0
