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
Never-ready parts of tests/test_graph_funnel.py's speed policies, in the library only.

The policies as the test builds them (tests/feeder_nodes.py funnel_policy: the triangle on its
40 cm arm, s = 0.005, 200 cells): the sensor-based one on 120:600:20 deg/s and one speed (320
deg/s). Parts at random states of the 120:600:20 policy's start set, drawn as the test's
``starts`` draws them; every throw at a random corner of the error box (as effect
release_noise with distribution corner, the speed's bound relative), a fresh error stream;
each part judged by a Tracker loaded from the policy dict (the monitor's rule) until its first
ready or MAX_THROWS throws. Prints one JSON line per policy. No ROS.

    python scripts/funnel_never_ready.py [PARTS] [SEED]     # default 5000 parts, seed 1
"""

import json
import math
import pathlib
import sys
import time

import numpy as np
from throwmap import funnel as F
from throwmap import load_scene
from throwmap.sensor import sees

TRIANGLE = str(pathlib.Path(__file__).resolve().parents[1] / 'scenes' / 'triangle.yaml')
ROBUST, MAX_THROWS = 0.005, 400


def policy(speeds):
    arm, _ = F.arm_scene(load_scene(TRIANGLE), None)
    res = F.plan(arm, F.parse_speeds(speeds), robust=ROBUST, cells=200, one_bit=False)
    return arm, res, json.loads(json.dumps(F.policy_dict(res, TRIANGLE)))


def starts(d, parts, seed):
    return F.Tracker(d).random_starts(parts, np.random.default_rng(seed))


def feed(arm, res, d, parts, rng):
    """Return per part the throws to the first ready (inf: none), false readies, lost."""
    tracker, s = F.Tracker(d), res.system
    thrower, part = F.Thrower(arm, s), arm.model.part
    throws, false, lost = [], 0, 0
    for e, R in parts:
        tracker.new_part()
        n = math.inf
        for t in range(1, MAX_THROWS + 1):
            k = tracker.last if tracker.speed() is not None else tracker.home
            u_w, u_h = (int(x) for x in rng.choice((-1, 1), size=2))
            e, R = thrower.throw(k, e, R, u_w, u_h)
            if e < 0:
                lost += 1
                break
            bit = bool(sees(part, e, R, s.sensor_radius, s.footprint))
            if tracker.observe(bit, float(s.speeds[k])) == 'ready':
                n = t
                false += e != s.goal_edge
                break
        throws.append(n)
    return np.array(throws), false, lost


def main(parts=5000, seed=1):
    t0 = time.process_time()
    multi = policy('120:600:20')       # its start set is the parts' for both policies
    for name, planned in (('sensor-based 120:600:20', multi), ('one speed 320', policy('320'))):
        arm, res, d = planned
        th, false, lost = feed(arm, res, d, starts(multi[2], parts, seed),
                               np.random.default_rng(seed + 1000))
        done = th[np.isfinite(th)]
        print(json.dumps({'policy': name, 'parts': parts, 'seed': seed,
                          'never': int(th.size - done.size),
                          'mean': round(float(done.mean()), 2),
                          'p95': float(np.percentile(done, 95)), 'worst': float(done.max()),
                          'false_readies': int(false), 'lost': lost}))
    print(f'cpu {time.process_time() - t0:.0f} s')


if __name__ == '__main__':
    main(*(int(a) for a in sys.argv[1:3]))
