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
One name and one range per parameter the nodes share (issue 23, item 4).

The driver, the stand-in and the monitor name their /diagnostics period alike, the driver and
its stand-in share cycle_period's range, the stand-in takes the driver's config/driver.yaml
(at start-up and with a parameter set), and a node on use_sim_time without /clock says so.
"""

from feeder_driver import params as driver_params
from feeder_monitor.params import MONITOR_PARAMS
from feeder_nodes import sim_as_hardware, STARTUP_TIMEOUT, TRIANGLE
from feeder_sim.params import PREDICTOR_PARAMS, STANDIN_PARAMS
from feeder_testing import INSTALL
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.srv import SetParametersAtomically
from rclpy.parameter import Parameter
from std_srvs.srv import SetBool
import yaml

DRIVER_YAML = INSTALL / 'feeder_driver' / 'share' / 'feeder_driver' / 'config' / 'driver.yaml'


def test_shared_parameters_have_one_name_and_one_spec():
    tables = {'driver': driver_params.SPECS, 'standin': STANDIN_PARAMS,
              'predictor': PREDICTOR_PARAMS, 'monitor': MONITOR_PARAMS}
    specs = {}
    for node, table in tables.items():
        for spec in table:
            specs.setdefault(spec.name, {})[node] = spec
    for name, by_node in specs.items():
        # Type, default, range, read-only alike (a description may say what it means there).
        shapes = {(s.kind, s.default, s.minimum, s.maximum, s.read_only, s.choices)
                  for s in by_node.values()}
        assert len(shapes) == 1, (name, by_node)
    assert 'diagnostics_period' not in specs
    assert set(specs['diagnostic_updater.period']) == set(tables)
    # Every run-time parameter of the driver's file is the stand-in's too.
    driver_file = yaml.safe_load(DRIVER_YAML.read_text())['/**']['ros__parameters']
    assert set(driver_file) <= {s.name for s in STANDIN_PARAMS}


def test_the_stand_in_takes_the_drivers_file(graph, ros):
    proc = graph.start('feeder_sim', 'standin_node', '--ros-args', '-r', '__ns:=/feeder', '-r',
                       '__node:=feeder_driver', '-p', f'scene:={TRIANGLE}',
                       '--params-file', DRIVER_YAML, name='stand_in')
    values = ros.get_parameters('/feeder/feeder_driver',
                                ['cycle_period', 'ack_timeout_s', 'diagnostic_updater.period'],
                                timeout=STARTUP_TIMEOUT)
    assert values == {'cycle_period': 1.0, 'ack_timeout_s': 0.5,
                      'diagnostic_updater.period': 1.0}, values
    log = graph.log(proc)
    assert 'is not a parameter of standin_node' not in log, log
    # As one batch (ros2 param load): every key of the file, set atomically.
    driver_file = yaml.safe_load(DRIVER_YAML.read_text())['/**']['ros__parameters']
    request = SetParametersAtomically.Request(parameters=[
        Parameter(k, value=v).to_parameter_msg() for k, v in driver_file.items()])
    assert all(isinstance(p, ParameterMsg) for p in request.parameters)
    result = ros.call(SetParametersAtomically,
                      '/feeder/feeder_driver/set_parameters_atomically', request).result
    assert result.successful, result.reason
    # The driver's rules across them hold on the stand-in too.
    bad = SetParametersAtomically.Request(parameters=[
        Parameter('ack_timeout_s', value=6.0).to_parameter_msg()])
    result = ros.call(SetParametersAtomically,
                      '/feeder/feeder_driver/set_parameters_atomically', bad).result
    assert not result.successful and 'smaller than cycle_timeout_s' in result.reason


def test_the_old_name_still_sets_the_one_name_with_a_warning(graph, ros):
    proc = sim_as_hardware(graph, 'diagnostics_period:=0.5')
    values = ros.get_parameters('/feeder/feeder_driver', ['diagnostic_updater.period'],
                                timeout=STARTUP_TIMEOUT)
    assert values == {'diagnostic_updater.period': 0.5}
    log = graph.log(proc)
    assert 'diagnostics_period is now called diagnostic_updater.period' in log, log
    assert 'is not a parameter of standin_node' not in log, log


def test_enable_on_sim_time_without_clock_says_why_nothing_fires(graph, ros):
    proc = sim_as_hardware(graph, 'use_sim_time:=true')
    res = ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=True),
                   timeout=STARTUP_TIMEOUT)
    assert res.success and 'no /clock has arrived' in res.message, res.message
    ros.spin_until(lambda: 'no /clock has arrived' in graph.log(proc), 10.0,
                   'the warning in the log')
