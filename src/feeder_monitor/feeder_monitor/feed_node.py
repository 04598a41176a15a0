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
feed_node: the feeder's "give me a part" action, ``~/feed_part`` (feeder_interfaces/FeedPart).

A cell controller sends a goal with a budget (cycles, time); the node fires the driver's
``~/trigger_cycle`` one cycle at a time and ends the goal on the first verdict of the monitor
that proves the part on the goal edge for the newest cycle (signed by the monitor under
``key_file`` and fresh, as ``feeder_common.messages.check_verdict`` says), or with the reason
it cannot (feeder_monitor.feed). A goal that cannot start (another goal runs, the budget is
empty, no current signed statement from the monitor, no driver) is accepted and ends at once
with reason ``refused`` and why: a ROS 2 goal rejection carries no reason.

One goal at a time: a second goal while one runs is refused (it does not preempt: the first
client keeps its part). Cancel: no cycle is fired after it; the goal ends ``canceled``.
"""

import math
import sys
import time

from feeder_common import auth, qos
from feeder_common.messages import (check_verdict, parse_cycle_status, parse_predicted_state,
                                    time_msg)
from feeder_common.node import run_node, StartupError
from feeder_common.parameters import ParameterGate
from feeder_interfaces.action import FeedPart
from feeder_interfaces.msg import CycleStatus, PredictedState, Verdict
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.node import Node
from rclpy.task import Future
from std_srvs.srv import Trigger

from . import feed
from .params import FEED_PARAMS
from .trust import ReportGate

WAKE_PERIOD_S = 0.02        # how often a running goal looks at its deadlines


class FeedNode(Node):
    """Serves ``~/feed_part``: cycles the driver until the monitor proves a part ready."""

    # rclpy 9.1's events executor does not run action servers' coroutines: the single one does.
    executor_kind = 'single'

    def __init__(self, **kwargs):
        # Set before Node.__init__: a refused parameter ends the context, which destroys the
        # half-built node.
        self._server = None
        super().__init__('feeder_feed', **kwargs)
        self._params = ParameterGate(self, FEED_PARAMS)
        p = self._params.declare_all()
        try:
            self._key = auth.node_key(p['key_file'])
        except auth.KeyFileError as exc:
            raise StartupError(f'key_file: {exc}') from None
        self._driver = self.resolve_topic_name(p['driver_node'])
        self._monitor = self.resolve_topic_name(p['monitor_node'])
        self._gate = ReportGate(self._key, self._driver, p['max_report_age'])
        self._goal = None               # the running feed.FeedGoal
        self._wake = None               # Future the running goal awaits
        self._statement = None          # (VerdictCheck, state) of the newest signed statement
        self._trigger = self.create_client(Trigger, f'{self._driver}/trigger_cycle')
        self._new_part = self.create_client(Trigger, f'{self._monitor}/new_part')
        self.create_subscription(Verdict, 'edge1_verdict', self._on_verdict,
                                 qos.EDGE1_VERDICT)
        self.create_subscription(Verdict, 'edge1_ready', self._on_statement,
                                 qos.edge1_ready(p['max_statement_age']))
        self.create_subscription(CycleStatus, 'cycle_status', self._on_cycle_status,
                                 qos.CYCLE_STATUS)
        self.create_subscription(PredictedState, 'predicted/state', self._on_prediction,
                                 qos.PREDICTED_STATE)
        # Feedback comes once per cycle, up to about 1000 a second with the stand-in: a deep
        # reliable history, so that a client that reads in bursts still gets every cycle's.
        self._server = ActionServer(self, FeedPart, '~/feed_part', self._execute,
                                    goal_callback=lambda goal: GoalResponse.ACCEPT,
                                    cancel_callback=self._on_cancel,
                                    feedback_pub_qos_profile=qos.FEED_FEEDBACK)
        self.get_logger().info(
            f'serving {self.resolve_topic_name("~/feed_part")}: cycles {self._driver}, '
            f'proof by {self._monitor} (key id {auth.key_id(self._key)})')

    def _param(self, name):
        return self._params.values[name]

    def _now_ns(self):
        return self.get_clock().now().nanoseconds

    # ------------------------------------------------------------------ inputs
    def _poke(self):
        if self._wake is not None and not self._wake.done():
            self._wake.set_result(None)

    def _on_statement(self, msg):
        check = check_verdict(msg, self._key, self._monitor, self._now_ns(),
                              self._param('max_statement_age'))
        if check.authentic:
            self._statement = (check, msg.state, time.monotonic())

    def _on_verdict(self, msg):
        check = check_verdict(msg, self._key, self._monitor, self._now_ns(),
                              self._param('max_statement_age'))
        if not check.authentic or self._goal is None:
            return
        self._goal.verdict(check.seq, check.ready_now, msg.state, msg.anomaly, check.stamp_ns,
                           time.monotonic())
        self._poke()

    def _on_cycle_status(self, msg):
        try:
            status = parse_cycle_status(msg)
        except ValueError:
            return
        if self._gate.admit(status, self._now_ns()).admitted and self._goal is not None:
            self._goal.cycle_report(status.seq, status.ok and status.sensor is not None,
                                    status.reason)
            self._poke()

    def _on_prediction(self, msg):
        try:
            state = parse_predicted_state(msg)
        except ValueError:
            return
        if self._goal is not None:
            self._goal.prediction(state.seq, state.edge,
                                  math.nan if state.R is None else state.R)
            self._poke()

    def _on_cancel(self, handle):
        if self._goal is not None:
            self._goal.cancel()
            self._poke()
        return CancelResponse.ACCEPT

    # ------------------------------------------------------------------ goals
    def _refusal(self, request):
        if self._goal is not None:
            return 'another goal is running: one goal at a time (cancel it first)'
        budget = _budget(request)
        why = budget.problem()
        if why:
            return why
        age = self._param('max_statement_age')
        if self._statement is None or time.monotonic() - self._statement[2] > age:
            return (f'the monitor is not tracking: no statement signed by {self._monitor} '
                    f'in the last {age:g} s (is it running and active, with this key_file?)')
        if not self._trigger.service_is_ready():
            return f'no driver: {self._driver}/trigger_cycle is not offered'
        if request.new_part and not self._new_part.service_is_ready():
            return f'new_part: {self._monitor}/new_part is not offered'
        return None

    async def _wait(self, until):
        """Return at ``until`` (monotonic s) or at the next input, whichever comes first."""
        self._wake = Future()
        timer = self.create_timer(max(0.0, min(until - time.monotonic(), WAKE_PERIOD_S)),
                                  self._poke)
        try:
            await self._wake
        finally:
            self.destroy_timer(timer)
            self._wake = None

    async def _call(self, client, until):
        """Call ``client`` with an empty Trigger request; (response or None, why)."""
        future = client.call_async(Trigger.Request())
        future.add_done_callback(lambda _: self._poke())
        while not future.done():
            if time.monotonic() >= until:
                client.remove_pending_request(future)
                return None, 'no reply'
            await self._wait(until)
        return future.result(), ''

    async def _execute(self, handle):
        request = handle.request
        why = self._refusal(request)
        if why:
            return self._finish(handle, feed.Outcome(False, feed.REFUSED, why, 0, None, 0))
        goal = feed.FeedGoal(_budget(request), time.monotonic(),
                             self._param('verdict_timeout'))
        self._goal = goal
        try:
            if request.new_part:
                reply, why = await self._call(self._new_part, time.monotonic() + 5.0)
                if reply is None or not reply.success:
                    why = why or reply.message
                    return self._finish(handle, feed.Outcome(
                        False, feed.REFUSED, f'{self._monitor}/new_part: {why}', 0, None, 0))
            while True:
                if handle.is_cancel_requested:
                    goal.cancel()
                step = goal.step(time.monotonic())
                self._send_feedback(handle, goal)
                if isinstance(step, feed.Done):
                    return self._finish(handle, step.outcome)
                if isinstance(step, feed.Fire):
                    goal.trigger_sent()
                    reply, why = await self._call(
                        self._trigger, time.monotonic() + self._param('verdict_timeout'))
                    if reply is None:
                        goal.trigger_failed(why)
                    else:
                        goal.trigger_reply(reply.success, reply.message, time.monotonic())
                else:
                    await self._wait(step.until)
        finally:
            self._goal = None

    @staticmethod
    def _send_feedback(handle, goal):
        while goal.feedback:
            f = goal.feedback.pop(0)
            edge = FeedPart.Feedback.EDGE_UNKNOWN if f.predicted_edge is None \
                else f.predicted_edge
            handle.publish_feedback(FeedPart.Feedback(
                seq=f.seq, predicted_edge=edge, predicted_r=f.predicted_r,
                monitor_state=f.monitor_state, cycles=f.cycles))

    def _finish(self, handle, outcome):
        result = FeedPart.Result(success=outcome.success, reason=outcome.reason,
                                 detail=outcome.detail, seq=outcome.seq, cycles=outcome.cycles)
        if outcome.stamp_ns is not None:
            result.stamp = time_msg(outcome.stamp_ns)
        if outcome.success:
            handle.succeed()
        elif outcome.reason == feed.CANCELED and handle.is_cancel_requested:
            handle.canceled()
        else:
            handle.abort()
        # (rclpy's logger takes one severity per call site: two calls.)
        if outcome.success:
            self.get_logger().info(f'goal {outcome.reason}: {outcome.detail}')
        else:
            self.get_logger().warning(f'goal {outcome.reason}: {outcome.detail}')
        return result

    def destroy_node(self):
        if self._server is not None:
            self._server.destroy()
            self._server = None
        return super().destroy_node()


def _budget(request):
    timeout = request.timeout.sec + request.timeout.nanosec * 1e-9
    return feed.Budget(int(request.max_cycles), timeout)


def main(args=None):
    return run_node(FeedNode, 'feed_node', args)


if __name__ == '__main__':
    sys.exit(main())
