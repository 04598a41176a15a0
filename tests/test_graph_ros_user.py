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
What a ROS user meets first (issue 9), every node as a process on real DDS.

Integers for doubles are taken and every other type error is one line and exit 2; every
shipped config loads at start-up (--params-file) and at run time (what ``ros2 param load``
does); SIGINT, SIGTERM and a lifecycle shutdown end every node with status 0 and take it off
the graph at once; the hardware stand-in offers exactly the driver's interface.
"""

import pathlib
import signal
import time

from feeder_nodes import REPO, STARTUP_TIMEOUT, TRIANGLE
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState
import pytest
from rclpy.parameter import parameter_dict_from_yaml_file, parameter_value_to_python
from std_srvs.srv import SetBool

NO_PORT = '/nonexistent/feeder-tty'     # the driver runs, disconnected, retrying


def driver(graph, *params, ns='/feeder', name=None, extra=()):
    args = ['--ros-args', '-r', f'__ns:={ns}', '-p', f'port:={NO_PORT}', *extra]
    return graph.start('feeder_driver', 'driver_node', *args,
                       *[a for p in params for a in ('-p', p)], name=name or 'driver')


def sim(graph, *params, ns='/feeder', hardware=False, extra=()):
    """predictor_node (node feeder_sim), or with ``hardware`` standin_node (feeder_driver)."""
    args = ['--ros-args', '-r', f'__ns:={ns}', '-p', f'scene:={TRIANGLE}', *extra]
    if hardware:
        args += ['-r', '__node:=feeder_driver']
    return graph.start('feeder_sim', 'standin_node' if hardware else 'predictor_node', *args,
                       *[a for p in params for a in ('-p', p)],
                       name='sim_hw' if hardware else 'predictor')


def monitor(graph, *params, ns='/feeder', extra=()):
    args = ['--ros-args', '-r', f'__ns:={ns}', '-p', f'scene:={TRIANGLE}', *extra]
    return graph.start('feeder_monitor', 'monitor_node', *args,
                       *[a for p in params for a in ('-p', p)], name='monitor')


def feed(graph, *params, ns='/feeder'):
    return graph.start('feeder_monitor', 'feed_node', '--ros-args', '-r', f'__ns:={ns}',
                       *[a for p in params for a in ('-p', p)], name='feed')


def nodes_on_graph(ros):
    return {f'{ns.rstrip("/")}/{n}' for n, ns in ros.node.get_node_names_and_namespaces()}


def wait_for_node(ros, fqn, timeout=STARTUP_TIMEOUT):
    ros.spin_until(lambda: fqn in nodes_on_graph(ros), timeout, f'{fqn} on the graph')
    # Its parameter services answer: the node is constructed and spinning.
    ros.get_parameters(fqn, ['use_sim_time'], timeout=timeout)


# ---- 1: parameter types ------------------------------------------------------------------

START = {       # node: (start function, fully qualified name)
    'driver': (driver, '/feeder/feeder_driver'),
    'standin': (lambda graph, *params: sim(graph, *params, hardware=True),
                '/feeder/feeder_driver'),
    'predictor': (sim, '/feeder/feeder_sim'),
    'monitor': (monitor, '/feeder/feeder_monitor'),
    'feed': (feed, '/feeder/feeder_feed'),
}


@pytest.mark.parametrize('node, param, given, expected', [
    ('driver', 'cycle_period', '1', 1.0),
    ('standin', 'cycle_period', '2', 2.0),
    ('predictor', 'markers_period', '1', 1.0),
    ('monitor', 'silence_margin', '2', 2.0),
    ('feed', 'verdict_timeout', '3', 3.0),
])
def test_an_integer_for_a_double_is_that_double(graph, ros, node, param, given, expected):
    start, fqn = START[node]
    proc = start(graph, f'{param}:={given}')
    wait_for_node(ros, fqn)
    value = ros.get_parameters(fqn, [param])[param]
    assert type(value) is float and value == expected
    assert proc.poll() is None


BAD = [
    ('driver', 'cycle_period:=abc', "cycle_period must be a double, got string 'abc'"),
    ('driver', 'baud_rate:=1.5', 'baud_rate must be an integer, got double 1.5'),
    ('driver', 'frame_id:=5', 'frame_id must be a string, got integer 5'),
    ('standin', 'cycle_period:=abc', "cycle_period must be a double, got string 'abc'"),
    ('standin', 'start_edge:=1.5', 'start_edge must be an integer, got double 1.5'),
    ('predictor', 'markers_period:=abc', "markers_period must be a double, got string 'abc'"),
    ('predictor', 'start_edge:=1.5', 'start_edge must be an integer, got double 1.5'),
    ('predictor', 'scene:=5', 'scene must be a string, got integer 5'),
    ('monitor', 'warmup_cycles:=1.5', 'warmup_cycles must be an integer, got double 1.5'),
    ('monitor', 'scene:=5', 'scene must be a string, got integer 5'),
    ('monitor', 'silence_margin:=true', 'silence_margin must be a double, got bool True'),
    ('feed', 'max_statement_age:=soon', "max_statement_age must be a double, got string 'soon'"),
    ('feed', 'verdict_timeout:=0.0', 'verdict_timeout'),
]


def test_every_other_type_error_is_one_line_and_exit_2(graph):
    procs = [(START[node][0](graph, arg), node, text) for node, arg, text in BAD]
    for proc, node, text in procs:
        assert proc.wait(timeout=60) == 2, graph.log(proc)
        log = graph.log(proc)
        assert 'Traceback' not in log, log
        errors = [line for line in log.splitlines() if ': error: ' in line]
        assert len(errors) == 1 and text in errors[0], log


# ---- 2: shipped configs ------------------------------------------------------------------

CONFIGS = {
    'driver': REPO / 'src' / 'feeder_driver' / 'config' / 'driver.yaml',
    'standin': REPO / 'src' / 'feeder_sim' / 'config' / 'standin.yaml',
    'predictor': REPO / 'src' / 'feeder_sim' / 'config' / 'predictor.yaml',
    'monitor': REPO / 'src' / 'feeder_monitor' / 'config' / 'monitor.yaml',
}


def config_values(path, fqn):
    """Return the parameters ``ros2 param load`` sends to ``fqn`` (rclpy's file parser)."""
    return {name: parameter_value_to_python(p.value) for name, p in
            parameter_dict_from_yaml_file(str(path), True, target_nodes=[fqn]).items()}


def test_every_shipped_config_loads_at_start_up_and_at_run_time(graph, ros):
    """--params-file at start-up; then the file's values set through the parameter services."""
    started = {
        '/feeder/feeder_driver': (CONFIGS['driver'], driver(graph)),
        '/feeder/feeder_sim': (CONFIGS['predictor'], sim(graph)),
        '/other/feeder_driver': (CONFIGS['standin'], sim(graph, ns='/other', hardware=True)),
        '/feeder/feeder_monitor': (CONFIGS['monitor'], monitor(graph)),
    }
    with_file = {
        '/f/feeder_driver': (CONFIGS['driver'], driver(
            graph, ns='/f', name='driver_file', extra=('--params-file', CONFIGS['driver']))),
        '/f/feeder_sim': (CONFIGS['predictor'], graph.start(
            'feeder_sim', 'predictor_node', '--ros-args', '-r', '__ns:=/f', '--params-file',
            CONFIGS['predictor'], '-p', f'scene:={TRIANGLE}', '-p', 'markers_period:=3',
            name='predictor_file')),
        '/g/feeder_driver': (CONFIGS['standin'], sim(
            graph, 'cycle_period:=3', ns='/g', hardware=True,
            extra=('--params-file', CONFIGS['standin']))),
        '/f/feeder_monitor': (CONFIGS['monitor'], graph.start(
            'feeder_monitor', 'monitor_node', '--ros-args', '-r', '__ns:=/f', '--params-file',
            CONFIGS['monitor'], '-p', f'scene:={TRIANGLE}', name='monitor_file')),
    }
    for fqn in [*started, *with_file]:
        wait_for_node(ros, fqn)
    for fqn, (path, proc) in with_file.items():
        values = config_values(path, fqn)
        assert values, f'{path} has no parameters for {fqn}'
        got = ros.get_parameters(fqn, list(values))
        # A -p after the file wins.
        expected = dict(values, **{'/f/feeder_sim': {'markers_period': 3.0},
                                   '/g/feeder_driver': {'cycle_period': 3.0}}.get(fqn, {}))
        assert got == expected, fqn
    for fqn, (path, proc) in started.items():
        values = config_values(path, fqn)
        results = ros.set_parameters(fqn, values)
        failed = {n: r.reason for n, r in results.items() if not r.successful}
        assert not failed, f'{path.name} on {fqn}: {failed}'
        assert proc.poll() is None
    for _, proc in [*started.values(), *with_file.values()]:
        assert proc.poll() is None


# ---- 3: clean exits ----------------------------------------------------------------------

# A node that exits cleanly leaves the graph at once (typically 0.1-0.3 s after a signal, 0.5 s
# more after a lifecycle shutdown, run_node's linger: its participant announces that it
# leaves); one that does not is dropped only when its DDS lease runs out, 17-20 s after its
# last announcement (Fast DDS: 20 s lease, announcements every 3 s). The
# bound lies between the two, with room for a loaded machine (one run beside two busy loops
# and another suite took more than 5 s).
LEAVE_BOUND_S = 15.0


def stop_and_wait_gone(ros, proc, fqn, sig):
    """Send ``sig``, wait until ``fqn`` left the graph (LEAVE_BOUND_S); return the exit status."""
    proc.send_signal(sig)
    ros.spin_until(lambda: fqn not in nodes_on_graph(ros), LEAVE_BOUND_S, f'{fqn} off the graph')
    return proc.wait(timeout=10)


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_every_node_exits_0_and_leaves_the_graph_at_once(graph, ros, tmp_path, sig):
    procs = {
        '/feeder/feeder_driver': sim(graph, 'cycle_period:=0.005', hardware=True),
        '/feeder/feeder_sim': sim(graph),
        '/feeder/feeder_monitor': monitor(graph),
        '/feeder/feeder_feed': feed(graph),
        '/drv/feeder_driver': driver(graph, ns='/drv'),
        '/feeder/feeder_bag_recorder': graph.start(
            'feeder_monitor', 'bag_recorder', tmp_path / 'bag', '--ros-args', '-r',
            '__ns:=/feeder', name='recorder'),
    }
    for fqn in procs:
        wait_for_node(ros, fqn)
    # The stand-in cycles at 200 Hz while it is stopped (a callback may be running).
    assert ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=True)).success
    ros.spin_for(1.0)
    for fqn, proc in procs.items():
        status = stop_and_wait_gone(ros, proc, fqn, sig)
        log = graph.log(proc)
        assert status == 0 and 'Traceback' not in log, log
    assert 'stopped: interrupted' in graph.log(procs['/feeder/feeder_bag_recorder'])


