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
A feeder_interfaces type in a bag: recorded with its full definition, decoded by mcap_ros2.

The Kilted type store has no feeder_interfaces; the writer reads Verdict's installed .msg
(the colcon install, on AMENT_PREFIX_PATH after ``. scripts/setup.sh``). The reader is the
independent one: mcap_ros2 decodes the CDR by the schema text the bag carries.
"""

import json
import pathlib
import time

from feeder_monitor.bag import BagWriter, installed_msg_file, installed_types, qos
import pytest
from rosbags.typesys import get_typestore, Stores

VERDICT = 'feeder_interfaces/msg/Verdict'
TOPIC = '/feeder/edge1_verdict'
RELIABLE = qos(1, 1000, 1, 2)          # keep last 1000, reliable, volatile


@pytest.fixture(scope='module')
def verdict_cls():
    try:
        from feeder_interfaces.msg import Verdict
    except ImportError as exc:
        pytest.fail(f'feeder_interfaces cannot be imported ({exc}): build and source the '
                    'colcon workspace (. scripts/setup.sh)')
    return Verdict


def _sample(verdict_cls, seq=41):
    from builtin_interfaces.msg import Time
    return verdict_cls(seq=seq, stamp=Time(sec=1_700_000_000, nanosec=123_456_789), ready=False,
                       state=verdict_cls.STATE_ANOMALY, anomaly='detection off the limit set',
                       session='c0ffee', sent=Time(sec=1_700_000_002, nanosec=5),
                       mac=bytes(range(32)))


def _read_back(bag_dir):
    """Decode every message of the bag's .mcap with mcap_ros2 (schema text -> fields)."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    (mcap_file,) = pathlib.Path(bag_dir).glob('*.mcap')
    with open(mcap_file, 'rb') as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        return list(reader.iter_decoded_messages())


def _check_decoded(got, want):
    schema, _, _, m = got
    assert schema.name == VERDICT and schema.encoding == 'ros2msg'
    text = schema.data.decode()
    assert 'uint8[] mac' in text and '\nMSG: builtin_interfaces/Time\n' in text
    assert (m.seq, m.ready, m.state, m.anomaly, m.session) == (
        want.seq, want.ready, want.state, want.anomaly, want.session)
    assert (m.stamp.sec, m.stamp.nanosec) == (want.stamp.sec, want.stamp.nanosec)
    assert (m.sent.sec, m.sent.nanosec) == (want.sent.sec, want.sent.nanosec)
    assert bytes(m.mac) == bytes(want.mac)


def _installed_hash():
    path = installed_msg_file(VERDICT).with_suffix('.json')
    hashes = json.loads(path.read_text())['type_hashes']
    return next(h['hash_string'] for h in hashes if h['type_name'] == VERDICT)


def test_an_installed_type_is_read_into_the_type_store(verdict_cls):
    ts = get_typestore(Stores.ROS2_KILTED)
    assert VERDICT not in ts.fielddefs
    assert installed_msg_file(VERDICT).name == 'Verdict.msg'
    assert installed_types(ts, VERDICT)
    consts, fields = ts.fielddefs[VERDICT]
    assert [f[0] for f in fields] == list(verdict_cls.get_fields_and_field_types())
    assert ('STATE_CYCLING', 'string', 'cycling') in consts
    # The hash rosidl wrote beside the .msg, the one a Verdict publisher announces.
    assert ts.hash_rihs01(VERDICT) == _installed_hash()
    assert installed_msg_file('feeder_interfaces/msg/Nope') is None
    assert installed_msg_file('no_such_pkg/msg/Nope') is None
    assert not installed_types(ts, 'no_such_pkg/msg/Nope')


def test_the_writer_records_a_verdict_that_mcap_ros2_decodes(verdict_cls, tmp_path):
    from rclpy.serialization import serialize_message
    w = BagWriter(tmp_path / 'bag')
    assert w.knows(VERDICT)
    w.add_topic(TOPIC, VERDICT, [RELIABLE])
    msgs = [_sample(verdict_cls, seq) for seq in (41, 42)]
    for k, msg in enumerate(msgs):
        w.write(TOPIC, 1000 + k, serialize_message(msg))
    w.close()
    got = _read_back(tmp_path / 'bag')
    assert [g[1].topic for g in got] == [TOPIC, TOPIC]
    assert got[0][1].metadata['topic_type_hash'] == _installed_hash()
    for g, want in zip(got, msgs):
        _check_decoded(g, want)


def test_a_type_that_is_nowhere_is_refused_naming_the_fix(tmp_path):
    w = BagWriter(tmp_path / 'bag')
    assert not w.knows('no_such_pkg/msg/Nope')
    with pytest.raises(ValueError, match='build and source the package'):
        w.add_topic('/x', 'no_such_pkg/msg/Nope')
    w.close()


def test_the_recorder_records_a_published_verdict(verdict_cls, domain_id, tmp_path):
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from feeder_monitor.bag_recorder import BagRecorder
    writer = BagWriter(tmp_path / 'bag')
    ctx = Context()
    rclpy.init(context=ctx, domain_id=domain_id)
    try:
        recorder = BagRecorder(writer, topics=[TOPIC], discovery_period=0.1, flush_period=0.2,
                               context=ctx)
        node = rclpy.create_node('verdict_pub', namespace='/feeder', context=ctx)
        pub = node.create_publisher(verdict_cls, 'edge1_verdict', 10)
        executor = SingleThreadedExecutor(context=ctx)
        executor.add_node(recorder)
        executor.add_node(node)
        msg = _sample(verdict_cls)
        end = time.monotonic() + 15.0
        while not writer.counts.get(TOPIC) and time.monotonic() < end:
            if pub.get_subscription_count():
                pub.publish(msg)
            executor.spin_once(timeout_sec=0.1)
        assert writer.counts.get(TOPIC), f'the recorder took no Verdict within 15 s: ' \
            f'{writer.counts}'
        executor.shutdown()
        recorder.destroy_node()
    finally:
        rclpy.shutdown(context=ctx)
        writer.close()
    got = _read_back(tmp_path / 'bag')
    assert got and all(g[1].topic == TOPIC for g in got)
    for g in got:
        _check_decoded(g, msg)
