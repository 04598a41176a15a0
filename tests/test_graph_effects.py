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

"""Scenes with effects on real DDS: the paper's experiment, a part lost off the arm's end."""

import math

from diagnostic_msgs.msg import DiagnosticStatus
from feeder_interfaces.msg import CycleStatus, PredictedState
from feeder_nodes import (check_ready_correctness, Collector, CycleStatuses, Diagnostics,
                          EXPERIMENT, monitor, PredictedStates, predictor, PREDICTOR, REPO,
                          run_cycles, SHORT_ARM, sim_as_hardware, Statements, wait_for_monitor,
                          wait_reports_matched)
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import Range
from std_srvs.srv import Trigger
from throwmap import load_scene

PERIOD = 0.01
HW = '/feeder/feeder_driver'
PRED = '/feeder/feeder_sim'
LOST_MESSAGE = 'part lost at cycle {}'


def test_experiment_ready_exactly_when_the_part_is_seen_on_the_goal_edge(graph, ros):
    """
    Back-plate friction and the 40 cm arm: the same ready-correctness as the triangle's.

    Not complete: after some detections on the goal edge the limit set's prediction is not sure
    of the edge (feeder_monitor.readiness, issue 20), so they are not ready; the in-process
    readiness decides which.
    """
    check_ready_correctness(graph, ros, EXPERIMENT, cycles=150, period=PERIOD, min_ready=5,
                            complete=False)


class Predictions:
    """predicted/state and predicted/part_pose of one sim (namespace prefix ``ns``)."""

    def __init__(self, ros, ns):
        self.states = PredictedStates(ros, ns)
        self.pose = Collector(ros, PoseStamped, f'{ns}/predicted/part_pose')

    def __len__(self):
        return len(self.states)

    def last(self, count):
        parsed = self.states.parsed[-count:]
        return [p.edge for p in parsed], [p.throw_kind for p in parsed]

    @property
    def radii(self):
        """R of every state with a part on the arm (a lost part has none: not NaN)."""
        return [p.R for p in self.states.parsed if p.R is not None]


def prediction_statuses(diags, node):
    return diags.by_name.get(f'{node}: prediction', [])


def wait_for_prediction_status(ros, diags, node, level, message):
    def seen():
        got = prediction_statuses(diags, node)
        return bool(got) and got[-1].level == level and got[-1].message == message
    ros.spin_until(seen, 10.0, f'{node}: prediction "{message}"')


