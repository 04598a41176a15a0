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
The run helper of every feeder node's ``main``, and the base of its lifecycle nodes.

:func:`run_node` owns the process: it handles SIGINT and SIGTERM itself (rclpy's handlers
would shut the context down under a running callback, which then fails to publish), spins the
node until a signal, a lifecycle shutdown or the node's own :meth:`finished`, then shuts the
node down in order - lifecycle shutdown transition (a driver aborts its cycle and reports it),
``destroy_node`` (the node leaves the graph at once), context shutdown - and returns 0. A bad
start-up parameter or a :class:`StartupError` prints one line ``<prog>: error: <reason>`` and
ends the process with status 2 itself (``os._exit``: see :func:`run_node`).
"""

import ctypes
import faulthandler
import gc
import os
import signal
import socket
import sys
import threading
import time

import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn
from rclpy.signals import SignalHandlerOptions

from .parameters import ParameterError
from .realtime import RealtimeError, set_realtime_priority

# The executor every node spins in (bench/graph_bench.py compares them; the environment
# variable FEEDER_EXECUTOR=single|events overrides it, for such comparisons).
DEFAULT_EXECUTOR = 'events'


# The longest wait of one spin_once: a wake-up (signal, work) ends it earlier.
SPIN_TIMEOUT = 1.0
# The middleware's teardown (rclpy shutdown, the DDS participant) takes milliseconds; once a
# fresh-clone CI run beside another saw a node that had printed its start-up error still
# running 60 s later. After this long the process ends anyway, with the status it had and the
# stacks of its threads on stderr (to find where it hung).
TEARDOWN_TIMEOUT = 10.0
# A node that ends itself (a lifecycle shutdown) has just handed its last answer, that of
# change_state, to DDS; it spins this long before its participant goes, so that the answer is
# delivered (once, beside a loaded machine, a caller never got it though the node exited 0).
FINISH_LINGER = 0.5


class StartupError(Exception):
    """The node cannot run (e.g. the scene's analysis fails); the text says why and the fix."""


NO_CLOCK = ("use_sim_time is true and no /clock has arrived: the node's time stands at 0 and "
            'its timers (cycling, diagnostics, joint_states) do not fire; publish /clock (a '
            'simulator, ros2 bag play --clock) or set use_sim_time:=false')
CLOCK_GRACE_S = 2.0     # wall-clock s after start-up before a missing /clock is reported


def waiting_for_clock(node):
    """Whether ``node`` runs on simulated time that has not started (no /clock yet)."""
    return bool(node.get_parameter('use_sim_time').value) and \
        node.get_clock().now().nanoseconds == 0


def watch_clock(node, grace_s=CLOCK_GRACE_S):
    """Warn once if ``use_sim_time`` is on and no /clock came within ``grace_s`` s (wall)."""
    timer = []

    def check():
        node.destroy_timer(timer[0])
        if waiting_for_clock(node):
            node.get_logger().warning(NO_CLOCK)

    timer.append(node.create_timer(grace_s, check, clock=Clock(clock_type=ClockType.STEADY_TIME)))


def clock_note(node):
    """Return a note for a reply that starts timed work: '' or why nothing will happen."""
    return f' (warning: {NO_CLOCK})' if waiting_for_clock(node) else ''


class FeederLifecycleNode(LifecycleNode):
    """
    A lifecycle node that tells its state and when its process should end.

    ``configure_error`` is the reason a configure failed (the run helper prints it);
    ``exit_reason`` is why the process is stopping (e.g. ``interrupted (SIGTERM)``), set before
    the shutdown transition so that ``on_shutdown`` can report it.
    """

    def __init__(self, node_name, **kwargs):
        self.configure_error = None
        self.exit_reason = None
        super().__init__(node_name, **kwargs)
        watch_clock(self)

    @property
    def lifecycle_state(self):
        """Label of the current state: unconfigured, inactive, active, finalized, ..."""
        # rclpy has no public accessor; its own trigger_shutdown reads the state this way.
        return self._state_machine.current_state[1]

    def finished(self):
        """Why the process should end now (a lifecycle shutdown happened), or None."""
        return 'lifecycle shutdown' if self.lifecycle_state == 'finalized' else None


def make_executor(kind=None, context=None):
    """
    Return the executor named ``kind`` (``events`` or ``single``).

    Default: FEEDER_EXECUTOR, else :data:`DEFAULT_EXECUTOR`. The events executor of rclpy 9.1
    supports no guard conditions (a thread that must wake the node hands the executor a task:
    ``node.executor.create_task(callback)``, thread-safe in both) and cannot pass a
    MessageInfo to a callback: a node that needs one names ``single`` in its ``executor_kind``
    attribute (the run helper passes it here).
    """
    kind = kind or os.environ.get('FEEDER_EXECUTOR') or DEFAULT_EXECUTOR
    if kind == 'events':
        from rclpy.experimental import EventsExecutor
        return EventsExecutor(context=context)
    if kind == 'single':
        return SingleThreadedExecutor(context=context)
    raise ValueError(f'FEEDER_EXECUTOR={kind!r}: use events or single')


class _SignalWake:
    """
    Wake the executor when a signal arrives.

    Python runs a signal handler only between bytecodes, and the executor waits in C: the
    signal's byte on the wakeup fd lets a thread hand the executor an empty task (thread-safe in
    both executors; the events executor supports no guard conditions), so the wait ends at once
    and the handler runs.
    """

    def __init__(self, executor):
        self._executor = executor
        self._rsock, self._wsock = socket.socketpair()
        self._wsock.setblocking(False)
        self._previous = signal.set_wakeup_fd(self._wsock.fileno(), warn_on_full_buffer=False)
        self._thread = threading.Thread(target=self._run, name='feeder-signal-wake', daemon=True)
        self._thread.start()

    def _run(self):
        while True:
            try:
                if not self._rsock.recv(64):
                    return
                self._executor.create_task(_nothing)
            except Exception:   # noqa: B902 - socket closed or the executor gone: done
                return

    def close(self):
        signal.set_wakeup_fd(self._previous)
        self._wsock.close()         # the reader sees the end of the stream and returns
        self._thread.join(timeout=1.0)
        self._rsock.close()


def _nothing():
    pass


# How long a node that stops waits for its last messages to be acknowledged.
FLUSH_TIMEOUT_S = 0.5


class RateTimer:
    """A node's timer at a rate that can change at run time (rate 0: no timer)."""

    def __init__(self, node, callback):
        self._node = node
        self._callback = callback
        self._timer = None

    def start(self, rate_hz):
        """(Re)start at ``rate_hz`` calls per second; 0 stops it."""
        self.stop()
        if rate_hz > 0:
            self._timer = self._node.create_timer(1.0 / rate_hz, self._callback)

    def stop(self):
        if self._timer is not None:
            self._node.destroy_timer(self._timer)
            self._timer = None


def publish(publisher, msg, logger):
    """
    Publish ``msg``; True if the middleware took it, else log why (throttled) and return False.

    A reliable writer may refuse a write: rclpy raises RCLError ("cannot publish data") when
    its history stays full of samples a stalled or slow reader has not acknowledged for the
    writer's max_blocking_time (100 ms); a write after the context's shutdown raises too. That
    is no bug of this node, so it must not end the node (a callback's exception does). What is
    lost shows to the readers: a gap in the cycle reports' seq, an edge1_ready that grows
    older than its deadline.
    """
    try:
        publisher.publish(msg)
        return True
    except (_rclpy.RCLError, _rclpy.InvalidHandle) as exc:
        logger.error(f'could not publish on {publisher.topic_name}: {exc}',
                     throttle_duration_sec=5.0)
        return False


def flush(publisher, timeout=FLUSH_TIMEOUT_S):
    """
    Wait until every reliable reader acknowledged ``publisher``'s messages (at most ``timeout``).

    A node that publishes on its way out (the driver's aborted cycle, the monitor's final false)
    calls it before destroying the publisher: DDS drops what a destroyed writer has not
    delivered. True if all were acknowledged.
    """
    from rclpy.duration import Duration
    try:
        return publisher.wait_for_all_acked(Duration(seconds=timeout))
    except Exception:   # noqa: B902 - publisher or context already gone: nothing to wait for
        return False


def _shutdown_transition(node, reason):
    """Tell the node why it stops; run the shutdown transition of a lifecycle node."""
    if hasattr(node, 'exit_reason') and not node.exit_reason:
        node.exit_reason = reason
    if not isinstance(node, LifecycleNode):
        return
    if isinstance(node, FeederLifecycleNode) and \
            node.lifecycle_state not in ('unconfigured', 'inactive', 'active'):
        return
    try:
        node.trigger_shutdown()
    except Exception as exc:    # noqa: B902 - report and go on tearing down
        print(f'{node.get_name()}: shutdown transition failed: {exc!r}', file=sys.stderr)


def autostart(node):
    """Configure and activate a lifecycle node whose ``autostart`` parameter is true."""
    if not isinstance(node, LifecycleNode) or not node.has_parameter('autostart') or \
            not node.get_parameter('autostart').value:
        return
    if node.trigger_configure() != TransitionCallbackReturn.SUCCESS:
        raise StartupError(getattr(node, 'configure_error', None) or
                           'configure failed (see the log above)')
    if node.trigger_activate() != TransitionCallbackReturn.SUCCESS:
        raise StartupError('activate failed (see the log above)')


def run_node(make_node, prog, args=None, before_exit=None):
    """
    Run ``make_node(context=...)`` until SIGINT, SIGTERM or its end; the executable's status.

    0 after a clean stop. A bad start-up parameter, a :class:`StartupError` or a failed
    autostart prints one line on stderr and ends the process with status 2 here: this call
    does not return then (the caller's clean-up goes in ``before_exit``, called first). An
    exception from a callback tears the node down and propagates (a bug: exit 1 with its
    traceback). A node that has an ``exit_reason`` attribute gets the reason it stops in it
    (``interrupted (SIGINT)``, or what its own ``finished()`` returned).
    """
    # A fatal signal prints every thread's stack.
    faulthandler.enable(all_threads=True)
    stop = {}

    def on_signal(signum, frame):
        stop.setdefault('reason', f'interrupted ({signal.Signals(signum).name})')

    # The handlers stay until the process ends: a Ctrl-C in a terminal reaches every process
    # of its group and ros2 launch forwards one more, so a second signal may come while the
    # node shuts down or the interpreter exits; it must not turn a clean exit into a crash.
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, on_signal)
    context = Context()
    try:
        with rclpy.init(args=args, context=context,
                        signal_handler_options=SignalHandlerOptions.NO):
            status = _run(make_node, prog, stop, context, before_exit)
            exit_after(TEARDOWN_TIMEOUT, status, prog)
            return status
    finally:
        # Destroying the context ends the DDS participant, which tells every peer at once
        # that this process left (else they wait for its lease, 20 s, to run out).
        context.destroy()
        # Nothing is left to stop: ignore further signals while the interpreter exits (it
        # resets handlers it runs to the default, which would end the process by the signal).
        for s in (signal.SIGINT, signal.SIGTERM):
            signal.signal(s, signal.SIG_IGN)


