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
Benchmarks of the sim and the monitor as processes on loopback DDS (prints a table).

1. Latency from a ``proximity`` message to the monitor's ``edge1_ready`` for the same cycle,
   over many cycles (sim as hardware + monitor). Times are the DDS source timestamp of the
   proximity message (when the sim published it) and the receive timestamps at a probe node
   (rmw ``MessageInfo``, system clock), so the probe's own executor adds nothing.
2. Cycles per second the sim sustains at ``cycle_period`` 0.005 s (its minimum), alone and
   with the whole graph listening (monitor, predictor, bag recorder).
3. CPU of each node process at 1 Hz cycling, from /proc/<pid>/stat (utime + stime) over a
   window, in % of one core.

Asserts nothing. Usage (after ``. scripts/setup.sh``):

    python bench/graph_bench.py [--latency-cycles 1000] [--rate-seconds 5] [--cpu-seconds 20]

The processes, the domain and the probe node are the harness's (tests/feeder_testing.py; the
one sys.path line below puts tests/ on the path). The benchmark's own nodes wait on matched
endpoints before cycling, as the tests do.
"""

import argparse
import bisect
import os
import pathlib
import shutil
import statistics
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'tests'))
import feeder_testing  # noqa: E402
from feeder_testing import Probe as HarnessProbe, Processes, REPO, use_domain  # noqa: E402

SCENE = str(REPO / 'scenes' / 'triangle.yaml')
CLK_TCK = os.sysconf('SC_CLK_TCK')


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(q / 100 * (len(xs) - 1))))]


def cpu_seconds(pid):
    """User + system CPU time of a process so far, s (fields 14 and 15 of /proc/pid/stat)."""
    with open(f'/proc/{pid}/stat') as fh:
        fields = fh.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK


def _seq(msg):
    """Return the seq of a cycle_status (feeder_interfaces/CycleStatus)."""
    return int(msg.seq)


def _ready_of(readies, verdict_info):
    """The last edge1_ready the monitor sent before (or with) this verdict."""
    sent = [r['source_timestamp'] for r in readies]
    k = bisect.bisect_right(sent, verdict_info['source_timestamp']) - 1
    return readies[k] if k >= 0 else None


class BenchNode(HarnessProbe):
    """A benchmark's own node (the harness's Probe): fails with SystemExit, watches ``procs``."""

    prog = 'graph_bench'

    def __init__(self, name, procs=None):
        super().__init__(name, procs=procs, watch=procs is not None, error=SystemExit)

    def enable(self, on, node_name='/feeder/feeder_driver'):
        """Switch the cycling of the stand-in on or off (once it is active)."""
        if on:
            self.wait_active(node_name)
        return super().enable(node_name, on)


class Probe(BenchNode):
    """The benchmark's node: subscriptions with receive timestamps, service calls."""

    def __init__(self, procs=None):
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from feeder_interfaces.msg import CycleStatus, Verdict
        from sensor_msgs.msg import Range
        super().__init__('feeder_bench', procs)
        reliable = QoSProfile(depth=5000, reliability=ReliabilityPolicy.RELIABLE)
        latched = QoSProfile(depth=5000, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.prox, self.ready, self.status, self.verdicts = [], [], [], []
        self.subs = {
            'proximity': self.node.create_subscription(
                Range, '/feeder/proximity', lambda m, i: self.prox.append(i), reliable),
            'edge1_ready': self.node.create_subscription(
                Verdict, '/feeder/edge1_ready', lambda m, i: self.ready.append(i), latched),
            'cycle_status': self.node.create_subscription(
                CycleStatus, '/feeder/cycle_status',
                lambda m, i: self.status.append((_seq(m), i)), reliable)}
        # The monitor publishes edge1_ready, then the cycle's edge1_verdict (the same signed
        # Verdict, with its seq); it also republishes edge1_ready while idle (and lowers it when
        # a cycle fires), so cycles are matched through the verdicts.
        self.subs['edge1_verdict'] = self.node.create_subscription(
            Verdict, '/feeder/edge1_verdict', lambda m, i: self.verdicts.append((m.seq, i)),
            reliable)

    def clear(self):
        self.prox.clear()
        self.ready.clear()
        self.status.clear()
        self.verdicts.clear()


# SCHED_FIFO priority of the sim, monitor and predictor (--realtime-priority; 0: normal)
REALTIME_PRIORITY = 0
# ... and of the probe and the baseline's echo (--probe-realtime)
PROBE_PRIORITY = 0


def probe_realtime():
    """
    Run this process's threads at PROBE_PRIORITY, once its node exists.

    rmw creates the DDS participant and its threads with the first node: set it after that.
    Not inherited: the nodes started from here run as their parameter says, and a busy process
    that inherited SCHED_FIFO would starve this one on its core.
    """
    if PROBE_PRIORITY:
        from feeder_common.realtime import set_realtime_priority
        set_realtime_priority(PROBE_PRIORITY, inherit=False)


def run_key(log_dir):
    """``('-p', 'key_file:=...')``: the run's own HMAC key file (made in ``log_dir``, 0600)."""
    from feeder_common import auth
    path = pathlib.Path(log_dir) / 'hmac.key'
    auth.ensure_key(path)
    return ('-p', f'key_file:={path}')


def start(procs, which, period):
    rt = ('-p', f'realtime_priority:={REALTIME_PRIORITY}') if REALTIME_PRIORITY else ()
    key = run_key(procs.log_dir)     # the stand-in signs, the monitor checks (not the predictor)
    if 'sim' in which:
        procs.start('feeder_sim', 'standin_node', '--ros-args', '-r', '__ns:=/feeder', '-r',
                    '__node:=feeder_driver', '-p',
                    f'scene:={SCENE}', '-p', f'cycle_period:={period}', *rt, *key, name='sim')
    if 'monitor' in which:
        procs.start('feeder_monitor', 'monitor_node', '--ros-args', '-r',
                    '__ns:=/feeder', '-p', f'scene:={SCENE}', *rt, *key, name='monitor')
    if 'predictor' in which:
        procs.start('feeder_sim', 'predictor_node', '--ros-args', '-r',
                    '__ns:=/feeder/predictor', '-r', 'cycle_status:=/feeder/cycle_status',
                    '-p', f'scene:={SCENE}', *rt, name='predictor')
    if 'recorder' in which:
        bag = pathlib.Path(procs.log_dir) / 'bag'
        shutil.rmtree(bag, ignore_errors=True)
        procs.start('feeder_monitor', 'bag_recorder', bag, '--ros-args', '-r',
                    '__ns:=/feeder', name='recorder')


def watch_diagnostics(probe):
    """The latest status of each name on /diagnostics, by local name (a dict kept up to date)."""
    from diagnostic_msgs.msg import DiagnosticArray
    from feeder_common.diagnostics import local_name
    diags = {}

    def on_diag(msg):
        for s in msg.status:
            diags[local_name(s.name)] = s

    probe.node.create_subscription(DiagnosticArray, '/diagnostics', on_diag, 50)
    return diags


def wait_graph(probe, which):
    """
    Wait until every writer matched its readers, by the writers' own accounts.

    Each feeder node reports its matched endpoints on /diagnostics (feeder_common.diagnostics):
    the stand-in's cycle_status and proximity writers matched the probe and the other nodes'
    readers, the monitor's edge1_verdict the probe's; then the stand-in is active.
    """
    status = 1 + ('monitor' in which) + ('predictor' in which) + ('recorder' in which)
    prox = 1 + ('monitor' in which) + ('recorder' in which)
    probe.wait_remote_matched('/feeder/feeder_driver', readers={
        '/feeder/cycle_status': status, '/feeder/proximity': prox})
    if 'monitor' in which:
        probe.spin_until(lambda: probe.ready, 90, 'the monitor')
        probe.wait_remote_matched('/feeder/feeder_monitor',
                                  readers={'/feeder/edge1_verdict': 1})
    probe.wait_active('/feeder/feeder_driver')


def bench_processes(log_dir):
    """The benchmark's node processes (from INSTALL: --install may name another)."""
    return Processes(log_dir, install=INSTALL, error=SystemExit, prog='graph_bench')


# The colcon install the nodes run from (--install)
INSTALL = feeder_testing.INSTALL


def latency(log_dir, cycles, period=0.01):
    procs = bench_processes(log_dir)
    probe = Probe(procs)
    probe_realtime()
    try:
        start(procs, ('sim', 'monitor'), period)
        wait_graph(probe, ('sim', 'monitor'))
        probe.clear()
        probe.enable(True)
        probe.spin_until(lambda: len(probe.status) >= cycles, 30 + 3 * cycles * period,
                         'cycles')
        probe.enable(False)
        probe.spin_for(1.0)
        # The sim publishes proximity k then cycle_status k (align them at the end: the probe
        # may have missed the first while discovery finished); verdicts name their seq.
        off = len(probe.prox) - len(probe.status)
        by_seq = {seq: (probe.prox[j + off], info) for j, (seq, info) in enumerate(probe.status)
                  if 0 <= j + off < len(probe.prox)}
        readies = sorted(probe.ready, key=lambda r: r['source_timestamp'])
        pairs = []
        for seq, v in probe.verdicts:
            r = _ready_of(readies, v)
            if seq in by_seq and r is not None:
                pairs.append((*by_seq[seq], r))

        def ms(xs):
            return [x * 1e-6 for x in xs]

        return {
            'proximity published -> edge1_ready received':
                ms(r['received_timestamp'] - p['source_timestamp'] for p, _, r in pairs),
            'proximity received -> edge1_ready received':
                ms(r['received_timestamp'] - p['received_timestamp'] for p, _, r in pairs),
            '  of which: proximity published -> cycle_status published (in the sim)':
                ms(c['source_timestamp'] - p['source_timestamp'] for p, c, _ in pairs),
            '  of which: cycle_status published -> edge1_ready published (the monitor)':
                ms(r['source_timestamp'] - c['source_timestamp'] for _, c, r in pairs),
            '  of which: edge1_ready published -> received (transport)':
                ms(r['received_timestamp'] - r['source_timestamp'] for _, _, r in pairs),
        }
    finally:
        probe.close()
        procs.stop_all()


ECHO = """
import sys
import rclpy
from std_msgs.msg import Float64
rclpy.init()
node = rclpy.create_node('feeder_bench_echo')
if int(sys.argv[1]):
    from feeder_common.realtime import set_realtime_priority
    set_realtime_priority(int(sys.argv[1]))
pub = node.create_publisher(Float64, '/bench/pong', 10)
node.create_subscription(Float64, '/bench/ping', pub.publish, 10)
try:
    rclpy.spin(node)
except BaseException:
    pass
"""


def echo_baseline(log_dir, cycles, period):
    """Two hops through a do-nothing rclpy node: the platform's floor for the monitor's path."""
    from std_msgs.msg import Float64
    procs = bench_processes(log_dir)
    procs.command([sys.executable, '-c', ECHO, PROBE_PRIORITY], 'echo')
    probe = BenchNode('feeder_bench_ping', procs)
    probe_realtime()
    got = []
    pub = probe.node.create_publisher(Float64, '/bench/ping', 10)
    sub = probe.node.create_subscription(Float64, '/bench/pong', lambda m, i: got.append(i), 10)
    try:
        # Both hops matched: the echo's reader with our writer, its writer with our reader.
        probe.wait_matched(pub, what='the echo to match /bench/ping')
        probe.wait_matched(sub, what='the echo to match /bench/pong')
        probe.spin_for(1.0)     # the echo's reader side of /bench/pong shows nowhere
        sent = []
        for _ in range(cycles):
            sent.append(time.time_ns())
            pub.publish(Float64(data=0.0))
            t_next = time.monotonic() + period
            while time.monotonic() < t_next:
                probe.executor.spin_once(timeout_sec=max(0.0, t_next - time.monotonic()))
        probe.spin_for(1.0)
        # the pong's source timestamp is the echo's publish; the ping's is in ``sent``
        return [(i['received_timestamp'] - t) * 1e-6 for i, t in zip(got, sent)]
    finally:
        probe.close()
        procs.stop_all()


def rate(log_dir, seconds, which, period=0.005):
    procs = bench_processes(log_dir)
    probe = Probe(procs)
    try:
        start(procs, which, period)
        wait_graph(probe, which)
        probe.enable(True)
        probe.spin_for(1.0)             # steady state
        probe.clear()
        t0 = time.monotonic()
        probe.spin_for(seconds)
        n = len(probe.status)
        dt = time.monotonic() - t0
        probe.enable(False)
        return n / dt
    finally:
        probe.close()
        procs.stop_all()


def cpu(log_dir, seconds, period):
    procs = bench_processes(log_dir)
    probe = Probe(procs)
    which = ('sim', 'monitor', 'predictor', 'recorder')
    try:
        start(procs, which, period)
        wait_graph(probe, which)
        probe.enable(True)
        probe.spin_for(2.0)
        before = {name: cpu_seconds(p.pid) for name, p in procs.procs.items()}
        t0 = time.monotonic()
        probe.spin_for(seconds)
        wall = time.monotonic() - t0
        after = {name: cpu_seconds(p.pid) for name, p in procs.procs.items()}
        probe.enable(False)
        return {name: 100.0 * (after[name] - before[name]) / wall for name in before}
    finally:
        probe.close()
        procs.stop_all()


def busy_load(n):
    """Start ``n`` processes that spin at nice 0 until killed: both cores busy on demand."""
    import subprocess
    return [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(n)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    ap.add_argument('--latency-cycles', type=int, default=1000)
    ap.add_argument('--latency-period', type=float, default=0.01,
                    help='cycle period of the latency run, s (default 0.01)')
    ap.add_argument('--only', choices=('latency', 'rate', 'cpu'), default=None)
    ap.add_argument('--rate-seconds', type=float, default=5.0)
    ap.add_argument('--cpu-seconds', type=float, default=20.0)
    ap.add_argument('--install', type=pathlib.Path, default=None,
                    help='colcon install space to run the nodes from (default ros2_ws/install; '
                    'e.g. a build of another commit, to compare before/after)')
    ap.add_argument('--executor', choices=('events', 'single'), default=None,
                    help="the nodes' executor (FEEDER_EXECUTOR; default: the nodes' own)")
    ap.add_argument('--load', type=int, default=0, metavar='N',
                    help='start N busy-looping processes (nice 0) for the whole run: a load '
                    'that can be reproduced, unlike other jobs (default 0)')
    ap.add_argument('--realtime-priority', type=int, default=0, metavar='P',
                    help="the sim's, monitor's and predictor's realtime_priority parameter "
                    '(SCHED_FIFO 1-99; needs the right to it; default 0: normal scheduler)')
    ap.add_argument('--probe-realtime', action='store_true',
                    help='run the probe (the consumer of edge1_ready) and the baseline echo at '
                    '--realtime-priority too; default: normal, a consumer without the right')
    args = ap.parse_args()
    if not 0 <= args.load <= 64:
        ap.error(f'--load must be 0-64 busy processes, got {args.load}')
    if not 0 <= args.realtime_priority <= 99:
        ap.error(f'--realtime-priority must be 0-99, got {args.realtime_priority}')
    if args.probe_realtime and not args.realtime_priority:
        ap.error('--probe-realtime needs --realtime-priority P')
    global REALTIME_PRIORITY, INSTALL
    REALTIME_PRIORITY = args.realtime_priority
    if args.install is not None:
        INSTALL = args.install.resolve()
    if args.executor:
        os.environ['FEEDER_EXECUTOR'] = args.executor
    domain, lock = use_domain()
    log_dir = pathlib.Path(tempfile.mkdtemp(prefix='feeder-bench-'))
    burners = busy_load(args.load)
    global PROBE_PRIORITY
    PROBE_PRIORITY = args.realtime_priority if args.probe_realtime else 0
    rows = []

    def row(*cells):
        rows.append(cells)
        print(' | '.join(cells), flush=True)

    try:
        load = ', '.join(f'{x:.1f}' for x in os.getloadavg())
        executor = os.environ.get('FEEDER_EXECUTOR', "the nodes' default")
        print(f'graph_bench: ROS_DOMAIN_ID={domain} (loopback), {os.cpu_count()} cores, load '
              f'average {load} (other work on the machine skews latency), {args.load} busy '
              f'processes started, realtime_priority {args.realtime_priority}'
              f'{" (probe too)" if args.probe_realtime else ""}, logs in {log_dir}; nodes '
              f'from {INSTALL}, executor: {executor}', flush=True)
        if args.only in (None, 'latency'):
            series = latency(log_dir, args.latency_cycles, args.latency_period)
            for k, (label, xs) in enumerate(series.items()):
                over = f'{len(xs)} cycles at {1 / args.latency_period:.0f} Hz'
                row(label, over, f'p50 {statistics.median(xs):.2f} ms, p90 {pct(xs, 90):.2f} '
                    f'ms, p99 {pct(xs, 99):.2f} ms, max {max(xs):.2f} ms',
                    'p99 < 5 ms' if k == 0 else '')
            xs = echo_baseline(log_dir, args.latency_cycles, args.latency_period)
            row('baseline: ping published -> pong received through a do-nothing rclpy node',
                f'{len(xs)} pings at {1 / args.latency_period:.0f} Hz',
                f'p50 {statistics.median(xs):.2f} ms, p90 {pct(xs, 90):.2f} ms, p99 '
                f'{pct(xs, 99):.2f} ms, max {max(xs):.2f} ms', '')
        if args.only in (None, 'rate'):
            for label, which in (('sim alone', ('sim',)),
                                 ('sim + monitor + predictor + recorder',
                                  ('sim', 'monitor', 'predictor', 'recorder'))):
                r = rate(log_dir, args.rate_seconds, which)
                row(f'cycles/s at cycle_period 0.005 s, {label}', f'{args.rate_seconds:.0f} s',
                    f'{r:.1f} cycles/s', '>= 100')
        if args.only in (None, 'cpu'):
            for period, label, secs in ((1.0, '1 Hz', args.cpu_seconds),
                                        (0.01, '100 Hz', min(args.cpu_seconds, 10.0))):
                for name, use in cpu(log_dir, secs, period).items():
                    row(f'CPU of {name} at {label} cycling', f'{secs:.0f} s',
                        f'{use:.2f} % of a core', '< 3 %' if period == 1.0 else '')
    finally:
        for b in burners:
            b.kill()
            b.wait()
        lock.close()
    load = ', '.join(f'{x:.1f}' for x in os.getloadavg())
    print(f'\nload average at the end: {load}')
    print('\n| measurement | over | result | target |\n|---|---|---|---|')
    for r in rows:
        print('| ' + ' | '.join(r) + ' |')


if __name__ == '__main__':
    main()
