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
The launch files as ``ros2 launch`` shows and runs them (issue 23, items 2 and 3).

* ``-p`` shows every process a launch file may start (not one OpaqueFunction), ``-s`` the
  arguments' choices, and a word outside them is refused;
* a launch whose arguments cannot work (rviz:=true without rviz2, robot_state_publisher:=true
  without it, a record directory that exists) ends with the reason and leaves no process
  behind: none of its session is left, and no node of it ever showed on the graph.

Run where the real CLI exists (tests/ros_cli.py; FEEDER_ROS_CLI_VENV), skipped elsewhere; the
same checks at plan level run everywhere (tests/test_bringup_checks.py).
"""

import os
import signal
import time

import pytest
import ros_cli

LAUNCH = ['launch', 'feeder_bringup']


@pytest.fixture
def cli(ros_domain):
    env = ros_cli.cli_env()
    if env is None:
        pytest.skip(ros_cli.SKIP_REASON)
    return env


def session_processes(sid):
    """Pids of the processes in session ``sid`` (a launch started in a session of its own)."""
    pids = []
    for entry in os.listdir('/proc'):
        if not entry.isdigit():
            continue
        try:
            with open(f'/proc/{entry}/stat') as f:
                fields = f.read().rsplit(')', 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != 'Z':
            pids.append(int(entry))
    return pids


@pytest.mark.parametrize('launch_file, shown', [
    ('sim.launch.py', ["pkg='feeder_sim', exec='standin_node'",
                       "pkg='feeder_sim', exec='predictor_node'", "exec='monitor_node'",
                       "exec='feed_node'", "exec='bag_recorder'", "exec='robot_state_publisher'", "exec='rviz2'"]),
    ('hardware.launch.py', ["exec='controller_emulator'", "exec='driver_node'",
                            "exec='predictor_node'", "exec='monitor_node'",
                            "exec='bag_recorder'"]),
])
def test_print_shows_the_nodes(cli, launch_file, shown):
    status, out = ros_cli.run([*LAUNCH[:1], '-p', *LAUNCH[1:], launch_file], cli)
    assert status == 0, out
    for text in shown:
        assert text in out, out
    assert 'OpaqueFunction' not in out, out


def test_show_args_lists_the_choices_and_launch_refuses_other_words(cli, tmp_path):
    status, out = ros_cli.run([*LAUNCH[:1], '-s', *LAUNCH[1:], 'hardware.launch.py'], cli)
    assert status == 0, out
    for choices in ("['auto', 'true', 'false']", "['true', 'false']"):
        assert choices in out, out
    status, out = ros_cli.run([*LAUNCH, 'sim.launch.py', 'rviz:=yes'], cli)
    assert status != 0 and 'rviz' in out and "['true', 'false']" in out, out


@pytest.mark.parametrize('launch_file, argument, words', [
    ('sim.launch.py', 'rviz:=true', 'rviz:=true but rviz2 is not installed'),
    ('sim.launch.py', 'robot_state_publisher:=true', 'robot_state_publisher:=true but '
     'robot_state_publisher is not installed'),
    ('sim.launch.py', 'record:={existing}', 'exists; the recorder makes a new directory'),
    ('hardware.launch.py', 'rviz:=true', 'rviz:=true but rviz2 is not installed'),
    ('feeders.launch.py', 'rviz:=true', 'rviz:=true but rviz2 is not installed'),
])
def test_a_launch_that_cannot_work_starts_nothing(cli, ros, tmp_path, launch_file, argument,
                                                  words):
    for package in ('rviz2', 'robot_state_publisher'):
        if package in argument and ros_cli.run(['pkg', 'prefix', package], cli)[0] == 0:
            pytest.skip(f'{package} is installed here')
    (tmp_path / 'existing').mkdir()
    space = 'namespaces:=doomed' if launch_file == 'feeders.launch.py' else 'namespace:=doomed'
    extra = ['emulator:=true'] if launch_file == 'hardware.launch.py' else []
    launch = ros_cli.start([*LAUNCH, launch_file, space, 'cycle_period:=0.05', *extra,
                            argument.format(existing=tmp_path / 'existing')], cli,
                           tmp_path / 'launch.log')
    seen = set()
    try:
        deadline = time.monotonic() + 60
        while launch.poll() is None and time.monotonic() < deadline:
            ros.spin_for(0.2)
            seen |= {ns for _, ns in ros.node.get_node_names_and_namespaces()}
        status = launch.wait(timeout=30)
        # Anything it started would be on the graph within a few seconds: look a while more.
        ros.spin_until(lambda: not session_processes(launch.pid), 10.0,
                       'the processes of the launch session to end')
        for _ in range(10):
            ros.spin_for(0.3)
            seen |= {ns for _, ns in ros.node.get_node_names_and_namespaces()}
    finally:
        left = session_processes(launch.pid)
        for pid in left:        # the launch's own, by id: never leave them running
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        if launch.poll() is None:
            launch.kill()
            launch.wait()
    log = (tmp_path / 'launch.log').read_text(errors='replace')
    assert status != 0, log
    assert words in log, log
    assert not left, f'processes left behind: {left}\n{log}'
    assert '/doomed' not in seen, log
    assert 'process started' not in log, log
