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
import numpy as np
import pytest
from rosbags.interfaces import QosDurability, QosReliability
from rosbags.rosbag2 import Reader
import yaml


LATCHED = qos(1, 1, 1, 1)              # keep last 1, reliable, transient local
VOLATILE = qos(1, 10, 1, 2)


VERDICT = 'feeder_interfaces/msg/Verdict'


def test_round_trip(tmp_path):
    """A latched signed Verdict (edge1_ready) and a volatile Int32 topic, read back."""
    path = tmp_path / 'bag'
    w = BagWriter(path)
    ts = w.typestore
    # The recorder's own question: the writer finds the project's message definition
    # (installed with feeder_interfaces), it is in no store of the ROS distribution.
    assert w.knows(VERDICT)
    Verdict = ts.types[VERDICT]
    Time = ts.types['builtin_interfaces/msg/Time']
    Int32 = ts.types['std_msgs/msg/Int32']
    w.add_topic('/feeder/edge1_ready', VERDICT, [LATCHED])
    w.add_topic('/feeder/predicted/edge', 'std_msgs/msg/Int32', [VOLATILE])
    for k in range(5):
        w.write('/feeder/predicted/edge', 1000 + k,
                ts.serialize_cdr(Int32(data=k), Int32.__msgtype__), publish_time_ns=900 + k,
                sequence=k + 1)
    stamp, sent = Time(sec=1795362335, nanosec=204302396), Time(sec=1795362335, nanosec=3)
    mac = bytes(range(32))
    verdict = Verdict(seq=7, stamp=stamp, ready=True, state='ready', anomaly='',
                      session='ab12', sent=sent,
                      mac=np.frombuffer(mac, dtype=np.uint8))
    w.write('/feeder/edge1_ready', 2000, ts.serialize_cdr(verdict, VERDICT))
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
        ts.hash_rihs01(VERDICT)
    with Reader(path) as r:
        conns = {c.topic: c for c in r.connections}
        assert conns['/feeder/predicted/edge'].msgcount == 5
        latched = conns['/feeder/edge1_ready'].ext.offered_qos_profiles[0]
        assert latched.durability == QosDurability.TRANSIENT_LOCAL
        assert latched.reliability == QosReliability.RELIABLE
        plain = conns['/feeder/predicted/edge'].ext.offered_qos_profiles[0]
        assert plain.durability == QosDurability.VOLATILE
        got = [(c.topic, t, ts.deserialize_cdr(raw, c.msgtype))
               for c, t, raw in r.messages()]
    assert [(topic, t, m.data) for topic, t, m in got[:5]] == \
        [('/feeder/predicted/edge', 1000 + k, k) for k in range(5)]
    topic, t, v = got[5]
    assert (topic, t, v.seq, v.ready, v.state, v.session) == \
        ('/feeder/edge1_ready', 2000, 7, True, 'ready', 'ab12')
    assert (v.stamp.sec, v.stamp.nanosec, v.sent.nanosec) == (1795362335, 204302396, 3)
    assert bytes(v.mac) == mac
    # rclpy reads the same bytes as the generated feeder_interfaces class (what a consumer of
    # a bag does before feeder_common.messages.check_verdict).
    from feeder_interfaces.msg import Verdict as RosVerdict
    from rclpy.serialization import deserialize_message
    with Reader(path) as r:
        raw = next(raw for c, _, raw in r.messages() if c.topic == '/feeder/edge1_ready')
    back = deserialize_message(bytes(raw), RosVerdict)
    assert (back.seq, back.ready, bytes(back.mac)) == (7, True, mac)
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


# ---------------------------------------------------------------- a writer killed at any moment
def fill(writer, first, count):
    """Write Int32 messages first..first+count-1 on /a (two of three) and /b (latched)."""
    ts = writer.typestore
    Int32 = ts.types['std_msgs/msg/Int32']
    for k in range(first, first + count):
        writer.write('/a' if k % 3 else '/b', 1000 + k,
                     ts.serialize_cdr(Int32(data=k), Int32.__msgtype__), 900 + k, k)


def new_bag(path):
    w = BagWriter(path)
    w.add_topic('/a', 'std_msgs/msg/Int32', [VOLATILE])
    w.add_topic('/b', 'std_msgs/msg/Int32', [LATCHED])
    return w


