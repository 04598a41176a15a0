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

Every test in tests/ runs with ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and a
``ROS_DOMAIN_ID`` of its own (autouse fixture ``ros_domain``): an id whose Fast DDS discovery
ports are free, held with a lock file for the test's duration, so concurrent test runs on one
machine never share a graph. Fixtures for the tests:

* ``key_file``: the test's own HMAC key file (in tmp_path, mode 0600, made with
  ``feeder_common.auth.ensure_key``); ``ROS_HOME`` points into tmp_path too, so no test reads
  or creates ``~/.ros/feeder/hmac.key``.
* ``graph``: starts colcon-installed executables (ros2_ws/install/<pkg>/lib/<pkg>/<exe>) as
  processes with that environment; every one is stopped (SIGINT, then SIGTERM, then SIGKILL)
  when the test ends; ``graph.log(proc)`` returns what a process printed. Every driver_node,
  standin_node and monitor_node it starts gets ``-p key_file:=<the test's key file>`` (unless
  the test gives a key_file of its own, or ``key_file=None``).
* ``ros``: a test node in its own rclpy context, with ``spin_until(predicate, timeout)``,
  ``call(srv_type, name, request)`` and ``set_parameters(node_name, {name: value})``; ``key``
  is the test's key (for ``feeder_common.messages.check_verdict``).
"""

import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

REPO = pathlib.Path(__file__).resolve().parents[1]
INSTALL = REPO / 'ros2_ws' / 'install'

# Before anything in this process calls rclpy.init: discovery stays on this machine.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'

# The domain picker and the process environment are feeder_testing's (beside this file; one
# implementation for the tests, the demo and the benchmarks).
from feeder_testing import claim_domain_id, install_env  # noqa: E402, I100, I202


# The executables that sign or check with the HMAC key (parameter key_file).
SIGNING = {('feeder_driver', 'driver_node'), ('feeder_sim', 'standin_node'),
           ('feeder_monitor', 'monitor_node')}


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


def _process_env():
    """Return this environment plus the colcon install (PYTHONPATH, AMENT_PREFIX_PATH)."""
    return install_env(INSTALL)


@pytest.fixture(scope='session', autouse=True)
def warm_numba_cache():
    """
    Compile throwmap's kernels once, as the node processes will import them.

    A fresh colcon install has no valid numba cache: the first process compiles for several
    seconds. Doing it here keeps that time out of every test's timeouts.
    """
    code = ('from throwmap import analyse, load_scene\n'
            f'analyse(load_scene({str(REPO / "scenes" / "triangle.yaml")!r}))\n')
    subprocess.run([sys.executable, '-c', code], env=_process_env(), check=True, timeout=300)


@pytest.fixture
def key_file(tmp_path):
    """The test's own key file (mode 0600), shared by every node it starts and its checks."""
    from feeder_common import auth
    path = tmp_path / 'keys' / 'hmac.key'
    auth.ensure_key(path)
    return path


class Graph:
    """Node processes of one test; all of them are stopped at the end of the test."""

    def __init__(self, log_dir, key_file=None):
        self.log_dir = pathlib.Path(log_dir)
        self.key_file = key_file
        self.procs = []
        self._logs = {}

    @staticmethod
    def executable(pkg, exe):
        path = INSTALL / pkg / 'lib' / pkg / exe
        if not path.exists():
            pytest.fail(f'{path} is missing: build the workspace first (. scripts/setup.sh)')
        return path

    def with_key(self, pkg, exe, args, key_file):
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
        name = name or exe
        log_path = self.log_dir / f'{name}-{len(self.procs)}.log'
        log = open(log_path, 'w')
        proc = subprocess.Popen([*wrapper, str(self.executable(pkg, exe)), *map(str, args)],
                                stdout=log,
                                stderr=subprocess.STDOUT, env=_process_env(), cwd=REPO,
                                start_new_session=True)
        log.close()
        self._logs[proc.pid] = log_path
        self.procs.append(proc)
        return proc

    def log(self, proc):
        return self._logs[proc.pid].read_text(errors='replace')

    def stop(self, proc, timeout=10.0):
        """SIGINT, then SIGTERM, then SIGKILL; returns the exit code."""
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
            if proc.poll() is not None:
                break
            proc.send_signal(sig)
            try:
                proc.wait(timeout=timeout if sig != signal.SIGKILL else None)
            except subprocess.TimeoutExpired:
                continue
        return proc.returncode

    def stop_all(self):
        for proc in reversed(self.procs):
            self.stop(proc, timeout=5.0)


@pytest.fixture
def graph(tmp_path, key_file):
    g = Graph(tmp_path, key_file)
    try:
        yield g
    finally:
        g.stop_all()


class RosTestNode:
    """A node of the test's own, in its own context, spun by hand."""

    def __init__(self, name='feeder_test'):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        self.rclpy = rclpy
        self.context = rclpy.context.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def spin_for(self, seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=min(0.05, max(0.0, end - time.monotonic())))

    def spin_until(self, predicate, timeout, what='condition'):
        end = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > end:
                raise AssertionError(f'timed out after {timeout} s waiting for {what}')
            self.executor.spin_once(timeout_sec=0.05)

    def call(self, srv_type, name, request, timeout=10.0):
        client = self.node.create_client(srv_type, name)
        try:
            self.spin_until(client.service_is_ready, timeout, f'service {name}')
            future = client.call_async(request)
            self.spin_until(future.done, timeout, f'answer of {name}')
            return future.result()
        finally:
            self.node.destroy_client(client)

    def set_parameters(self, node_name, values, timeout=10.0):
        """Set parameters of a remote node; returns {name: SetParametersResult}."""
        from rcl_interfaces.srv import SetParameters
        from rclpy.parameter import Parameter
        req = SetParameters.Request(parameters=[Parameter(k, value=v).to_parameter_msg()
                                                for k, v in values.items()])
        res = self.call(SetParameters, f'{node_name}/set_parameters', req, timeout)
        return dict(zip(values, res.results))

    def get_parameters(self, node_name, names, timeout=10.0):
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python
        res = self.call(GetParameters, f'{node_name}/get_parameters',
                        GetParameters.Request(names=list(names)), timeout)
        return {n: parameter_value_to_python(v) for n, v in zip(names, res.values)}

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.shutdown(context=self.context)


@pytest.fixture
def ros(ros_domain, key_file):
    from feeder_common import auth
    node = RosTestNode()
    node.key = auth.load_key(key_file)
    try:
        yield node
    finally:
        node.close()
