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
Issue 11 item 6: chosen designs proven on the node graph, with bounded release noise. Not in CI.

For each design scene written by `throwmap design-search` (default: the triangle's,
docs/design/triangle_design.yaml, at the floor 0.005 of its search, and the house part's,
docs/design/house_base_design.yaml, at its search's floor 0.0005): the sim stands in for the
hardware on the design plus release errors within the floor's box (every throw's speed within
+-s w and offset within +-s d_min, effect release_noise with distribution uniform or corner,
throwmap.search.noisy_design_scene) and writes its truth log; a predictor and the monitor run on
the noise-free design scene, as beside a real feeder. Processes on loopback DDS, own
ROS_DOMAIN_ID. After N cycles the edge1_verdict stream is judged against the truth
(feeder_monitor.feed_check; every verdict's signature checked under the run's own key):
readies per cycle after the warm-up and the settling with a 95 % Wilson interval
against the prediction (the monitor's analysis: the sensor's detection rate in the limit set;
the design kernel's figure printed beside it), false readies (must be 0), anomalies.

Usage (after ``. scripts/setup.sh``):

    python bench/design_graph.py [--cycles 3000] [--period 0.01] [--distribution uniform]
        [--seed 1] [--out DIR] [DESIGN.yaml:FLOOR ...]

Exit status 0 when no run has a false ready or a cycle without truth and every run ran, else
1 (a node that fails, e.g. the stand-in whose analysis of the noisy scene leaves the domain of
f, is reported with its log and the next design runs). The interval
treats cycles as independent draws; the orbit's cycles are correlated (a limit set is close to
periodic), so it is a guide, not a test. The processes, the domain and the node are the
harness's (tests/feeder_testing.py through graph_bench; the one sys.path line adds tests/).
"""

import argparse
import os
import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'tests'))
from feeder_testing import Processes, REPO, use_domain  # noqa: E402
from graph_bench import BenchNode  # noqa: E402

DEFAULT_RUNS = (f'{REPO}/docs/design/triangle_design.yaml:0.005',
                f'{REPO}/docs/design/house_base_design.yaml:0.0005')


class Listener(BenchNode):
    """The bench's node: collects cycle_status and edge1_verdict, enables the stand-in."""

    prog = 'design_graph'

    def __init__(self, procs):
        from feeder_interfaces.msg import CycleStatus, Verdict
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        super().__init__('feeder_design_graph', procs)
        qos = QoSProfile(depth=10_000, reliability=ReliabilityPolicy.RELIABLE)
        self.statuses, self.verdicts = [], []
        self.status_sub = self.node.create_subscription(CycleStatus, '/feeder/cycle_status',
                                                        self.statuses.append, qos)
        self.verdict_sub = self.node.create_subscription(Verdict, '/feeder/edge1_verdict',
                                                         self.verdicts.append, qos)


def kernel_prediction(scene):
    """Return the design search's own figure (throwmap.design): proven readies per throw."""
    from throwmap import design as D
    res = D.evaluate_grid(scene, [scene.h], [scene.release_speed], [scene.goal_edge], [0.25],
                          workers=1)
    return float(res.column('readies_per_throw', 0, 0)[0])


