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
Issue 25 item 5 end to end: the speed policy through the real driver and the serial line.

monitor_node (speed_policy) -> release_speed_setpoint (signed) -> driver_node
(release_speed_mode setpoint) -> FIRE,<seq>,<mrad/s> -> controller_emulator (CAP,SPEED),
which throws its part at that speed -> REL, SENS -> cycle_status with the setpoint, signed ->
the monitor follows the part with it. Checked against the emulator's truth log: each cycle
was thrown at the setpoint its report names; every ready is on the goal edge. With an old
controller (--no-speed-setpoint) the driver keeps the fixed speed (the reports say none) and
the monitor follows with the scene's speed.
"""

import math
import time

from feeder_nodes import (CycleStatuses, funnel_policy, monitor, start_emulator,
                          STARTUP_TIMEOUT, Statements, Verdicts, wait_for_monitor,
                          wait_reports_matched)
from feeder_sim.truth import read_truth_log
from std_srvs.srv import SetBool

CYCLES = 120
PERIOD = 0.02


def run(graph, ros, tmp_path, emulator_args):
    link = tmp_path / 'feeder-tty'
    truth_path = tmp_path / 'truth.jsonl'
    policy = funnel_policy(tmp_path)
    start_emulator(graph, link, '--truth-log', truth_path, '--cycle-time', '0.01',
                   '--heartbeat', '0.2', *emulator_args)
    graph.start('feeder_driver', 'driver_node', '--ros-args', '-r', '__ns:=/feeder', '-p',
                f'port:={link}', '-p', f'cycle_period:={PERIOD}', '-p',
                'release_speed_mode:=setpoint', name='driver')
    monitor(graph, f'speed_policy:={policy}')
    ready = Statements(ros)
    verdicts = Verdicts(ros)
    statuses = CycleStatuses(ros)
    wait_for_monitor(ros, ready)
    wait_reports_matched(ros, status_readers=2, proximity_readers=1)
    end = time.monotonic() + STARTUP_TIMEOUT
    while True:     # refused until the driver's handshake with the controller is done
        res = ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=True))
        if res.success:
            break
        assert time.monotonic() < end, res.message
        ros.spin_for(0.1)
    ros.spin_until(lambda: len(statuses) >= CYCLES, 120 + 20 * CYCLES * PERIOD,
                   f'{CYCLES} cycles')
    ros.enable('/feeder/feeder_driver', False)
    ros.spin_for(1.0)
    header, truth = read_truth_log(truth_path)
    return statuses.parsed, verdicts.parsed, truth


def check(statuses, verdicts, truth):
    assert [s.seq for s in statuses] == list(range(1, len(statuses) + 1))
    assert all(s.ok for s in statuses)
    assert all(v.authentic for v in verdicts)
    readies = [v for v in verdicts if v.ready]
    assert all(truth[v.seq]['edge'] == 1 for v in readies), 'a false ready'
    return readies


def test_each_cycle_is_thrown_at_the_policys_setpoint_through_the_serial_line(
        graph, ros, tmp_path):
    statuses, verdicts, truth = run(graph, ros, tmp_path, [])
    readies = check(statuses, verdicts, truth)
    speeds = [s.release_speed for s in statuses]
    assert all(w is not None for w in speeds), 'a cycle without its setpoint'
    for s in statuses:      # thrown at the setpoint its signed report names (mrad/s)
        assert truth[s.seq]['setpoint'] == s.release_speed
        assert round(s.release_speed * 1000) == s.release_speed * 1000
    assert len(set(speeds)) > 1, 'the policy chose one speed only'
    assert readies, 'no ready in the run'


def test_a_controller_that_cannot_set_the_speed_keeps_its_own(graph, ros, tmp_path):
    statuses, verdicts, truth = run(graph, ros, tmp_path, ['--no-speed-setpoint'])
    readies = check(statuses, verdicts, truth)
    assert all(s.release_speed is None for s in statuses)
    assert all(truth[s.seq]['setpoint'] is None for s in statuses)
    assert all(math.isclose(truth[s.seq]['release_speed'], 5.5851) for s in statuses)
    assert readies
