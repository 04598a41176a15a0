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
The FeedPart action's logic without ROS: fire a cycle at a time until a part is proven ready.

One :class:`FeedGoal` per goal. The node (feeder_monitor.feed_node) tells it what happened
(the driver's reply to a trigger, the authentic verdicts, cycle reports and predictions) and
asks :meth:`FeedGoal.step` what to do next: ``Fire`` (call the driver's ``~/trigger_cycle``),
``Wait`` (until the given time or the next event) or ``Done`` (the result).

Why one cycle at a time: a cancel then stops the feeder at once (no cycle is fired after it),
the budget is exact, and a ready verdict for the newest fired cycle is a statement about the
part as it lies now. The goal succeeds only on a verdict the node found authentic and fresh
(``feeder_common.messages.check_verdict``) that says ready for the cycle this goal fired last;
everything else fires another cycle or ends the goal with its reason.
"""

from dataclasses import dataclass
import math
import re
from typing import Optional

# The result reasons: the same text as feeder_interfaces/action/FeedPart's REASON_ constants
# (the node's test checks they agree; this module imports no ROS type).
READY = 'ready'
BUDGET_SPENT = 'budget spent'
TIMEOUT = 'timeout'
SERIAL_FAULT = 'serial fault'
ANOMALY = 'anomaly'
PART_LOST = 'part lost'
CANCELED = 'canceled'
REFUSED = 'refused'
REASONS = (READY, BUDGET_SPENT, TIMEOUT, SERIAL_FAULT, ANOMALY, PART_LOST, CANCELED, REFUSED)

# A driver refusal that passes: another client's cycle is in flight (retry after it).
_BUSY = 'refused: busy'
_FIRED = re.compile(r'^fired cycle seq (\d+)')
RETRY_BUSY_S = 0.05
# A verdict and its cycle's report travel on two topics: an anomaly verdict waits this long for
# the report that may say the cycle failed (a serial fault, not an anomaly of the part).
REPORT_GRACE_S = 0.5
# The predictor's state of a cycle comes about when its verdict does: with a predictor on the
# graph the next cycle waits this long for it, so that each feedback carries the prediction.
PREDICTION_GRACE_S = 0.2


@dataclass(frozen=True)
class Budget:
    """What a goal may spend: cycles and seconds; 0 means no limit of that kind."""

    max_cycles: int
    timeout_s: float

    def problem(self):
        """Return why this budget cannot be a goal's, or None."""
        if self.max_cycles < 0:
            return f'max_cycles = {self.max_cycles}: give 0 (no limit) or a positive count'
        if not math.isfinite(self.timeout_s) or self.timeout_s < 0:
            return f'timeout = {self.timeout_s} s: give 0 (no limit) or a positive duration'
        if self.max_cycles == 0 and self.timeout_s == 0:
            return ('no budget: give max_cycles or timeout (or both); a goal without either '
                    'could cycle for ever')
        return None


@dataclass(frozen=True)
class Outcome:
    """A goal's result: ``seq`` and ``stamp_ns`` of the proven ready (0, None otherwise)."""

    success: bool
    reason: str
    detail: str
    seq: int
    stamp_ns: Optional[int]
    cycles: int


@dataclass(frozen=True)
class Feedback:
    """After each judged cycle of the goal: the prediction for it and the monitor's state."""

    seq: int
    predicted_edge: Optional[int]       # None: no prediction for this cycle
    predicted_r: float
    monitor_state: str
    cycles: int


@dataclass(frozen=True)
class Fire:
    """Call the driver's ``~/trigger_cycle`` now and report the reply."""


@dataclass(frozen=True)
class Wait:
    """Nothing to do before ``until`` (monotonic s) or the next event."""

    until: float


@dataclass(frozen=True)
class Done:
    """The goal ended."""

    outcome: Outcome


class FeedGoal:
    """
    One FeedPart goal: fire, wait for the cycle's verdict, fire again, until ready or spent.

    Times are monotonic seconds. ``verdict_timeout_s``: how long a fired cycle may go without
    its verdict before the goal ends as a serial fault (driver, link or monitor not working).
    """

    def __init__(self, budget, now, verdict_timeout_s):
        why = budget.problem()
        if why:
            raise ValueError(why)
        self.budget = budget
        self.started = now
        self.verdict_timeout_s = verdict_timeout_s
        self.cycles = 0
        self.in_flight = None           # seq of the cycle fired and not judged yet
        self.fired_at = None
        self.calling = False            # a trigger call is out, its reply not in
        self._retry_at = None
        self._outcome = None
        self._cancel = False
        self._predictions = {}          # seq -> (edge, r), the newest few
        # What came for a seq before the driver's reply named it (a fast stand-in's verdict
        # can overtake the reply to the trigger that fired it): seq -> the event's arguments.
        self._early_verdicts = {}
        self._early_failures = {}
        self._anomaly = None            # (seq, text, until): an anomaly verdict, report due
        self._feedback_due = None       # (seq, monitor state, until): prediction due
        self.feedback = []              # Feedback not yet sent (the node drains it)

    # ---------------------------------------------------------------- events
    def cancel(self):
        """Take the client's cancel: no cycle is fired after it."""
        self._cancel = True

    def trigger_sent(self):
        """Note that the node called ``~/trigger_cycle``."""
        self.calling = True

    def trigger_reply(self, success, message, now):
        """Take the driver's reply to the trigger (``success`` False with its refusal)."""
        self.calling = False
        if self._outcome:
            return
        if success:
            m = _FIRED.match(message)
            if not m:
                self._end(False, SERIAL_FAULT, f'the driver fired but named no seq: {message!r}')
                return
            self.in_flight = int(m.group(1))
            self.fired_at = now
            self.cycles += 1
            seq = self.in_flight
            if seq in self._early_failures:
                self.cycle_report(seq, False, self._early_failures[seq])
            if seq in self._early_verdicts:
                self.verdict(seq, *self._early_verdicts[seq])
            self._early_verdicts.clear()
            self._early_failures.clear()
        elif message.startswith(_BUSY):
            self._retry_at = now + RETRY_BUSY_S
        else:
            self._end(False, SERIAL_FAULT, f'the driver refused to fire: {message}')

    def trigger_failed(self, why):
        """End the goal: the trigger call itself failed (no driver, timed out)."""
        self.calling = False
        if not self._outcome:
            self._end(False, SERIAL_FAULT, f'~/trigger_cycle: {why}')

    def cycle_report(self, seq, completed, reason):
        """Take an authentic ``cycle_status``: a failed cycle of this goal ends it."""
        if completed or self._outcome:
            return
        if self.calling:
            _keep(self._early_failures, seq, reason)
        if seq == self.in_flight or (self._anomaly and self._anomaly[0] == seq):
            self._end(False, SERIAL_FAULT, f'cycle seq {seq} failed: {reason}')

    def prediction(self, seq, edge, r):
        """Take the predictor's state after cycle ``seq`` (``edge`` -1: the part left the arm)."""
        _keep(self._predictions, seq, (edge, r))
        due = self._feedback_due
        if due and due[0] == seq:
            self._send_feedback()
        if edge < 0 and seq in (self.in_flight, due and due[0]) and not self._outcome:
            self._end(False, PART_LOST, f'the part left the arm at cycle seq {seq}')

    def verdict(self, seq, ready_now, state, anomaly, stamp_ns, now):
        """
        Take an authentic verdict on ``edge1_verdict`` (``ready_now`` as check_verdict says).

        Only the verdict on this goal's newest cycle counts; older ones are late news.
        """
        if self.calling and not self._outcome:
            _keep(self._early_verdicts, seq, (ready_now, state, anomaly, stamp_ns, now))
        if seq != self.in_flight or self._outcome:
            return
        edge, r = self._predictions.get(seq, (None, math.nan))
        self._feedback_due = (seq, state, now + PREDICTION_GRACE_S)
        if edge is not None or not self._predictions:
            self._send_feedback()       # no predictor on the graph: nothing to wait for
        self.in_flight = None
        if ready_now:
            self._end(True, READY, f'ready at cycle seq {seq} after {self.cycles} cycles',
                      seq, stamp_ns)
        elif anomaly:
            self._anomaly = (seq, f'cycle seq {seq}: {anomaly}', now + REPORT_GRACE_S)
        elif edge is not None and edge < 0:
            self._end(False, PART_LOST, f'the part left the arm at cycle seq {seq}')

    # ---------------------------------------------------------------- decisions
    def step(self, now):
        """Return what to do now: Fire, Wait(until) or Done(outcome)."""
        if self._outcome is None and self._anomaly is not None:
            if now < self._anomaly[2] and not self._cancel:
                return Wait(self._anomaly[2])
            self._end(False, ANOMALY, self._anomaly[1])
        if self._outcome is None:
            self._check_limits(now)
        if self._outcome is not None:
            self._send_feedback()
            return Done(self._outcome)
        if self._feedback_due is not None:
            if now < self._feedback_due[2]:
                return Wait(self._feedback_due[2])
            self._send_feedback()
        if self.calling:
            return Wait(now + self.verdict_timeout_s)
        if self.in_flight is not None:
            return Wait(self.fired_at + self.verdict_timeout_s)
        if self._retry_at is not None and now < self._retry_at:
            return Wait(self._retry_at)
        self._retry_at = None
        return Fire()

    def _check_limits(self, now):
        if self._cancel:
            self._end(False, CANCELED, f'canceled after {self.cycles} cycles'
                      + (f' (cycle seq {self.in_flight} was in flight)'
                         if self.in_flight is not None else ''))
        elif self.in_flight is not None and now - self.fired_at > self.verdict_timeout_s:
            self._end(False, SERIAL_FAULT, f'no verdict on cycle seq {self.in_flight} within '
                      f'{self.verdict_timeout_s:g} s: is the link to the driver up, '
                      'the monitor running?')
        elif self.in_flight is None and not self.calling:
            # Between cycles: a budget is spent only when the next cycle would exceed it.
            if self.budget.max_cycles and self.cycles >= self.budget.max_cycles:
                self._end(False, BUDGET_SPENT, f'{self.cycles} cycles fired, none proven ready')
            elif self.budget.timeout_s and now - self.started >= self.budget.timeout_s:
                self._end(False, TIMEOUT, f'{now - self.started:.1f} s and {self.cycles} '
                          'cycles, none proven ready')

    def _send_feedback(self):
        if self._feedback_due is None:
            return
        seq, state, _ = self._feedback_due
        edge, r = self._predictions.get(seq, (None, math.nan))
        self.feedback.append(Feedback(seq, edge, r, state, self.cycles))
        self._feedback_due = None

    def _end(self, success, reason, detail, seq=0, stamp_ns=None):
        self._outcome = Outcome(success, reason, detail, seq, stamp_ns, self.cycles)


def _keep(table, seq, value, size=8):
    """Keep ``value`` for ``seq`` in ``table``, with at most ``size`` newest seqs."""
    table[seq] = value
    while len(table) > size:
        del table[min(table)]
