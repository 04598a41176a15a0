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

import math

from feeder_sim.predictor import Predictor, resting_pose, wrap_angle, yaw_quaternion
import numpy as np
import pytest
from throwmap import DomainError, sees


def body_to_world(part, pose):
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    rel = part.vertices - part.cm
    return np.stack([x + c * rel[:, 0] - s * rel[:, 1], y + s * rel[:, 0] + c * rel[:, 1]], 1)


@pytest.mark.parametrize('edge', [0, 1, 2])
def test_resting_pose_places_the_body_like_pose_vertices(triangle, edge):
    part, h = triangle.part, triangle.h
    R = 0.15
    world = body_to_world(part, resting_pose(part, edge, R, h))
    np.testing.assert_allclose(world, part.pose_vertices(edge, R, h), atol=1e-12)
    # Resting on the edge: its two vertices lie on the arm surface y = h, the rest above.
    assert np.isclose(world[:, 1].min(), h)
    assert np.sum(np.isclose(world[:, 1], h)) == 2


def test_quaternion_and_wrap():
    for yaw in (-3.0, -1.0, 0.0, 0.5, 3.0):
        qx, qy, qz, qw = yaw_quaternion(yaw)
        assert (qx, qy) == (0.0, 0.0)
        assert math.isclose(qz * qz + qw * qw, 1.0)
        assert math.isclose(2 * math.atan2(qz, qw), yaw)
    assert wrap_angle(-math.pi) == math.pi
    assert math.isclose(wrap_angle(3 * math.pi / 2), -math.pi / 2)


def test_step_follows_the_throw_map(triangle):
    model = triangle.model
    edge, R = triangle.default_start()
    pred = Predictor(triangle, edge, R, sensor_radius=0.2671)
    for k in range(1, 60):
        expected = model.f(edge, R)
        throw = pred.step()
        assert (throw.edge0, throw.R0) == (edge, R)
        assert (throw.edge, throw.R, throw.kind) == expected
        assert throw.count == k
        assert throw.detected == bool(sees(triangle.part, throw.edge, throw.R, 0.2671, 0.0))
        edge, R = expected[0], expected[1]
        assert pred.state == (edge, R)
        assert pred.pose()[0] == R


def test_sensor_fires_in_the_limit_set_only_on_the_goal_edge(triangle, triangle_analysis):
    sensor = triangle_analysis.sensor
    pred = Predictor(triangle, *triangle.default_start(), sensor.radius)
    seen = [pred.step() for _ in range(600)]
    hits = [t for t in seen[sensor.warmup_throws:] if t.detected]
    assert len(hits) > 10
    assert all(t.edge == sensor.goal_edge for t in hits)


def test_reset_rejects_states_outside_the_domain(triangle):
    pred = Predictor(triangle, 1, 0.12, 0.26)
    with pytest.raises(DomainError, match='no dynamic grasp'):
        pred.reset(1, 0.001)
    assert pred.state == (1, 0.12)
    pred.step()
    pred.reset(0, 0.16)
    assert (pred.state, pred.count) == ((0, 0.16), 0)


def test_stamp_text_round_trip():
    from feeder_sim.ros_glue import stamp_from_text, stamp_text
    t = stamp_from_text('1795362335.204302396')
    assert (t.sec, t.nanosec) == (1795362335, 204302396)
    assert stamp_text(t) == '1795362335.204302396'
    assert stamp_from_text(stamp_text(stamp_from_text('3.000000007'))).nanosec == 7
    assert stamp_from_text('12.5').nanosec == 500_000_000
    assert stamp_from_text('7').sec == 7
    for bad in ('', '-1.5', '1.2e3', 'x'):
        with pytest.raises(ValueError):
            stamp_from_text(bad)