def run_one(design_path, floor, args, out):
    from feeder_common import auth
    from feeder_common.messages import check_verdict
    from feeder_monitor.feed_check import design_prediction, judge_feed
    from feeder_sim.truth import read_truth_log
    from throwmap import load_scene
    from throwmap.search import noisy_design_scene, write_scene
    design = load_scene(str(design_path))
    an, rules = design_prediction(design)
    name = design.name
    noisy = out / f'{name}_noisy.yaml'
    write_scene(noisy_design_scene(design, floor, args.distribution, args.seed), noisy)
    truth_path = out / f'{name}_truth.jsonl'
    logs = out / name
    logs.mkdir(exist_ok=True)
    procs = Processes(logs, error=SystemExit, prog='design_graph')
    lis = Listener(procs)
    ns = ['-r', '__ns:=/feeder']
    key_file = logs / 'hmac.key'        # the run's own key (mode 0600)
    key = auth.ensure_key(key_file)
    k = ['-p', f'key_file:={key_file}']
    try:
        procs.start('feeder_sim', 'standin_node', '--ros-args', *ns, '-r',
                    '__node:=feeder_driver', '-p',
                    f'scene:={noisy}', '-p', f'cycle_period:={args.period}', '-p',
                    f'truth_log:={truth_path}', *k, name='sim_hw')
        procs.start('feeder_sim', 'predictor_node', '--ros-args', *ns, '-p',
                    f'scene:={design_path}', name='predictor')
        procs.start('feeder_monitor', 'monitor_node', '--ros-args', *ns, '-p',
                    f'scene:={design_path}', *k, name='monitor')
        # The writers matched their readers, by their own accounts: the stand-in's
        # cycle_status the monitor's, the predictor's and ours; the monitor's verdicts ours.
        lis.wait_remote_matched('/feeder/feeder_driver', readers={
            '/feeder/cycle_status': 3, '/feeder/proximity': 1, '/feeder/cycle_fired': 1},
            timeout=120)
        lis.wait_remote_matched('/feeder/feeder_monitor', readers={'/feeder/edge1_verdict': 1},
                                timeout=120)
        t0 = time.monotonic()
        lis.enable(True)
        lis.spin_until(lambda: len(lis.statuses) >= args.cycles,
                       60 + 3 * args.cycles * args.period, f'{args.cycles} cycles')
        lis.enable(False)
        wall = time.monotonic() - t0
        lis.spin_until(lambda: len(lis.verdicts) >= len(lis.statuses), 20, 'the last verdicts')
        lis.spin_for(1.0)       # late messages
    finally:
        lis.close()
        procs.stop_all()
    header, truth = read_truth_log(truth_path)
    verdicts, unsigned = {}, 0
    for v in lis.verdicts:
        ok = check_verdict(v, key, '/feeder/feeder_monitor', 0, max_age_s=float('inf')).authentic
        unsigned += not ok
        verdicts[v.seq] = (v.ready and ok, v.anomaly or ('' if ok else 'unsigned verdict'))
    if unsigned:
        print(f'  {unsigned} verdicts NOT signed by /feeder/feeder_monitor under the run key')
    # Rates from the first cycle that can be ready: the warm-up and the settling done.
    first = max(rules.warmup_cycles, rules.settle_cycles)
    report = judge_feed(verdicts, truth, an.sensor.goal_edge, an.sensor.detection_rate, first)
    kernel = kernel_prediction(design)
    fired = len(truth)
    print(f'\n{name}: h {design.h * 100:.4f} cm, {design.release_speed * 57.29578:.2f} deg/s, '
          f'goal edge {an.sensor.goal_edge}, sensor {an.sensor.radius * 100:.2f} cm, warm-up '
          f'{rules.warmup_cycles} cycles, settling {rules.settle_cycles}; release errors '
          f'{args.distribution} within '
          f'+-{floor * design.release_speed * 57.29578:.3f} deg/s, '
          f'+-{floor * design.part.d_min * 1000:.3f} mm (s = {floor})')
    print(f'  {fired} cycles fired in {wall:.1f} s, {len(verdicts)} verdicts')
    print(f'  {report.line()}')
    print(f'  predicted: monitor analysis {report.predicted:.4f}, design kernel {kernel:.4f} '
          'readies per throw')
    return report


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    ap.add_argument('runs', nargs='*', default=list(DEFAULT_RUNS), metavar='DESIGN:FLOOR',
                    help='design scene and the joint robustness floor s of its search')
    ap.add_argument('--cycles', type=int, default=3000)
    ap.add_argument('--period', type=float, default=0.01, help='cycle_period of the stand-in')
    ap.add_argument('--distribution', choices=('uniform', 'corner'), default='uniform')
    ap.add_argument('--seed', type=int, default=1)
    ap.add_argument('--out', type=pathlib.Path, default=None,
                    help='directory for scenes, truth logs and node logs (default: temporary)')
    args = ap.parse_args()
    runs = []
    for spec in args.runs:
        path, _, floor = spec.rpartition(':')
        try:
            runs.append((pathlib.Path(path).resolve(), float(floor)))
        except ValueError:
            ap.error(f'{spec!r}: give DESIGN.yaml:FLOOR, e.g. docs/design/triangle_design.yaml'
                     ':0.005')
    out = (args.out or pathlib.Path(tempfile.mkdtemp(prefix='feeder-design-graph-'))).resolve()
    out.mkdir(parents=True, exist_ok=True)
    domain, lock = use_domain()
    load = ', '.join(f'{x:.1f}' for x in os.getloadavg())
    print(f'design_graph: {args.cycles} cycles per design at cycle_period {args.period} s, '
          f'ROS_DOMAIN_ID={domain} (loopback), load average {load}, output in {out}',
          flush=True)
    bad = 0
    try:
        for path, floor in runs:
            try:
                report = run_one(path, floor, args, out)
            except SystemExit as exc:     # a node failed: say which and why, go on
                print(f'\n{path.name} at s = {floor}: the run failed: {exc}', flush=True)
                bad += 1
                continue
            bad += report.false_readies + report.missing_truth
    finally:
        lock.close()
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main())
