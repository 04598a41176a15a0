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

from feeder_monitor.bag import BagWriter, qos, qos_time
import pytest
from rosbags.interfaces import QosDurability, QosReliability
from rosbags.rosbag2 import Reader
import yaml


LATCHED = qos(1, 1, 1, 1)              # keep last 1, reliable, transient local
VOLATILE = qos(1, 10, 1, 2)


def test_round_trip(tmp_path):
    path = tmp_path / 'bag'
    w = BagWriter(path)
    ts = w.typestore
    Bool = ts.types['std_msgs/msg/Bool']
    Int32 = ts.types['std_msgs/msg/Int32']
    w.add_topic('/feeder/edge1_ready', 'std_msgs/msg/Bool', [LATCHED])
    w.add_topic('/feeder/predicted/edge', 'std_msgs/msg/Int32', [VOLATILE])
    for k in range(5):
        w.write('/feeder/predicted/edge', 1000 + k,
                ts.serialize_cdr(Int32(data=k), Int32.__msgtype__), publish_time_ns=900 + k,
                sequence=k + 1)
    w.write('/feeder/edge1_ready', 2000, ts.serialize_cdr(Bool(data=True), Bool.__msgtype__))
    assert w.counts == {'/feeder/edge1_ready': 1, '/feeder/predicted/edge': 5} and w.total == 6
    w.close()
    w.close()                          # idempotent
    meta = yaml.safe_load((path / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['storage_identifier'] == 'mcap' and meta['version'] == 9
    assert meta['message_count'] == 6 and meta['ros_distro'] == 'kilted'
    assert meta['starting_time']['nanoseconds_since_epoch'] == 1000
    assert meta['duration']['nanoseconds'] == 1000
    topics = {t['topic_metadata']['name']: t for t in meta['topics_with_message_count']}
    assert topics['/feeder/edge1_ready']['topic_metadata']['type_description_hash'] == \
        ts.hash_rihs01('std_msgs/msg/Bool')
    with Reader(path) as r:
        conns = {c.topic: c for c in r.connections}
        assert conns['/feeder/predicted/edge'].msgcount == 5
        latched = conns['/feeder/edge1_ready'].ext.offered_qos_profiles[0]
        assert latched.durability == QosDurability.TRANSIENT_LOCAL
        assert latched.reliability == QosReliability.RELIABLE
        plain = conns['/feeder/predicted/edge'].ext.offered_qos_profiles[0]
        assert plain.durability == QosDurability.VOLATILE
        got = [(c.topic, t, ts.deserialize_cdr(raw, c.msgtype).data)
               for c, t, raw in r.messages()]
    assert got[:5] == [('/feeder/predicted/edge', 1000 + k, k) for k in range(5)]
    assert got[5] == ('/feeder/edge1_ready', 2000, True)
    # The MCAP layout rosbag2_storage_mcap writes, read with the mcap library.
    from mcap.reader import make_reader
    with open(path / 'bag.mcap', 'rb') as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        chans = {c.topic: c for c in summary.channels.values()}
        assert chans['/feeder/edge1_ready'].metadata['topic_type_hash'].startswith('RIHS01_')
        assert 'transient_local' in chans['/feeder/edge1_ready'].metadata[
            'offered_qos_profiles']
        msgs = [(m.log_time, m.publish_time, m.sequence) for _, c, m in reader.iter_messages()
                if c.topic == '/feeder/predicted/edge']
        assert msgs == [(1000 + k, 900 + k, k + 1) for k in range(5)]
        assert [m.name for m in reader.iter_metadata()] == ['rosbag2']


def test_refuses_an_existing_path_and_a_second_connection(tmp_path):
    with pytest.raises(FileExistsError, match='exists'):
        BagWriter(tmp_path)
    w = BagWriter(tmp_path / 'b')
    assert w.knows('sensor_msgs/msg/Range') and not w.knows('feeder_msgs/msg/Nope')
    w.add_topic('/a', 'std_msgs/msg/Bool')
    with pytest.raises(ValueError, match='already'):
        w.add_topic('/a', 'std_msgs/msg/Bool')
    w.close()


def test_infinite_durations_like_rosbag2():
    t = qos_time(0x7FFFFFFFFFFFFFFF)
    assert (t.sec, t.nsec) == (9223372036, 854775807)
    assert qos_time(1_500_000_000) == qos_time(1_500_000_000)
    assert (qos_time(1_500_000_000).sec, qos_time(1_500_000_000).nsec) == (1, 500_000_000)
