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
The real ``ros2`` CLI (launch, param load, interface show, topic echo); feeders side by side.

The ``ros2`` tests run where the CLI exists (tests/ros_cli.py) and are skipped elsewhere with
the reason; three feeders side by side also run as plain processes everywhere.
"""

import os
import re
import signal
import time

from builtin_interfaces.msg import Time
from feeder_common import auth
from feeder_common.messages import (check_verdict, parse_cycle_fired, parse_cycle_status,
                                    parse_predicted_state)
from feeder_interfaces.msg import CycleStatus, PredictedState, Verdict
from feeder_nodes import (CycleStatuses, DRIVER, MONITOR, monitor, predictor, REPO,
                          sim_as_hardware, Statements, STARTUP_TIMEOUT, TRIANGLE, Verdicts,
                          wait_for_monitor)
import pytest
import ros_cli
from std_srvs.srv import SetBool, Trigger
import yaml

SHARE = REPO / 'ros2_ws' / 'install'


@pytest.fixture
def cli(ros_domain):
    env = ros_cli.cli_env()
    if env is None:
        pytest.skip(ros_cli.SKIP_REASON)
    return env


def nodes_on_graph(ros):
    return {f'{ns.rstrip("/")}/{n}' for n, ns in ros.node.get_node_names_and_namespaces()}


def wait_nodes(ros, fqns, timeout=STARTUP_TIMEOUT):
    ros.spin_until(lambda: set(fqns) <= nodes_on_graph(ros), timeout, f'{sorted(fqns)}')
    for fqn in fqns:
        ros.get_parameters(fqn, ['use_sim_time'], timeout=timeout)


class Launch:
    """``ros2 launch feeder_bringup ...`` with the test's key file (conftest ``key_file``)."""

    def __init__(self, env, tmp_path, *argv):
        self.log_path = tmp_path / 'launch.log'
        if not any(a.startswith('key_file:=') for a in argv):
            argv = (*argv, f'key_file:={tmp_path / "keys" / "hmac.key"}')
        self.proc = ros_cli.start(['launch', 'feeder_bringup', *argv], env, self.log_path)

    @property
    def log(self):
        return self.log_path.read_text(errors='replace')

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                return self.proc.wait(timeout=30)
            except Exception:   # noqa: B902 - never leave it running
                self.proc.kill()
                self.proc.wait()
                raise
        return self.proc.returncode


@pytest.fixture
def launches():
    started = []
    yield started
    for launch in started:
        launch.stop()


def param_load(cli, fqn, path):
    # No daemon (a test leaves no process behind); a fresh CLI participant may take a few
    # seconds to discover the node on a loaded machine: try again then.
    for _ in range(3):
        status, out = ros_cli.run(['param', 'load', '--no-daemon', '--spin-time', '3', fqn,
                                   path], cli)
        if 'Node not found' not in out:
            break
    assert status == 0 and 'failed' not in out and 'Set parameter' in out, out
    return out


def test_sim_launch_param_load_lifecycle_and_ctrl_c(cli, ros, tmp_path, launches):
    launch = Launch(cli, tmp_path, 'sim.launch.py', 'cycle_period:=0.02',
                    f'record:={tmp_path / "bag"}')
    launches.append(launch)
    names = ['/feeder/feeder_driver', '/feeder/feeder_sim', '/feeder/feeder_monitor',
             '/feeder/feeder_bag_recorder']
    wait_nodes(ros, names)
    ready = Statements(ros)
    assert ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=True)).success
    # (after the monitor's settling: 87 throws of the triangle, under 2 s at 0.02 s)
    ros.spin_until(lambda: ready.any_ready(), 30.0, 'an edge1_ready true, signed and fresh')

    share = {pkg: SHARE / pkg / 'share' / pkg / 'config' for pkg in
             ('feeder_sim', 'feeder_monitor', 'feeder_driver')}
    param_load(cli, '/feeder/feeder_driver', share['feeder_sim'] / 'standin.yaml')
    param_load(cli, '/feeder/feeder_sim', share['feeder_sim'] / 'predictor.yaml')
    param_load(cli, '/feeder/feeder_monitor', share['feeder_monitor'] / 'monitor.yaml')

    status, out = ros_cli.run(['lifecycle', 'set', '--no-daemon', '--spin-time', '3',
                               '/feeder/feeder_sim', 'shutdown'], cli)
    assert status == 0 and 'Transitioning successful' in out, out
    ros.spin_until(lambda: '/feeder/feeder_sim' not in nodes_on_graph(ros), 5.0,
                   'the predictor off the graph')
    ros.spin_until(lambda: '[predictor_node-2]: process has finished cleanly' in launch.log, 10.0,
                   'the predictor process to end')
    assert launch.stop() == 0, launch.log
    log = launch.log
    for exe in ('standin_node-1', 'predictor_node-2', 'monitor_node-3', 'feed_node-4',
                'bag_recorder-5'):
        assert f'[INFO] [{exe}]: process has finished cleanly' in log, log
    assert 'Traceback' not in log and 'process has died' not in log, log
    ros.spin_until(lambda: not set(names) & nodes_on_graph(ros), 3.0, 'every node gone')
    assert (tmp_path / 'bag' / 'metadata.yaml').is_file()