def read_back(bag):
    """Return the Int32 values in the bag by rosbags, the mcap library's two readers, as one."""
    from mcap.reader import make_reader, NonSeekingReader
    with Reader(bag) as r:
        values = [int.from_bytes(raw[4:8], 'little') for _, _, raw in r.messages()]
        counts = {c.topic: c.msgcount for c in r.connections}
    mcap_file = next(bag.glob('*.mcap'))
    with open(mcap_file, 'rb') as fh:
        seeking = [int.from_bytes(m.data[4:8], 'little')
                   for _, _, m in make_reader(fh).iter_messages()]
    with open(mcap_file, 'rb') as fh:
        streamed = [int.from_bytes(m.data[4:8], 'little') for _, _, m in
                    NonSeekingReader(fh, validate_crcs=True).iter_messages()]
    assert values == seeking == streamed
    assert sum(counts.values()) == len(values)
    return values, counts


def has_summary(bag):
    from mcap.reader import make_reader
    with open(next(bag.glob('*.mcap')), 'rb') as fh:
        return make_reader(fh).get_summary() is not None


def test_metadata_yaml_exists_from_the_start(tmp_path):
    w = new_bag(tmp_path / 'bag')
    meta = yaml.safe_load((tmp_path / 'bag' / 'metadata.yaml').read_text())
    assert meta['rosbag2_bagfile_information']['message_count'] == 0
    w.flush()
    assert read_back(tmp_path / 'bag') == ([], {'/a': 0, '/b': 0})
    w.close()


def test_what_a_kill_leaves_is_a_readable_bag_of_every_flushed_message(tmp_path):
    """
    After each flush the bag reads back with every message written before it.

    Copying the directory while the writer runs is what SIGKILL leaves (the kernel keeps every
    write); the graph test kills a real recorder.
    """
    import shutil
    w = new_bag(tmp_path / 'bag')
    fill(w, 1, 100)
    shutil.copytree(tmp_path / 'bag', tmp_path / 'before_flush')
    w.flush()
    fill(w, 101, 50)
    shutil.copytree(tmp_path / 'bag', tmp_path / 'killed')
    w.flush()
    w.flush()                               # nothing new: no write
    fill(w, 151, 10)
    w.close()
    assert read_back(tmp_path / 'before_flush') == ([], {})    # topics come with a flush
    values, counts = read_back(tmp_path / 'killed')
    assert values == list(range(1, 101)) and counts == {'/a': 67, '/b': 33}
    assert not has_summary(tmp_path / 'killed')
    meta = yaml.safe_load((tmp_path / 'killed' / 'metadata.yaml').read_text())
    assert meta['rosbag2_bagfile_information']['message_count'] == 100
    assert read_back(tmp_path / 'bag')[0] == list(range(1, 161))
    assert has_summary(tmp_path / 'bag')


def test_a_big_chunk_is_written_before_the_flush(tmp_path, monkeypatch):
    import feeder_monitor.bag as bag_module
    monkeypatch.setattr(bag_module, 'CHUNK_BYTES', 1000)
    w = new_bag(tmp_path / 'bag')
    fill(w, 1, 100)                         # 34 bytes a message: a chunk every 30
    assert len(w._log.chunk_indexes) == 3
    w.close()
    assert read_back(tmp_path / 'bag')[0] == list(range(1, 101))


def test_reindex_finishes_a_killed_bag_and_rebuilds_metadata(tmp_path):
    import shutil
    from feeder_monitor.bag import reindex
    w = new_bag(tmp_path / 'bag')
    fill(w, 1, 100)
    w.flush()
    shutil.copytree(tmp_path / 'bag', tmp_path / 'killed')
    w.close()
    (tmp_path / 'killed' / 'metadata.yaml').unlink()
    report = reindex(tmp_path / 'killed')
    assert report == (f'{tmp_path / "killed"}: 100 messages on 2 topics; bag.mcap had no '
                      'summary (writer killed?): summary and footer written; metadata.yaml '
                      'rebuilt')
    assert has_summary(tmp_path / 'killed')
    assert read_back(tmp_path / 'killed') == read_back(tmp_path / 'bag')
    assert reindex(tmp_path / 'killed').endswith('complete; metadata.yaml rebuilt')
    meta = yaml.safe_load((tmp_path / 'killed' / 'metadata.yaml').read_text())
    full = yaml.safe_load((tmp_path / 'bag' / 'metadata.yaml').read_text())
    assert meta == full
    assert reindex(tmp_path / 'bag').endswith('bag.mcap complete; metadata.yaml rebuilt')


