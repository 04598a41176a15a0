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
Where the nodes' CPU goes while cycling: per thread, and (with py-spy) per Python function.

    python bench/node_cpu.py [--period 0.01] [--seconds 10] [--install DIR] [--py-spy DIR]

Runs graph_bench's graph (sim as hardware, monitor, predictor, recorder; loopback DDS, its own
domain) and prints each node's CPU split over its threads (the Python main thread runs the
callbacks and the DDS writes; ``dds.*`` threads are Fast DDS's receive and event threads).
``--py-spy DIR`` also records each node with py-spy (not a requirement of the project:
``pip install py-spy``) into ``DIR/<node>.txt`` (raw collapsed stacks, e.g. for
flamegraph.pl or speedscope). Figures, not assertions: the machine's other load skews them.
The processes, the domain and the probe are the harness's (tests/feeder_testing.py, through
graph_bench: this script's directory is on sys.path; the one line below adds tests/).
"""

import argparse
import collections
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'tests'))
from feeder_testing import use_domain  # noqa: E402
import graph_bench  # noqa: E402
from graph_bench import bench_processes, Probe, start, wait_graph  # noqa: E402

NODES = ('sim', 'monitor', 'predictor', 'recorder')


def thread_cpu(pid):
    """CPU seconds used so far by each thread of ``pid``: {(tid, name): s}."""
    tick = os.sysconf('SC_CLK_TCK')
    used = {}
    for tid in os.listdir(f'/proc/{pid}/task'):
        try:
            with open(f'/proc/{pid}/task/{tid}/stat') as f:
                stat = f.read()
        except FileNotFoundError:       # the thread ended meanwhile
            continue
        name = stat[stat.index('(') + 1:stat.rindex(')')]
        fields = stat[stat.rindex(')') + 2:].split()
        used[(tid, name)] = (int(fields[11]) + int(fields[12])) / tick
    return used


def split(before, after, pid, wall):
    """Per thread name, % of a core between the two samples (the main thread marked)."""
    shares = collections.Counter()
    for (tid, name), t in after.items():
        label = f'{name} (main)' if tid == str(pid) else name
        shares[label] += 100.0 * (t - before.get((tid, name), 0.0)) / wall
    return shares


def main():
    """Run the graph, print the split; 0."""
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    ap.add_argument('--period', type=float, default=0.01, help='cycle period, s (0.01)')
    ap.add_argument('--seconds', type=float, default=10.0)
    ap.add_argument('--install', type=pathlib.Path, default=None,
                    help='colcon install space to run the nodes from (default ros2_ws/install)')
    ap.add_argument('--py-spy', type=pathlib.Path, default=None, dest='py_spy',
                    help='also record each node with py-spy into this directory')
    args = ap.parse_args()
    if args.py_spy is not None:
        if shutil.which('py-spy') is None:
            ap.error('--py-spy: py-spy is not on PATH (pip install py-spy)')
        args.py_spy.mkdir(parents=True, exist_ok=True)
    if args.install is not None:
        graph_bench.INSTALL = args.install.resolve()
    domain, lock = use_domain()
    log_dir = pathlib.Path(tempfile.mkdtemp(prefix='feeder-node-cpu-'))
    procs = bench_processes(log_dir)
    probe = Probe(procs)
    spies = []
    try:
        start(procs, NODES, args.period)
        wait_graph(probe, NODES)
        probe.enable(True)
        probe.spin_for(2.0)
        if args.py_spy is not None:
            for name, p in procs.procs.items():
                spies.append(subprocess.Popen(
                    ['py-spy', 'record', '--nonblocking', '-r', '200', '-f', 'raw',
                     '-d', str(int(args.seconds)), '-p', str(p.pid),
                     '-o', str(args.py_spy / f'{name}.txt')],
                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        before = {name: thread_cpu(p.pid) for name, p in procs.procs.items()}
        t0 = time.monotonic()
        probe.spin_for(args.seconds)
        wall = time.monotonic() - t0
        after = {name: thread_cpu(p.pid) for name, p in procs.procs.items()}
        for spy in spies:
            while spy.poll() is None:
                probe.spin_for(0.2)
        probe.enable(False)
    finally:
        probe.close()
        procs.stop_all()
    load = ', '.join(f'{x:.1f}' for x in os.getloadavg())
    print(f'node_cpu: {1 / args.period:.0f} Hz cycling, {wall:.1f} s, load average {load}, '
          f'nodes from {graph_bench.INSTALL}')
    print('| node | % of a core | by thread |')
    print('|---|---|---|')
    for name, p in procs.procs.items():
        shares = split(before[name], after[name], p.pid, wall)
        threads = ', '.join(f'{k} {v:.1f}' for k, v in shares.most_common() if v > 0.05)
        print(f'| {name} | {sum(shares.values()):.1f} | {threads} |')
    if spies:
        print(f'py-spy profiles: {args.py_spy}/<node>.txt')
    del lock
    return 0


if __name__ == '__main__':
    sys.exit(main())
