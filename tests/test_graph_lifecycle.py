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
Lifecycles with autostart:=false: services refuse, and no ready is stated, until active.

The sim's services refuse until it is active; the monitor judges and states a ready only while
active, says false on deactivate, and a scene it cannot run fails its configure.
"""

from feeder_interfaces.msg import Verdict
from feeder_nodes import (Collector, CycleStatuses, Diagnostics, monitor, REPO, SHORT_ARM,
                          sim_as_hardware, Statements, TRIANGLE, Verdicts, wait_for_monitor)
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from sensor_msgs.msg import Range
from std_srvs.srv import SetBool, Trigger

NODE = '/feeder/feeder_driver'


def state(ros, node=NODE):
    return ros.call(GetState, f'{node}/get_state', GetState.Request()).current_state.label


def change(ros, transition_id, node=NODE):
    req = ChangeState.Request(transition=Transition(id=transition_id))
    return ros.call(ChangeState, f'{node}/change_state', req).success


def test_services_follow_the_lifecycle(graph, ros):
    graph.start('feeder_sim', 'standin_node', '--ros-args', '-r', '__ns:=/feeder', '-r',
                '__node:=feeder_driver', '-p', 'autostart:=false',
                '-p', f'scene:={TRIANGLE}', '-p', 'cycle_period:=0.05')
    edges = CycleStatuses(ros)
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


MONITOR = '/feeder/feeder_monitor'
READINESS = 'feeder_monitor: readiness'


def enable(ros, on):
    res = ros.call(SetBool, f'{NODE}/enable', SetBool.Request(data=on))
    assert res.success, res.message


def readiness(ros, diags, words):
    """Wait for a readiness status of the monitor whose message starts with ``words``."""
    def seen():
        return [s for s in diags.by_name.get(READINESS, []) if s.message.startswith(words)]
    ros.spin_until(seen, 30.0, f'monitor readiness {words!r}')
    return Diagnostics.values(seen()[-1])


def test_the_monitor_states_a_ready_only_while_active(graph, ros):
    sim_as_hardware(graph, 'cycle_period:=0.02')
    mon = monitor(graph, 'autostart:=false')
    ready = Statements(ros)
    verdicts = Verdicts(ros)
    statuses = CycleStatuses(ros)
    diags = Diagnostics(ros)
    # Unconfigured: no analysis, nothing judged, nothing said; the cycles go on.
    assert state(ros, MONITOR) == 'unconfigured'
    values = readiness(ros, diags, 'unconfigured: not judging, edge1_ready false')
    assert 'goal_edge' not in values and values['analyses'] == '0'
    enable(ros, True)
    ros.spin_until(lambda: len(statuses) >= 20, 20.0, '20 cycles')
    enable(ros, False)
    # Configure: the analysis is done; inactive, still nothing judged or said.
    assert change(ros, Transition.TRANSITION_CONFIGURE, MONITOR)
    assert state(ros, MONITOR) == 'inactive'
    values = readiness(ros, diags, 'inactive: not judging, edge1_ready false')
    assert (values['goal_edge'], values['warmup_cycles'], values['analyses']) == ('1', '1', '1')
    enable(ros, True)
    ros.spin_until(lambda: len(statuses) >= 40, 20.0, '20 more cycles')
    enable(ros, False)
    ros.spin_for(0.5)
    assert not ready.msgs and not verdicts.msgs
    # Activate: a statement at once (false, warming up), verdicts, a ready in time.
    assert change(ros, Transition.TRANSITION_ACTIVATE, MONITOR)
    assert state(ros, MONITOR) == 'active'
    wait_for_monitor(ros, ready)
    verdicts.wait_matched()
    enable(ros, True)
    ros.spin_until(lambda: ready.any_ready(), 60.0, 'a ready statement')
    enable(ros, False)
    ros.spin_for(0.5)
    assert verdicts.msgs and all(v.authentic for v in verdicts.checked)
    # Deactivate: a final false statement, signed; then no statement, no verdict, whatever
    # the driver does.
    assert change(ros, Transition.TRANSITION_DEACTIVATE, MONITOR)
    ros.spin_until(lambda: not ready.checked[-1].ready, 5.0, 'the final false statement')
    last = ready.checked[-1]
    assert last.authentic and last.state == Verdict.STATE_ANOMALY, last
    assert 'deactivated' in last.anomaly
    n_ready, n_verdicts, n_status = len(ready), len(verdicts), len(statuses)
    enable(ros, True)
    ros.spin_until(lambda: len(statuses) >= n_status + 50, 20.0, '50 cycles while inactive')
    enable(ros, False)
    ros.spin_for(0.5)
    assert (len(ready), len(verdicts)) == (n_ready, n_verdicts)
    readiness(ros, diags, 'inactive: not judging')
    # Cleanup, shutdown: the process ends (status 0); never a ready but from an active monitor.
    assert change(ros, Transition.TRANSITION_CLEANUP, MONITOR)
    assert state(ros, MONITOR) == 'unconfigured'
    assert change(ros, Transition.TRANSITION_UNCONFIGURED_SHUTDOWN, MONITOR)
    assert mon.wait(timeout=10) == 0
    ready_verdicts = {v.seq for v in verdicts.checked if v.ready}
    assert all(c.seq in ready_verdicts for c in ready.checked if c.ready)


def test_a_scene_the_monitor_cannot_run_fails_its_configure(graph, ros, tmp_path):
    """autostart:=false: configure fails with throwmap's message; it stays unconfigured."""
    lost = tmp_path / 'lost_from_start.yaml'
    lost.write_text(open(SHORT_ARM).read().replace('start: {edge: 1, R: 0.12}',
                                                   'start: {edge: 1, R: 0.32}'))
    mon = monitor(graph, 'autostart:=false', scene=str(lost))
    fast_spin = monitor(graph, 'autostart:=false', ns='/other',
                        scene=str(REPO / 'scenes' / 'hard' / 'fast_spin.yaml'))
    for proc, node, text in ((mon, MONITOR, 'the part was lost at throw 1 (first contact at x'),
                             (fast_spin, '/other/feeder_monitor',
                              'outside the domain of f')):
        assert state(ros, node) == 'unconfigured'
        assert not change(ros, Transition.TRANSITION_CONFIGURE, node)
        assert state(ros, node) == 'unconfigured'
        assert proc.poll() is None
        log = graph.log(proc)
        assert 'configure failed: scene ' in log and text in log, log
