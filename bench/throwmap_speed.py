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

"""Speed of the throw map (issue targets: <= 20 us per f, >= 200k throws/s batch, basin < 1 s).

Prints figures; asserts nothing. Usage: python bench/throwmap_speed.py [scene.yaml ...]
"""

import argparse
import os
import pathlib
import platform
import time

import numpy as np
from throwmap import basin, default_grid, limit_set, load_scene

ROOT = pathlib.Path(__file__).resolve().parents[1]


def states_in_domain(model, count, seed=0):
    rng = np.random.default_rng(seed)
    part = model.part
    d = __import__('throwmap').design_radii(model)
    edges, radii = [], []
    for _ in range(count):
        row = d['edges'][rng.integers(len(d['edges']))]
        edges.append(row['edge'])
        radii.append(rng.uniform(row['R_min'] * 1.001, max(row['R_max'], row['R_min'] * 1.5)))
    del part
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


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('scenes', nargs='*', default=[str(ROOT / 'scenes' / 'triangle.yaml'),
                                                      str(ROOT / 'scenes' / 'bracket.yaml')])
    parser.add_argument('--singles', type=int, default=20_000)
    parser.add_argument('--batch', type=int, default=1_000_000)
    args = parser.parse_args()
    print(f'python {platform.python_version()}, {platform.machine()}, '
          f'{os.cpu_count()} cores, numba JIT: {__import__("throwmap").kernel.HAVE_NUMBA}')
    for path in args.scenes:
        bench(path, args.singles, args.batch)


if __name__ == '__main__':
    main()
