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
The one test-and-bench harness of the feeder graph: DDS domains, node processes, a probe node.

It lives with the tests in one module that no package installs (nothing to build or keep in
step with an install; every user already has tests/ on its path). Users: tests/conftest.py
(fixtures ``graph`` and ``ros``), the package tests, scripts/demo_graph.py and bench/*.py.
How each finds it:

* ``python -m pytest`` from the repository root, and ``colcon test`` (which finds the same
  pytest.ini above the package): pytest.ini's ``pythonpath`` puts tests/ and the packages'
  source trees on sys.path; no test or conftest edits sys.path.
* ``python scripts/demo_graph.py``, ``python bench/x.py``: one line at the top of the script,
  ``sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'tests'))``.

What it offers:

* :func:`claim_domain_id` picks a ROS_DOMAIN_ID that no other test or demo process of this
  machine holds (an exclusive ``flock`` on ``<tmp>/feeder-ros-domain-<id>.lock``, released when
  the returned file is closed) and whose Fast DDS discovery ports on loopback are free, so
  parallel runs never share a DDS domain; :func:`reserve_domain_id` holds one for the whole
  process; :func:`use_domain` exports one in this process's environment.
* :func:`dds_env` and :func:`install_env`: environments for child processes (DDS on loopback
  in a given domain; the executables of a colcon install).
* :class:`Processes`: node processes (colcon-installed executables, or any command) started
  with their output in a log file each, checked (:meth:`Processes.check` fails with the dead
  one's log), stopped (SIGINT, SIGTERM, SIGKILL).
* :class:`Probe`: the caller's own node (in a context of its own, spun by hand):
  ``spin_for``, ``spin_until(cond, timeout, what)`` (also fails at once when a watched
  process died), :meth:`Probe.wait_matched` (a reader or writer of this node MATCHED with
  ``n`` remote endpoints: rclpy's ``Subscription.get_publisher_count()`` and
  ``Publisher.get_subscription_count()`` are ``rmw_subscription_count_matched_publishers``
  and ``rmw_publisher_count_matched_subscriptions``, unlike ``Node.count_subscribers``, which
  counts endpoints on the graph that may not have matched yet, so volatile messages sent in
  between go nowhere), :meth:`Probe.wait_remote_matched` (another process's writers or
  readers matched, by that node's own account: the ``<node>: endpoints`` status every feeder
  node ends its /diagnostics with), :meth:`Probe.wait_active` (a lifecycle node answers
  ``~/get_state`` with ``active``: the stand-in analyses its scene in on_configure, before its
  executor answers any service), ``call`` (a timeout that says what it waited for and what the node
  processes logged), ``set_parameters`` / ``get_parameters`` of remote nodes, ``enable``.
* :class:`EmulatorThread`: the controller emulator served from a thread.
"""

import errno
import fcntl
import os
import pathlib
import random
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

REPO = pathlib.Path(__file__).resolve().parents[1]
INSTALL = REPO / 'ros2_ws' / 'install'

_HELD = {}
# Fast DDS well-known ports: PB 7400, DG 250, PG 2; unicast discovery at offset 10 (d1) and
# user traffic at offset 11 (d3) per participant.
_PB, _DG, _PG = 7400, 250, 2


def _ports_free(domain, participants=6):
    for part in range(participants):
        for offset in (10, 11):
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
                try:
                    s.bind(('127.0.0.1', _PB + _DG * domain + offset + _PG * part))
                except OSError as exc:
                    if exc.errno == errno.EADDRINUSE:
                        return False
                    raise
    return True


def claim_domain_id(lo=1, hi=101, exclude=None):
    """
    Claim a free domain id in [lo, hi]: return (id, open lock file); close the file to free it.

    Ids are tried in random order. ``exclude`` (default: this environment's ROS_DOMAIN_ID, the
    interactive shell's own domain) is never returned.
    """
    if exclude is None:
        exclude = {int(os.environ['ROS_DOMAIN_ID'])} \
            if os.environ.get('ROS_DOMAIN_ID', '').isdigit() else set()
    ids = [d for d in range(lo, hi + 1) if d not in exclude]
    random.shuffle(ids)
    for domain in ids:
        path = os.path.join(tempfile.gettempdir(), f'feeder-ros-domain-{domain}.lock')
        fh = open(path, 'w')
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            fh.close()
            continue
        if _ports_free(domain):
            return domain, fh
        fh.close()
    raise RuntimeError(f'no free ROS_DOMAIN_ID in [{lo}, {hi}]: every lock file '
                       f'{tempfile.gettempdir()}/feeder-ros-domain-*.lock is held or its '
                       'ports are in use')


def reserve_domain_id(lo=1, hi=101):
    """Reserve a domain id in [lo, hi] for this process (the same id on repeated calls)."""
    if 'id' not in _HELD:
        _HELD['id'], _HELD['file'] = claim_domain_id(lo, hi)
    return _HELD['id']


def dds_env(domain_id, base=None):
    """Environment for child processes: DDS on loopback, the given domain."""
    env = dict(os.environ if base is None else base)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env['ROS_DOMAIN_ID'] = str(domain_id)
    env.pop('ROS_LOCALHOST_ONLY', None)
    env.pop('ROS_STATIC_PEERS', None)
    return env


def install_env(install=INSTALL, base=None):
    """
    Environment for the executables of the colcon install ``install`` (e.g. ros2_ws/install).

    Its packages' site-packages go first on PYTHONPATH, their prefixes, then this Python's
    (the venv with the ROS wheels), on AMENT_PREFIX_PATH, and the ``lib`` folders of those that
    have shared libraries (feeder_interfaces' typesupports) on LD_LIBRARY_PATH, as colcon's
    setup scripts do; output unbuffered and uncoloured.
    """
    env = dict(os.environ if base is None else base)
    install = pathlib.Path(install)
    site = f'lib/python{sys.version_info.major}.{sys.version_info.minor}/site-packages'
    pkgs = sorted(p for p in install.iterdir() if p.is_dir()) if install.is_dir() else []
    paths = [str(p / site) for p in pkgs if (p / site).is_dir()]
    env['PYTHONPATH'] = os.pathsep.join(paths + [env.get('PYTHONPATH', '')]).strip(os.pathsep)
    prefixes = [str(p) for p in pkgs] + [sys.prefix]
    env['AMENT_PREFIX_PATH'] = os.pathsep.join(
        prefixes + [env.get('AMENT_PREFIX_PATH', '')]).strip(os.pathsep)
    libs = [str(p / 'lib') for p in pkgs if any((p / 'lib').glob('lib*.so'))]
    env['LD_LIBRARY_PATH'] = os.pathsep.join(
        libs + [env.get('LD_LIBRARY_PATH', '')]).strip(os.pathsep)
    env['PYTHONUNBUFFERED'] = '1'
    env['RCUTILS_COLORIZED_OUTPUT'] = '0'
    return env


def use_domain(keep_given=False):
    """
    Export a domain of this process's own: ``(id, lock file or None)``; close the file at the end.

    ``keep_given``: use ROS_DOMAIN_ID from the environment if one is set (the demo: the caller's
    shell then sees the graph); otherwise a free one is claimed. DDS stays on loopback.
    """
    given = os.environ.get('ROS_DOMAIN_ID', '').strip() if keep_given else ''
    if given:
        if not given.isdigit() or not 0 <= int(given) <= 232:
            raise SystemExit(f'ROS_DOMAIN_ID={given!r} is not a domain id (0..232; 0..101 keeps '
                             'Fast DDS ports valid everywhere)')
        domain, lock = int(given), None
    else:
        domain, lock = claim_domain_id()
    os.environ['ROS_DOMAIN_ID'] = str(domain)
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.pop('ROS_LOCALHOST_ONLY', None)
    return domain, lock


STARTUP_TIMEOUT = 90.0      # a process's discovery, numba and scene analysis, under load


class ProcessError(AssertionError):
    """A node process is missing or died, or a wait timed out (the message has the logs)."""


class Processes:
    """
    Node processes of one test, demo or benchmark, each with its output in a log file.

    ``start(pkg, exe, *args, name=..., wrapper=...)`` runs a colcon-installed executable
    (``<install>/<pkg>/lib/<pkg>/<exe>``; ``wrapper``: a command that runs it, e.g. setpriv);
    ``command(argv, name)`` any other. The environment is ``install_env(install, env)``
    (``env``: a base environment, default this process's at each start, so the domain a test
    exported is the nodes' too); the log is ``<log_dir>/<name>.log``. ``error`` is the
    exception raised when something is wrong: ProcessError (an AssertionError) for tests,
    SystemExit for scripts.
    """

    def __init__(self, log_dir, install=INSTALL, env=None, error=ProcessError, prog=''):
        self.log_dir = pathlib.Path(log_dir)
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.install = pathlib.Path(install)
        self.env = env
        self.error = error
        self.prog = f'{prog}: ' if prog else ''
        self.procs = {}         # name -> Popen, in start order
        self._logs = {}         # pid -> log path
        self._names = {}        # pid -> name
        self._stopped = set()   # pids stopped on purpose

    def executable(self, pkg, exe):
        path = self.install / pkg / 'lib' / pkg / exe
        if not path.exists():
            raise self.error(f'{self.prog}{path} is missing: build the workspace first '
                             '(. scripts/setup.sh)')
        return path

    def start(self, pkg, exe, *args, name=None, wrapper=()):
        """Start an installed executable; returns its Popen."""
        return self.command([*wrapper, self.executable(pkg, exe), *args], name or exe)

    def command(self, argv, name, env=None):
        """Start any command (``env``: instead of the install's environment)."""
        if name in self.procs:
            name = f'{name}-{len(self.procs)}'
        log_path = self.log_dir / f'{name}.log'
        with open(log_path, 'w') as log:
            proc = subprocess.Popen([str(a) for a in argv], stdout=log,
                                    stderr=subprocess.STDOUT,
                                    env=env or install_env(self.install, self.env), cwd=REPO,
                                    start_new_session=True)
        self.procs[name] = proc
        self._logs[proc.pid] = log_path
        self._names[proc.pid] = name
        return proc

    def _proc(self, proc_or_name):
        return self.procs[proc_or_name] if isinstance(proc_or_name, str) else proc_or_name

    def log(self, proc_or_name):
        """Return everything the process printed so far."""
        return self._logs[self._proc(proc_or_name).pid].read_text(errors='replace')

    def report(self, lines=12):
        """Each process's state and the last ``lines`` lines of its log (for error messages)."""
        out = []
        for name, proc in self.procs.items():
            rc = proc.poll()
            tail = self.log(proc).rstrip().splitlines()[-lines:]
            state = 'running' if rc is None else f'exited {rc}'
            out.append(f'--- {name} (pid {proc.pid}, {state}), {self._logs[proc.pid]}:\n' +
                       '\n'.join(f'    {t}' for t in tail))
        return '\n'.join(out)

    def check(self):
        """Raise ``error`` with the log if a process exited that nobody stopped."""
        for name, proc in self.procs.items():
            if proc.pid not in self._stopped and proc.poll() is not None:
                raise self.error(f'{self.prog}{name} exited ({proc.returncode}):\n'
                                 f'{self.log(proc)[-3000:]}')

    def stop(self, proc_or_name, timeout=10.0):
        """SIGINT, then SIGTERM, then SIGKILL; returns the exit code."""
        proc = self._proc(proc_or_name)
        self._stopped.add(proc.pid)
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
            if proc.poll() is not None:
                break
            proc.send_signal(sig)
            try:
                proc.wait(timeout=timeout if sig != signal.SIGKILL else None)
            except subprocess.TimeoutExpired:
                continue
        return proc.returncode

    def stop_all(self, timeout=5.0):
        for proc in reversed(list(self.procs.values())):
            self.stop(proc, timeout)


class Probe:
    """
    The caller's own node, in an rclpy context of its own, spun by hand.

    ``procs``: the :class:`Processes` whose logs a timed-out wait reports; ``watch``: moreover
    fail at once when one of them died (scripts; a test may kill nodes on purpose).
    """

    def __init__(self, name='feeder_probe', procs=None, watch=False, error=ProcessError):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        self.rclpy = rclpy
        self.procs, self.watch, self.error = procs, watch, error
        self.context = rclpy.context.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def spin_for(self, seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=min(0.05, max(0.0, end - time.monotonic())))

    def failure(self, message):
        """``message`` and what the node processes logged."""
        if self.procs is not None and self.procs.procs:
            message = f'{message}\nthe node processes:\n{self.procs.report()}'
        return self.error(message)

    def spin_until(self, predicate, timeout, what='condition'):
        """Spin until ``predicate()``; fail after ``timeout`` s naming ``what`` (or what())."""
        end = time.monotonic() + timeout
        while not predicate():
            if self.watch and self.procs is not None:
                self.procs.check()
            if time.monotonic() > end:
                what = what() if callable(what) else what
                raise self.failure(f'timed out after {timeout} s waiting for {what}')
            self.executor.spin_once(timeout_sec=0.05)

    def wait_matched(self, endpoint, n=1, timeout=STARTUP_TIMEOUT, what=None):
        """
        Wait until a subscription (publisher) of this node matched ``n`` writers (readers).

        Matched, not merely on the graph: only then does a volatile message reach its reader.
        """
        if hasattr(endpoint, 'get_publisher_count'):
            count, kind = endpoint.get_publisher_count, 'writers'
        else:
            count, kind = endpoint.get_subscription_count, 'readers'
        self.spin_until(lambda: count() >= n, timeout,
                        what or f'{n} {kind} matched with our {endpoint.topic_name}')

    def _endpoint_reports(self):
        """{status name: {key: value}} of the latest ``<node>: endpoints`` statuses."""
        if getattr(self, '_endpoints', None) is None:
            from diagnostic_msgs.msg import DiagnosticArray
            from rclpy.qos import QoSProfile, ReliabilityPolicy
            self._endpoints = {}

            def on_diagnostics(msg):
                for st in msg.status:
                    if st.name.endswith(': endpoints'):
                        self._endpoints[st.name] = {kv.key: kv.value for kv in st.values}

            self._endpoints_sub = self.node.create_subscription(
                DiagnosticArray, '/diagnostics', on_diagnostics,
                QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
        return self._endpoints

    def remote_matched(self, node_name, role, topic):
        """What the node ``node_name`` last said its writers (readers) of ``topic`` matched."""
        from feeder_common.diagnostics import status_prefix
        ns, _, name = node_name.rpartition('/')
        report = self._endpoint_reports().get(f'{status_prefix(ns or "/", name)}: endpoints')
        return None if report is None else int(report.get(f'matched {role} of {topic}', 0))

    def wait_remote_matched(self, node_name, readers=None, writers=None,
                            timeout=STARTUP_TIMEOUT):
        """
        Wait until a feeder node reports its writers (readers) of topics matched enough peers.

        ``readers``: {topic: n}, the node's writer of ``topic`` has matched at least ``n``
        readers (the one condition under which its volatile messages reach them all);
        ``writers``: {topic: n} for its readers. From the node's ``<node>: endpoints`` status
        on /diagnostics (feeder_common.diagnostics; every update, 1 s by default).
        """
        want = [('readers', t, n) for t, n in (readers or {}).items()] + \
            [('writers', t, n) for t, n in (writers or {}).items()]
        self._endpoint_reports()

        def matched():
            return all((self.remote_matched(node_name, role, t) or 0) >= n
                       for role, t, n in want)

        def what():
            return ', '.join(f'{n} {role} of {t} (it reported '
                             f'{self.remote_matched(node_name, role, t)})'
                             for role, t, n in want)

        self.spin_until(matched, timeout, lambda: f'{node_name} to match {what()}')

    def call(self, srv_type, name, request, timeout=10.0, what=None,
             startup_timeout=STARTUP_TIMEOUT):
        """
        Call a service; fail if it gives no answer within ``timeout`` s.

        The server may take ``startup_timeout`` s to appear (a process starting under load).
        The service of a lifecycle node (one that offers ``<node>/get_state``) is called once
        that node answers get_state (up to ``startup_timeout``): a starting node configures
        (the stand-in analyses its scene, seconds under load) before its executor answers any
        service. The failure says what it waited for and what the node processes logged.
        """
        client = self.node.create_client(srv_type, name)
        try:
            self.spin_until(client.service_is_ready, max(timeout, startup_timeout),
                            what or f'service {name}')
            owner = name.rsplit('/', 1)[0]
            if name.startswith('/') and not name.endswith('/get_state') and owner and \
                    self.is_lifecycle(owner):
                self.lifecycle_state(owner, startup_timeout)
            future = client.call_async(request)
            self.spin_until(future.done, timeout, what or f'the answer of {name}')
            return future.result()
        finally:
            self.node.destroy_client(client)

    def is_lifecycle(self, node_name):
        """Whether the graph shows a lifecycle node ``node_name`` (its ~/get_state service)."""
        return any(n == f'{node_name}/get_state'
                   for n, _ in self.node.get_service_names_and_types())

    def lifecycle_state(self, node_name, timeout=STARTUP_TIMEOUT, attempt_s=5.0):
        """
        The label of a lifecycle node's state (its ~/get_state: answered once it spins).

        Asked again every ``attempt_s`` (get_state changes nothing): a request that went only
        to a killed predecessor still on the graph, or before the response path matched, is
        never answered.
        """
        from lifecycle_msgs.srv import GetState
        name = f'{node_name}/get_state'
        what = (f'{node_name} to answer ~/get_state (it configures and activates before it '
                'answers any service)')
        client = self.node.create_client(GetState, name)
        try:
            self.spin_until(client.service_is_ready, timeout, what)
            end = time.monotonic() + timeout
            while True:
                future = client.call_async(GetState.Request())
                attempt_end = min(end, time.monotonic() + attempt_s)
                self.spin_until(lambda: future.done() or time.monotonic() > attempt_end,
                                timeout + attempt_s, what)
                if future.done():
                    return future.result().current_state.label
                client.remove_pending_request(future)
                if time.monotonic() > end:
                    raise self.failure(f'timed out after {timeout} s waiting for {what}')
        finally:
            self.node.destroy_client(client)

    def wait_active(self, node_name, timeout=STARTUP_TIMEOUT):
        """Wait until the lifecycle node ``node_name`` is active (before calling its services)."""
        end = time.monotonic() + timeout
        while True:
            state = self.lifecycle_state(node_name, max(0.5, end - time.monotonic()))
            if state == 'active':
                return
            if time.monotonic() > end:
                raise self.failure(f'{node_name} is {state}, not active, after {timeout} s')
            self.spin_for(0.1)

    def enable(self, node_name, on, timeout=10.0):
        """Switch the cycling of a driver (or the stand-in) on or off: its ~/enable."""
        from std_srvs.srv import SetBool
        res = self.call(SetBool, f'{node_name}/enable', SetBool.Request(data=on), timeout)
        if not res.success:
            raise self.failure(f'{node_name}/enable {on} refused: {res.message}')
        return res

    def set_parameters(self, node_name, values, timeout=10.0):
        """Set parameters of a remote node; returns {name: SetParametersResult}."""
        from rcl_interfaces.srv import SetParameters
        from rclpy.parameter import Parameter
        req = SetParameters.Request(parameters=[Parameter(k, value=v).to_parameter_msg()
                                                for k, v in values.items()])
        res = self.call(SetParameters, f'{node_name}/set_parameters', req, timeout)
        return dict(zip(values, res.results))

    def get_parameters(self, node_name, names, timeout=10.0):
        """Return {name: value} of a remote node's parameters."""
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python
        res = self.call(GetParameters, f'{node_name}/get_parameters',
                        GetParameters.Request(names=list(names)), timeout)
        return {n: parameter_value_to_python(v) for n, v in zip(names, res.values)}

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.shutdown(context=self.context)


class EmulatorThread:
    """A :class:`feeder_driver.emulator.Controller` served from a background thread."""

    def __init__(self, scene, link, **kwargs):
        from feeder_driver.emulator import from_scene
        self.controller = from_scene(scene, link=link, **kwargs)
        self._thread = threading.Thread(target=self.controller.run, name='feeder-emulator',
                                        daemon=True)

    @property
    def records(self):
        return [r for r in self.controller.records if r.get('type') == 'fire']

    def start(self):
        self.controller.start()
        self._thread.start()
        return self

    def stop(self):
        self.controller.stop()
        self._thread.join(timeout=5)
        self.controller.close()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()
