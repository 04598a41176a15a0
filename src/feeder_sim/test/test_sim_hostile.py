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

The real PredictorNode runs in-process (own context, own domain), configured and
active; its one subscription callback (``cycle_status``, found by topic) is called with
hypothesis-generated reports (feeder_interfaces/CycleStatus with any value each field holds) as
a subscriber receives them. No exception may escape, its count of bad statuses (/diagnostics)
is exactly the number the parser refuses, and a valid cycle still gets its prediction.
"""

import pathlib
import time

from builtin_interfaces.msg import Time
from feeder_common import messages
# tests/ (test support in no package) is on sys.path by pytest.ini
from feeder_testing import reserve_domain_id
from hostile_messages import statuses, wire
from hypothesis import given, HealthCheck, settings, strategies as st
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter

REPO = pathlib.Path(__file__).resolve().parents[3]

TRIANGLE = str(REPO / 'scenes' / 'triangle.yaml')
NS = '/hostile'
STAMP = 1_800_000_000_000_000_000


def spy(node, topic, parse=lambda msg: msg):
    """Return the list that every message ``node`` publishes on ``topic`` is appended to."""
    pub = next(p for p in node.publishers if p.topic_name == topic)
    sent, publish = [], pub.publish

    def record(msg):
        sent.append(parse(msg))
        publish(msg)

    pub.publish = record
    return sent


class Predictor:
    """The predictor in its own context: its callback by topic, what it publishes."""

    def __init__(self):
        from feeder_common.node import autostart
        from feeder_sim.predictor_node import PredictorNode
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=reserve_domain_id())
        self.node = PredictorNode(context=self.ctx, namespace=NS, parameter_overrides=[
            Parameter('scene', value=TRIANGLE), Parameter('diagnostic_updater.period', value=0.1)])
        autostart(self.node)
        self.on = {sub.topic_name: sub.callback for sub in self.node.subscriptions}
        assert set(self.on) == {f'{NS}/cycle_status'}, self.on
        self.states = spy(self.node, f'{NS}/predicted/state', messages.parse_predicted_state)
        self.diagnostics = spy(self.node, '/diagnostics')
        self.refused = 0
        self.executor = SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)

    def status(self, msg):
        try:
            messages.parse_cycle_status(msg)
        except ValueError:
            self.refused += 1
        self.on[f'{NS}/cycle_status'](msg)

    def bad_status(self):
        """Return the count of bad statuses in the predictor's next /diagnostics message."""
        n = len(self.diagnostics)
        end = time.monotonic() + 2.0
        while len(self.diagnostics) == n and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)
        assert len(self.diagnostics) > n, 'no /diagnostics'
        agreement = next(s for s in self.diagnostics[-1].status
                         if s.name.endswith(': sensor agreement'))
        return int({kv.key: kv.value for kv in agreement.values}['bad_status'])

    def valid_cycle(self):
        """Send a valid completed cycle (seq 0: never a jump); return its state, or None."""
        n = len(self.states)
        self.status(wire(messages.cycle_status(0, True, '', True, STAMP, 'test')))
        return next((s for s in self.states[n:] if s.seq == 0), None)

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.ctx)


@pytest.fixture(scope='module')
def predictor():
    p = Predictor()
    try:
        yield p
    finally:
        p.close()


# Issue 20's killers in typed fields: numbers beyond every bound, codes no driver writes.
KILLERS = [{'stamp': Time(sec=-2**31, nanosec=2**32 - 1)}, {'stamp': Time(sec=-1)},
           {'stamp': Time(sec=5, nanosec=10**9)}, {'seq': 2**64 - 1}, {'seq': 2**63},
           {'sensor': 127}, {'sensor': -1}, {'outcome': 'fired'}, {'outcome': 'Completed'},
           {'reason': 'x'}, {'hardware_id': 'h' * 4097}, {'session': 'AB12'},
           {'mac': [1] * 31}]


def test_the_killer_reports_of_issue_20_are_counted_not_followed(predictor):
    # Before: its stamp reached time_msg (Time(sec=10**391...)): an exception, node dead.
    for change in KILLERS:
        msg = messages.cycle_status(7, True, '', True, STAMP, 'forger')
        for name, value in change.items():
            setattr(msg, name, value)
        predictor.status(wire(msg))
    assert predictor.refused == len(KILLERS) and predictor.bad_status() == len(KILLERS)
    assert not predictor.states
    assert predictor.valid_cycle() is not None


@settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.lists(statuses(), min_size=1, max_size=5))
def test_no_status_crashes_the_predictor(predictor, msgs):
    for msg in msgs:
        predictor.status(msg)


def test_the_predictor_counted_every_refusal_and_still_follows_cycles(predictor):
    assert predictor.refused > 100
    assert predictor.bad_status() == predictor.refused
    state = predictor.valid_cycle()
    assert state is not None, 'a valid cycle got no prediction after the hostile statuses'
    assert state.stamp_ns == STAMP
