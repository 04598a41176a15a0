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
``predicted/limit_set`` and ``predicted/analysis`` carry the scene's analysis field by field.

feeder_common.messages.limit_set_msg and analysis_msg build them from an analysis' ``as_dict()``
(what the predictor publishes); each field is compared here with the throwmap objects the
analysis of the triangle scene is made of (throwmap.analyse), not with numbers copied from a
run: the limit set's pattern, bands, jog counts and cycle lengths, the design radii, the basin,
the sensor design and the pull sample.
"""

import dataclasses
import math
import pathlib

from feeder_common import messages
from feeder_interfaces.msg import Analysis, LimitSet
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from throwmap import analyse, load_scene

REPO = pathlib.Path(__file__).resolve().parents[3]
TRIANGLE = REPO / 'scenes' / 'triangle.yaml'
SCENE_HASH = 2**64 - 1          # the largest a uint64 holds


@pytest.fixture(scope='module')
def analysis():
    return analyse(load_scene(str(TRIANGLE)))


def wire(msg):
    return deserialize_message(serialize_message(msg), type(msg))


def check_limit_set(msg, ls):
    """Check a LimitSet message field by field against a throwmap.LimitSet ``ls``."""
    assert list(msg.pattern) == list(ls.pattern)
    # One band per edge of the limit set, in edge order; -1 jogs where none were counted.
    assert [b.edge for b in msg.bands] == sorted(ls.bands)
    for band in msg.bands:
        assert (band.r_min, band.r_max) == tuple(ls.bands[band.edge])
        assert (band.jogs_min, band.jogs_max) == tuple(ls.jogs.get(band.edge, (-1, -1)))
    assert (msg.periodic, msg.transient) == (ls.periodic, ls.transient)
    lengths = ls.cycle_lengths
    if lengths:
        assert (msg.cycle_length_min, msg.cycle_length_max) == (min(lengths), max(lengths))
        assert msg.cycle_length_mean == pytest.approx(sum(lengths) / len(lengths), rel=1e-12)
    else:
        assert all(math.isnan(x) for x in (msg.cycle_length_min, msg.cycle_length_mean,
                                           msg.cycle_length_max))


def test_the_triangles_limit_set_is_carried_field_by_field(analysis):
    ls = analysis.limit_set
    assert len(ls.bands) == 3 and ls.cycle_lengths      # the scene's: a 3-edge cycle
    msg = wire(messages.limit_set_msg(ls.as_dict()))
    assert isinstance(msg, LimitSet)
    check_limit_set(msg, ls)


def test_an_edge_without_jog_counts_has_jogs_minus_one(analysis):
    ls = analysis.limit_set
    missing = sorted(ls.jogs)[0]
    fewer = dataclasses.replace(ls, jogs={e: j for e, j in ls.jogs.items() if e != missing})
    msg = wire(messages.limit_set_msg(fewer.as_dict()))
    check_limit_set(msg, fewer)
    (band,) = [b for b in msg.bands if b.edge == missing]
    assert (band.jogs_min, band.jogs_max) == (-1, -1)
    assert all(b.jogs_min >= 0 for b in msg.bands if b.edge != missing)


@pytest.mark.filterwarnings('ignore:All-NaN slice:RuntimeWarning',
                            'ignore:Mean of empty slice:RuntimeWarning')
def test_bands_come_in_edge_order_not_text_order(analysis):
    # as_dict() keys the bands by text: '10' sorts before '2' there, not on the message.
    ls = analysis.limit_set
    bands = {10: (0.2, 0.3), 2: (0.1, 0.15), 0: (0.05, 0.06)}
    other = dataclasses.replace(ls, pattern=(0, 10, 2), bands=bands,
                                jogs={10: (1, 2), 2: (0, 0)}, cycle_lengths=())
    msg = wire(messages.limit_set_msg(other.as_dict()))
    assert [b.edge for b in msg.bands] == [0, 2, 10]
    check_limit_set(msg, other)       # no cycle seen: the lengths are NaN


def test_the_triangles_analysis_is_carried_field_by_field(analysis):
    msg = wire(messages.analysis_msg(analysis.as_dict(), 'triangle', SCENE_HASH))
    assert isinstance(msg, Analysis)
    assert (msg.scene, msg.scene_hash) == ('triangle', SCENE_HASH)
    assert (msg.start_edge, msg.start_r) == analysis.start
    check_limit_set(msg.limit_set, analysis.limit_set)
    radii = analysis.radii
    assert [(e.edge, e.r_grasp, e.r_min, e.r_flip, e.r_max) for e in msg.edges] == [
        (row['edge'], row['R_grasp'], row['R_min'], row['R_flip'], row['R_max'])
        for row in radii['edges']]
    assert (msg.r_max_all, msg.invariant) == (radii['R_max_all'], radii['invariant'])
    assert [(x.edge, x.to_edge, x.r) for x in msg.escapes] == \
        [tuple(x) for x in radii['escapes']]
    assert {b.pattern: b.starts for b in msg.basin} == analysis.basin.summary()
    assert [b.pattern for b in msg.basin] == sorted(analysis.basin.summary())
    s = analysis.sensor
    assert (msg.goal_edge, msg.sensor_radius, msg.sensor_footprint, msg.guarantee_radius,
            msg.reach_radius, msg.detection_rate, msg.warmup_throws, msg.sensor_feasible) == \
        (s.goal_edge, s.radius, s.footprint, s.guarantee_radius, s.reach_radius,
         s.detection_rate, s.warmup_throws, s.feasible)
    pull = analysis.pull
    assert (msg.pull_throws, msg.pulling_throws, msg.worst_normal_force) == \
        (pull['throws'], pull['pulling'], pull['worst'])


def test_escapes_and_an_analysis_without_a_pull_sample(analysis):
    # The triangle's design is invariant and it has a pull sample: the other case, made up.
    escapes = [(1, -1, 0.3), (2, 0, 0.01)]
    radii = dict(analysis.radii, invariant=False, escapes=escapes)
    other = dataclasses.replace(analysis, radii=radii, pull=None)
    msg = wire(messages.analysis_msg(other.as_dict(), 'made up', 0))
    assert [(x.edge, x.to_edge, x.r) for x in msg.escapes] == escapes
    assert msg.invariant is False and msg.scene_hash == 0
    assert (msg.pull_throws, msg.pulling_throws) == (0, 0)
    assert math.isnan(msg.worst_normal_force)
