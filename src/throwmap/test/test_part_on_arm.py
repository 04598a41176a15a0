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

"""PartOnArm, the part the sim, the emulator and the monitor follow: throws, losses, readings."""

import math

import numpy as np
import pytest
from throwmap import (analyse, DomainError, load_scene, PartOnArm, resting_pose, Scene, sees,
                      ThrowmapError, wrap_angle)
from throwmap.part_on_arm import LOST
from throwmap_testing import PAPER_W, SCENES, TRIANGLE_VERTICES

HOUSE = str(SCENES / 'house.yaml')


@pytest.fixture(scope='module')
def short_arm():
    """Return the triangle on a 33 cm arm: a part resting near the end falls off."""
    return Scene({'name': 'short_arm', 'part': {'vertices': TRIANGLE_VERTICES},
                  'arm': {'offset': -0.005, 'length_cm': 33},
                  'throw': {'release_speed': PAPER_W}, 'gravity': -9.66,
                  'effects': ['finite_arm'], 'sensor': {'goal_edge': 1},
                  'start': {'edge': 1, 'R': 0.12}})


def body_to_world(part, pose):
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    rel = part.vertices - part.cm
    return np.stack([x + c * rel[:, 0] - s * rel[:, 1], y + s * rel[:, 0] + c * rel[:, 1]], 1)


@pytest.mark.parametrize('edge', [0, 1, 2])
def test_resting_pose_places_the_body_like_pose_vertices(triangle_scene, edge):
    part, h = triangle_scene.part, triangle_scene.h
    R = 0.15
    world = body_to_world(part, resting_pose(part, edge, R, h))
    np.testing.assert_allclose(world, part.pose_vertices(edge, R, h), atol=1e-12)
    # Resting on the edge: its two vertices lie on the arm surface y = h, the rest above.
    assert np.isclose(world[:, 1].min(), h)
    assert np.sum(np.isclose(world[:, 1], h)) == 2
    assert wrap_angle(-math.pi) == math.pi
    assert math.isclose(wrap_angle(3 * math.pi / 2), -math.pi / 2)


def test_a_throw_follows_the_throw_map(triangle_scene):
    model = triangle_scene.model
    edge, R = triangle_scene.default_start()
    part = PartOnArm(triangle_scene, edge, R, sensor_radius=0.2671)
    for k in range(1, 60):
        expected = model.f(edge, R)
        throw = part.throw()
        assert (throw.edge0, throw.R0) == (edge, R)
        assert (throw.edge, throw.R, throw.kind) == expected
        assert throw.count == k
        assert throw.detected == bool(sees(triangle_scene.part, throw.edge, throw.R, 0.2671, 0.0))
        edge, R = expected[0], expected[1]
        assert part.state == (edge, R)
        assert part.pose()[0] == R


def test_the_sensor_fires_in_the_limit_set_only_on_the_goal_edge(triangle_scene):
    sensor = analyse(triangle_scene).sensor
    part = PartOnArm(triangle_scene, sensor_radius=sensor.radius)
    seen = [part.throw() for _ in range(600)]
    hits = [t for t in seen[sensor.warmup_throws:] if t.detected]
    assert len(hits) > 10
    assert all(t.edge == sensor.goal_edge for t in hits)


def test_placing_a_part_outside_the_domain_is_refused(triangle_scene):
    part = PartOnArm(triangle_scene, 1, 0.12, 0.26)
    with pytest.raises(DomainError, match='no dynamic grasp'):
        part.place(1, 0.001)
    assert part.state == (1, 0.12)
    part.throw()
    part.place(0, 0.16)
    assert (part.state, part.count) == ((0, 0.16), 0)


def test_a_part_lost_off_the_arm_end_leaves_the_arm_empty(short_arm):
    part = PartOnArm(short_arm, 1, 0.32, sensor_radius=0.2672)
    lost = part.throw()
    assert (lost.edge0, lost.R0, lost.edge, lost.kind, lost.count) == (1, 0.32, -1, LOST, 1)
    assert math.isnan(lost.R) and not lost.on_arm and not lost.detected
    assert part.lost and part.lost_at == 1 and part.pose() is None and part.polygon() is None
    for k in range(2, 6):           # nothing left to throw, nothing to see
        empty = part.throw()
        assert (empty.edge0, empty.edge, empty.kind, empty.detected, empty.count) == \
            (-1, -1, LOST, False, k)
    assert part.lost_at == 1
    part.place(1, 0.12)             # a part is put back
    assert part.state == (1, 0.12) and not part.lost and part.lost_at is None
    assert (part.throw().edge, part.state) == (1, short_arm.model.f(1, 0.12)[:2])


def noisy_run(seed, throws=300, noisy_sensor=True):
    """(edge, R, kind, bit) of each throw on the noisy house scene (or the error text)."""
    scene = load_scene(HOUSE)
    part = PartOnArm(scene, sensor_radius=0.2129, footprint=0.005, noisy_sensor=noisy_sensor,
                     seed=seed)
    out = []
    for _ in range(throws):
        try:
            t = part.throw()
        except ThrowmapError as exc:    # a noisy throw may leave the domain of f
            out.append(str(exc))
            continue
        out.append((t.edge, round(t.R, 12), t.kind, t.detected))
    return out


def test_a_noisy_scene_is_reproducible_with_its_seed():
    scene = load_scene(HOUSE)
    assert scene.stochastic and scene.noisy_sensor
    first = noisy_run(7)
    assert noisy_run(7) == first
    assert noisy_run(8) != first
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


def test_the_nominal_model_predicts_without_noise(triangle_scene):
    scene = load_scene(HOUSE)
    model = scene.model.nominal()
    assert model is not scene.model and not model.stochastic
    assert model.f(0, 0.15) == model.f(0, 0.15)      # no release noise
    assert triangle_scene.model.nominal() is triangle_scene.model
    part = PartOnArm(scene, 0, 0.15, 0.2129, 0.005, model=model, noisy_sensor=False)
    bits = [part.throw() for _ in range(200)]
    assert all(t.detected == part.sees(t.edge, t.R) for t in bits)


def test_an_orbit_and_its_readings_at_once(triangle_scene, short_arm):
    part = PartOnArm(triangle_scene, sensor_radius=0.2671)
    orb = part.orbit(100)
    assert part.count == 0 and orb.segments == ((0, 100),)
    step = PartOnArm(triangle_scene, sensor_radius=0.2671)
    throws = [step.throw() for _ in range(100)]
    assert [t.edge for t in throws] == orb.edges.tolist()
    assert [t.R for t in throws] == orb.radii.tolist()
    assert part.readings(orb.edges, orb.radii).tolist() == [t.detected for t in throws]
    # On a short arm the orbit from far out ends when the part is lost.
    lost = PartOnArm(short_arm).orbit(50, start=(1, 0.32))
    assert lost.edges.size == 0 and lost.segments == ()
