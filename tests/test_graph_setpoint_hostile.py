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
A stand-in in release_speed_mode setpoint throws only at a setpoint that proves itself.

On the graph, with no monitor: setpoints signed under another key, unsigned, signed as another
node, stale, or addressed to another cycle or run leave the cycle waiting (the trigger is
refused with the reason, no cycle fires); a valid one (signed as the monitor under the test's
key) fires exactly one cycle at its speed, reported signed on cycle_status. A monitor killed
with SIGKILL stops the cycles; a restarted stand-in takes up the policy at once.
"""

from feeder_common import messages
from feeder_interfaces.msg import SpeedSetpoint
from feeder_nodes import CycleStatuses, sim_as_hardware, STARTUP_TIMEOUT
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_srvs.srv import Trigger

DRIVER = '/feeder/feeder_driver'
MONITOR = '/feeder/feeder_monitor'
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)


def test_only_a_setpoint_that_proves_itself_fires_a_cycle_and_only_one(graph, ros):
    sim_as_hardware(graph, 'release_speed_mode:=setpoint', 'joint_states_rate:=0.0')
    statuses = CycleStatuses(ros)
    pub = ros.node.create_publisher(SpeedSetpoint, '/feeder/release_speed_setpoint', LATCHED)
    ros.wait_active(DRIVER)
    ros.spin_until(lambda: pub.get_subscription_count() >= 1, STARTUP_TIMEOUT,
                   "the stand-in's setpoint reader")

    def now():
        return ros.node.get_clock().now().nanoseconds

    def trigger():
        return ros.call(Trigger, f'{DRIVER}/trigger_cycle', Trigger.Request())

    res = trigger()
    assert not res.success and 'no release-speed setpoint' in res.message, res.message
    other_key = bytes(32)
    forged = [
        messages.signed_setpoint(other_key, MONITOR, 'aa', 0, '', 6.0, now()),
        messages.signed_setpoint(ros.key, '/feeder/other', 'aa', 0, '', 6.0, now()),
        messages.signed_setpoint(ros.key, MONITOR, 'aa', 0, '', 6.0, now() - 5 * 10**9),
    ]
    unsigned = messages.signed_setpoint(ros.key, MONITOR, 'aa', 0, '', 6.0, now())
    unsigned.mac = []
    for msg in forged + [unsigned]:
        pub.publish(msg)
        ros.spin_for(0.2)
        res = trigger()
        assert not res.success and 'setpoint' in res.message, res.message
    assert len(statuses) == 0
    pub.publish(messages.signed_setpoint(ros.key, MONITOR, 'aa', 0, '', 4.5, now()))
    ros.spin_for(0.2)
    res = trigger()
    assert res.success, res.message
    ros.spin_until(lambda: len(statuses) >= 1, 10, 'the cycle report')
    report = statuses.parsed[0]
    assert report.release_speed == 4.5 and report.ok
    # The same message serves one cycle only, however often it is delivered.
    res = trigger()
    assert not res.success and 'was used' in res.message, res.message
    # Signed, fresh, but for another cycle or run (after the run's first cycle: that one
    # takes any fresh setpoint, see feeder_common.setpoints).
    for seq, run in ((7, report.session), (2, 'feedbeef')):
        pub.publish(messages.signed_setpoint(ros.key, MONITOR, 'aa', seq, run, 6.0, now()))
        ros.spin_for(0.2)
        res = trigger()
        assert not res.success and 'this is cycle 2' in res.message, res.message
    ros.spin_for(0.3)
    assert len(statuses) == 1


def test_a_killed_policy_monitor_stops_the_cycles_and_its_successor_proves_afresh(
        graph, ros, tmp_path):
    import signal
    from feeder_nodes import funnel_policy, monitor, Verdicts
    from feeder_sim.truth import read_truth_log
    policy = funnel_policy(tmp_path)
    truth_path = tmp_path / 'truth.jsonl'
    sim_as_hardware(graph, 'release_speed_mode:=setpoint', 'joint_states_rate:=0.0',
                    'cycle_period:=0.01', f'truth_log:={truth_path}')
    statuses = CycleStatuses(ros)
    verdicts = Verdicts(ros)
    mon = monitor(graph, f'speed_policy:={policy}')
    ros.wait_active(MONITOR)
    ros.enable(DRIVER, True)
    ros.spin_until(lambda: len(statuses) >= 40, 60, '40 cycles')
    graph._stopped.add(mon.pid)
    mon.send_signal(signal.SIGKILL)
    mon.wait(10)
    # The last setpoint is used at most once, then none is fresh: the cycles stop.
    ros.spin_for(1.5)
    stopped_at = len(statuses)
    ros.spin_for(1.0)
    assert len(statuses) == stopped_at, 'cycles went on without a live policy'
    monitor(graph, f'speed_policy:={policy}')
    ros.spin_until(lambda: len(statuses) >= stopped_at + 40, 60, 'cycles again')
    ros.enable(DRIVER, False)
    ros.spin_for(0.5)
    _, truth = read_truth_log(truth_path)
    readies = [v for v in verdicts.parsed if v.ready]
    assert all(v.authentic for v in verdicts.parsed)
    assert all(truth[v.seq]['edge'] == 1 for v in readies), 'a false ready'


def test_a_restarted_stand_in_takes_up_the_policy_at_once(graph, ros, tmp_path):
    from feeder_nodes import funnel_policy, monitor, Verdicts
    from feeder_sim.truth import read_truth_log
    policy = funnel_policy(tmp_path)
    params = ('release_speed_mode:=setpoint', 'joint_states_rate:=0.0', 'cycle_period:=0.01')
    first = sim_as_hardware(graph, *params, f'truth_log:={tmp_path / "truth1.jsonl"}')
    statuses = CycleStatuses(ros)
    verdicts = Verdicts(ros)
    monitor(graph, f'speed_policy:={policy}')
    ros.wait_active(MONITOR)
    ros.enable(DRIVER, True)
    ros.spin_until(lambda: len(statuses) >= 30, 60, '30 cycles')
    graph.stop(first)
    n = len(statuses)
    sim_as_hardware(graph, *params, f'truth_log:={tmp_path / "truth2.jsonl"}')
    ros.wait_active(DRIVER)
    ros.enable(DRIVER, True)
    # The new run's first cycle takes the setpoint the monitor made for the old run's next.
    ros.spin_until(lambda: len(statuses) >= n + 30, 60, '30 cycles of the new run')
    ros.enable(DRIVER, False)
    ros.spin_for(0.5)
    new = [s for s in statuses.parsed[n:]]
    assert new[0].seq == 1 and all(s.release_speed is not None for s in new)
    _, truth = read_truth_log(tmp_path / 'truth2.jsonl')
    sessions = {s.session for s in new}
    readies = [v for v in verdicts.parsed[n:] if v.ready]
    assert len(sessions) == 1 and all(truth[v.seq]['edge'] == 1 for v in readies)
