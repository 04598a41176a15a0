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

from feeder_sim.markers import feeder_markers, part_markers, static_markers
import numpy as np
import pytest


@pytest.fixture(scope='module')
def specs(triangle, triangle_analysis):
    return feeder_markers(triangle, triangle_analysis, triangle_analysis.sensor.radius, 1, 0.2,
                          True)


def by_key(specs):
    return {(s.ns, s.marker_id): s for s in specs}


def test_namespaces_and_ids_are_stable_and_unique(triangle, triangle_analysis, specs):
    keys = [(s.ns, s.marker_id) for s in specs]
    assert len(keys) == len(set(keys))
    other = feeder_markers(triangle, triangle_analysis, triangle_analysis.sensor.radius, 0, 0.17,
                           False)
    assert keys == [(s.ns, s.marker_id) for s in other]
    assert {'arm', 'part', 'sensor', 'limit_set'} <= {s.ns for s in specs}


def test_every_marker_is_visible(specs):
    for s in specs:
        assert 0.0 < s.color[3] <= 1.0, s
        assert all(0.0 <= c <= 1.0 for c in s.color[:3])
        assert max(s.scale) > 0.0, s
        if s.kind in ('line_strip', 'line_list', 'triangle_list'):
            assert len(s.points) >= 2, s


def test_part_outline_is_the_resting_polygon(triangle):
    part, h = triangle.part, triangle.h
    outline, fill = part_markers(part, 2, 0.14, h, on_goal=False)
    verts = part.pose_vertices(2, 0.14, h)
    np.testing.assert_allclose(np.array(outline.points[:-1]), verts)
    assert outline.points[0] == outline.points[-1]
    assert len(fill.points) == 3 * (len(verts) - 2)
    goal_outline, _ = part_markers(part, 2, 0.14, h, on_goal=True)
    assert goal_outline.color != outline.color


def test_bands_follow_the_limit_set_and_the_arm_reaches_the_sensor(triangle, triangle_analysis):
    an = triangle_analysis
    radius = an.sensor.radius
    m = by_key(static_markers(triangle, an, radius))
    for edge, (lo, hi) in an.limit_set.bands.items():
        band = m[('limit_set', edge)]
        xs = sorted(p[0] for p in band.points)
        assert xs == pytest.approx([lo, hi])
        assert all(p[1] < triangle.h for p in band.points)     # drawn under the arm
    arm = m[('arm', 0)]
    assert arm.position[0] + arm.scale[0] / 2 > radius
    assert arm.position[0] - arm.scale[0] / 2 == pytest.approx(0.0)
    guarantee = m[('guarantee', 0)]
    assert guarantee.points[0][0] == pytest.approx(an.sensor.guarantee_radius)


def test_sensor_marker_sits_at_the_radius_and_shows_the_bit(specs, triangle, triangle_analysis):
    m = by_key(specs)
    radius = triangle_analysis.sensor.radius
    assert m[('sensor', 0)].position[0] == pytest.approx(radius)
    assert all(p[0] == pytest.approx(radius) for p in m[('sensor', 1)].points)
    off = by_key(feeder_markers(triangle, triangle_analysis, radius, 1, 0.2, False))
    assert off[('sensor', 0)].color != m[('sensor', 0)].color


def test_a_lost_part_is_deleted_and_a_finite_arm_drawn_to_its_length(short_arm):
    from throwmap import analyse
    an = analyse(short_arm)
    specs = by_key(feeder_markers(short_arm, an, an.sensor.radius, -1, float('nan'), False))
    assert specs[('part', 0)].delete and specs[('part', 1)].delete
    assert specs[('arm', 0)].scale[0] == pytest.approx(0.33)
    assert not any(s.delete for k, s in specs.items() if k[0] != 'part')
