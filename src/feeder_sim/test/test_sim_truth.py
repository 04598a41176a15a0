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

"""The hardware stand-in's truth log (feeder_sim.truth), without ROS."""

import json
import math
import pathlib

from feeder_sim.truth import read_truth_log, TruthLog, TruthLogError
import pytest
from throwmap import load_scene, PartOnArm

SCENES = pathlib.Path(__file__).resolve().parents[3] / 'scenes'


def test_every_cycle_is_the_state_the_part_was_thrown_to(tmp_path):
    scene = load_scene(str(SCENES / 'triangle.yaml'))
    part = PartOnArm(scene, sensor_radius=0.27)
    path = tmp_path / 'truth.jsonl'
    log = TruthLog(str(path), {'goal_edge': 1, 'sensor_radius': 0.27})
    throws = []
    for seq in range(1, 41):
        t = part.throw()
        throws.append(t)
        log.cycle(seq, 1000 * seq, t, part.sees())
    log.cycle(41, 41_000, error='throw outside the domain of f')
    # flushed per record: readable while the log is open
    header, cycles = read_truth_log(path)
    log.close()
    assert header == {'type': 'header', 'goal_edge': 1, 'sensor_radius': 0.27}
    assert sorted(cycles) == list(range(1, 42))
    model = scene.model
    for seq, t in enumerate(throws, 1):
        rec = cycles[seq]
        assert (rec['edge'], rec['R'], rec['kind']) == model.f(rec['edge0'], rec['R0'])
        assert rec['detected'] == rec['seen'] == t.detected
    assert cycles[2]['edge0'] == cycles[1]['edge'] and cycles[2]['R0'] == cycles[1]['R']
    assert cycles[41]['error'] and 'edge' not in cycles[41]


def test_a_lost_part_is_null_not_nan(tmp_path):
    scene = load_scene(str(SCENES / 'triangle.yaml'))
    part = PartOnArm(scene, sensor_radius=0.27)
    part.edge, part.R = -1, math.nan      # lost: an empty throw
    path = tmp_path / 'truth.jsonl'
    log = TruthLog(str(path), {})
    log.cycle(1, 0, part.throw(), False)
    log.close()
    rec = json.loads(path.read_text().splitlines()[1])      # strict JSON: no NaN
    assert rec['edge'] == -1 and rec['R'] is None and rec['kind'] == 'lost'


def test_an_unwritable_path_names_the_file_and_the_fix(tmp_path):
    with pytest.raises(TruthLogError, match='cannot open it for writing.*writable path'):
        TruthLog(str(tmp_path / 'missing' / 'truth.jsonl'), {})
