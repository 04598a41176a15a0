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
What a node's memory grows by while cycling: tracemalloc in-process (issue 10's soak).

    python bench/mem_trace.py --node predictor|recorder [--seconds 120] [--period 0.005]

The sim runs as the hardware (a process, as in bench/soak.py); the traced node (the predictor:
feeder_sim's PredictorNode; or the bag recorder, recording the soak's topics) runs in this process
under tracemalloc, started after a warm-up. Prints the Python allocations still alive at the
end that were made after the warm-up, by line, per 1000 cycles, beside the process's RSS
growth: Python objects that grow are a leak or an index; RSS growth without them is C-level
(rclpy, Fast DDS, the allocator). For the recorder it also prints the bag's size and its chunk
index count. Figures, not assertions.
"""

import argparse
import os
import pathlib
import sys
import tempfile
import time
import tracemalloc

# The harness (tests/feeder_testing.py: processes, domain, probe node); bench/ is this
# script's own directory, on sys.path already.
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'tests'))
from feeder_testing import Probe, Processes, use_domain  # noqa: E402
from soak import SCENE, TOPICS, rss_kb  # noqa: E402


def make_node(which, context, out):
    from rclpy.parameter import Parameter
    if which == 'predictor':
        from feeder_common.node import autostart
        from feeder_sim.predictor_node import PredictorNode
        node = PredictorNode(context=context, namespace='/feeder',
                             parameter_overrides=[Parameter('scene', value=SCENE)])
        autostart(node)
        return node, None
    from feeder_monitor.bag import BagWriter
    from feeder_monitor.bag_recorder import BagRecorder
    writer = BagWriter(out / 'bag')
    return BagRecorder(writer, list(TOPICS), context=context, namespace='/feeder'), writer


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    ap.add_argument('--node', choices=('predictor', 'recorder'), required=True)
    ap.add_argument('--seconds', type=float, default=120.0, help='traced time (default 120)')
    ap.add_argument('--warmup', type=float, default=20.0, help='untraced start (default 20)')
    ap.add_argument('--period', type=float, default=0.005)
    ap.add_argument('--top', type=int, default=12)
    args = ap.parse_args()
    out = pathlib.Path(tempfile.mkdtemp(prefix='feeder-memtrace-'))
    domain, lock = use_domain()
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    procs = Processes(out, error=SystemExit, prog='mem_trace')
    procs.start('feeder_sim', 'standin_node', '--ros-args', '-r', '__ns:=/feeder', '-r',
                '__node:=feeder_driver', '-p', f'scene:={SCENE}',
                '-p', f'cycle_period:={args.period}', name='sim')
    context = Context()
    rclpy.init(context=context)
    node, writer = make_node(args.node, context, out)
    ctl = rclpy.create_node('feeder_mem_trace', context=context)
    ex = SingleThreadedExecutor(context=context)
    ex.add_node(node)
    ex.add_node(ctl)
    seq = {'n': 0}
    from feeder_interfaces.msg import CycleStatus
    ctl.create_subscription(CycleStatus, '/feeder/cycle_status',
                            lambda m: seq.__setitem__('n', seq['n'] + 1), 1000)

    def spin(seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            procs.check()
            ex.spin_once(timeout_sec=0.05)

    # Switches the stand-in's cycling once its cycle_status writer matched the traced node's
    # reader and ctl's (the stand-in's own account) and it is active.
    probe = Probe('feeder_mem_trace_probe', procs=procs, watch=True, error=SystemExit)
    try:
        probe.wait_remote_matched('/feeder/feeder_driver',
                                  readers={'/feeder/cycle_status': 2}, timeout=120)
        probe.enable('/feeder/feeder_driver', True)
        spin(args.warmup)
        tracemalloc.start(6)
        n0, rss0, t0 = seq['n'], rss_kb(os.getpid()), time.monotonic()
        spin(args.seconds)
        snap = tracemalloc.take_snapshot()
        n1, rss1, t1 = seq['n'], rss_kb(os.getpid()), time.monotonic()
        traced, _ = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        probe.enable('/feeder/feeder_driver', False)
    finally:
        probe.close()
        procs.stop_all()
    cycles = n1 - n0
    per = 1000.0 / max(cycles, 1)
    print(f'mem_trace {args.node}: {cycles} cycles traced in {t1 - t0:.0f} s '
          f'({cycles / (t1 - t0):.0f} cycles/s), load average '
          f'{", ".join(f"{x:.1f}" for x in os.getloadavg())}')
    print(f'RSS {rss0} -> {rss1} KB: {(rss1 - rss0) * per:+.2f} KB per 1000 cycles')
    print(f'Python allocations made while traced and still alive: {traced / 1024:.0f} KB, '
          f'{traced / 1024 * per:.2f} KB per 1000 cycles; by traceback:')
    stats = snap.filter_traces([tracemalloc.Filter(False, tracemalloc.__file__)]) \
        .statistics('traceback')
    for st in stats[:args.top]:
        print(f'  {st.size / 1024:9.1f} KB in {st.count:7d} blocks '
              f'({st.size / 1024 * per:7.2f} KB per 1000 cycles)')
        for line in st.traceback.format()[-6:]:
            print('      ' + line)
    if writer is not None:
        log = writer._log
        size = sum(p.stat().st_size for p in (out / 'bag').glob('*.mcap'))
        print(f'bag: {writer.total} messages, {size / 1024:.0f} KB, '
              f'{len(log.chunk_indexes)} chunk indexes')
    node.destroy_node()
    ctl.destroy_node()
    context.try_shutdown()
    lock.close()
    print(f'(logs and bag in {out})')
    return 0


if __name__ == '__main__':
    sys.exit(main())
