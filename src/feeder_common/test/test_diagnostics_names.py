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

"""/diagnostics status names carry the node's namespace (issue 23, item 1)."""

import time

from diagnostic_msgs.msg import DiagnosticStatus
from feeder_common.diagnostics import (local_name, matched_endpoints, namespace_of,
                                       status_prefix, Updater)
from feeder_interfaces.msg import CycleStatus
import rclpy
from rclpy.context import Context


def test_names_carry_the_namespace_and_give_it_back():
    assert status_prefix('/feeder_1', 'feeder_driver') == 'feeder_1/feeder_driver'
    assert status_prefix('/line_2/feeder', 'feeder_monitor') == 'line_2/feeder/feeder_monitor'
    assert status_prefix('/', 'feeder_driver') == 'feeder_driver'
    name = 'line_2/feeder/feeder_monitor: readiness'
    assert namespace_of(name) == '/line_2/feeder'
    assert local_name(name) == 'feeder_monitor: readiness'
    assert namespace_of('feeder_driver: cycles') == '/'
    assert local_name('feeder_driver: cycles') == 'feeder_driver: cycles'


def test_an_updater_names_its_statuses_with_the_namespace():
    ctx = Context()
    rclpy.init(context=ctx)
    try:
        node = rclpy.create_node('feeder_driver', namespace='/feeder_2', context=ctx)
        updater = Updater(node, period=60.0)
        updater.add('cycles', lambda st: st.summary('ok', 'fine'))
        pub = node.create_publisher(CycleStatus, 'cycle_status', 10)
        status, endpoints = updater.statuses()
        assert status.name == 'feeder_2/feeder_driver: cycles'
        assert status.level == DiagnosticStatus.OK
        # Last, the node's matched endpoints: none matched here (no peer).
        assert endpoints.name == 'feeder_2/feeder_driver: endpoints'
        assert {kv.key: kv.value for kv in endpoints.values} == {
            'matched readers of /feeder_2/cycle_status': '0',
            'matched readers of /diagnostics': '0'}
        node.destroy_publisher(pub)
        node.destroy_node()
    finally:
        rclpy.shutdown(context=ctx)


def test_the_endpoints_status_counts_matched_peers(domain_id):
    """A writer's count goes up once a reader matched it, and the reader's likewise."""
    ctx = Context()
    rclpy.init(context=ctx, domain_id=domain_id)
    try:
        writer = rclpy.create_node('writer', namespace='/feeder', context=ctx)
        reader = rclpy.create_node('reader', namespace='/feeder', context=ctx)
        writer.create_publisher(CycleStatus, 'cycle_status', 10)
        reader.create_subscription(CycleStatus, 'cycle_status', lambda m: None, 10)
        end = time.monotonic() + 30.0
        while matched_endpoints(writer).get('matched readers of /feeder/cycle_status') != 1:
            assert time.monotonic() < end, matched_endpoints(writer)
            time.sleep(0.05)
        while matched_endpoints(reader).get('matched writers of /feeder/cycle_status') != 1:
            assert time.monotonic() < end, matched_endpoints(reader)
            time.sleep(0.05)
        writer.destroy_node()
        reader.destroy_node()
    finally:
        rclpy.shutdown(context=ctx)
