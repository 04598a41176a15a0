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

"""The sim's lifecycle with autostart:=false: services refuse until it is active."""

from diagnostic_msgs.msg import DiagnosticStatus
from feeder_nodes import Collector, TRIANGLE
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from sensor_msgs.msg import Range
from std_srvs.srv import SetBool, Trigger

NODE = '/feeder/feeder_driver'


def state(ros):
    return ros.call(GetState, f'{NODE}/get_state', GetState.Request()).current_state.label


def change(ros, transition_id):
    req = ChangeState.Request(transition=Transition(id=transition_id))
    return ros.call(ChangeState, f'{NODE}/change_state', req).success


def test_services_follow_the_lifecycle(graph, ros):
    graph.start('feeder_sim', 'standin_node', '--ros-args', '-r', '__ns:=/feeder', '-r',
                '__node:=feeder_driver', '-p', 'autostart:=false',
                '-p', f'scene:={TRIANGLE}', '-p', 'cycle_period:=0.05')
    edges = Collector(ros, DiagnosticStatus, '/feeder/cycle_status')
    prox = Collector(ros, Range, '/feeder/proximity')
    assert state(ros) == 'unconfigured'
    res = ros.call(Trigger, f'{NODE}/trigger_cycle', Trigger.Request())
    assert not res.success and 'unconfigured' in res.message
    assert change(ros, Transition.TRANSITION_CONFIGURE)
    assert state(ros) == 'inactive'
    res = ros.call(SetBool, f'{NODE}/enable', SetBool.Request(data=True))
    assert not res.success and 'inactive' in res.message
    assert not edges.msgs and not prox.msgs
    assert change(ros, Transition.TRANSITION_ACTIVATE)
    assert state(ros) == 'active'
    res = ros.call(Trigger, f'{NODE}/trigger_cycle', Trigger.Request())
    assert res.success and res.message == 'fired cycle seq 1'
    ros.spin_until(lambda: len(edges) == 1 and len(prox) == 1, 10.0, 'the first cycle')
    res = ros.call(SetBool, f'{NODE}/enable', SetBool.Request(data=True))
    assert res.success
    ros.spin_until(lambda: len(edges) >= 4, 10.0, 'cycling')
    res = ros.call(Trigger, f'{NODE}/trigger_cycle', Trigger.Request())
    assert not res.success and 'enabled' in res.message
    assert change(ros, Transition.TRANSITION_DEACTIVATE)      # stops cycling
    ros.spin_for(0.3)
    n = len(edges)
    ros.spin_for(1.5)
    assert len(edges) == n
    res = ros.call(Trigger, f'{NODE}/trigger_cycle', Trigger.Request())
    assert not res.success and 'inactive' in res.message
    assert change(ros, Transition.TRANSITION_CLEANUP)
    assert state(ros) == 'unconfigured'
