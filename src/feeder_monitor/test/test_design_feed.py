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
A design's predicted feed rate against the monitor's verdicts, with bounded throw errors.

Library level (no DDS; the graph run is tests/test_graph_design.py, docs/design.md): the part is
thrown with every release speed and offset drawn uniformly within +-s of the design (s below
its robustness), the sensor bit is the sensor geometry, and the monitor's ReadinessMonitor
(the rules the node derives from the scene) judges each cycle. Readies per cycle must match
the predicted proven readies per throw, and no ready may come while the part is on another
edge.
"""

import pathlib

from feeder_monitor.feed_check import design_prediction, judge_feed, truth_from_throw
from feeder_monitor.readiness import ReadinessMonitor
import numpy as np
import pytest
from throwmap import load_scene, sees
from throwmap.model import ThrowModel

TRIANGLE = pathlib.Path(__file__).resolve().parents[3] / 'scenes' / 'triangle.yaml'


@pytest.fixture(scope='module')
def triangle():
    scene = load_scene(str(TRIANGLE))
    return (scene,) + design_prediction(scene)


@pytest.mark.parametrize('s', [0.0, 0.004])
def test_readies_per_cycle_match_the_prediction_and_none_is_false(triangle, s):
    # s = 0.004: inside the paper design's joint robustness (about 0.008, docs/design.md).
    scene, an, rules = triangle
    monitor = ReadinessMonitor(rules)
    part, g = scene.part, scene.model.g
    h, w = scene.h, scene.release_speed
    dh, dw = s * part.d_min, s * w
    rng = np.random.default_rng(11)
    edge, R = scene.default_start()
    verdicts, truth = {}, {}
    for seq in range(1, 4001):
        model = ThrowModel(part, h + dh * rng.uniform(-1, 1), w + dw * rng.uniform(-1, 1), g)
        edge, R, _ = model.f(edge, R)
        seen = bool(sees(part, edge, R, an.sensor.radius, an.sensor.footprint))
        verdict = monitor.completed(seq, seen)
        verdicts[seq] = (verdict.ready, verdict.anomaly)
        truth[seq] = truth_from_throw(edge, seen)
    report = judge_feed(verdicts, truth, an.sensor.goal_edge, an.sensor.detection_rate,
                        rules.warmup_cycles)
    print(f's = {s}: {report.line()}')
    assert report.false_readies == 0 and report.missing_truth == 0
    # Issue 20: an anomaly makes the sensor suspect for 150 cycles (readiness.SUSPECT_CYCLES),
    # and the throw errors at s = 0.004 cause 3 pattern anomalies in 4000 cycles: 27 of 232
    # detections are then not proven (rate 0.048 against 0.058 predicted). At s = 0 none.
    assert report.rate == pytest.approx(report.predicted, rel=0.15 if s == 0 else 0.2)
