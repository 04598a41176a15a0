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
The hardware stand-in's joint_states at a steady rate (issue 23, item 5).

Between its (instantaneous) cycles the stand-in publishes the arm's follow-through at
``joint_states_rate`` (default 30 Hz), so robot_state_publisher and RViz animate the arm;
with 0 only the release and rest messages remain (two per cycle).
"""

from feeder_nodes import Collector, sim_as_hardware, STARTUP_TIMEOUT
from sensor_msgs.msg import JointState
from std_srvs.srv import SetBool, Trigger

W = 5.585       # rad/s, the triangle's release speed


def seconds(msg):
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


def test_the_stand_in_swings_the_arm_at_30_hz_by_default(graph, ros):
    sim_as_hardware(graph, 'cycle_period:=0.4')
    joints = Collector(ros, JointState, '/feeder/joint_states')
    ros.spin_until(lambda: len(joints) >= 5, STARTUP_TIMEOUT, 'idle joint_states')
    idle = len(joints)
    assert all(j.position[0] == 0.0 and j.velocity[0] == 0.0 for j in joints.msgs[:idle])
    assert ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=True)).success
    ros.spin_for(2.0)
    assert ros.call(SetBool, '/feeder/feeder_driver/enable',
                    SetBool.Request(data=False)).success
    ros.spin_for(0.5)
    msgs = joints.msgs[idle:]
    steady = [m for m in msgs if m.velocity[0] != W and m.position[0] != 0.0]
    span = seconds(msgs[-1]) - seconds(msgs[0])
    assert len(msgs) >= 0.7 * 30 * span, (len(msgs), span)
    follow = min(0.5, 0.4 / 2)
    top = 4 / 27 * W * follow
    assert steady and max(m.position[0] for m in steady) > 0.5 * top
    assert all(0.0 <= m.position[0] <= top + 1e-9 for m in msgs)
    assert msgs[-1].position[0] == 0.0 and msgs[-1].velocity[0] == 0.0


def test_rate_0_leaves_the_release_and_rest_messages(graph, ros):
    sim_as_hardware(graph, 'joint_states_rate:=0')
    joints = Collector(ros, JointState, '/feeder/joint_states')
    ros.spin_until(lambda: joints.sub.get_publisher_count() >= 1, STARTUP_TIMEOUT,
                   'the stand-in matched')
    for _ in range(3):
        assert ros.call(Trigger, '/feeder/feeder_driver/trigger_cycle', Trigger.Request(),
                        timeout=STARTUP_TIMEOUT).success
    ros.spin_for(1.0)
    assert [round(j.velocity[0], 3) for j in joints.msgs] == [W, 0.0] * 3
