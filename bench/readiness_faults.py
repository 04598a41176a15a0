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
False and missed readies of ReadinessMonitor with a flaky sensor, the throw map as the truth.

ROS-free (src/feeder_monitor/test/readiness_faults.py). For each spurious = missed rate, each
seed, with and without seq faults: false readies (part off the goal edge), spurious readies
(true bit 0), missed readies (true detection on the goal edge after settling), anomalies, and
what two other ready rules would give on the same run ('allowed': any consistent state may
show a detection; 'expected': every one shows it). Asserts nothing. Usage (after
``. scripts/setup.sh``):

    python bench/readiness_faults.py [--scene scenes/triangle.yaml] [--cycles 20000]
"""

import argparse
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parents[1]
# feeder_monitor's test support (readiness_faults); the package itself from the colcon install
sys.path.insert(0, str(REPO / 'src' / 'feeder_monitor' / 'test'))

from feeder_monitor.readiness import limit_set_orbit, rules_from_analysis  # noqa: E402
from readiness_faults import run_faults, truth_orbit  # noqa: E402
from throwmap import analyse, load_scene  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument('--scene', default=str(REPO / 'scenes' / 'triangle.yaml'))
    ap.add_argument('--cycles', type=int, default=20000)
    ap.add_argument('--seeds', type=int, default=3)
    args = ap.parse_args()
    scene = load_scene(args.scene)
    an = analyse(scene)
    rules = rules_from_analysis(scene, an, limit_set_orbit(scene, an, 20000))
    print(f'{scene.name}: prediction {rules.prediction.as_dict() if rules.prediction else None}'
          f' {rules.prediction_off}; settle {rules.settle_cycles}')
    truth = truth_orbit(scene, scene.default_start(), int(args.cycles * 1.5) + 200)
    for resettle in (False, True):
        for rate in (0.0, 0.01, 0.05):
            for jumps in (0.0, 0.002):
                for seed in range(1, args.seeds + 1):
                    run = run_faults(scene, rules, args.cycles, rate, rate, jumps, jumps / 2,
                                     seed=seed, truth=truth, resettle_on_any_anomaly=resettle)
                    alt = ', '.join(f"{k}: false {v['false']} missed {v['missed']}"
                                    for k, v in run.alt.items())
                    print(f'resettle {resettle!s:5} rate {rate:.2f} seq faults {jumps:.3f} '
                          f'seed {seed}: {run.line()} | {alt}', flush=True)


if __name__ == '__main__':
    main()
