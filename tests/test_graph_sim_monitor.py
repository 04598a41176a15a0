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

"""(a) The sim as hardware and the monitor over a few hundred cycles on real DDS."""

from diagnostic_msgs.msg import DiagnosticStatus
from feeder_nodes import (check_ready_correctness, CycleStatuses, Diagnostics, monitor,
                          run_cycles, sim_as_hardware, Statements, TRIANGLE, wait_for_monitor,
                          wait_reports_matched)

PERIOD = 0.01


def test_ready_exactly_when_the_part_is_seen_on_the_goal_edge(graph, ros):
    check_ready_correctness(graph, ros, TRIANGLE, cycles=250, period=PERIOD, min_ready=8)


def test_a_misplaced_sensor_shows_as_an_anomaly(graph, ros):
    """The sensor sits at 21 cm, inside the guarantee radius; the monitor expects the design."""
    sim_as_hardware(graph, f'cycle_period:={PERIOD}', 'sensor_radius:=0.21')
    monitor(graph, 'settle_cycles:=0')
    ready = Statements(ros)
    statuses = CycleStatuses(ros)
    diags = Diagnostics(ros)
    wait_for_monitor(ros, ready)
    wait_reports_matched(ros, status_readers=2, proximity_readers=1, verdict_readers=0)
    run_cycles(ros, 150, statuses, PERIOD)
    name = 'feeder_monitor: readiness'
    ros.spin_until(lambda: any(lv == DiagnosticStatus.ERROR for lv in diags.levels(name)), 5.0,
                   'an anomaly in the monitor diagnostics')
    errors = [s for s in diags.by_name[name] if s.level == DiagnosticStatus.ERROR]
    assert 'anomaly' in errors[0].message
    assert int(diags.values(diags.by_name[name][-1])['anomalies']) >= 1
    assert not ready.any_ready()