def exit_after(seconds, status, prog):
    """
    End the process with ``status`` if it is still running ``seconds`` from now.

    For the teardown that follows a node's end: if it hangs, the threads' stacks go to stderr
    and the process exits (os._exit: no more Python clean-up, which is what hangs).
    """
    def expire():
        print(f'{prog}: teardown took more than {seconds:g} s; exiting with status {status} '
              '(thread stacks follow)', file=sys.stderr, flush=True)
        faulthandler.dump_traceback(file=sys.stderr, all_threads=True)
        os._exit(status)

    timer = threading.Timer(seconds, expire)
    timer.daemon = True
    timer.start()
    # A hang that holds the GIL stops that timer too; faulthandler's own thread does not need
    # it (it exits with status 1).
    faulthandler.dump_traceback_later(2 * seconds, exit=True)
    return timer


def _linger(executor, seconds):
    """Spin ``executor`` for ``seconds``: its callbacks still run."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=min(0.05, max(0.0, end - time.monotonic())))


def _startup_failed(prog, exc, before_exit):
    """Print the start-up error's line and end the process with status 2 at once."""
    print(f'{prog}: error: {exc}', file=sys.stderr, flush=True)
    # Nothing of the half-built node is torn down. That teardown (the middleware's entities
    # and participant, destroyed with the GIL held) hung or died of SIGSEGV in about 1 of 20
    # runs of test_graph_ros_user's bad-parameter test (7 nodes failing at once): in the
    # interpreter's exit, and, once that was skipped, in gc.collect() of the half-built node
    # (faulthandler's stack, 2026-11-27). Peers drop its participant when its lease runs out.
    exit_after(TEARDOWN_TIMEOUT, 2, prog)     # (before_exit is the caller's file I/O)
    if before_exit is not None:
        before_exit()
    sys.stdout.flush()
    sys.stderr.flush()
    ctypes.CDLL(None).fflush(None)     # the C streams (rcutils' log lines) too
    os._exit(2)


