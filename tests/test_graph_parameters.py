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

"""(d) Bad parameters are rejected with a reason, through the parameter services."""

from feeder_nodes import (CycleStatuses, Diagnostics, monitor, PredictedStates, predictor, REPO,
                          sim_as_hardware, Statements, TRIANGLE, wait_for_monitor,
                          wait_for_publishers)
from std_srvs.srv import Trigger
from throwmap import analyse, load_scene, sees
import yaml

SIM = '/feeder/feeder_driver'
PRED = '/feeder/feeder_sim'
MON = '/feeder/feeder_monitor'


def rejected(result, *words):
    assert not result.successful, 'accepted'
    assert result.reason, 'rejected without a reason'
    for w in words:
        assert w in result.reason, result.reason


def test_bad_values_are_rejected_and_good_ones_applied(graph, ros):
    sim_as_hardware(graph)
    predictor(graph)
    monitor(graph)
    ready = Statements(ros)
    states = PredictedStates(ros)
    statuses = CycleStatuses(ros)
    wait_for_monitor(ros, ready)
    wait_for_publishers(ros, '/feeder/predicted/state', 1)

    # sim: domain of f, ranges, read-only, types
    r = ros.set_parameters(SIM, {'start_radius': 0.001, 'start_edge': 7, 'cycle_period': 0.001,
                                 'sensor_radius': -1.0, 'scene': 'scenes/bracket.yaml'})
    rejected(r['start_radius'], 'no dynamic grasp on edge 1', 'R >= 0.016')
    rejected(r['start_edge'], 'edge 7 does not exist')
    rejected(r['cycle_period'])
    rejected(r['sensor_radius'])
    rejected(r['scene'], 'read-only')
    # One node per executable (issue 23 item 7a): the stand-in has none of the predictor's
    # parameters, the predictor none of the driver's, and neither has a mode switch.
    for name, node in (('hardware_mode', SIM), ('hardware_mode', PRED),
                       ('markers_period', SIM), ('cycle_period', PRED), ('key_file', PRED)):
        rejected(ros.set_parameters(node, {name: 0.5})[name])
    rejected(ros.set_parameters(SIM, {'start_radius': 'far'})['start_radius'])
    assert ros.get_parameters(SIM, ['start_edge', 'start_radius', 'cycle_period']) == \
        {'start_edge': 1, 'start_radius': 0.12, 'cycle_period': 1.0}

    # A good start state is applied: the next throw starts from it, on the stand-in's arm (its
    # sensor bit) and in the predictor (integers for doubles are taken as doubles).
    assert ros.set_parameters(SIM, {'start_radius': 0.15})['start_radius'].successful
    assert ros.set_parameters(PRED, {'start_radius': 0.15})['start_radius'].successful
    assert ros.set_parameters(SIM, {'cycle_period': 2})['cycle_period'].successful
    assert ros.get_parameters(SIM, ['cycle_period']) == {'cycle_period': 2.0}
    res = ros.call(Trigger, f'{SIM}/trigger_cycle', Trigger.Request())
    assert res.success, res.message
    ros.spin_until(lambda: len(states) == 1 and len(statuses) == 1, 10.0, 'the prediction')
    scene = load_scene(TRIANGLE)
    edge, R, _ = scene.model.f(1, 0.15)
    assert (states.parsed[0].edge, states.parsed[0].R) == (edge, R)
    sensor = analyse(scene).sensor
    assert statuses.parsed[0].sensor == \
        bool(sees(scene.part, edge, R, sensor.radius, sensor.footprint))

    # monitor: the proven warm-up, ranges, read-only (the key file too: a node never changes
    # the key it checks with while it runs)
    r = ros.set_parameters(MON, {'warmup_cycles': 0, 'silence_margin': 0.5,
                                 'orbit_throws': 5000, 'max_report_age': 0.001,
                                 'key_file': '/tmp/other.key'})
    rejected(r['warmup_cycles'], 'below the proven warm-up of 1')
    rejected(r['silence_margin'])
    rejected(r['orbit_throws'], 'read-only')
    rejected(r['max_report_age'])
    rejected(r['key_file'], 'read-only')
    # stamp_tolerance and pair_timeout are gone (the monitor judges the signed cycle_status
    # alone): not parameters of the monitor any more.
    for gone in ('stamp_tolerance', 'pair_timeout'):
        rejected(ros.set_parameters(MON, {gone: 0.5})[gone])
    assert ros.set_parameters(MON, {'warmup_cycles': 4, 'max_report_age': 2})[
        'warmup_cycles'].successful
    assert ros.get_parameters(MON, ['warmup_cycles', 'silence_margin', 'max_report_age']) == \
        {'warmup_cycles': 4, 'silence_margin': 1.5, 'max_report_age': 2.0}


