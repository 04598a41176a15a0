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
Does a design keep the part on an arm of a given length? Every grid start, many throws.

Each scene (a base-model design, e.g. what `throwmap design-search` wrote) gets effect
``finite_arm`` with the arm length given (default 40 cm, the paper's), and its basin grid of
starts (``throwmap.basins.default_grid``: every stable edge, R from R_min to R_max of Z) is
iterated; a start counts as lost when a throw leaves the arm (or, with the arm, the domain of
f). The design search keeps to the arm only when the scene names finite_arm (else it takes the
arm as endless, and says so); this checks a chosen design against the real arm, for many more
throws than the search's. Prints figures; asserts nothing.

    python bench/arm_check.py SCENE [SCENE ...] [--length-cm 40] [--throws 10000]
"""

import argparse
import time

import numpy as np
from throwmap import load_scene, Scene
from throwmap.basins import default_grid
from throwmap.status import LOST, OK


def on_arm(path, length_cm, throws):
    data = dict(load_scene(path).data)
    data['arm'] = dict(data['arm'], length_cm=float(length_cm))
    data['effects'] = sorted(set(data.get('effects') or []) | {'finite_arm'})
    model = Scene(data).model
    edges, radii = default_grid(model)
    start = time.perf_counter()
    status = model.orbits(edges, radii, throws)[3]
    seconds = time.perf_counter() - start
    lost = int(np.sum(status == LOST))
    failed = int(np.sum((status != OK) & (status != LOST)))
    beyond = int(np.sum(radii > length_cm / 100.0))
    print(f'{path}: {edges.size} grid starts ({beyond} of them beyond the end of the arm) x '
          f'{throws} throws on a {length_cm:g} cm arm: {lost} lost, {failed} other failures '
          f'({seconds:.1f} s)')


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('scenes', nargs='+')
    ap.add_argument('--length-cm', type=float, default=40.0)
    ap.add_argument('--throws', type=int, default=10000)
    args = ap.parse_args()
    for path in args.scenes:
        on_arm(path, args.length_cm, args.throws)


if __name__ == '__main__':
    main()
