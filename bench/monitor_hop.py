#!/usr/bin/env python3
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
Where the monitor's hop goes: the monitor in this process, timed around its own calls.

The sim runs as hardware (a process, 100 Hz); the monitor runs in this process with
time.perf_counter_ns() around its callbacks and the calls inside them, so the figures are the
monitor's own work (robust to other load on the machine, unlike a wall-clock p99 across
processes). ``cycle_status entry -> edge1_ready published`` is the part of the hop the
monitor's code adds before ``edge1_ready`` leaves (parsing, the report's MAC check in
``ReportGate.admit``, the rules, the signed ``Verdict``); ``stamp -> ... entry`` is the
cycle's stamp (system clock, set by the sim before it publishes) to the callback's start: sim
work after the stamp, transport and the executor's dispatch. Asserts nothing. Usage (after
``. scripts/setup.sh``):

    python bench/monitor_hop.py [--executor events|single] [--seconds 10]

The sim process, the domain and the probe node that switches the cycling are the harness's
(tests/feeder_testing.py; the one sys.path line below puts tests/ on the path).
"""

import argparse
import functools
import os
import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'tests'))
from feeder_testing import Probe, Processes, REPO, use_domain  # noqa: E402

SCENE = str(REPO / 'scenes' / 'triangle.yaml')


def timed(times, key, fn):
    """Return ``fn`` wrapped to append its duration (ns) to ``times[key]``."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        t0 = time.perf_counter_ns()
        try:
            return fn(*args, **kwargs)
        finally:
            times.setdefault(key, []).append(time.perf_counter_ns() - t0)
    return wrapper


def instrument(times):
    """Wrap the monitor's callbacks and the calls inside them (class attributes)."""
    from feeder_common import messages
    from feeder_monitor import monitor_node, readiness, trust
    mark = {}
    node_cls = monitor_node.MonitorNode
    on_status, on_proximity, publish_ready = (node_cls._on_cycle_status, node_cls._on_proximity,
                                              node_cls._publish_statement)

    def cycle_status(self, msg):
        mark['status'] = t0 = time.perf_counter_ns()
        stamp = messages.parse_cycle_status(msg).stamp_ns
        if stamp is not None:
            times.setdefault('cycle stamp -> cycle_status callback entry',
                             []).append(time.time_ns() - stamp)
        on_status(self, msg)
        times.setdefault('cycle_status callback (whole)', []).append(time.perf_counter_ns() - t0)

    def proximity(self, msg):
        times.setdefault('cycle stamp -> proximity callback entry', []).append(
            time.time_ns() - messages.time_ns(msg.header.stamp))
        t0 = time.perf_counter_ns()
        on_proximity(self, msg)
        times.setdefault('proximity callback (whole)', []).append(time.perf_counter_ns() - t0)

    def ready(self):
        msg = publish_ready(self)
        if 'status' in mark:
            times.setdefault('cycle_status entry -> edge1_ready published', []).append(
                time.perf_counter_ns() - mark.pop('status'))
        return msg

    node_cls._on_cycle_status, node_cls._on_proximity, node_cls._publish_statement = \
        cycle_status, proximity, ready
    trust.ReportGate.admit = timed(times, '  ReportGate.admit (MAC, age, session, seq)',
                                   trust.ReportGate.admit)
    monitor_node.signed_verdict = timed(times, '  signed_verdict',
                                        monitor_node.signed_verdict)
    readiness.ReadinessMonitor.completed = timed(times, '  ReadinessMonitor.completed',
                                                 readiness.ReadinessMonitor.completed)
    monitor_node.parse_cycle_status = timed(times, '  parse_cycle_status',
                                            monitor_node.parse_cycle_status)
    return node_cls


def main():
    """Run the sim, time the monitor in this process, print the table."""
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    ap.add_argument('--executor', choices=('events', 'single'), default=None)
    ap.add_argument('--seconds', type=float, default=10.0)
    ap.add_argument('--period', type=float, default=0.01)
    args = ap.parse_args()
    domain, _lock = use_domain()        # held until the process ends
    import rclpy
    from rclpy.parameter import Parameter
    from feeder_common.node import autostart, make_executor
    times = {}
    node_cls = instrument(times)
    from feeder_common import auth
    procs = Processes(pathlib.Path(tempfile.mkdtemp(prefix='monitor_hop-')), error=SystemExit,
                      prog='monitor_hop')
    key_file = str(procs.log_dir / 'hmac.key')      # the run's own key (mode 0600)
    auth.ensure_key(key_file)
    rclpy.init()
    probe = None
    try:
        procs.start('feeder_sim', 'standin_node', '--ros-args', '-r', '__ns:=/feeder', '-r',
                    '__node:=feeder_driver', '-p',
                    f'scene:={SCENE}', '-p', f'cycle_period:={args.period}',
                    '-p', f'key_file:={key_file}', name='sim')
        executor = make_executor(args.executor)
        node = node_cls(namespace='/feeder',
                        parameter_overrides=[Parameter('scene', value=SCENE),
                                             Parameter('key_file', value=key_file)])
        autostart(node)     # configure + activate (a lifecycle node), as the run helper does
        executor.add_node(node)
        probe = Probe('feeder_monitor_hop', procs=procs, watch=True, error=SystemExit)

        def spin(seconds, until=lambda: False):
            end = time.monotonic() + seconds
            while time.monotonic() < end and not until():
                executor.spin_once(timeout_sec=0.05)

        # The sim's reports matched the monitor here (the sim's own account), the sim is active.
        probe.wait_remote_matched('/feeder/feeder_driver', readers={
            '/feeder/cycle_status': 1, '/feeder/proximity': 1, '/feeder/cycle_fired': 1})
        probe.wait_active('/feeder/feeder_driver')
        probe.enable('/feeder/feeder_driver', True)
        spin(2.0)
        times.clear()
        spin(args.seconds)
    finally:
        if probe is not None:
            probe.close()
        procs.stop_all()
    kind = args.executor or os.environ.get('FEEDER_EXECUTOR', 'default')
    print(f'monitor hop, executor {kind}, {args.seconds:g} s at {1 / args.period:g} Hz '
          f'(load {os.getloadavg()[0]:.2f})')
    for key, xs in times.items():
        xs = sorted(xs)
        print(f'{key:48s} n={len(xs):5d}  p50 {xs[len(xs) // 2] / 1e3:8.1f} us  '
              f'p99 {xs[int(0.99 * (len(xs) - 1))] / 1e3:8.1f} us')


if __name__ == '__main__':
    main()
