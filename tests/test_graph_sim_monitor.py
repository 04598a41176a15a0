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
from feeder_nodes import (Collector, Diagnostics, LATCHED, monitor, sim_as_hardware,
                          status_values, TRIANGLE, wait_for_monitor, wait_for_readers)
import pytest
from sensor_msgs.msg import Range
from std_msgs.msg import Bool, Float64, Int32
from std_srvs.srv import SetBool
from throwmap import analyse, load_scene, sees

CYCLES = 250
PERIOD = 0.01


def run_cycles(ros, cycles, statuses, period=PERIOD):
    res = ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=True))
    assert res.success, res.message
    ros.spin_until(lambda: len(statuses) >= cycles, 20 + 3 * cycles * period,
                   f'{cycles} cycles')
    res = ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=False))
    assert res.success, res.message


def test_ready_exactly_when_the_part_is_seen_on_the_goal_edge(graph, ros):
    sim = sim_as_hardware(graph, f'cycle_period:={PERIOD}')
    mon = monitor(graph)
    scene = load_scene(TRIANGLE)
    an = analyse(scene)
    goal, radius = an.sensor.goal_edge, an.sensor.radius
    warmup, footprint = an.sensor.warmup_throws, an.sensor.footprint

    ready = Collector(ros, Bool, '/feeder/edge1_ready', LATCHED)
    statuses = Collector(ros, DiagnosticStatus, '/feeder/cycle_status')
    prox = Collector(ros, Range, '/feeder/proximity')
    edges = Collector(ros, Int32, '/feeder/predicted/edge')
    radii = Collector(ros, Float64, '/feeder/predicted/radius')
    diags = Diagnostics(ros)
    wait_for_monitor(ros, ready)
    for topic in ('/feeder/cycle_status', '/feeder/proximity'):
        wait_for_readers(ros, topic, 2)         # the monitor's and ours
    ros.spin_for(0.5)

    run_cycles(ros, CYCLES, statuses)
    ros.spin_for(1.5)                           # let the monitor finish the last cycles
    n = len(statuses)
    assert n >= CYCLES
    assert len(prox) == len(edges) == len(radii) == n
    seqs = [int(status_values(s)['seq']) for s in statuses.msgs]
    assert seqs == list(range(seqs[0], seqs[0] + n))
    assert all(s.level == DiagnosticStatus.OK for s in statuses.msgs)

    # The sim's sensor bit is the sensor geometry applied to its predicted state.
    truth = [bool(sees(scene.part, e.data, r.data, radius, footprint))
             for e, r in zip(edges.msgs, radii.msgs)]
    assert [p.range == float('-inf') for p in prox.msgs] == truth
    assert [status_values(s)['sensor'] == '1' for s in statuses.msgs] == truth
    for p in prox.msgs:
        assert p.radiation_type == Range.INFRARED and p.header.frame_id == 'feeder_sensor'
        assert p.min_range == p.max_range == pytest.approx(0.02, rel=1e-6)     # float32

    # One edge1_ready per cycle after the initial latched one; align them at the end (the
    # monitor may have missed the very first cycles while discovery finished).
    verdicts = [m.data for m in ready.msgs[1:]]
    missed = n - len(verdicts)
    assert 0 <= missed <= 3, f'{len(verdicts)} verdicts for {n} cycles'
    on_goal = 0
    for j, verdict in enumerate(verdicts):
        k = j + missed
        edge, R = edges.msgs[k].data, radii.msgs[k].data
        seen_on_goal = truth[k] and edge == goal
        if verdict:
            assert seen_on_goal, f'edge1_ready at cycle {seqs[k]} but the part is on edge ' \
                f'{edge} at R {R:.4f} m (sensor sees it: {truth[k]})'
        if seen_on_goal and j + 1 >= warmup:
            on_goal += 1
            assert verdict, f'cycle {seqs[k]}: part seen on the goal edge, not reported'
    assert on_goal >= 8 and sum(verdicts) == on_goal

    # The monitor saw nothing the limit set cannot produce, and counted the same.
    ros.spin_for(1.2)
    name = 'feeder_monitor: readiness'
    assert diags.levels(name), 'no monitor diagnostics'
    assert DiagnosticStatus.ERROR not in diags.levels(name), \
        [s.message for s in diags.by_name[name] if s.level == DiagnosticStatus.ERROR]
    last = diags.values(diags.by_name[name][-1])
    assert int(last['ready']) == on_goal and int(last['anomalies']) == 0
    assert int(last['completed']) == len(verdicts)
    assert sim.poll() is None and mon.poll() is None


def test_a_misplaced_sensor_shows_as_an_anomaly(graph, ros):
    """The sensor sits at 21 cm, inside the guarantee radius; the monitor expects the design."""
    sim_as_hardware(graph, f'cycle_period:={PERIOD}', 'sensor_radius:=0.21')
    monitor(graph, 'settle_cycles:=0')
    ready = Collector(ros, Bool, '/feeder/edge1_ready', LATCHED)
    statuses = Collector(ros, DiagnosticStatus, '/feeder/cycle_status')
    diags = Diagnostics(ros)
    wait_for_monitor(ros, ready)
    wait_for_readers(ros, '/feeder/cycle_status', 2)
    wait_for_readers(ros, '/feeder/proximity', 1)
    ros.spin_for(0.5)
    run_cycles(ros, 150, statuses)
    name = 'feeder_monitor: readiness'
    ros.spin_until(lambda: any(lv == DiagnosticStatus.ERROR for lv in diags.levels(name)), 5.0,
                   'an anomaly in the monitor diagnostics')
    errors = [s for s in diags.by_name[name] if s.level == DiagnosticStatus.ERROR]
    assert 'anomaly' in errors[0].message
    assert int(diags.values(diags.by_name[name][-1])['anomalies']) >= 1
