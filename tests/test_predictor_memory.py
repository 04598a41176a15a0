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
The predictor's memory while it cycles: what grows per cycle must not (issue 10's soak).

rclpy's callback group keeps a reference to every timer a node ever created, also after
``destroy_timer``: a node that creates a timer per cycle, or per markers period, grows without
bound. The predictor re-arms one markers timer instead (bench/mem_trace.py found the growth).
"""

import time

from feeder_common.node import make_executor
from feeder_nodes import TRIANGLE
import pytest
import rclpy
from rclpy.context import Context
from rclpy.parameter import Parameter

MARKERS_PERIOD = 0.02


@pytest.mark.parametrize('kind', ['events', 'single'])
def test_markers_that_wait_reuse_one_timer(kind):
    from feeder_common.node import autostart
    from feeder_sim.predictor_node import PredictorNode
    context = Context()
    rclpy.init(context=context)
    try:
        node = PredictorNode(context=context, namespace='/memtest', parameter_overrides=[
            Parameter('scene', value=TRIANGLE),
            Parameter('markers_period', value=MARKERS_PERIOD)])
        autostart(node)
        executor = make_executor(kind, context)
        executor.add_node(node)
        sent = []
        markers = node._pubs['markers']
        publish = markers.publish
        markers.publish = lambda msg: (sent.append(time.monotonic()), publish(msg))
        entities = len(node.default_callback_group.entities)
        end = time.monotonic() + 1.0
        # A new state every 5 ms, as at the fastest cycle: most of them must wait for the
        # markers period (the path a predicted throw takes, without a driver to follow).
        while time.monotonic() < end:
            last = time.monotonic()
            node._publish_markers()
            executor.spin_once(timeout_sec=0.005)
        # the last state follows within a period
        settle = time.monotonic() + 3 * MARKERS_PERIOD
        while time.monotonic() < settle:
            executor.spin_once(timeout_sec=0.005)
        grown = len(node.default_callback_group.entities) - entities
        executor.shutdown()
        node.destroy_node()
    finally:
        context.try_shutdown()
    assert len(sent) >= 10, 'the markers that waited were never sent'
    # At most one per period: counted over the whole run, not gap by gap (under load the
    # time this test reads after a late publish can make the next gap look short: 17.4 ms of
    # 20 in a loaded run); unthrottled, one per state (5 ms) would be 4 times too many.
    gaps = [b - a for a, b in zip(sent, sent[1:])]
    assert len(gaps) <= (sent[-1] - sent[0]) / (MARKERS_PERIOD * 0.9), gaps
    assert last <= sent[-1] <= last + 2 * MARKERS_PERIOD, (last, sent[-1])
    assert grown <= 1, f'{grown} timers created for {len(sent)} markers messages'