def test_reindex_copes_with_an_mcap_cut_off_anywhere(tmp_path, monkeypatch):
    """A kill in the middle of a write: every whole chunk before the cut is recovered."""
    import feeder_monitor.bag as bag_module
    from mcap.reader import make_reader
    monkeypatch.setattr(bag_module, 'CHUNK_BYTES', 400)
    w = new_bag(tmp_path / 'full')
    fill(w, 1, 60)
    w.close()
    data = (tmp_path / 'full' / 'full.mcap').read_bytes()
    with open(tmp_path / 'full' / 'full.mcap', 'rb') as fh:
        chunks = make_reader(fh).get_summary().chunk_indexes
    ends = sorted((c.chunk_start_offset + c.chunk_length, c) for c in chunks)
    header_end = 8 + 9 + int.from_bytes(data[9:17], 'little')
    near_ends = {end + d for end, _ in ends for d in (-1, 0, 1, 9, 30)}
    cuts = sorted((set(range(header_end, len(data), 31)) | near_ends
                   | {len(data) - 1, len(data) - 40}) & set(range(header_end, len(data))))
    for n, cut in enumerate(cuts):
        bag = tmp_path / f'cut{n}'
        bag.mkdir()
        (bag / 'cut.mcap').write_bytes(data[:cut])
        bag_module.reindex(bag)
        whole = [c for end, c in ends if end <= cut]
        values, _ = read_back(bag)
        assert len(values) == sum(sum(len(r) for r in _message_indexes(data, c)) for c in whole)
        assert values == list(range(1, len(values) + 1)), cut
        assert has_summary(bag)


def _message_indexes(data, chunk):
    from mcap.data_stream import ReadDataStream
    from mcap.records import MessageIndex
    import io
    out = []
    for offset in chunk.message_index_offsets.values():
        length = int.from_bytes(data[offset + 1:offset + 9], 'little')
        out.append(MessageIndex.read(ReadDataStream(io.BytesIO(data[offset + 9:
                                                                    offset + 9 + length]))
                                     ).records)
    return out


def test_reindex_refuses_what_it_cannot_repair(tmp_path):
    from feeder_monitor.bag import BagError, reindex, reindex_main
    (tmp_path / 'notmcap').mkdir()
    (tmp_path / 'notmcap' / 'x.mcap').write_bytes(b'hello world, not an mcap')
    with pytest.raises(BagError, match='does not start with the MCAP magic bytes'):
        reindex(tmp_path / 'notmcap')
    (tmp_path / 'short').mkdir()
    (tmp_path / 'short' / 'x.mcap').write_bytes(b'\x89MCAP0\r\n\x01\x30')
    with pytest.raises(BagError, match='ends inside its header record'):
        reindex(tmp_path / 'short')
    with pytest.raises(BagError, match='expected one .mcap file, found 0'):
        reindex(tmp_path)
    assert reindex_main([str(tmp_path / 'notmcap'), str(tmp_path / 'missing')]) == 2


def test_log_time_never_goes_back_so_an_unindexed_bag_reads(tmp_path):
    """A killed bag whose receive times were out of order: rosbags refused it."""
    import shutil
    w = new_bag(tmp_path / 'bag')
    ts = w.typestore
    Int32 = ts.types['std_msgs/msg/Int32']
    for k, t in enumerate([1000, 1005, 1003, 1010]):
        w.write('/a', t, ts.serialize_cdr(Int32(data=k + 1), Int32.__msgtype__), t - 100)
    w.flush()
    shutil.copytree(tmp_path / 'bag', tmp_path / 'killed')
    w.close()
    assert read_back(tmp_path / 'killed')[0] == [1, 2, 3, 4]
    with Reader(tmp_path / 'killed') as r:
        assert [t for _, t, _ in r.messages()] == [1000, 1005, 1005, 1010]
