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

"""Throughput of the design search: designs/s and throws/s; growth with grid and catalogue.

Prints figures; asserts nothing. Issue 11's target: one part's 100 x 100 (h, speed) grid,
each design with its basin, in under 60 s on 2 cores.

Usage: python bench/design_search.py [--grids 10,20,50,100] [--workers 2]
       python bench/design_search.py --catalogue 1,2,4 --grid 20   # on a local Dask cluster
"""

import argparse
import os
import pathlib
import shutil
import tempfile
import time

import numpy as np
from throwmap import design as D
from throwmap import load_scene
from throwmap import search as S

ROOT = pathlib.Path(__file__).resolve().parents[1]


def load():
    return os.getloadavg()[0]


def grid_run(scene, n, workers):
    d = scene.part.d_min
    w0 = scene.release_speed
    H, W = np.meshgrid(np.linspace(-0.95 * d, -0.05 * d, n), np.linspace(0.5 * w0, 1.5 * w0, n),
                       indexing='ij')
    res = D.evaluate_grid(scene, H.ravel(), W.ravel(), workers=workers)
    ok = int(S.eligible(res).any(axis=(1, 2)).sum())
    print(f'  {scene.name} {n:4d} x {n:<4d} {res.h.size:6d} designs  {res.seconds:7.2f} s  '
          f'{res.h.size / res.seconds:7.1f} designs/s  {res.throws / res.seconds:12,.0f} '
          f'throws/s  ({ok} eligible; load {load():.1f})', flush=True)


def catalogue_run(counts, n):
    names = ['triangle', 'bracket', 'house_base', 'rectangle_base']
    with tempfile.TemporaryDirectory() as tmp:
        base = []
        for name in ('triangle', 'bracket'):
            shutil.copy(ROOT / 'scenes' / f'{name}.yaml', os.path.join(tmp, f'{name}.yaml'))
            base.append(os.path.join(tmp, f'{name}.yaml'))
        paths = []
        for k in range(max(counts)):
            src = base[k % len(base)]
            dst = os.path.join(tmp, f'part{k:02d}_{names[k % len(names)]}.yaml')
            if not os.path.exists(dst):
                shutil.copy(src, dst)
            paths.append(dst)
        cluster = S.local_cluster(2)
        from distributed import Client
        with Client(cluster) as client:
            for c in counts:
                sel = paths[:c]
                scenes = [load_scene(p) for p in sel]
                ranges = [((-0.95 * s.part.d_min, -0.05 * s.part.d_min),
                           (0.5 * s.release_speed, 1.5 * s.release_speed)) for s in scenes]
                t0 = time.perf_counter()
                out = S.run_catalogue(sel, ranges, n, n, top=4, refine=3, client=client)
                dt = time.perf_counter() - t0
                designs = sum(r['designs'] for r in out)
                print(f'  catalogue of {c} scenes, {n} x {n} each: {dt:6.1f} s on 2 Dask '
                      f'workers ({designs / dt:.1f} designs/s with robustness of the best; '
                      f'load {load():.1f})', flush=True)
        cluster.close()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--grids', default='10,20,50,100')
    ap.add_argument('--workers', type=int, default=2)
    ap.add_argument('--scene', default=str(ROOT / 'scenes' / 'triangle.yaml'))
    ap.add_argument('--catalogue', help='numbers of scenes, e.g. 1,2,4')
    ap.add_argument('--grid', type=int, default=20, help='grid per scene in the catalogue')
    args = ap.parse_args()
    if args.catalogue:
        catalogue_run([int(x) for x in args.catalogue.split(',')], args.grid)
        return
    scene = load_scene(args.scene)
    opt = D.eval_options(scene)
    print(f'design grid, {args.workers} threads; per design: {opt.radii_per_edge} radii per '
          f'stable edge x {opt.throws} throws, a {opt.ref_throws}-throw reference orbit, Z '
          f'with {opt.zmax_samples} samples per edge; load {load():.1f}')
    D.evaluate_grid(scene, [scene.h], [scene.release_speed])     # compile / load the cache
    for n in (int(x) for x in args.grids.split(',')):
        grid_run(scene, n, args.workers)


if __name__ == '__main__':
    main()