def test_hardware_launch_with_the_emulator(cli, ros, tmp_path, launches):
    launch = Launch(cli, tmp_path, 'hardware.launch.py', 'emulator:=true',
                    f'emulator_link:={tmp_path / "tty"}', 'namespace:=hw')
    launches.append(launch)
    wait_nodes(ros, ['/hw/feeder_driver', '/hw/feeder_sim', '/hw/feeder_monitor'])
    statuses = CycleStatuses(ros, '/hw/cycle_status')
    deadline = time.monotonic() + 30
    while True:     # the driver connects once the emulator's pty is there
        res = ros.call(Trigger, '/hw/feeder_driver/trigger_cycle', Trigger.Request())
        if res.success or time.monotonic() > deadline:
            break
        ros.spin_for(0.3)
    assert res.success, res.message
    ros.spin_until(lambda: len(statuses) == 1, 10.0, 'the cycle')
    assert statuses.parsed[0].ok and statuses.parsed[0].sensor is not None
    param_load(cli, '/hw/feeder_driver', SHARE / 'feeder_driver' / 'share' / 'feeder_driver' /
               'config' / 'driver.yaml')
    assert launch.stop() == 0, launch.log
    assert 'process has died' not in launch.log, launch.log


def test_an_integer_for_a_double_in_launch_xml(cli, ros, tmp_path, launches):
    xml = tmp_path / 'one.launch.xml'
    xml.write_text(f"""<launch>
  <node pkg="feeder_sim" exec="standin_node" name="feeder_driver" namespace="/xml">
    <param name="scene" value="{TRIANGLE}"/>
    <param name="cycle_period" value="1"/>
  </node>
</launch>
""")
    log = tmp_path / 'xml.log'
    proc = ros_cli.start(['launch', str(xml)], cli, log)
    try:
        wait_nodes(ros, ['/xml/feeder_driver'])
        value = ros.get_parameters('/xml/feeder_driver', ['cycle_period'])['cycle_period']
        assert type(value) is float and value == 1.0
    finally:
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=30) == 0, log.read_text()


def test_realtime_priority_through_ros2_launch(cli, ros, tmp_path, launches):
    from test_graph_realtime import may_use_fifo, threads
    if not may_use_fifo():
        pytest.skip('this user may not use SCHED_FIFO here (no rtprio limit, no CAP_SYS_NICE)')
    launch = Launch(cli, tmp_path, 'hardware.launch.py', 'emulator:=true',
                    f'emulator_link:={tmp_path / "tty"}', 'namespace:=rt',
                    'realtime_priority:=5')
    launches.append(launch)
    wait_nodes(ros, ['/rt/feeder_driver', '/rt/feeder_sim', '/rt/feeder_monitor',
                     '/rt/feeder_feed'])
    pids = {int(line.rsplit('[', 1)[1].rstrip(']')): line.split('[')[2].split(']')[0]
            for line in launch.log.splitlines() if 'process started with pid' in line}
    nodes = {pid: exe for pid, exe in pids.items() if not exe.startswith('controller_emulator')}
    assert sorted(exe.rsplit('-', 1)[0] for exe in nodes.values()) == \
        ['driver_node', 'feed_node', 'monitor_node', 'predictor_node'], launch.log
    for pid, exe in nodes.items():
        assert set(threads(pid).values()) == {(os.SCHED_FIFO, 5)}, exe
    emulator = next(pid for pid, exe in pids.items() if exe.startswith('controller_emulator'))
    assert os.sched_getscheduler(emulator) == os.SCHED_OTHER   # not a ROS node: untouched
    assert launch.stop() == 0, launch.log
    assert 'process has died' not in launch.log, launch.log


# ---- several feeders side by side --------------------------------------------------------

