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

"""The FeedPart goal's logic (feeder_monitor.feed): fire, judge, end, against every ordering."""

import math

from feeder_monitor import feed
from feeder_monitor.feed import Budget, Done, FeedGoal, Fire, Wait
from hypothesis import given, settings, strategies as st
import pytest


def fire(goal, seq, now):
    assert isinstance(goal.step(now), Fire)
    goal.trigger_sent()
    goal.trigger_reply(True, f'fired cycle seq {seq}', now)


def test_a_budget_needs_cycles_or_time_and_no_negative():
    assert 'no budget' in Budget(0, 0.0).problem()
    assert 'max_cycles = -1' in Budget(-1, 5.0).problem()
    assert 'timeout = nan' in Budget(3, math.nan).problem()
    assert Budget(3, 0.0).problem() is None and Budget(0, 2.5).problem() is None
    with pytest.raises(ValueError, match='no budget'):
        FeedGoal(Budget(0, 0.0), 0.0, 5.0)


def test_fires_one_cycle_at_a_time_and_succeeds_on_the_ready_of_its_newest_cycle():
    g = FeedGoal(Budget(10, 0.0), 0.0, 5.0)
    fire(g, 41, 0.0)
    assert isinstance(g.step(0.1), Wait)          # no second cycle while 41 is in flight
    g.prediction(41, 1, 0.2)
    g.verdict(40, True, 'ready', '', 1, 0.0)           # late news of an older cycle: ignored
    assert isinstance(g.step(0.2), Wait)
    g.verdict(41, False, 'tracking', '', 2, 0.0)
    fire(g, 42, 0.3)
    g.verdict(42, True, 'ready', '', 3_000, 0.0)
    out = g.step(0.4)
    assert isinstance(out, Done)
    assert (out.outcome.success, out.outcome.reason, out.outcome.seq, out.outcome.stamp_ns,
            out.outcome.cycles) == (True, feed.READY, 42, 3_000, 2)
    assert [(f.seq, f.predicted_edge, f.monitor_state) for f in g.feedback] == [
        (41, 1, 'tracking'), (42, None, 'ready')]


def test_every_way_a_goal_ends_without_a_part():
    g = FeedGoal(Budget(2, 0.0), 0.0, 5.0)
    fire(g, 1, 0.0)
    g.verdict(1, False, 'warming up', '', 1, 0.0)
    fire(g, 2, 0.1)
    g.verdict(2, False, 'tracking', '', 2, 0.0)
    assert g.step(0.2).outcome.reason == feed.BUDGET_SPENT

    g = FeedGoal(Budget(0, 1.0), 0.0, 5.0)
    fire(g, 1, 0.0)
    g.verdict(1, False, 'tracking', '', 1, 0.0)
    assert g.step(1.0).outcome.reason == feed.TIMEOUT

    g = FeedGoal(Budget(5, 0.0), 0.0, 5.0)
    fire(g, 7, 0.0)
    g.cycle_report(7, False, 'no SENS within 5 s')
    out = g.step(0.1).outcome
    assert (out.reason, out.cycles) == (feed.SERIAL_FAULT, 1) and 'no SENS' in out.detail

    g = FeedGoal(Budget(5, 0.0), 0.0, 5.0)
    fire(g, 7, 0.0)
    assert g.step(5.01).outcome.reason == feed.SERIAL_FAULT       # no verdict came

    g = FeedGoal(Budget(5, 0.0), 0.0, 5.0)
    fire(g, 7, 0.0)
    g.verdict(7, False, 'anomaly', 'bad MAC', 1, 0.0)
    assert isinstance(g.step(0.1), Wait)        # the cycle's report may yet say it failed
    assert g.step(feed.REPORT_GRACE_S).outcome.reason == feed.ANOMALY

    g = FeedGoal(Budget(5, 0.0), 0.0, 5.0)
    fire(g, 7, 0.0)
    g.verdict(7, False, 'anomaly', 'cycle failed', 1, 0.0)
    g.cycle_report(7, False, 'no ACK within 0.5 s')   # after its verdict: still a serial fault
    assert g.step(0.1).outcome.reason == feed.SERIAL_FAULT

    g = FeedGoal(Budget(5, 0.0), 0.0, 5.0)
    fire(g, 7, 0.0)
    g.prediction(7, -1, math.nan)
    assert g.step(0.1).outcome.reason == feed.PART_LOST

    g = FeedGoal(Budget(5, 0.0), 0.0, 5.0)
    assert isinstance(g.step(0.0), Fire)
    g.trigger_sent()
    g.trigger_reply(False, 'refused: serial link disconnected (reconnecting)', 0.0)
    assert g.step(0.0).outcome.reason == feed.SERIAL_FAULT


def test_a_busy_driver_is_retried_and_a_cancel_fires_nothing_more():
    g = FeedGoal(Budget(5, 0.0), 0.0, 5.0)
    g.step(0.0)
    g.trigger_sent()
    g.trigger_reply(False, 'refused: busy with cycle seq 3 (fired 0.1 s ago)', 0.0)
    assert isinstance(g.step(0.01), Wait) and isinstance(g.step(0.06), Fire)
    g.trigger_sent()
    g.trigger_reply(True, 'fired cycle seq 4', 0.06)
    g.cancel()
    out = g.step(0.07).outcome
    assert (out.reason, out.cycles, out.success) == (feed.CANCELED, 1, False)
    assert 'in flight' in out.detail


