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
Issue 20 (deliverable 5): no ``cycle_status`` crashes the predictor; a refused one counts.

The real SimNode in predictor mode runs in-process (own context, own domain), configured and
active; its one subscription callback (``cycle_status``) is called with hypothesis-generated
statuses as a subscriber receives them (tests/hostile_messages.py). No exception may escape,
every refused status counts in ``bad_status``, and a valid cycle still gets its prediction.
"""

import pathlib
import sys

from feeder_common import messages
from hypothesis import given, HealthCheck, settings, strategies as st
import pytest
import rclpy
from rclpy.context import Context
from rclpy.parameter import Parameter

REPO = pathlib.Path(__file__).resolve().parents[3]
# tests/: the hostile messages and the domain picker (test support, in no package)
sys.path.insert(0, str(REPO / 'tests'))
from feeder_testing import reserve_domain_id  # noqa: E402, I100
from hostile_messages import KILLER_STAMP, statuses, wire  # noqa: E402

TRIANGLE = str(REPO / 'scenes' / 'triangle.yaml')


class Predictor:
    """The predictor in its own context; every predicted/state it publishes, parsed."""

    def __init__(self):
        from feeder_common.node import autostart
        from feeder_sim.sim_node import SimNode
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=reserve_domain_id())
        self.node = SimNode(context=self.ctx, namespace='/hostile',
                            parameter_overrides=[Parameter('scene', value=TRIANGLE)])
        autostart(self.node)
        self.states = []
        pub = self.node._pubs['state']
        publish = pub.publish

        def spy(msg):
            self.states.append(messages.parse_predicted_state(msg))
            publish(msg)

        pub.publish = spy

    def valid_cycle(self):
        """Send the next valid completed cycle; return its published state, or None."""
        last = self.node._last_followed_seq
        seq = last + 1 if last is not None and last < messages.MAX_SEQ else 0
        n = len(self.states)
        self.node._on_cycle_status(wire(messages.cycle_status(seq, True, 'completed', True,
                                                              1_800_000_000_000_000_000,
                                                              'test')))
        return next((s for s in self.states[n:] if s.seq == seq), None)

    def close(self):
        self.node.destroy_node()
        rclpy.shutdown(context=self.ctx)


@pytest.fixture(scope='module')
def predictor():
    p = Predictor()
    try:
        yield p
    finally:
        p.close()


def test_the_killer_status_of_issue_20_is_counted_not_followed(predictor):
    # Before: its stamp reached time_msg (Time(sec=10**391...)): AssertionError, node dead.
    counts = predictor.node._counts
    bad = counts['bad_status']
    for stamp in (KILLER_STAMP, '2147483648.000000000'):
        msg = messages.cycle_status(7, True, 'completed', True, 0, 'forger')
        msg.values[2].value = stamp
        predictor.node._on_cycle_status(wire(msg))
    assert counts['bad_status'] == bad + 2
    assert predictor.valid_cycle() is not None


def _refused(msg):
    try:
        messages.parse_cycle_status(msg)
    except ValueError:
        return True
    return False


@settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.lists(statuses(), min_size=1, max_size=5))
def test_no_status_crashes_the_predictor_and_every_refusal_counts(predictor, msgs):
    counts = predictor.node._counts
    for msg in msgs:
        bad = counts['bad_status']
        predictor.node._on_cycle_status(msg)
        assert counts['bad_status'] == bad + _refused(msg)


def test_the_predictor_still_follows_cycles_after_the_fuzzing(predictor):
    assert predictor.node._counts['bad_status'] > 0
    state = predictor.valid_cycle()
    assert state is not None, 'a valid cycle got no prediction after the hostile statuses'
    assert state.stamp_ns == 1_800_000_000_000_000_000