def check_feeders_apart(ros, spaces, cycles=40):
    """
    Cycle every feeder but the middle one; each monitor follows its own feeder only.

    Per namespace: cycle_status seqs 1..n of its own; one edge1_verdict per cycle of its own,
    naming that cycle (none for the idle one), signed by its own monitor; its predictor
    followed exactly those.
    """
    statuses = {ns: CycleStatuses(ros, f'{ns}/cycle_status') for ns in spaces}
    ready = {ns: Statements(ros, f'{ns}/edge1_ready', monitor=f'{ns}/feeder_monitor')
             for ns in spaces}
    verdicts = {ns: Verdicts(ros, f'{ns}/edge1_verdict', monitor=f'{ns}/feeder_monitor')
                for ns in spaces}
    # The same key everywhere, but a verdict names its monitor: one feeder's cannot pass as
    # another's.
    crossed = Verdicts(ros, f'{spaces[0]}/edge1_verdict', monitor=f'{spaces[2]}/feeder_monitor')
    for ns in spaces:
        ros.spin_until(lambda ns=ns: len(ready[ns]) >= 1, STARTUP_TIMEOUT, f'{ns} monitor')
        # The writers' own accounts: the driver's cycle_status matched 3 readers (ours among
        # them), the monitor's edge1_verdict ours (two on the first feeder: ``crossed``).
        ros.wait_remote_matched(f'{ns}/feeder_driver', readers={f'{ns}/cycle_status': 3})
        ros.wait_remote_matched(f'{ns}/feeder_monitor',
                                readers={f'{ns}/edge1_verdict': 2 if ns == spaces[0] else 1})
    busy = [ns for k, ns in enumerate(spaces) if k != 1]
    for ns in busy:
        assert ros.call(SetBool, f'{ns}/feeder_driver/enable',
                        SetBool.Request(data=True)).success
    ros.spin_until(lambda: all(len(statuses[ns]) >= cycles for ns in busy), 60.0, 'cycles')
    for ns in busy:
        assert ros.call(SetBool, f'{ns}/feeder_driver/enable',
                        SetBool.Request(data=False)).success
    ros.spin_for(1.5)
    for ns in spaces:
        seqs = statuses[ns].seqs
        assert seqs == list(range(1, len(seqs) + 1)), ns
        assert [v.seq for v in verdicts[ns].parsed] == seqs, ns
        assert all(v.authentic for v in verdicts[ns].parsed), ns
        assert all(c.authentic for c in ready[ns].checked), ns
        assert all(s.hardware_id == 'sim' for s in statuses[ns].parsed)
    assert not statuses[spaces[1]].msgs
    assert len(crossed) == len(verdicts[spaces[0]]) and \
        not any(v.authentic for v in crossed.parsed)


def test_three_feeders_side_by_side_as_processes(graph, ros):
    spaces = ['/feeder_1', '/feeder_2', '/feeder_3']
    for k, ns in enumerate(spaces):
        sim_as_hardware(graph, f'cycle_period:={0.01 * (k + 1)}', ns=ns)
        predictor(graph, ns=ns)
        monitor(graph, ns=ns)
    check_feeders_apart(ros, spaces)


def test_three_feeders_side_by_side_with_ros2_launch(cli, ros, tmp_path, launches):
    launch = Launch(cli, tmp_path, 'feeders.launch.py', 'namespaces:=left,middle,right',
                    'cycle_period:=0.01')
    launches.append(launch)
    spaces = ['/left', '/middle', '/right']
    wait_nodes(ros, [f'{ns}/{n}' for ns in spaces for n in
                     ('feeder_driver', 'feeder_sim', 'feeder_monitor')])
    check_feeders_apart(ros, spaces)
    assert launch.stop() == 0, launch.log
    assert 'process has died' not in launch.log, launch.log


