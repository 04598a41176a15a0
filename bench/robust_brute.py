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
A design's robustness graph against brute force, with the scene's own physics.

For one design of a scene (its own by default): the design kernel's figures, the limit spec
the search would give it, the robustness graph at error s (speed +- s w, offset +- s d_min,
`throwmap.robustness.robust_check`), then every sequence of ``--depth`` worst-case throws (the
four corners of the error box) from the nominal limit set's states through the scene's model
(`robustness.worst_case_sequences`): how many throws, how many lost the part, left the closure
the graph proved, or showed another edge to the sensor. What the design search's robustness
claims, checked where it is too slow to test (the experiment scene's plate drag). Prints
figures; asserts nothing.

    python bench/robust_brute.py scenes/experiment.yaml [--h-cm -0.5] [--w-deg 320]
        [--s 0.002] [--depth 5] [--cells 120]
"""

import argparse
import math
import time

from throwmap import design as D
from throwmap import load_scene
from throwmap import robustness as RB
from throwmap import search as S


def main():
    """Run the check on the design the arguments name and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('scene')
    parser.add_argument('--h-cm', type=float, help="the offset (default: the scene's)")
    parser.add_argument('--w-deg', type=float, help="the release speed (default: the scene's)")
    parser.add_argument('--goal', type=int, default=1)
    parser.add_argument('--s', type=float, default=0.002, help='the error box, as a fraction')
    parser.add_argument('--depth', type=int, default=5, help='throws per worst-case sequence')
    parser.add_argument('--cells', type=int, default=120)
    parser.add_argument('--orbit', type=int, default=400,
                        help='throws of the nominal orbit; its last quarter are the starts')
    args = parser.parse_args()
    scene = load_scene(args.scene)
    h = scene.model.h if args.h_cm is None else args.h_cm / 100.0
    w = scene.model.w if args.w_deg is None else math.radians(args.w_deg)
    print(f'{args.scene}: h {h * 100:.3f} cm, {math.degrees(w):.1f} deg/s, goal edge '
          f'{args.goal}, s {args.s}, depth {args.depth}')
    t0 = time.perf_counter()
    opt = D.eval_options(scene)
    res = D.evaluate_grid(scene, [h], [w], goals=[args.goal], options=opt, workers=1)
    status = int(res.design[0, D.D_STATUS])
    print(f'  design kernel: {D.STATUS_TEXT[status]} ({time.perf_counter() - t0:.1f} s)')
    if status != D.ST_OK:
        return
    cand = S.Candidate(h, w, args.goal, 0.25, S._figures(res, 0, 0, 0))
    spec = S.limit_spec(scene, cand, opt)
    print(f'  sensor at {spec.x * 100:.2f} cm; limit-set bands {spec.bands.tolist()}')
    dh, dw = args.s * scene.part.d_min, args.s * w
    t0 = time.perf_counter()
    verdict, cmap = RB.robust_check(scene.model, h, w, dh, dw, spec, cells=args.cells,
                                    with_map=True)
    print(f'  robustness graph: ok {verdict.ok} {verdict.reason!r}, closure '
          f'{verdict.closure_cells} cells, transient bound {verdict.transient_bound} '
          f'({time.perf_counter() - t0:.1f} s)')
    model = scene.model.at(h, w)
    e, r, _ = model.orbit_arrays(args.goal, 1.5 * model.r_min(args.goal), args.orbit)
    starts = slice(3 * args.orbit // 4, None)
    t0 = time.perf_counter()
    counts = RB.worst_case_sequences(scene.model, h, w, dh, dw, cmap, verdict, spec, e[starts],
                                     r[starts], depth=args.depth)
    print(f'  brute force from {len(e[starts])} limit-set states, 4^{args.depth} sequences '
          f'each: {counts} ({time.perf_counter() - t0:.1f} s)')


if __name__ == '__main__':
    main()
