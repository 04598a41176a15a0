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

"""Helpers of the graph tests: start the feeder's nodes, collect what they publish."""

import pathlib

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

# The test's own QoS (written out here, not taken from the code under test).
RELIABLE = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)
LATCHED = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
STARTUP_TIMEOUT = 60.0
REPO = pathlib.Path(__file__).resolve().parents[1]
TRIANGLE = str(REPO / 'scenes' / 'triangle.yaml')


def sim_as_hardware(graph, *params, scene=TRIANGLE, ns='/feeder'):
    """sim_node in place of the driver: /feeder/feeder_driver with hardware_mode."""
    args = ['--ros-args', '-r', f'__ns:={ns}', '-r', '__node:=feeder_driver',
            '-p', 'hardware_mode:=true', '-p', f'scene:={scene}']
    for p in params:
        args += ['-p', p]
    return graph.start('feeder_sim', 'sim_node', *args, name='sim_hw')


def monitor(graph, *params, scene=TRIANGLE, ns='/feeder'):
    args = ['--ros-args', '-r', f'__ns:={ns}', '-p', f'scene:={scene}']
    for p in params:
        args += ['-p', p]
    return graph.start('feeder_monitor', 'monitor_node', *args, name='monitor')


class Collector:
    """Messages of one topic, in arrival order."""

    def __init__(self, ros, msg_type, topic, qos=RELIABLE):
        self.msgs = []
        self.sub = ros.node.create_subscription(msg_type, topic, self.msgs.append, qos)

    def __len__(self):
        return len(self.msgs)


class Diagnostics:
    """Every DiagnosticStatus on /diagnostics, by name."""

    def __init__(self, ros):
        self.by_name = {}
        ros.node.create_subscription(DiagnosticArray, '/diagnostics', self._on, RELIABLE)

    def _on(self, msg):
        for s in msg.status:
            self.by_name.setdefault(s.name, []).append(s)

    def levels(self, name):
        return [s.level for s in self.by_name.get(name, [])]

    @staticmethod
    def values(status):
        return {kv.key: kv.value for kv in status.values}


def status_values(msg):
    return {kv.key: kv.value for kv in msg.values}


def wait_for_monitor(ros, ready):
    """Wait for the monitor's latched initial edge1_ready (False)."""
    ros.spin_until(lambda: len(ready) >= 1, STARTUP_TIMEOUT, 'latched edge1_ready')
    assert ready.msgs[0].data is False


def wait_for_readers(ros, topic, count):
    ros.spin_until(lambda: ros.node.count_subscribers(topic) >= count, STARTUP_TIMEOUT,
                   f'{count} readers of {topic}')