def test_the_feed_action_through_ros2_action_send_goal(cli, ros, tmp_path, launches):
    """Issue 22: the interface, the action's listing and a goal with feedback, by the CLI."""
    launch = Launch(cli, tmp_path, 'sim.launch.py', 'cycle_period:=0.05')
    launches.append(launch)
    wait_nodes(ros, ['/feeder/feeder_driver', '/feeder/feeder_sim', '/feeder/feeder_monitor',
                     '/feeder/feeder_feed'])
    status, out = ros_cli.run(['interface', 'show', 'feeder_interfaces/action/FeedPart'], cli)
    assert status == 0 and 'string REASON_READY = "ready"' in out and 'bool new_part' in out, out
    # (ros2 action list has no --no-daemon: the daemon it starts is stopped right after)
    try:
        status, out = ros_cli.run(['action', 'list', '-t'], cli)
    finally:
        ros_cli.run(['daemon', 'stop'], cli)
    assert '/feeder/feeder_feed/feed_part [feeder_interfaces/action/FeedPart]' in out, out
    goal = ['action', 'send_goal', '/feeder/feeder_feed/feed_part',
            'feeder_interfaces/action/FeedPart', '{max_cycles: 400, new_part: true}',
            '--feedback']
    deadline = time.monotonic() + STARTUP_TIMEOUT
    while True:     # refused until the feed node holds a fresh statement of the monitor
        status, out = ros_cli.run(goal, cli, timeout=120)
        if 'reason: refused' not in out or time.monotonic() > deadline:
            break
        time.sleep(1.0)
    assert status == 0 and 'Goal finished with status: SUCCEEDED' in out, out
    # (the CLI's client reads feedback with a history of 10: it shows some cycles, not all)
    assert 'reason: ready' in out and 'Feedback:' in out, out
    cycles = int(re.search(r'detail: ready at cycle seq \d+ after (\d+) cycles', out).group(1))
    assert cycles > 87, out       # the settling after a new part
    assert launch.stop() == 0, launch.log


# ---- the feeder's own message types, as a ROS user sees them -------------------------------

def interface_lines(cli, *argv):
    """Return the lines of ``ros2 interface show ARGV`` without comments (indented)."""
    status, out = ros_cli.run(['interface', 'show', *argv], cli)
    assert status == 0, out
    return {line.split('#')[0].rstrip() for line in out.splitlines()} - {''}


def test_ros2_interface_show_of_the_typed_messages(cli):
    """Show the installed definitions, nested types expanded (one tab per level)."""
    lines = interface_lines(cli, 'feeder_interfaces/msg/CycleStatus')
    assert {'string OUTCOME_FIRED = "fired"', 'string OUTCOME_COMPLETED = "completed"',
            'string OUTCOME_FAILED = "failed"', 'int8 SENSOR_NONE = -1', 'int8 SENSOR_CLEAR = 0',
            'int8 SENSOR_DETECTED = 1', 'uint64 seq', 'builtin_interfaces/Time stamp',
            '\tint32 sec', '\tuint32 nanosec', 'string outcome', 'int8 sensor', 'string reason',
            'string hardware_id', 'string session', 'uint8[] mac'} <= lines, sorted(lines)
    lines = interface_lines(cli, 'feeder_interfaces/msg/PredictedState')
    assert {'string THROW_LOST = "lost"', 'int32 EDGE_LOST = -1', 'uint64 seq',
            '\tuint32 nanosec', 'int32 edge', 'float64 r', 'string throw_kind'} <= lines
    # Analysis -> LimitSet -> EdgeBand, and the other nested sequences. (ros2interface 0.36.1
    # cuts a nested line at the first occurrence of its comment's text when it shows no
    # comments: "float64 r_min  # m" showed as "float64 r"; the comments now say "metres".)
    nested = {'LimitSet limit_set', '\tint32[] pattern', '\tEdgeBand[] bands', '\t\tint32 edge',
              '\t\tint32 jogs_min', '\t\tint32 jogs_max', '\tbool periodic',
              '\tfloat64 cycle_length_mean', 'EdgeDesign[] edges', '\tfloat64 r_grasp',
              '\tfloat64 r_flip', 'Escape[] escapes', '\tint32 to_edge', 'BasinOutcome[] basin',
              '\tstring pattern', '\tuint32 starts', 'string scene', 'uint64 scene_hash',
              'int32 goal_edge', 'bool sensor_feasible', 'float64 worst_normal_force',
              '\t\tfloat64 r_min', '\t\tfloat64 r_max', 'float64 start_r'}
    lines = interface_lines(cli, 'feeder_interfaces/msg/Analysis')
    assert nested <= lines, sorted(nested - lines)


def echo_once(cli, topic):
    """Return the message ``ros2 topic echo --once TOPIC`` printed, as YAML data."""
    status, out = ros_cli.run(['topic', 'echo', '--once', '--no-daemon', '--spin-time', '5',
                               topic], cli, timeout=90)
    assert status == 0 and '\n---' in out, (topic, out)
    return yaml.safe_load(out.split('\n---')[0])


