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

from diagnostic_msgs.msg import DiagnosticStatus
from feeder_common.diagnostics import local_name, namespace_of, status_prefix, Updater
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
        (status,) = updater.statuses()
        assert status.name == 'feeder_2/feeder_driver: cycles'
        assert status.level == DiagnosticStatus.OK
        node.destroy_node()
    finally:
        rclpy.shutdown(context=ctx)
