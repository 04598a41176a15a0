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
Predictor mode: a sim follows the sim-as-hardware through cycle_status alone, in its namespace.

The hardware stand-in offers only the driver's interface, so the predictor runs beside it in
/feeder without a collision; its predictions are checked against the throw map itself and the
sensor bits the hardware sent.
"""

import math

from diagnostic_msgs.msg import DiagnosticStatus
from feeder_common.messages import time_ns
from feeder_nodes import (Collector, CycleStatuses, Diagnostics, DRIVER, PredictedStates,
                          predictor, PREDICTOR, sim_as_hardware, TRIANGLE)
from geometry_msgs.msg import PoseStamped
import pytest
from std_srvs.srv import Trigger
from throwmap import analyse, load_scene, sees

N = 40


def test_predictor_follows_the_hardware(graph, ros):
    sim_as_hardware(graph, 'diagnostics_period:=0.2')
    predictor(graph, 'diagnostics_period:=0.2')
    states = PredictedStates(ros)
    poses = Collector(ros, PoseStamped, '/feeder/predicted/part_pose')
    statuses = CycleStatuses(ros)
    diags = Diagnostics(ros)
    # The stand-in's cycle_status matched the predictor's reader and ours, the predictor's
    # writers ours.
    ros.wait_remote_matched(DRIVER, readers={'/feeder/cycle_status': 2})
    ros.wait_remote_matched(PREDICTOR, readers={'/feeder/predicted/state': 1,
                                                '/feeder/predicted/part_pose': 1})
    # Exactly one publisher: the predictor; the hardware stand-in publishes no predictions.
    assert ros.node.count_publishers('/feeder/predicted/state') == 1
    for _ in range(N):
        assert ros.call(Trigger, '/feeder/feeder_driver/trigger_cycle', Trigger.Request()).success
    ros.spin_until(lambda: all(len(c) == N for c in (states, poses, statuses)), 20.0,
                   f'{N} predictions')

    # The throw map itself, from the scene's start.
    scene = load_scene(TRIANGLE)
    an = analyse(scene)
    state, expected = scene.default_start(), []
    for _ in range(N):
        state = scene.model.f(*state)
        expected.append(state)
        state = state[:2]
    predicted = states.parsed
    assert [(p.edge, p.R, p.throw_kind) for p in predicted] == expected     # to the bit
    # Each state names its cycle: the seq and the sample stamp of its cycle_status.
    reports = statuses.parsed
    assert [(p.seq, p.stamp_ns) for p in predicted] == [(s.seq, s.stamp_ns) for s in reports]
    # ... the same fields on the wire (PredictedState's stamp is CycleStatus's).
    assert [(m.seq, m.stamp) for m in states.msgs] == [(m.seq, m.stamp) for m in statuses.msgs]
    assert len({e for e, _, _ in expected}) >= 2         # it did flip
    # The hardware's sensor bits are what the sensor sees of that state.
    bits = [s.sensor for s in reports]
    assert bits == [bool(sees(scene.part, e, r, an.sensor.radius, an.sensor.footprint))
                    for e, r, _ in expected]
    # Poses in feeder_base (REP 103: z up), stamped like the hardware's samples.
    for pose, (e, r, _), status in zip(poses.msgs, expected, reports):
        assert pose.header.frame_id == 'feeder_base'
        assert pose.pose.position.x == r and pose.pose.position.y == 0.0
        assert pose.pose.position.z == pytest.approx(scene.h + scene.part.d[e])
        q = pose.pose.orientation
        assert q.x == 0.0 and q.z == 0.0 and math.isclose(q.y ** 2 + q.w ** 2, 1.0)
        assert time_ns(pose.header.stamp) == status.stamp_ns

    name = 'feeder_sim: sensor agreement'

    def agreed():
        got = diags.by_name.get(name)
        return bool(got) and Diagnostics.values(got[-1])['followed'] == str(N)

    ros.spin_until(agreed, 5.0, 'predictor diagnostics')
    last = Diagnostics.values(diags.by_name[name][-1])
    assert (last['agree'], last['disagree'], last['missed'], last['failed']) == \
        (str(N), '0', '0', '0')
    assert diags.by_name[name][-1].level == DiagnosticStatus.OK
    # The stand-in's simulated part and the prediction end in the same state.
    ros.spin_until(lambda: Diagnostics.values(
        diags.by_name['feeder_driver: prediction'][-1])['throws'] == str(N), 5.0,
        'the stand-in diagnostics')
    hw = Diagnostics.values(diags.by_name['feeder_driver: prediction'][-1])
    pr_state = Diagnostics.values(diags.by_name['feeder_sim: prediction'][-1])
    assert (hw['edge'], hw['R']) == (pr_state['edge'], pr_state['R']) == \
        (str(expected[-1][0]), f'{expected[-1][1]:.6f}')