@settings(max_examples=400, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(['fire', 'reply', 'refuse', 'verdict', 'stale',
                                           'report', 'predict', 'cancel', 'tick']),
                          st.integers(0, 4), st.booleans()), max_size=60),
       st.integers(1, 6))
def test_never_ready_but_on_its_newest_cycle_and_never_past_its_budget(events, max_cycles):
    g = FeedGoal(Budget(max_cycles, 0.0), 0.0, 5.0)
    now, seq, fired, canceled, ready_for = 0.0, 100, [], False, set()
    for kind, k, flag in events:
        now += 0.01
        step = g.step(now)
        if isinstance(step, Done):
            break
        if kind == 'fire' and isinstance(step, Fire):
            assert not canceled
            seq += 1
            g.trigger_sent()
            g.trigger_reply(True, f'fired cycle seq {seq}', now)
            fired.append(seq)
        elif kind == 'refuse' and isinstance(step, Fire):
            g.trigger_sent()
            g.trigger_reply(False, 'refused: busy with cycle seq 1', now)
        elif kind in ('verdict', 'stale') and fired:
            s = fired[-1] - k if kind == 'stale' else fired[-1]
            g.verdict(s, flag, 'ready' if flag else 'tracking', '', s, now)
            if flag:
                ready_for.add(s)
        elif kind == 'report' and fired:
            g.cycle_report(fired[-1] - k, flag, 'lost')
        elif kind == 'predict' and fired:
            g.prediction(fired[-1] - k, 1 if flag else -1, 0.2)
        elif kind == 'cancel':
            g.cancel()
            canceled = True
    out = g.step(now + 0.01)
    assert g.cycles == len(fired) <= max_cycles
    if isinstance(out, Done) and out.outcome.success:
        assert out.outcome.seq == fired[-1] and out.outcome.seq in ready_for
    if canceled:
        assert isinstance(out, Done) and not out.outcome.success


def test_the_feed_logic_speaks_the_action_s_reasons():
    from feeder_interfaces.action import FeedPart
    result = FeedPart.Result
    assert {getattr(result, n) for n in dir(result) if n.startswith('REASON_')} == set(
        feed.REASONS)


def test_a_verdict_that_overtakes_the_trigger_reply_still_counts():
    # The stand-in fires inside its service callback: the cycle's report and verdict can
    # arrive before the reply that names the seq (seen on the graph: every goal timed out).
    g = FeedGoal(Budget(5, 0.0), 0.0, 5.0)
    assert isinstance(g.step(0.0), Fire)
    g.trigger_sent()
    g.prediction(9, 1, 0.26)
    g.verdict(9, True, 'ready', '', 123, 0.0)
    g.trigger_reply(True, 'fired cycle seq 9', 0.01)
    out = g.step(0.02).outcome
    assert (out.success, out.seq, out.cycles) == (True, 9, 1)
    assert [(f.seq, f.predicted_edge) for f in g.feedback] == [(9, 1)]

    g = FeedGoal(Budget(5, 0.0), 0.0, 5.0)
    g.step(0.0)
    g.trigger_sent()
    g.cycle_report(3, False, 'no ACK')
    g.verdict(2, True, 'ready', '', 1, 0.0)        # an older cycle's: not this goal's
    g.trigger_reply(True, 'fired cycle seq 3', 0.01)
    assert g.step(0.02).outcome.reason == feed.SERIAL_FAULT


def test_with_a_predictor_each_feedback_waits_briefly_for_its_prediction():
    g = FeedGoal(Budget(5, 0.0), 0.0, 5.0)
    fire(g, 1, 0.0)
    g.prediction(1, 1, 0.1)                       # a predictor is on the graph
    g.verdict(1, False, 'tracking', '', 1, 0.0)
    fire(g, 2, 0.0)
    g.verdict(2, False, 'tracking', '', 2, 0.01)  # its prediction is late
    assert isinstance(g.step(0.02), Wait) and not [f for f in g.feedback if f.seq == 2]
    g.prediction(2, 0, 0.15)
    assert isinstance(g.step(0.03), Fire)
    assert [(f.seq, f.predicted_edge, f.predicted_r) for f in g.feedback] == [
        (1, 1, 0.1), (2, 0, 0.15)]
    fire(g, 3, 0.03)
    g.verdict(3, False, 'tracking', '', 3, 0.04)  # no prediction ever comes
    assert isinstance(g.step(0.04 + feed.PREDICTION_GRACE_S / 2), Wait)
    assert isinstance(g.step(0.04 + feed.PREDICTION_GRACE_S), Fire)
    assert g.feedback[-1].seq == 3 and g.feedback[-1].predicted_edge is None
    g.trigger_sent()
    g.trigger_reply(True, 'fired cycle seq 4', 0.3)
    g.verdict(4, False, 'tracking', '', 4, 0.31)
    g.prediction(4, -1, math.nan)                 # after its verdict: the part is gone
    assert g.step(0.32).outcome.reason == feed.PART_LOST
