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

"""Predictor mode: a second sim follows the sim-as-hardware through cycle_status alone."""

from diagnostic_msgs.msg import DiagnosticStatus
from feeder_nodes import (Collector, Diagnostics, sim_as_hardware, STARTUP_TIMEOUT, TRIANGLE,
                          wait_for_readers)
from geometry_msgs.msg import PoseStamped
from std_msgs.msg import Float64, Int32, String
from std_srvs.srv import Trigger

N = 40
PRED = '/feeder/predictor'


def test_predictor_follows_the_hardware(graph, ros):
    sim_as_hardware(graph)
    graph.start('feeder_sim', 'sim_node', '--ros-args', '-r', f'__ns:={PRED}', '-r',
                'cycle_status:=/feeder/cycle_status', '-p', f'scene:={TRIANGLE}',
                '-p', 'diagnostics_period:=0.2', name='predictor')
    hw = {n: Collector(ros, t, f'/feeder/predicted/{n}') for n, t in
          (('edge', Int32), ('radius', Float64), ('throw_kind', String),
           ('part_pose', PoseStamped))}
    pr = {n: Collector(ros, t, f'{PRED}/predicted/{n}') for n, t in
          (('edge', Int32), ('radius', Float64), ('throw_kind', String),
           ('part_pose', PoseStamped))}
    statuses = Collector(ros, DiagnosticStatus, '/feeder/cycle_status')
    diags = Diagnostics(ros)
    wait_for_readers(ros, '/feeder/cycle_status', 2)        # the predictor's and ours
    ros.spin_until(lambda: ros.node.count_publishers(f'{PRED}/predicted/edge') >= 1,
                   STARTUP_TIMEOUT, 'the predictor active')
    ros.spin_for(0.5)
    for _ in range(N):
        assert ros.call(Trigger, '/feeder/feeder_driver/trigger_cycle', Trigger.Request()).success
    ros.spin_until(lambda: all(len(c) == N for c in [*hw.values(), *pr.values(), statuses]),
                   20.0, f'{N} predictions from both')
    for name in ('edge', 'radius', 'throw_kind'):
        assert [m.data for m in pr[name].msgs] == [m.data for m in hw[name].msgs], name
    assert [p.pose for p in pr['part_pose'].msgs] == [p.pose for p in hw['part_pose'].msgs]
    # Stamped like the hardware's samples.
    assert [p.header.stamp for p in pr['part_pose'].msgs] == \
        [p.header.stamp for p in hw['part_pose'].msgs]
    assert len({m.data for m in hw['edge'].msgs}) >= 2       # it did flip

    name = 'feeder_sim: sensor agreement'

    def agreed():
        got = diags.by_name.get(name)
        return bool(got) and Diagnostics.values(got[-1])['followed'] == str(N)

    ros.spin_until(agreed, 5.0, 'predictor diagnostics')
    last = Diagnostics.values(diags.by_name[name][-1])
    assert (last['agree'], last['disagree'], last['missed'], last['failed']) == \
        (str(N), '0', '0', '0')
    assert diags.by_name[name][-1].level == DiagnosticStatus.OK