def _run(make_node, prog, stop, context, before_exit):
    try:
        node = make_node(context=context)
    except (ParameterError, StartupError) as exc:
        _startup_failed(prog, exc, before_exit)
    wake = None
    executor = None
    try:
        try:
            if node.has_parameter('realtime_priority'):
                set_realtime_priority(node.get_parameter('realtime_priority').value)
            autostart(node)
        except (StartupError, RealtimeError) as exc:
            _startup_failed(prog, exc, before_exit)
        executor = make_executor(getattr(node, 'executor_kind', None), context)
        executor.add_node(node)
        wake = _SignalWake(executor)
        # Start-up objects (numba, throwmap's analysis) never die: keep them out of the
        # garbage collector's way, so that a collection cannot stall a cycle.
        gc.freeze()
        finished = getattr(node, 'finished', lambda: None)
        while 'reason' not in stop:
            reason = finished()
            if reason:
                stop['reason'] = reason
                _linger(executor, FINISH_LINGER)
                break
            # (The events executor's spin_once without a timeout does not wait: it spins.)
            executor.spin_once(timeout_sec=SPIN_TIMEOUT)
        return 0
    finally:
        _shutdown_transition(node, stop.get('reason', 'stopped'))
        if wake is not None:
            wake.close()
        if executor is not None:
            executor.remove_node(node)
            executor.shutdown()
        node.destroy_node()
        # The frozen start-up objects hold the context's users: let them go.
        gc.unfreeze()
