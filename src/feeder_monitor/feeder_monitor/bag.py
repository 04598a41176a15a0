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
rosbag2 MCAP bags as ``ros2 bag record`` writes them (ROS-free: the recorder feeds CDR bytes).

A bag is a directory with ``metadata.yaml`` (rosbag2 format version 9, ``ros_distro:
kilted``) and one ``.mcap`` file laid out as rosbag2_storage_mcap writes it: profile ``ros2``,
one ``ros2msg`` schema per type (the full definition with its dependencies, from the rosbags
Kilted type store), one ``cdr`` channel per topic whose metadata carries
``offered_qos_profiles`` (so a latched topic is replayed latched) and ``topic_type_hash`` (the
RIHS01 hash of the type), messages with ``log_time`` = receive time and ``publish_time`` = send
time, and a ``rosbag2`` metadata record holding the serialized bag metadata.
"""

from dataclasses import dataclass
import os
import pathlib
from typing import Optional

from mcap.writer import CompressionType, Writer
from rosbags.interfaces import (Qos, QosDurability, QosHistory, QosLiveliness, QosReliability,
                                QosTime)
from rosbags.rosbag2.metadata import dump_qos_v9
from rosbags.typesys import get_typestore, Stores
import yaml

VERSION = 9
ROS_DISTRO = 'kilted'
LIBRARY = 'feeder bag_recorder (rosbag2_storage_mcap layout)'


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


@dataclass
class _Topic:
    name: str
    msgtype: str
    type_hash: str
    qos_profiles: list
    channel_id: int
    count: int = 0
    first_ns: Optional[int] = None
    last_ns: Optional[int] = None


def _yaml(data):
    return yaml.safe_dump(data, default_flow_style=False, sort_keys=False)


class BagWriter:
    """A rosbag2 MCAP directory being written: topics, then serialized CDR messages."""

    def __init__(self, path):
        self.path = pathlib.Path(path)
        if self.path.exists():
            raise FileExistsError(f'{self.path} exists; give a new directory for the bag')
        self.path.mkdir(parents=True)
        self.typestore = get_typestore(Stores.ROS2_KILTED)
        self.file_name = f'{self.path.name}.mcap'
        self._stream = open(self.path / self.file_name, 'xb')
        # rosbag2's defaults: chunked, no compression.
        self._writer = Writer(self._stream, compression=CompressionType.NONE)
        self._writer.start(profile='ros2', library=LIBRARY)
        self._schemas = {}
        self._topics = {}
        self.closed = False

    def knows(self, msgtype):
        """Whether the Kilted type store has ``msgtype`` (e.g. 'std_msgs/msg/Bool')."""
        return msgtype in self.typestore.fielddefs

    def type_hash(self, msgtype):
        """RIHS01 hash of ``msgtype`` from the type store (what the type's .json file says)."""
        return self.typestore.hash_rihs01(msgtype)

    def add_topic(self, topic, msgtype, offered_qos=(), type_hash=None):
        """
        Add a topic with its publishers' QoS profiles (rosbags Qos) and type hash.

        ``type_hash`` is the hash the publishers announced (rosbag2 records that one); None:
        the type store's.
        """
        if topic in self._topics:
            raise ValueError(f'{topic} is already in the bag')
        if msgtype not in self._schemas:
            msgdef, _ = self.typestore.generate_msgdef(msgtype, ros_version=2)
            self._schemas[msgtype] = self._writer.register_schema(
                name=msgtype, encoding='ros2msg', data=msgdef.encode())
        type_hash = type_hash or self.type_hash(msgtype)
        profiles = list(offered_qos)
        channel = self._writer.register_channel(
            topic=topic, message_encoding='cdr', schema_id=self._schemas[msgtype],
            metadata={'offered_qos_profiles': _yaml(dump_qos_v9(profiles)).strip(),
                      'topic_type_hash': type_hash})
        self._topics[topic] = _Topic(topic, msgtype, type_hash, profiles, channel)

    def write(self, topic, log_time_ns, data, publish_time_ns=None, sequence=0):
        """Write one serialized message (times: received, sent; int ns)."""
        t = self._topics[topic]
        log_time_ns = int(log_time_ns)
        self._writer.add_message(
            channel_id=t.channel_id, log_time=log_time_ns, data=bytes(data),
            publish_time=int(log_time_ns if publish_time_ns is None else publish_time_ns),
            sequence=int(sequence) & 0xFFFFFFFF)
        t.count += 1
        t.first_ns = log_time_ns if t.first_ns is None else min(t.first_ns, log_time_ns)
        t.last_ns = log_time_ns if t.last_ns is None else max(t.last_ns, log_time_ns)

    @property
    def counts(self):
        return {name: t.count for name, t in self._topics.items()}

    @property
    def total(self):
        return sum(t.count for t in self._topics.values())

    def metadata(self):
        """Return the ``rosbag2_bagfile_information`` of the bag so far (version 9)."""
        times = [(t.first_ns, t.last_ns) for t in self._topics.values() if t.count]
        start = min(a for a, _ in times) if times else 0
        duration = max(b for _, b in times) - start if times else 0
        count = self.total
        return {
            'version': VERSION,
            'storage_identifier': 'mcap',
            'duration': {'nanoseconds': duration},
            'starting_time': {'nanoseconds_since_epoch': start},
            'message_count': count,
            'topics_with_message_count': [
                {'topic_metadata': {'name': t.name, 'type': t.msgtype,
                                    'serialization_format': 'cdr',
                                    'offered_qos_profiles': dump_qos_v9(t.qos_profiles),
                                    'type_description_hash': t.type_hash},
                 'message_count': t.count}
                for t in self._topics.values()],
            'compression_format': '',
            'compression_mode': '',
            'relative_file_paths': [self.file_name],
            'files': [{'path': self.file_name,
                       'starting_time': {'nanoseconds_since_epoch': start},
                       'duration': {'nanoseconds': duration},
                       'message_count': count}],
            'custom_data': {},
            'ros_distro': ROS_DISTRO,
        }

    def close(self):
        """Finish the MCAP file (summary, metadata record) and write metadata.yaml."""
        if self.closed:
            return
        self.closed = True
        info = self.metadata()
        self._writer.add_metadata('rosbag2', {'serialized_metadata': _yaml(info)})
        self._writer.finish()
        self._stream.close()
        tmp = self.path / 'metadata.yaml.tmp'
        tmp.write_text(_yaml({'rosbag2_bagfile_information': info}))
        os.replace(tmp, self.path / 'metadata.yaml')
