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
callbacks (``proximity``, ``cycle_status``, the driver's ``transition_event``) is called with
hypothesis-generated messages as a subscriber receives them (tests/hostile_messages.py). No
exception may escape, every refused message counts in ``bad_input``, and afterwards a valid
cycle still gets its verdict.
"""

import pathlib
import sys
import time

from feeder_common import messages
from hypothesis import given, HealthCheck, settings, strategies as st
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter

REPO = pathlib.Path(__file__).resolve().parents[3]
# tests/: the hostile messages and the domain picker (test support, in no package)
sys.path.insert(0, str(REPO / 'tests'))
from feeder_testing import reserve_domain_id  # noqa: E402, I100
from hostile_messages import (KILLER_STAMP, ranges, statuses,  # noqa: E402
                              TRANSITION_EVENTS, wire)

TRIANGLE = str(REPO / 'scenes' / 'triangle.yaml')


class Harness:
    """The monitor in its own context; every verdict it publishes, parsed."""

    def __init__(self):
        from feeder_monitor.monitor_node import MonitorNode
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=reserve_domain_id())
        self.node = MonitorNode(context=self.ctx, namespace='/hostile', parameter_overrides=[
            Parameter('scene', value=TRIANGLE), Parameter('orbit_throws', value=1000)])
        self.verdicts = []
        publish = self.node._verdict_pub.publish

        def spy(msg):
            self.verdicts.append(messages.parse_edge_verdict(msg))
            publish(msg)

        self.node._verdict_pub.publish = spy
        self.executor = SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)

    def spin_until(self, cond, timeout):
        end = time.monotonic() + timeout
        while not cond() and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)
        return cond()

    def valid_cycle(self, seq):
        """Send one valid cycle (proximity, then cycle_status); return its verdict or None."""
        stamp = time.time_ns()
        n = len(self.verdicts)
        self.node._on_proximity(wire(messages.proximity(stamp, True, 0.02)))
        self.node._on_cycle_status(wire(messages.cycle_status(seq, True, 'completed', True,
                                                              stamp, 'test')))
        self.spin_until(lambda: any(v.seq == seq for v in self.verdicts[n:]), 2.0)
        return next((v for v in self.verdicts[n:] if v.seq == seq), None)

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.ctx)


@pytest.fixture(scope='module')
def harness():
    h = Harness()
    try:
        yield h
    finally:
        h.close()


def next_seq(node):
    """Return the seq after the monitor's last one (0 if none, or at the top of the range)."""
    last = node._monitor.last_seq
    return last + 1 if last is not None and last < messages.MAX_SEQ else 0


def _refused(parse, msg):
    try:
        return parse(msg) is None
    except ValueError:
        return True


def _proximity_refused(msg):
    return _refused(messages.proximity_detected, msg) or \
        _refused(lambda m: messages.time_ns(m.header.stamp), msg)


def test_the_killer_status_of_issue_20_is_counted_and_the_next_cycle_judged(harness):
    # Before: OverflowError in stamps.ns_seconds out of _on_cycle_status, the node died.
    bad = harness.node._bad_input
    for stamp in (KILLER_STAMP, KILLER_STAMP + '.000000000', '2147483648.000000000'):
        msg = messages.cycle_status(7, True, 'completed', True, 0, 'forger')
        msg.values[2].value = stamp
        harness.node._on_cycle_status(wire(msg))
    for seq in (' 12 ', '\u0661\u0662', '999999_0'):
        msg = messages.cycle_status(7, True, 'completed', True, 0, 'forger')
        msg.values[0].value = seq
        harness.node._on_cycle_status(wire(msg))
    assert harness.node._bad_input == bad + 6
    assert not [v for v in harness.verdicts if v.seq in (7, 12, 9999990)]
    assert harness.valid_cycle(next_seq(harness.node)) is not None


MESSAGES = st.lists(st.one_of(statuses().map(lambda m: ('status', m)),
                              ranges().map(lambda m: ('proximity', m)),
                              TRANSITION_EVENTS.map(lambda m: ('transition', m))),
                    min_size=1, max_size=6)


@settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck))
@given(MESSAGES)
def test_no_message_crashes_the_monitor_and_every_refusal_counts(harness, msgs):
    node = harness.node
    for kind, msg in msgs:
        bad = node._bad_input
        if kind == 'status':
            node._on_cycle_status(msg)
            assert node._bad_input == bad + _refused(messages.parse_cycle_status, msg)
        elif kind == 'proximity':
            node._on_proximity(msg)
            assert node._bad_input == bad + _proximity_refused(msg)
        else:
            node._on_driver_transition(msg)
    harness.executor.spin_once(timeout_sec=0)     # its timers too (pair expiry, heartbeat)


def test_the_monitor_still_judges_cycles_after_the_fuzzing(harness):
    # Whatever the fuzzing left waiting for its other half expires first.
    harness.spin_until(lambda: harness.node._pairer.pending == (0, 0), 3.0)
    verdict = harness.valid_cycle(next_seq(harness.node))
    assert verdict is not None, 'a valid cycle got no verdict after the hostile messages'
    assert isinstance(verdict.ready, bool)
    stat = _Stat()
    harness.node._diag_inputs(stat)
    assert stat.values['bad_input'] == harness.node._bad_input > 0


class _Stat:
    """Collects what a diagnostics task reports (summary and values)."""

    def summary(self, level, message):
        self.level, self.message = level, message

    def update(self, values):
        self.values = dict(values)
