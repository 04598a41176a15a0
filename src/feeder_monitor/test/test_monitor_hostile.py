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
Issue 20 (attack 3, deliverable 5): no message crashes the monitor; bad input is counted.

The real MonitorNode runs in-process (own context, own domain); each of its subscription
callbacks (``proximity``, ``cycle_status``, ``cycle_fired``, the driver's ``transition_event``,
found by topic among the node's subscriptions) is called with hypothesis-generated messages as
a subscriber receives them: cycle reports (feeder_interfaces/CycleStatus) with any value each
field holds, Ranges and transition events (tests/hostile_messages.py). No exception may escape,
the node's own count of bad input (/diagnostics) is exactly the number of messages the parsers
refuse, and afterwards a valid cycle still gets its verdict.
"""

import pathlib
import time

from builtin_interfaces.msg import Time
from feeder_common import auth, messages
# tests/ (test support in no package) is on sys.path by pytest.ini
from feeder_testing import reserve_domain_id
from hostile_messages import ranges, statuses, TRANSITION_EVENTS, wire
from hypothesis import given, HealthCheck, settings, strategies as st
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter

REPO = pathlib.Path(__file__).resolve().parents[3]

TRIANGLE = str(REPO / 'scenes' / 'triangle.yaml')
NS = '/hostile'


def spy(node, topic, parse=lambda msg: msg):
    """Return the list that every message ``node`` publishes on ``topic`` is appended to."""
    pub = next(p for p in node.publishers if p.topic_name == topic)
    sent, publish = [], pub.publish

    def record(msg):
        sent.append(parse(msg))
        publish(msg)

    pub.publish = record
    return sent


class Harness:
    """The monitor in its own context: its callbacks by topic, what it publishes."""

    def __init__(self, key_file):
        from feeder_common.node import autostart
        from feeder_monitor.monitor_node import MonitorNode
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=reserve_domain_id())
        self.node = MonitorNode(context=self.ctx, namespace=NS, parameter_overrides=[
            Parameter('scene', value=TRIANGLE), Parameter('orbit_throws', value=1000),
            Parameter('diagnostic_updater.period', value=0.1),
            Parameter('key_file', value=str(key_file))])
        autostart(self.node)        # configure + activate, as the run helper does
        self.signer = messages.CycleSigner(auth.load_key(key_file), f'{NS}/feeder_driver')
        self.seq = 0
        self.on = {sub.topic_name: sub.callback for sub in self.node.subscriptions}
        assert set(self.on) == {f'{NS}/proximity', f'{NS}/cycle_status', f'{NS}/cycle_fired',
                                f'{NS}/feeder_driver/transition_event'}, self.on
        self.verdicts = spy(self.node, f'{NS}/edge1_verdict')
        self.diagnostics = spy(self.node, '/diagnostics')
        self.refused = 0            # messages the parsers refuse, sent so far
        self.executor = SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)

    def spin_until(self, cond, timeout):
        end = time.monotonic() + timeout
        while not cond() and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)
        return cond()

    def status(self, msg):
        self.refused += _refused(messages.parse_cycle_status, msg)
        self.on[f'{NS}/cycle_status'](msg)

    def fired(self, msg):
        self.refused += _refused(messages.parse_cycle_fired, msg)
        self.on[f'{NS}/cycle_fired'](msg)

    def proximity(self, msg):
        self.refused += _proximity_refused(msg)
        self.on[f'{NS}/proximity'](msg)

    def transition(self, msg):
        self.on[f'{NS}/feeder_driver/transition_event'](msg)

    def bad_input(self):
        """Return the count of bad input in the monitor's next /diagnostics message."""
        n = len(self.diagnostics)
        assert self.spin_until(lambda: len(self.diagnostics) > n, 2.0), 'no /diagnostics'
        inputs = next(s for s in self.diagnostics[-1].status if s.name.endswith(': inputs'))
        return int({kv.key: kv.value for kv in inputs.values}['bad_input'])

    def valid_cycle(self):
        """Send one valid signed cycle (proximity, then cycle_status); its verdict or None."""
        self.seq += 1
        seq, stamp = self.seq, time.time_ns()
        n = len(self.verdicts)
        self.proximity(wire(messages.proximity(stamp, True, 0.02)))
        self.status(wire(self.signer.cycle_status(seq, True, '', True, stamp, 'test')))
        self.spin_until(lambda: any(v.seq == seq for v in self.verdicts[n:]), 2.0)
        return next((v for v in self.verdicts[n:] if v.seq == seq), None)

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.ctx)