def test_a_scene_that_does_not_load_stops_the_node_with_throwmaps_message(graph, tmp_path):
    bad = tmp_path / 'bad.yaml'
    bad.write_text(open(TRIANGLE).read() + 'bogus_key: 1\n')
    sim = graph.start('feeder_sim', 'standin_node', '--ros-args', '-p', f'scene:={bad}')
    mon = graph.start('feeder_monitor', 'monitor_node', '--ros-args', '-p',
                      f'scene:={tmp_path / "missing.yaml"}')
    unset = graph.start('feeder_sim', 'predictor_node')
    assert sim.wait(timeout=60) == 2
    assert 'bogus_key: unknown key' in graph.log(sim)
    assert 'allowed here' in graph.log(sim)
    assert mon.wait(timeout=60) == 2
    assert 'no such file' in graph.log(mon)
    assert unset.wait(timeout=60) == 2
    assert 'scene: not set' in graph.log(unset)


def test_the_old_mode_switch_is_an_unknown_parameter_of_both_nodes(graph, ros):
    """hardware_mode is gone: each node warns as for any parameter it does not take."""
    hw = sim_as_hardware(graph, 'hardware_mode:=true', 'markers_period:=0.2')
    pred = predictor(graph, 'hardware_mode:=false', 'cycle_period:=0.5')
    wait_for_publishers(ros, '/feeder/predicted/state', 1)
    for proc, prog, names in ((hw, 'standin_node', ('hardware_mode', 'markers_period')),
                              (pred, 'predictor_node', ('hardware_mode', 'cycle_period'))):
        for name in names:
            line = f'parameter {name} is not a parameter of {prog}; ignored'
            ros.spin_until(lambda line=line, proc=proc: line in graph.log(proc), 30.0, line)
    assert hw.poll() is None and pred.poll() is None


def test_a_parameter_file_costs_the_monitor_one_analysis(graph, ros):
    """
    ros2 param load sends the file in one SetParameters request; rclpy sets it one at a time.

    The monitor checks each value, but analyses the scene once for the new sensor radius (the
    readiness diagnostics count the analyses: the configure's, then this one).
    """
    monitor(graph)
    ready = Statements(ros)
    diags = Diagnostics(ros)
    wait_for_monitor(ros, ready)
    config = REPO / 'src' / 'feeder_monitor' / 'config' / 'monitor.yaml'
    values = yaml.safe_load(config.read_text())['/**']['ros__parameters']
    values.update(sensor_radius=0.28, warmup_cycles=3)
    results = ros.set_parameters(MON, values)
    assert all(r.successful for r in results.values()), results
    name = 'feeder_monitor: readiness'

    def latest():
        return Diagnostics.values(diags.by_name[name][-1]) if diags.by_name.get(name) else {}

    ros.spin_until(lambda: latest().get('sensor_radius') == '0.28', 10.0, 'the new rules')
    ros.spin_for(1.5)
    values = latest()
    assert (values['analyses'], values['warmup_cycles']) == ('2', '3'), values
