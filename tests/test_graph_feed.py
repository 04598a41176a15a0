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
The FeedPart action on the simulated feeder (issue 22): a cell feeds parts one after another.

The stand-in (with a truth log: where the part really is after each cycle), the predictor, the
monitor and feed_node run as processes; the test is the cell controller, with an rclpy
ActionClient on /feeder/feeder_feed/feed_part. A part is "taken" after each ready and a new one
put on the arm: the stand-in's and the predictor's start_radius are set (a chute dropping parts
on edge 1 over a range of R), and the goal says new_part. Every success must name a cycle
whose part the truth log puts on the goal edge; no ready verdict of the whole run may be false.
"""

import os
import signal
import time

from builtin_interfaces.msg import Duration
from feeder_interfaces.action import FeedPart
from feeder_nodes import (monitor, predictor, RELIABLE, sim_as_hardware, STARTUP_TIMEOUT,
                          TRIANGLE, Verdicts)
from feeder_sim.truth import read_truth_log
import pytest
from rclpy.action import ActionClient
from throwmap import analyse, load_scene

ACTION = '/feeder/feeder_feed/feed_part'
STANDIN = '/feeder/feeder_driver'
PREDICTOR = '/feeder/feeder_sim'


def feed_node(graph, *params):
    args = ['--ros-args', '-r', '__ns:=/feeder']        # the graph gives it the test's key
    for p in params:
        args += ['-p', p]
    return graph.start('feeder_monitor', 'feed_node', *args, name='feed')


class Cell:
    """The test as a cell controller: sends goals, keeps their feedback and results."""

    def __init__(self, ros):
        self.ros = ros
        # The test's own QoS, as deep as the server's (feeder_common.qos.FEED_FEEDBACK).
        self.client = ActionClient(ros.node, FeedPart, ACTION,
                                   feedback_sub_qos_profile=RELIABLE)
        # rclpy's client drops a feedback that arrives after its goal's result (the two
        # travel apart); the feedback topic itself, as `ros2 topic echo` shows it, keeps all.
        self.feedback = {}          # goal id (bytes) -> [Feedback]
        ros.node.create_subscription(FeedPart.Impl.FeedbackMessage, f'{ACTION}/_action/feedback',
                                     self._on_feedback, RELIABLE)
        ros.spin_until(lambda: self.client.server_is_ready(), STARTUP_TIMEOUT, 'the action')

    def _on_feedback(self, msg):
        self.feedback.setdefault(bytes(msg.goal_id.uuid), []).append(msg.feedback)

    def send(self, max_cycles=0, timeout_s=0.0, new_part=False):
        """Send a goal; return (goal handle, its feedback list) once it was answered."""
        goal = FeedPart.Goal(max_cycles=max_cycles, new_part=new_part,
                             timeout=Duration(sec=int(timeout_s),
                                              nanosec=int(timeout_s % 1 * 1e9)))
        future = self.client.send_goal_async(goal)
        self.ros.spin_until(future.done, 10.0, 'the goal to be answered')
        handle = future.result()
        assert handle.accepted        # refusals are accepted goals that end 'refused'
        return handle, self.feedback.setdefault(bytes(handle.goal_id.uuid), [])

    def result(self, handle, timeout=120.0):
        future = handle.get_result_async()
        self.ros.spin_until(future.done, timeout, 'the goal result')
        return future.result().status, future.result().result

    def feed(self, **kwargs):
        handle, feedback = self.send(**kwargs)
        status, result = self.result(handle)
        # The result and the feedback come by different ways: the last may still be on its way.
        end = time.monotonic() + 10.0
        while len(feedback) < result.cycles:
            assert time.monotonic() < end, (
                f'feedback of the {result.cycles} cycles of {result}: got '
                f'{[(f.seq, f.cycles) for f in feedback]}')
            self.ros.spin_for(0.05)
        return status, result, feedback


def start_feeder(graph, ros, tmp_path, *feed_params):
    truth = tmp_path / 'truth.jsonl'
    sim_as_hardware(graph, f'truth_log:={truth}')
    predictor(graph)
    monitor(graph)
    feed_node(graph, *feed_params)
    verdicts = Verdicts(ros)
    verdicts.wait_matched()
    cell = Cell(ros)
    # The feed node refuses until it holds a fresh signed statement of the monitor.
    deadline = time.monotonic() + STARTUP_TIMEOUT
    while True:
        status, result, _ = cell.feed(max_cycles=1)
        if result.reason != FeedPart.Result.REASON_REFUSED or time.monotonic() > deadline:
            break
        ros.spin_for(0.5)
    assert result.reason != FeedPart.Result.REASON_REFUSED, result.detail
    return cell, verdicts, truth


def test_twenty_parts_in_a_row_each_a_true_ready(graph, ros, tmp_path):
    cell, verdicts, truth_path = start_feeder(graph, ros, tmp_path)
    scene = load_scene(TRIANGLE)
    goal_edge = analyse(scene).sensor.goal_edge
    results = []
    for k in range(20):
        # A new part from the chute: on edge 1, R spread over [0.07, 0.21] m.
        R = 0.07 + 0.14 * k / 19
        for node in (STANDIN, PREDICTOR):
            res = ros.set_parameters(node, {'start_radius': R})
            assert res['start_radius'].successful, (node, res['start_radius'].reason)
        status, result, feedback = cell.feed(max_cycles=600, new_part=True)
        assert result.success, (k, result.reason, result.detail)
        assert result.reason == FeedPart.Result.REASON_READY
        assert [f.cycles for f in feedback] == list(range(1, result.cycles + 1))
        assert feedback[-1].seq == result.seq and feedback[-1].monitor_state == 'ready'
        results.append(result)

    _, truth = read_truth_log(truth_path)
    for r in results:
        # The ready's cycle: the part truly on the goal edge, seen by the sensor.
        assert truth[r.seq]['edge'] == goal_edge and truth[r.seq]['detected'], truth[r.seq]
        assert r.stamp.sec * 10**9 + r.stamp.nanosec == truth[r.seq]['stamp_ns']
    # No ready verdict of the whole run on a cycle whose part was off the goal edge.
    ros.spin_for(0.5)
    false = [c.seq for c in verdicts.checked
             if c.ready and truth.get(c.seq, {}).get('edge') != goal_edge]
    assert false == []
    # Each part waited for the settling after it was put on the arm.
    assert min(r.cycles for r in results) > 1
    print('cycles per part:', [r.cycles for r in results])


def fired_so_far(truth_path):
    """The highest seq the stand-in fired (its truth log is written at each fire)."""
    return max(read_truth_log(truth_path)[1], default=0)


def test_budget_cancel_and_refusals(graph, ros, tmp_path):
    cell, verdicts, truth_path = start_feeder(graph, ros, tmp_path)
    # A budget too small for the settling after a new part.
    status, result, feedback = cell.feed(max_cycles=3, new_part=True)
    assert (result.success, result.reason, result.cycles) == (
        False, FeedPart.Result.REASON_BUDGET, 3)
    assert len(feedback) == 3 and all(f.monitor_state != 'ready' for f in feedback)
    # No budget at all.
    status, result, _ = cell.feed()
    assert result.reason == FeedPart.Result.REASON_REFUSED and 'no budget' in result.detail

    # A second goal while one runs is refused; cancel ends the first with no cycle after it.
    before = fired_so_far(truth_path)
    first, feedback = cell.send(max_cycles=1000, new_part=True)
    ros.spin_until(lambda: len(feedback) >= 5, 30.0, 'five cycles of the first goal')
    status, second, _ = cell.feed(max_cycles=10)
    assert second.reason == FeedPart.Result.REASON_REFUSED
    assert 'another goal' in second.detail
    cancel = first.cancel_goal_async()
    ros.spin_until(cancel.done, 10.0, 'the cancel reply')
    status, result = cell.result(first)
    assert result.reason == FeedPart.Result.REASON_CANCELED and not result.success
    # Every cycle the stand-in fired since was this goal's, and none came after the cancel
    # (counted from the stand-in's own log, not from messages that may arrive late).
    ros.spin_for(1.0)
    assert fired_so_far(truth_path) - before == result.cycles >= 5


def test_a_goal_without_a_monitor_is_refused_and_a_dead_driver_is_a_serial_fault(
        graph, ros, tmp_path):
    truth = tmp_path / 'truth.jsonl'
    hw = sim_as_hardware(graph, f'truth_log:={truth}')
    feed_node(graph, 'verdict_timeout:=2.0')
    cell = Cell(ros)
    status, result, _ = cell.feed(max_cycles=10)
    assert result.reason == FeedPart.Result.REASON_REFUSED
    assert 'not tracking' in result.detail

    mon = monitor(graph)
    deadline = time.monotonic() + STARTUP_TIMEOUT
    while True:
        handle, feedback = cell.send(max_cycles=2000, new_part=True)
        # The hardware hangs (SIGSTOP) right after the goal's first cycle, well before the
        # settling could end in a ready.
        ros.spin_until(lambda: feedback or handle.status >= 4, 30.0, 'the first cycle')
        if feedback:
            os.kill(hw.pid, signal.SIGSTOP)
            break
        # Until the monitor is up and matched to the stand-in: refused, or a first cycle that
        # nobody judged (a serial fault after verdict_timeout).
        status, result = cell.result(handle)
        assert result.reason in (FeedPart.Result.REASON_REFUSED,
                                 FeedPart.Result.REASON_SERIAL_FAULT), result.detail
        assert time.monotonic() < deadline, result.detail
        ros.spin_for(0.5)
    try:
        status, result = cell.result(handle, timeout=30.0)
    finally:
        os.kill(hw.pid, signal.SIGCONT)
    assert result.reason == FeedPart.Result.REASON_SERIAL_FAULT, result.detail
    assert not result.success and 1 <= result.cycles < 87, result
    assert mon.poll() is None

if __name__ == '__main__':
    pytest.main([__file__, '-v'])