def report_of(printed):
    """Rebuild the CycleStatus the CLI printed from its fields."""
    return CycleStatus(seq=printed['seq'], stamp=Time(**printed['stamp']),
                       outcome=printed['outcome'], sensor=printed['sensor'],
                       reason=printed['reason'], hardware_id=printed['hardware_id'],
                       session=printed['session'], mac=printed['mac'])


def test_ros2_topic_echo_prints_the_typed_fields(cli, graph, ros):
    """
    Echo each typed topic of the sim graph once with ``ros2 topic echo``, field by field.

    What it prints is the message: the cycle reports and the verdict rebuilt from the printed
    fields parse (feeder_common.messages) and their MACs verify under the run's key; the
    latched limit set is the analysis' own.
    """
    sim_as_hardware(graph, 'cycle_period:=0.1')
    predictor(graph)
    monitor(graph)
    ready = Statements(ros)
    wait_for_monitor(ros, ready)
    ros.wait_active(DRIVER)
    assert ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=True)).success
    try:
        printed = {topic: echo_once(cli, f'/feeder/{topic}') for topic in (
            'cycle_status', 'cycle_fired', 'predicted/state', 'predicted/limit_set',
            'predicted/analysis', 'edge1_verdict')}
    finally:
        ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=False))

    got = printed['cycle_status']
    assert list(got) == ['seq', 'stamp', 'outcome', 'sensor', 'reason', 'hardware_id',
                         'session', 'mac'], got
    status = parse_cycle_status(report_of(got))
    assert (got['outcome'], status.ok, status.reason, status.hardware_id) == \
        ('completed', True, '', 'sim')
    assert got['sensor'] in (0, 1) and status.seq >= 1 and len(status.mac) == 32
    assert auth.mac_ok(ros.key, auth.CYCLE_LABEL, auth.cycle_fields(
        DRIVER, status.session, status.seq, status.stamp_ns, 'completed',
        str(got['sensor']), ''), status.mac)

    got = printed['cycle_fired']
    fired = parse_cycle_fired(report_of(got))
    assert (got['outcome'], got['sensor'], got['reason']) == ('fired', -1, '')
    assert fired.session == status.session
    assert auth.mac_ok(ros.key, auth.FIRED_LABEL, auth.fired_fields(
        DRIVER, fired.session, fired.seq, fired.stamp_ns), fired.mac)

    got = printed['predicted/state']
    assert list(got) == ['seq', 'stamp', 'edge', 'r', 'throw_kind'], got
    state = parse_predicted_state(PredictedState(
        seq=got['seq'], stamp=Time(**got['stamp']), edge=got['edge'], r=got['r'],
        throw_kind=got['throw_kind']))
    assert state.seq >= 1 and state.edge in (0, 1, 2) and 0 < state.R < 0.4
    assert state.throw_kind in ('jog', 'flip')

    limit_set = printed['predicted/limit_set']
    assert list(limit_set) == ['pattern', 'bands', 'periodic', 'transient', 'cycle_length_min',
                               'cycle_length_mean', 'cycle_length_max'], limit_set
    assert limit_set['pattern'] == [0, 2, 1] and limit_set['periodic'] is True
    assert [b['edge'] for b in limit_set['bands']] == [0, 1, 2]
    assert all(list(b) == ['edge', 'r_min', 'r_max', 'jogs_min', 'jogs_max'] and
               0 < b['r_min'] <= b['r_max'] for b in limit_set['bands'])
    analysis = printed['predicted/analysis']
    assert analysis['scene'] == 'triangle' and analysis['goal_edge'] == 1
    assert analysis['limit_set'] == limit_set
    assert [e['edge'] for e in analysis['edges']] == [0, 1, 2]
    assert all(e['r_grasp'] <= e['r_flip'] for e in analysis['edges'])
    assert analysis['basin'] == [{'pattern': '0-2-1', 'starts': analysis['basin'][0]['starts']}]
    assert analysis['invariant'] is True and analysis['escapes'] == []

    got = printed['edge1_verdict']
    assert list(got) == ['seq', 'stamp', 'ready', 'state', 'anomaly', 'session', 'sent', 'mac']
    verdict = Verdict(seq=got['seq'], stamp=Time(**got['stamp']), ready=got['ready'],
                      state=got['state'], anomaly=got['anomaly'], session=got['session'],
                      sent=Time(**got['sent']), mac=got['mac'])
    check = check_verdict(verdict, ros.key, MONITOR, ros.node.get_clock().now().nanoseconds,
                          max_age_s=3600.0)
    assert check.authentic and check.seq >= 1, check