def test_a_part_lost_off_the_arm_end_is_reported(graph, ros):
    """
    The part starts near the end of the 33 cm arm and falls off at the first throw.

    The hardware stand-in reports it in /diagnostics (its simulated part) and on the sensor
    (nothing seen); the predictor on predicted/state (edge -1, kind lost, R none on every
    cycle from then on; no pose) and in /diagnostics; the monitor sees a silence the limit set
    cannot produce. The start parameters put a part back on the stand-in's arm; ~/place_part
    tells the predictor.
    """
    start = ('start_radius:=0.32', 'diagnostics_period:=0.2')
    sim_as_hardware(graph, f'cycle_period:={PERIOD}', *start, scene=SHORT_ARM)
    predictor(graph, *start, scene=SHORT_ARM)
    monitor(graph, 'settle_cycles:=0', 'diagnostics_period:=0.2', scene=SHORT_ARM)
    ready = Statements(ros)
    statuses = CycleStatuses(ros)
    prox = Collector(ros, Range, '/feeder/proximity')
    pred = Predictions(ros, '/feeder')
    diags = Diagnostics(ros)
    wait_for_monitor(ros, ready)
    # cycle_status: the predictor, the monitor, us; proximity: the monitor, us
    wait_reports_matched(ros, status_readers=3, proximity_readers=2, verdict_readers=0)
    ros.wait_remote_matched(PREDICTOR, readers={'/feeder/predicted/state': 1})

    # 40 cycles: the part is lost in the first; the arm keeps cycling empty.
    cycles = 40
    run_cycles(ros, cycles, statuses, PERIOD)
    last_seq = statuses.parsed[-1].seq
    ros.spin_until(lambda: len(pred) == len(statuses) and ready.checked[-1].seq == last_seq,
                   10.0, 'the predictor and the monitor to follow')
    n = len(statuses)
    reports = statuses.parsed
    assert [s.sensor for s in reports] == [False] * n
    assert all(s.ok and s.reason == '' for s in reports)
    assert all((m.outcome, m.sensor) == (CycleStatus.OUTCOME_COMPLETED, CycleStatus.SENSOR_CLEAR)
               for m in statuses.msgs)
    assert len(prox) == n and all(p.range == float('inf') for p in prox.msgs)
    assert [p.seq for p in pred.states.parsed] == [s.seq for s in reports]
    assert pred.last(n) == ([-1] * n, ['lost'] * n)
    # On the wire: EDGE_LOST, r NaN, THROW_LOST, each matched to its cycle's sample stamp.
    assert all((m.edge, m.throw_kind) == (PredictedState.EDGE_LOST, PredictedState.THROW_LOST)
               and math.isnan(m.r) for m in pred.states.msgs)
    assert [p.stamp_ns for p in pred.states.parsed] == [s.stamp_ns for s in reports]
    assert pred.radii == [] and len(pred.pose) == 0    # no NaN, no made-up pose
    for node in ('feeder_driver', 'feeder_sim'):
        wait_for_prediction_status(ros, diags, node, DiagnosticStatus.ERROR,
                                   LOST_MESSAGE.format(1))
        values = Diagnostics.values(prediction_statuses(diags, node)[-1])
        assert (values['edge'], values['R'], values['lost_at_seq']) == ('-1', 'none', '1')
        assert 'off the arm' in values['lost_reason'], values
    # The monitor: no detection for longer than the limit set allows.
    name = 'feeder_monitor: readiness'
    ros.spin_until(lambda: DiagnosticStatus.ERROR in diags.levels(name), 5.0,
                   'the monitor anomaly')
    error = [s for s in diags.by_name[name] if s.level == DiagnosticStatus.ERROR][0]
    assert 'no detection for' in error.message and "fallen off the arm's end" in error.message
    assert not any(c.ready for c in ready.checked) and all(c.authentic for c in ready.checked)

    # A part back at the start state (near the end again): lost at once.
    assert ros.set_parameters(HW, {'start_radius': 0.32})['start_radius'].successful
    res = ros.call(Trigger, f'{PRED}/place_part', Trigger.Request())
    assert res.success and res.message == 'part placed on edge 1 at R 0.3200 m', res.message
    res = ros.call(Trigger, f'{HW}/trigger_cycle', Trigger.Request())
    assert res.success and res.message == f'fired cycle seq {n + 1}', res.message
    ros.spin_until(lambda: len(pred) == n + 1, 10.0, 'cycle n + 1')
    assert pred.last(1) == ([-1], ['lost'])
    for node in ('feeder_driver', 'feeder_sim'):
        wait_for_prediction_status(ros, diags, node, DiagnosticStatus.ERROR,
                                   LOST_MESSAGE.format(n + 1))

    # New start parameters put the part back where it stays on the arm.
    for node in (HW, PRED):
        assert ros.set_parameters(node, {'start_radius': 0.12})['start_radius'].successful
    ros.call(Trigger, f'{HW}/trigger_cycle', Trigger.Request())
    ros.spin_until(lambda: len(pred) == n + 2 and len(pred.radii) == len(pred.pose) == 1,
                   10.0, 'cycle n + 2')
    edge, R, kind = load_scene(SHORT_ARM).model.f(1, 0.12)
    assert pred.last(1) == ([edge], [kind]) and pred.radii == [R]
    for node in ('feeder_driver', 'feeder_sim'):
        wait_for_prediction_status(
            ros, diags, node, DiagnosticStatus.OK, f'edge {edge}, R {100 * R:.2f} cm after 1 '
            'throws')


def test_scenes_the_nodes_cannot_run_stop_them_with_the_reason(graph, tmp_path):
    """Exit status 2 and throwmap's message when the analysis fails or gives no sensor."""
    lost = tmp_path / 'lost_from_start.yaml'
    lost.write_text(open(SHORT_ARM).read().replace('start: {edge: 1, R: 0.12}',
                                                   'start: {edge: 1, R: 0.32}'))
    cases = {   # scene: what the message says
        str(lost): 'the part was lost at throw 1 (first contact at x',
        str(REPO / 'scenes' / 'hard' / 'fast_spin.yaml'): 'outside the domain of f',
    }
    procs = []
    for scene, text in cases.items():
        procs.append((graph.start('feeder_sim', 'predictor_node', '--ros-args', '-p',
                                  f'scene:={scene}'), text))
        procs.append((graph.start('feeder_sim', 'standin_node', '--ros-args', '-p',
                                  f'scene:={scene}'), text))
        procs.append((graph.start('feeder_monitor', 'monitor_node', '--ros-args', '-p',
                                  f'scene:={scene}'), text))
    for proc, text in procs:
        assert proc.wait(timeout=60) == 2, graph.log(proc)
        log = graph.log(proc)
        assert text in log and ': error: scene ' in log, log