def test_sigterm_at_200_hz_never_ends_with_a_traceback(graph, ros):
    """The issue saw exit 1 and a traceback in 3 of 8 runs."""
    for k in range(4):
        ns = f'/run{k}'
        hw = sim(graph, 'cycle_period:=0.005', ns=ns, hardware=True)
        mon = monitor(graph, ns=ns)
        wait_for_node(ros, f'{ns}/feeder_driver')
        wait_for_node(ros, f'{ns}/feeder_monitor')
        assert ros.call(SetBool, f'{ns}/feeder_driver/enable',
                        SetBool.Request(data=True)).success
        ros.spin_for(0.3 + 0.1 * k)
        for proc in (mon, hw):
            proc.send_signal(signal.SIGTERM)
        for proc in (hw, mon):
            assert proc.wait(timeout=10) == 0, graph.log(proc)
            assert 'Traceback' not in graph.log(proc), graph.log(proc)


@pytest.mark.parametrize('role', ['stand-in', 'predictor', 'driver'])
def test_a_lifecycle_shutdown_ends_the_process(graph, ros, role):
    proc = {'stand-in': lambda: sim(graph, hardware=True),
            'predictor': lambda: sim(graph),
            'driver': lambda: driver(graph)}[role]()
    fqn = '/feeder/feeder_sim' if role == 'predictor' else '/feeder/feeder_driver'
    wait_for_node(ros, fqn)
    req = ChangeState.Request(transition=Transition(id=Transition.TRANSITION_ACTIVE_SHUTDOWN))
    assert ros.call(ChangeState, f'{fqn}/change_state', req).success
    assert proc.wait(timeout=10) == 0, graph.log(proc)
    ros.spin_until(lambda: fqn not in nodes_on_graph(ros), LEAVE_BOUND_S, f'{fqn} off the graph')
    assert 'Traceback' not in graph.log(proc)