@pytest.fixture(scope='module')
def harness(tmp_path_factory):
    key_file = tmp_path_factory.mktemp('key') / 'hmac.key'
    auth.ensure_key(key_file)
    h = Harness(key_file)
    try:
        yield h
    finally:
        h.close()


def _refused(parse, msg):
    try:
        return parse(msg) is None
    except ValueError:
        return True


def _proximity_refused(msg):
    return _refused(messages.proximity_detected, msg) or \
        _refused(lambda m: messages.time_ns(m.header.stamp), msg)


# Issue 20's killers in typed fields: numbers beyond every bound, codes no driver writes; the
# change of a signed cycle_status, and of a signed cycle_fired.
KILLERS = [
    ({'stamp': Time(sec=-2**31, nanosec=2**32 - 1)},) * 2, ({'stamp': Time(sec=-1)},) * 2,
    ({'stamp': Time(sec=5, nanosec=10**9)},) * 2, ({'seq': 2**64 - 1},) * 2,
    ({'seq': 2**63},) * 2, ({'sensor': 127},) * 2, ({'sensor': -1}, {'sensor': 1}),
    ({'outcome': 'fired'}, {'outcome': 'completed'}), ({'mac': [1] * 33},) * 2,
    ({'session': 'AB12'},) * 2, ({'reason': 'x'}, {'reason': 'x'}),
    ({'hardware_id': 'h' * 4097},) * 2]


def _changed(msg, change):
    for name, value in change.items():
        setattr(msg, name, value)
    return wire(msg)


def test_the_killer_reports_of_issue_20_are_counted_and_the_next_cycle_judged(harness):
    # Before: OverflowError in stamps.ns_seconds out of the cycle_status callback: node dead.
    # Each is the signed report of a cycle (seq 7) with one field changed.
    for status, fired in KILLERS:
        harness.status(_changed(harness.signer.cycle_status(7, True, '', True, time.time_ns(),
                                                            'test'), status))
        harness.fired(_changed(harness.signer.cycle_fired(7, time.time_ns(), 'test'), fired))
    assert harness.refused == 2 * len(KILLERS)
    assert harness.bad_input() == 2 * len(KILLERS)
    assert not [v for v in harness.verdicts if v.seq in (7, 2**63, 2**64 - 1)]
    assert harness.valid_cycle() is not None


MESSAGES = st.lists(st.one_of(statuses().map(lambda m: ('status', m)),
                              statuses().map(lambda m: ('fired', m)),
                              ranges().map(lambda m: ('proximity', m)),
                              TRANSITION_EVENTS.map(lambda m: ('transition', m))),
                    min_size=1, max_size=6)


@settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck))
@given(MESSAGES)
def test_no_message_crashes_the_monitor(harness, msgs):
    for kind, msg in msgs:
        getattr(harness, kind)(msg)
    harness.executor.spin_once(timeout_sec=0)     # its timers too (pair expiry, heartbeat)


def test_the_monitor_counted_every_refusal_and_still_judges_cycles(harness):
    assert harness.refused > 100
    assert harness.bad_input() == harness.refused
    verdict = harness.valid_cycle()
    assert verdict is not None, 'a valid cycle got no verdict after the hostile messages'


def test_a_write_the_middleware_refuses_does_not_end_the_monitor(harness):
    """
    A reliable writer refuses a write when a stalled reader leaves its history full.

    rclpy raises RCLError ("cannot publish data", seen in CI from a test's own writer); the
    monitor publishes from its callbacks and timers, so before this raised out of the
    cycle_status callback and ended the node. Now the refusal is logged, the cycle's verdict
    is lost to the readers (edge1_ready ages past its deadline), and the next cycle is judged.
    """
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    topics = (f'{NS}/edge1_ready', f'{NS}/edge1_verdict', '/diagnostics')
    pubs = [p for p in harness.node.publishers if p.topic_name in topics]
    assert len(pubs) == len(topics), [p.topic_name for p in harness.node.publishers]
    refused = []

    def refuse(msg):
        refused.append(msg)
        raise _rclpy.RCLError('cannot publish data')

    saved = [p.publish for p in pubs]
    try:
        for p in pubs:
            p.publish = refuse
        assert harness.valid_cycle() is None      # judged, but nothing reached the readers
        harness.spin_until(lambda: False, 0.3)    # the heartbeat and /diagnostics refused too
    finally:
        for p, publish in zip(pubs, saved):
            p.publish = publish
    kinds = {type(m).__name__ for m in refused}
    assert kinds == {'Verdict', 'DiagnosticArray'}, kinds
    verdict = harness.valid_cycle()
    assert verdict is not None, 'no verdict for the cycle after the refused writes'
