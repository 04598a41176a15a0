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

"""Speed of the throw map: f, throw, f_batch, basins; the batch CLI; a process's start-up.

Targets (issue 8): f <= 3 us, f_batch >= 900,000 throws/s, the batch CLI >= 150,000 throws/s
on one core. Prints figures; asserts nothing.

Usage: python bench/throwmap_speed.py [scene.yaml ...]
       python bench/throwmap_speed.py --cli 1000000            # throwmap throw --json on stdin
       python bench/throwmap_speed.py --startup scenes/*.yaml  # cold and warm start-up
"""

import argparse
import json
import os
import pathlib
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np
from throwmap import basin, default_grid, design_radii, limit_set, load_scene
from throwmap.jit import HAVE_NUMBA

ROOT = pathlib.Path(__file__).resolve().parents[1]


def states_in_domain(model, count, seed=0):
    rng = np.random.default_rng(seed)
    d = design_radii(model)
    edges, radii = [], []
    for _ in range(count):
        row = d['edges'][rng.integers(len(d['edges']))]
        edges.append(row['edge'])
        radii.append(rng.uniform(row['R_min'] * 1.001, max(row['R_max'], row['R_min'] * 1.5)))
    return np.array(edges), np.array(radii)


def per_call(fn, edges, radii):
    times = np.empty(len(edges))
    clock = time.perf_counter_ns
    for k in range(len(edges)):
        e, r = int(edges[k]), float(radii[k])
        t0 = clock()
        fn(e, r)
        times[k] = clock() - t0
    return times / 1000.0


def bench(scene_path, singles, batch):
    scene = load_scene(scene_path)
    model = scene.model
    edges, radii = states_in_domain(model, max(singles, 1000))
    model.f(int(edges[0]), float(radii[0]))           # compile (or load the numba cache)
    model.throw(int(edges[0]), float(radii[0]))
    t_f = per_call(model.f, edges[:singles], radii[:singles])
    t_throw = per_call(model.throw, edges[:singles], radii[:singles])
    be, br = states_in_domain(model, batch, seed=1)
    model.f_batch(be[:10], br[:10])
    t0 = time.perf_counter()
    res = model.f_batch(be, br)
    t_batch = time.perf_counter() - t0
    assert np.all(res['status'] == 0)
    start = scene.default_start()
    ref = limit_set(model, start[0], start[1], 10_000)
    ge, gr = default_grid(model, 50)
    model.orbits(ge[:2], gr[:2], 10)
    t0 = time.perf_counter()
    model.orbits(ge, gr, 100)
    t_orbits = time.perf_counter() - t0
    t0 = time.perf_counter()
    bas = basin(model, ge, gr, 100, reference=ref)
    t_basin = time.perf_counter() - t0
    print(f'\n{scene.name} ({model.part.n} vertices)')
    print(f'  f(i, R), one call          median {np.median(t_f):7.2f} us   p99 '
          f'{np.percentile(t_f, 99):7.2f} us   ({singles} random states in Z)')
    print(f'  throw(i, R) with impacts   median {np.median(t_throw):7.2f} us   p99 '
          f'{np.percentile(t_throw, 99):7.2f} us')
    print(f'  f_batch, one core          {batch / t_batch:12,.0f} throws/s   ({batch:,} states,'
          f' {t_batch:.3f} s)')
    print(f'  Figure-7 basin             {len(ge)} starts x 100 throws: orbits {t_orbits:.3f} s,'
          f' with limit-set bookkeeping {t_basin:.3f} s '
          f'({bas.summary()})')


STARTUP = """
import sys, time
t0 = time.perf_counter()
from throwmap import load_scene
t1 = time.perf_counter()
scene = load_scene(sys.argv[1])
t2 = time.perf_counter()
e, R = scene.default_start()
scene.model.f(e, R)
scene.model.f_batch([e], [R])
scene.model.orbits([e], [R], 2)
t3 = time.perf_counter()
print(t1 - t0, t2 - t1, t3 - t2)
"""


def startup(paths):
    """Start-up of a fresh process per scene, with an empty numba cache (cold), then again."""
    print('\nstart-up of a process: import, load_scene, first f, f_batch, orbits '
          '(numba cache: empty, then warm)')
    for path in paths:
        with tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ, NUMBA_CACHE_DIR=cache)
            times = []
            for _ in ('cold', 'warm'):
                t0 = time.perf_counter()
                out = subprocess.run([sys.executable, '-c', STARTUP, path], env=env, check=True,
                                     capture_output=True, text=True).stdout.split()
                times.append((time.perf_counter() - t0, [float(x) for x in out]))
        (cold, cparts), (warm, wparts) = times
        compiled = cparts[1] + cparts[2]
        print(f'  {pathlib.Path(path).name:22s} cold {cold:6.2f} s (load and first calls '
              f'{compiled:5.2f} s)   warm {warm:5.2f} s (import {wparts[0]:.2f} s, load '
              f'{wparts[1]:.2f} s, first calls {wparts[2]:.2f} s)')


def cli(scene, lines):
    """Throughput of `throwmap throw SCENE --json` on ``lines`` states from stdin, one core."""
    model = load_scene(scene).model
    edges, radii = states_in_domain(model, lines, seed=2)
    with tempfile.NamedTemporaryFile('w', suffix='.jsonl', delete=False) as fh:
        fh.writelines(json.dumps({'edge': int(e), 'R': float(r)}) + '\n'
                      for e, r in zip(edges, radii))
        path = fh.name
    try:
        cmd = [sys.executable, '-m', 'throwmap.cli', 'throw', scene, '--json']
        if hasattr(os, 'sched_getaffinity'):
            cmd = ['taskset', '-c', str(min(os.sched_getaffinity(0)))] + cmd
        with open(path) as stdin:
            subprocess.run(cmd[:-5] + ['-c', 'import throwmap.cli'], check=True)   # warm cache
            t0 = time.perf_counter()
            with open(os.devnull, 'w') as sink:
                subprocess.run(cmd, stdin=stdin, stdout=sink, check=False)
            total = time.perf_counter() - t0
        t0 = time.perf_counter()
        subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, check=False)
        start = time.perf_counter() - t0
    finally:
        os.unlink(path)
    print(f'\nbatch CLI ({" ".join(cmd[:3]) if cmd[0] == "taskset" else "one process"}), '
          f'{lines:,} lines of {pathlib.Path(scene).name}: {total:.2f} s, '
          f'{lines / total:,.0f} throws/s end to end; start-up alone {start:.2f} s, so '
          f'{lines / max(total - start, 1e-9):,.0f} throws/s once running')


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('scenes', nargs='*', default=[str(ROOT / 'scenes' / 'triangle.yaml'),
                                                      str(ROOT / 'scenes' / 'bracket.yaml')])
    parser.add_argument('--singles', type=int, default=20_000)
    parser.add_argument('--batch', type=int, default=1_000_000)
    parser.add_argument('--cli', type=int, metavar='LINES',
                        help='measure the batch CLI on this many lines instead')
    parser.add_argument('--startup', action='store_true',
                        help="measure a process's start-up (cold and warm) instead")
    args = parser.parse_args()
    print(f'python {platform.python_version()}, {platform.machine()}, '
          f'{os.cpu_count()} cores, numba JIT: {HAVE_NUMBA}; load {os.getloadavg()[0]:.2f}')
    if args.startup:
        startup(args.scenes)
        return
    if args.cli:
        cli(args.scenes[0], args.cli)
        return
    for path in args.scenes:
        bench(path, args.singles, args.batch)


if __name__ == '__main__':
    main()
