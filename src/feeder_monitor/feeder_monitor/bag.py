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
rosbag2 MCAP bags written with rosbags (ROS-free: the recorder node feeds it CDR bytes).

The bag is a directory with ``metadata.yaml`` and one ``.mcap`` file, rosbag2 format version 9
(Kilted), the layout rosbag2_storage_mcap writes, so ``ros2 bag info/play`` read it. Each topic
keeps the QoS its publishers offered (``offered_qos_profiles``): a latched topic stays transient
local on replay.
"""

import pathlib

from rosbags.interfaces import (Qos, QosDurability, QosHistory, QosLiveliness, QosReliability,
                                QosTime)
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores


def qos_time(nanoseconds):
    """Convert a duration in ns to QosTime (rosbag2: infinite = 9223372036 s 854775807 ns)."""
    sec, nsec = divmod(int(nanoseconds), 1_000_000_000)
    return QosTime(sec, nsec)


def qos(history, depth, reliability, durability, deadline_ns=0, lifespan_ns=0, liveliness=0,
        lease_ns=0, avoid_ros_namespace_conventions=False):
    """Build a rosbags Qos from rmw enum values (the same integers rclpy's policies use)."""
    return Qos(QosHistory(int(history)), int(depth), QosReliability(int(reliability)),
               QosDurability(int(durability)), qos_time(deadline_ns), qos_time(lifespan_ns),
               QosLiveliness(int(liveliness)), qos_time(lease_ns),
               bool(avoid_ros_namespace_conventions))


class BagWriter:
    """A rosbag2 MCAP directory being written: topics, then serialized CDR messages."""

    def __init__(self, path):
        self.path = pathlib.Path(path)
        if self.path.exists():
            raise FileExistsError(f'{self.path} exists; give a new directory for the bag')
        self.typestore = get_typestore(Stores.ROS2_KILTED)
        self._writer = Writer(self.path, version=Writer.VERSION_LATEST,
                              storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        self._connections = {}
        self.counts = {}
        self.closed = False

    def knows(self, msgtype):
        """Whether the Kilted type store has ``msgtype`` (e.g. 'std_msgs/msg/Bool')."""
        return msgtype in self.typestore.fielddefs

    def add_topic(self, topic, msgtype, offered_qos=()):
        """Add a topic with its publishers' QoS profiles (a list of rosbags Qos)."""
        if topic in self._connections:
            raise ValueError(f'{topic} is already in the bag')
        self._connections[topic] = self._writer.add_connection(
            topic, msgtype, typestore=self.typestore, serialization_format='cdr',
            offered_qos_profiles=list(offered_qos))
        self.counts[topic] = 0

    def write(self, topic, stamp_ns, data):
        """Write one serialized message received at ``stamp_ns`` (int ns)."""
        self._writer.write(self._connections[topic], int(stamp_ns), bytes(data))
        self.counts[topic] += 1

    @property
    def total(self):
        return sum(self.counts.values())

    def close(self):
        if not self.closed:
            self.closed = True
            self._writer.close()
