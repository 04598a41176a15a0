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
Issue 11 item 6: the triangle's chosen design on the node graph, with bounded release noise.

The sim stands in for the hardware with the design scene of `throwmap design-search`
(docs/design/triangle_design.yaml) plus release errors uniform within the robustness floor
(s = 0.005: +-s w, +-s d_min) and writes its truth log; the monitor runs on the noise-free
design scene, as it would beside a real feeder. Every verdict is checked against the true
part (no false ready) and the readies per cycle after the warm-up and the settling (issue 20:
no ready while a pattern check is off) against the design's prediction (a 99.7 % Wilson
interval that fails when the rate is off by about 40 %).
The long run: bench/design_graph.py.
"""

from feeder_common.messages import parse_cycle_status
from feeder_monitor.feed_check import design_prediction, judge_feed
from feeder_nodes import (monitor, predictor, REPO, run_cycles, sim_as_hardware,
                          watch_monitor)
from feeder_sim.truth import read_truth_log
from throwmap import load_scene
from throwmap.search import noisy_design_scene, write_scene

DESIGN = REPO / 'docs' / 'design' / 'triangle_design.yaml'
FLOOR = 0.005       # the --robust floor of the search that chose it (docs/design.md section 6)
CYCLES = 500        # >= 400 after the design's warm-up and settling (70 throws for it)
PERIOD = 0.01


def test_the_chosen_design_feeds_as_predicted_with_no_false_ready(graph, ros, tmp_path):
    design = load_scene(str(DESIGN))
    noisy = tmp_path / 'noisy_design.yaml'
    write_scene(noisy_design_scene(design, FLOOR, 'uniform', seed=3), noisy)
    truth_path = tmp_path / 'truth.jsonl'
    sim_as_hardware(graph, f'cycle_period:={PERIOD}', f'truth_log:={truth_path}',
                    scene=str(noisy))
    monitor(graph, scene=str(DESIGN))
    _, verdict_stream, statuses = watch_monitor(ros)
    run_cycles(ros, CYCLES, statuses, PERIOD)
    ros.spin_for(1.5)

    header, truth = read_truth_log(truth_path)
    status = {s.seq: s for s in (parse_cycle_status(m) for m in statuses.msgs)}
    assert sorted(truth) == sorted(status) == list(range(1, len(status) + 1))
    # The truth log is the state behind every reported bit.
    assert all(truth[k]['detected'] == bool(s.sensor) for k, s in status.items() if s.ok)
    an, rules = design_prediction(design)
    assert header['goal_edge'] == an.sensor.goal_edge
    assert header['sensor_radius'] == an.sensor.radius
    # The noise acted: some throws differ from the design's nominal map.
    nominal = design.model
    moved = [r for r in truth.values() if 'error' not in r and r['edge0'] >= 0
             and nominal.f(r['edge0'], r['R0'])[1] != r['R']]
    assert len(moved) > len(truth) // 2

    assert all(v.authentic for v in verdict_stream.parsed)
    verdicts = {v.seq: (v.ready, v.anomaly) for v in verdict_stream.parsed}
    assert len(verdicts) == len(verdict_stream.parsed)       # one per cycle
    assert len(verdicts) >= len(status) - 3       # discovery may miss the very first ones
    # Rates from the first cycle that can be ready: the warm-up and the settling done.
    first = max(rules.warmup_cycles, rules.settle_cycles)
    assert not any(ready for seq, (ready, _) in verdicts.items() if seq <= first)
    assert len(status) - first >= 400
    report = judge_feed(verdicts, truth, an.sensor.goal_edge, an.sensor.detection_rate,
                        first, z=3.0)
    print(report.line())
    assert report.false_readies == 0 and report.missing_truth == 0
    assert report.readies > 0
    assert report.consistent, report.line()


def test_a_truth_log_is_the_stand_ins_and_needs_a_writable_path(graph, ros, tmp_path):
    # The predictor has no true part: truth_log is not one of its parameters.
    pred = predictor(graph, f'truth_log:={tmp_path / "truth.jsonl"}', scene=str(DESIGN))
    hw = sim_as_hardware(graph, f'truth_log:={tmp_path / "missing" / "truth.jsonl"}',
                         scene=str(DESIGN))
    line = 'parameter truth_log is not a parameter of predictor_node; ignored'
    ros.spin_until(lambda: line in graph.log(pred), 60.0, line)
    assert pred.poll() is None
    assert hw.wait(timeout=60) == 2
    assert 'cannot open it for writing' in graph.log(hw)
    assert not (tmp_path / 'truth.jsonl').exists()