# ---- 4: the stand-in's interface ---------------------------------------------------------

def interface(ros, name, ns):
    """Publishers, subscriptions, services of a node: names relative to ``ns``, with types."""
    def rel(items):
        out = set()
        for topic, types in items:
            if topic.startswith(ns + '/'):
                topic = topic[len(ns) + 1:]
            out.add((topic, tuple(types)))
        return out

    n = ros.node
    return {'publishers': rel(n.get_publisher_names_and_types_by_node(name, ns)),
            'subscriptions': rel(n.get_subscriber_names_and_types_by_node(name, ns)),
            'services': rel(n.get_service_names_and_types_by_node(name, ns))}


def test_the_hardware_stand_in_offers_exactly_the_drivers_interface(graph, ros):
    driver(graph, ns='/real')
    sim(graph, ns='/simulated', hardware=True)
    for fqn in ('/real/feeder_driver', '/simulated/feeder_driver'):
        wait_for_node(ros, fqn)

    def both():
        return (interface(ros, 'feeder_driver', '/real'),
                interface(ros, 'feeder_driver', '/simulated'))

    deadline = time.monotonic() + 10.0
    real, simulated = both()
    while real != simulated and time.monotonic() < deadline:      # discovery settling
        ros.spin_for(0.2)
        real, simulated = both()
    assert ('proximity', ('sensor_msgs/msg/Range',)) in real['publishers']
    assert ('feeder_driver/trigger_cycle', ('std_srvs/srv/Trigger',)) in real['services']
    for kind in real:
        assert simulated[kind] == real[kind], (kind, simulated[kind] ^ real[kind])


def test_the_configs_are_the_installed_ones():
    """Check that the files tested above are the installed ones (share/<pkg>/config)."""
    install = REPO / 'ros2_ws' / 'install'
    for pkg, path in (('feeder_driver', CONFIGS['driver']), ('feeder_sim', CONFIGS['standin']),
                      ('feeder_sim', CONFIGS['predictor']),
                      ('feeder_monitor', CONFIGS['monitor'])):
        installed = install / pkg / 'share' / pkg / 'config' / path.name
        assert installed.read_text() == pathlib.Path(path).read_text(), installed
