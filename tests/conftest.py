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
Graph-level test fixtures: DDS on loopback, a free domain id per test, node processes.

The harness is tests/feeder_testing.py (one implementation for the tests, the demo and the
benchmarks); this file only makes fixtures of it. Every test in tests/ runs with
``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and a ``ROS_DOMAIN_ID`` of its own (autouse fixture
``ros_domain``): an id whose Fast DDS discovery ports are free, held with a lock file for the
test's duration, so concurrent test runs on one machine never share a graph. Fixtures:

* ``key_file``: the test's own HMAC key file (in tmp_path, mode 0600, made with
  ``feeder_common.auth.ensure_key``); ``ROS_HOME`` points into tmp_path too, so no test reads
  or creates ``~/.ros/feeder/hmac.key``.
* ``graph``: a :class:`feeder_testing.Processes`: ``graph.start(pkg, exe, *args, name=...,
  wrapper=..., key_file=...)`` starts colcon-installed executables as processes with that
  environment; every one is stopped (SIGINT, then SIGTERM, then SIGKILL) when the test ends;
  ``graph.log(proc)`` returns what a process printed. Every driver_node, standin_node,
  monitor_node and feed_node it starts gets ``-p key_file:=<the test's key file>`` (unless
  the test gives a key_file of its own, or ``key_file=None``).
* ``ros``: a :class:`feeder_testing.Probe` (a test node in its own rclpy context):
  ``spin_until(predicate, timeout, what)``, ``wait_matched(sub_or_pub, n)``,
  ``wait_active(node_name)``, ``call(srv_type, name, request)``, ``set_parameters`` /
  ``get_parameters``; a timed-out wait reports the logs of the graph's processes; ``key`` is
  the test's key (for ``feeder_common.messages.check_verdict``).
"""

import os
import subprocess
import sys

from feeder_testing import claim_domain_id, install_env, Probe, Processes, REPO
import pytest

# Before anything in this process calls rclpy.init: discovery stays on this machine.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'

# The executables that sign or check with the HMAC key (parameter key_file).
SIGNING = {('feeder_driver', 'driver_node'), ('feeder_sim', 'standin_node'),
           ('feeder_monitor', 'monitor_node'), ('feeder_monitor', 'feed_node')}


@pytest.fixture(autouse=True)
def ros_domain(monkeypatch, tmp_path):
    """Export a free ROS_DOMAIN_ID and a ROS_HOME of this test (node processes inherit them)."""
    domain, lock = claim_domain_id()
    monkeypatch.setenv('ROS_DOMAIN_ID', str(domain))
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    # Nothing of a test goes to ~/.ros: not the default key file, not the logs.
    monkeypatch.setenv('ROS_HOME', str(tmp_path / 'ros_home'))
    try:
        yield domain
    finally:
        lock.close()


@pytest.fixture(scope='session', autouse=True)
def warm_numba_cache():
    """
    Compile throwmap's kernels once, as the node processes will import them.

    A fresh colcon install has no valid numba cache: the first process compiles for several
    seconds. Doing it here keeps that time out of every test's timeouts.
    """
    code = ('from throwmap import analyse, load_scene\n'
            f'analyse(load_scene({str(REPO / "scenes" / "triangle.yaml")!r}))\n')
    subprocess.run([sys.executable, '-c', code], env=install_env(), check=True, timeout=300)


@pytest.fixture
def key_file(tmp_path):
    """The test's own key file (mode 0600), shared by every node it starts and its checks."""
    from feeder_common import auth
    path = tmp_path / 'keys' / 'hmac.key'
    auth.ensure_key(path)
    return path


class Graph(Processes):
    """Node processes of one test (their logs in tmp_path); all stopped when it ends."""

    def __init__(self, log_dir, key_file=None):
        super().__init__(log_dir)
        self.key_file = key_file

    @staticmethod
    def with_key(pkg, exe, args, key_file):
        """``args`` plus ``-p key_file:=...`` for a node that signs or checks reports."""
        if key_file is None or (pkg, exe) not in SIGNING or \
                any(str(a).startswith('key_file:=') for a in args):
            return list(args)
        args = list(args)
        if '--ros-args' not in args:
            args.append('--ros-args')
        elif '--' in args[args.index('--ros-args'):]:
            # the node's own arguments follow the ROS ones: the parameter goes before them
            end = args.index('--', args.index('--ros-args'))
            return [*args[:end], '-p', f'key_file:={key_file}', *args[end:]]
        return [*args, '-p', f'key_file:={key_file}']

    def start(self, pkg, exe, *args, name=None, wrapper=(), key_file=''):
        """
        Start a node; ``wrapper`` is a command that runs it (e.g. setpriv with options).

        A signing node gets the test's key file; ``key_file``: another one, None: none given.
        """
        args = self.with_key(pkg, exe, args, self.key_file if key_file == '' else key_file)
        return super().start(pkg, exe, *args, name=name, wrapper=wrapper)


@pytest.fixture
def graph(tmp_path, key_file):
    g = Graph(tmp_path, key_file)
    try:
        yield g
    finally:
        g.stop_all()


@pytest.fixture
def ros(ros_domain, key_file, graph):
    """The test's node; its timed-out waits show what the graph's processes logged."""
    from feeder_common import auth
    node = Probe('feeder_test', procs=graph)
    node.key = auth.load_key(key_file)
    try:
        yield node
    finally:
        node.close()
