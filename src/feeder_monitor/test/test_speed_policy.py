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
The monitor under a speed policy (feeder_monitor.speed_policy), against the part's truth.

The monitor's judgement is followed through the real throw map at the speeds it chooses, with
throws anywhere in the error box: every ready is checked against the part's true edge; a
failed or unseen cycle forgets the part; a cycle at a speed it did not choose is followed with
that speed; a policy made for another feeder is refused at configure.
"""

import json
import math
import pathlib
import types

from feeder_monitor.readiness import ANOMALY, READY, TRACKING
from feeder_monitor.speed_policy import load_tracker, PolicyReadiness
import numpy as np
import pytest
from throwmap import funnel as F
from throwmap import load_scene
from throwmap.part_on_arm import PartOnArm

SCENES = pathlib.Path(__file__).resolve().parents[3] / 'scenes'
TRIANGLE = str(SCENES / 'triangle.yaml')


@pytest.fixture(scope='module')
def scene():
    return load_scene(TRIANGLE)


@pytest.fixture(scope='module')
def policy_path(scene, tmp_path_factory):
    arm, _ = F.arm_scene(scene, None)
    result = F.plan(arm, F.parse_speeds('200:440:40'), robust=0.005, cells=200,
                    one_bit=False)
    path = tmp_path_factory.mktemp('policy') / 'triangle_funnel_policy.json'
    path.write_text(json.dumps(F.policy_dict(result, TRIANGLE)))
    return str(path)


def rules_of(policy_path, **change):
    d = json.loads(open(policy_path).read())
    return types.SimpleNamespace(**{'goal_edge': d['goal_edge'], 'noisy_sensor': False,
                                    'sensor_radius': d['sensor_radius'], **change})


def test_a_policy_for_another_feeder_is_refused_naming_what_differs(scene, policy_path):
    load_tracker(policy_path, rules_of(policy_path), scene)
    with pytest.raises(ValueError, match='sensor at .* the monitor.s at 0.250000 m'):
        load_tracker(policy_path, rules_of(policy_path, sensor_radius=0.25), scene)
    with pytest.raises(ValueError, match="goal edge 1, the monitor's is 0"):
        load_tracker(policy_path, rules_of(policy_path, goal_edge=0), scene)
    other = load_scene(str(SCENES / 'bracket.yaml'))
    with pytest.raises(ValueError, match='another feeder'):
        load_tracker(policy_path, rules_of(policy_path), other)
    with pytest.raises(ValueError, match='sensor is noisy'):
        load_tracker(policy_path, rules_of(policy_path, noisy_sensor=True), scene)
    with pytest.raises(ValueError, match='cannot read'):
        load_tracker(policy_path + '.missing', rules_of(policy_path), scene)


def run_parts(scene, policy_path, parts, rng, corner=True):
    """Feed ``parts`` parts from random start cells; return throws per part and the readies."""
    tracker = load_tracker(policy_path, rules_of(policy_path), scene)
    system = tracker.system
    monitor = PolicyReadiness(rules_of(policy_path), tracker)
    start_cells = np.nonzero(tracker.start)[0]
    part = PartOnArm(scene, *scene.default_start(), sensor_radius=system.sensor_radius,
                     footprint=system.footprint)
    seq, throws, readies = 0, [], []
    for _ in range(parts):
        edge, lo, hi = system.bounds(rng.choice(start_cells))
        part.place(edge, rng.uniform(lo, hi))
        monitor.new_part()
        for n in range(1, 301):
            seq += 1
            w = monitor.next_speed
            s = rng.choice([-1.0, 1.0]) if corner else rng.uniform(-1, 1)
            t = part.throw(release_speed=w * (1 + system.robust * s))
            assert t.on_arm, 'the policy lost a part'
            v = monitor.completed(seq, t.detected, speed=w)
            if v.ready:
                readies.append((part.edge, v.state))
                break
        throws.append(n)
    return np.array(throws), readies


def test_every_ready_under_the_policy_is_on_the_goal_edge_with_errors_in_the_box(
        scene, policy_path):
    throws, readies = run_parts(scene, policy_path, 40, np.random.default_rng(1))
    assert len(readies) == 40
    assert all(edge == 1 and state == READY for edge, state in readies)
    assert throws.max() < 300


def test_what_breaks_the_premise_forgets_the_part(scene, policy_path):
    tracker = load_tracker(policy_path, rules_of(policy_path), scene)
    monitor = PolicyReadiness(rules_of(policy_path), tracker)
    every = tracker.system.n
    monitor.new_part()
    start = monitor.knowledge_cells
    assert 0 < start < every
    v = monitor.failed(1, 'no ACK')
    assert v.state == ANOMALY and monitor.knowledge_cells == every
    monitor.new_part()
    w = monitor.next_speed
    v = monitor.completed(5, False, speed=w)    # cycles 2..4 unseen
    assert v.state == ANOMALY and 'missing cycles' in v.anomaly
    every_cell = np.ones(every, dtype=bool)
    after = tracker.system.update(every_cell, tracker.speed_index(w), False)
    assert np.array_equal(tracker.know, after)
    # A cycle the driver fired at the controller's own speed (no setpoint): the scene's.
    monitor.new_part()
    know = tracker.know.copy()
    v = monitor.completed(6, False, speed=None)
    assert v.state == TRACKING and monitor.counts['fixed_speed_cycles'] == 1
    assert np.array_equal(tracker.know,
                          tracker.system.update(know, tracker.home, False))
    # At a speed the policy has no map for: every cell the bit allows.
    v = monitor.completed(7, False, speed=1.234)
    assert monitor.counts['unknown_speed'] == 1 and 'none of the policy' in v.note
    assert monitor.knowledge_cells == int(tracker.system.can_miss.sum())


def test_a_ready_is_never_given_for_a_superseded_cycle(scene, policy_path):
    tracker = load_tracker(policy_path, rules_of(policy_path), scene)
    monitor = PolicyReadiness(rules_of(policy_path), tracker)
    monitor.new_part()
    system = tracker.system
    # Knowledge: one goal cell in the window with every image cell seen and on the goal edge.
    for c in np.nonzero(system.goal & system.can_see & ~system.can_miss)[0]:
        tracker.know[:] = False
        tracker.know[c] = True
        k = tracker.speed_index(monitor.choose())
        image = system.image(tracker.know, k)
        if image.any() and not (image & ~system.goal).any() and \
                not (image & system.can_miss).any():
            break
    else:
        pytest.fail('the cell map has no goal cell in the window whose image is all seen and '
                    'on the goal edge: the test needs one')
    monitor.fired(2)        # the next cycle fired before this one was judged
    v = monitor.completed(1, True, speed=monitor.next_speed)
    assert not v.ready and monitor.counts['superseded'] == 1
    assert math.isfinite(monitor.next_speed)
    # The same knowledge and detection for the newest cycle fired: a ready.
    tracker.know[:] = False
    tracker.know[c] = True
    monitor.choose()
    v = monitor.completed(2, True, speed=monitor.next_speed)
    assert v.ready and v.state == READY
