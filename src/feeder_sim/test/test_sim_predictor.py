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

from feeder_sim.predictor import (has_noisy_sensor, LOST, prediction_model, Predictor,
                                  resting_pose, wrap_angle, yaw_quaternion)
import numpy as np
import pytest
from throwmap import DomainError, load_scene, sees, ThrowmapError


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


def test_a_part_lost_off_the_arm_end_leaves_the_arm_empty(short_arm):
    pred = Predictor(short_arm, 1, 0.32, sensor_radius=0.2672)
    lost = pred.step()
    assert (lost.edge0, lost.R0, lost.edge, lost.kind, lost.count) == (1, 0.32, -1, LOST, 1)
    assert math.isnan(lost.R) and not lost.on_arm and not lost.detected
    assert pred.lost and pred.lost_at == 1 and pred.pose() is None and pred.polygon() is None
    for k in range(2, 6):           # nothing left to throw, nothing to see
        empty = pred.step()
        assert (empty.edge0, empty.edge, empty.kind, empty.detected, empty.count) == \
            (-1, -1, LOST, False, k)
    assert pred.lost_at == 1
    pred.reset(1, 0.12)             # a part is put back
    assert pred.state == (1, 0.12) and not pred.lost and pred.lost_at is None
    assert (pred.step().edge, pred.state) == (1, short_arm.model.f(1, 0.12)[:2])


def noisy_run(path, seed, throws=300, noisy_sensor=True):
    """(edge, R, kind, bit) of each throw of a hardware-mode predictor (or the error text)."""
    scene = load_scene(path)
    pred = Predictor(scene, *scene.default_start(), sensor_radius=0.2129, footprint=0.005,
                     noisy_sensor=noisy_sensor, seed=seed)
    out = []
    for _ in range(throws):
        try:
            t = pred.step()
        except ThrowmapError as exc:    # a noisy throw may leave the domain of f
            out.append(str(exc))
            continue
        out.append((t.edge, round(t.R, 12), t.kind, t.detected))
    return out


def test_noisy_scene_is_reproducible_with_its_seed(house_path):
    scene = load_scene(house_path)
    assert scene.stochastic and has_noisy_sensor(scene)
    first = noisy_run(house_path, 7)
    assert noisy_run(house_path, 7) == first
    assert noisy_run(house_path, 8) != first
    # The same sequence, computed independently: each throw draws from the scene's generator
    # (release_noise), then the reading (sensor_noise).
    scene.model.reseed(7)
    state, expected = scene.default_start(), []
    for _ in range(len(first)):
        try:
            edge, R, kind = scene.model.f(*state)
        except ThrowmapError as exc:
            expected.append(str(exc))
            continue
        state = (edge, R)
        bit = bool(scene.sense(edge, R, 0.2129, 0.005))
        expected.append((edge, round(R, 12), kind, bit))
    assert first == expected
    # The readings are the sensor's, not the geometry's: some differ from throwmap.sees.
    geometric = [bool(sees(scene.part, e, R, 0.2129, 0.005)) for e, R, _, _ in
                 (x for x in first if isinstance(x, tuple))]
    readings = [x[3] for x in first if isinstance(x, tuple)]
    assert readings != geometric


def test_predictor_mode_predicts_with_the_noise_free_map(house_path, triangle):
    scene = load_scene(house_path)
    model = prediction_model(scene)
    assert model is not scene.model
    assert model.f(0, 0.15) == model.f(0, 0.15)      # no release noise
    assert prediction_model(triangle) is triangle.model
    pred = Predictor(scene, 0, 0.15, 0.2129, 0.005, model=model)
    bits = [pred.step() for _ in range(200)]
    assert all(t.detected == pred.sees(t.edge, t.R) for t in bits)
