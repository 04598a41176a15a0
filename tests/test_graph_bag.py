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
(c) A bag of the running graph, recorded by bag_recorder and read back.

Read back three ways: with rosbags (the recorder's own library) and rclpy's deserializer, and
with an independent reader (the ``mcap`` and ``mcap-ros2-support`` packages) that decodes every
message from nothing but the schema text in the bag, so the feeder's own types
(feeder_interfaces: CycleStatus, PredictedState, LimitSet, Analysis, Verdict) must come with
their full definitions, the types they nest included.
"""

import hashlib
import math
import signal

from diagnostic_msgs.msg import DiagnosticArray
from feeder_common.messages import (check_verdict, parse_cycle_fired, parse_cycle_status,
                                    parse_predicted_state)
from feeder_interfaces.msg import Analysis, CycleStatus, LimitSet, PredictedState, Verdict
from feeder_nodes import (CycleStatuses, MONITOR, monitor, predictor, sim_as_hardware,
                          Statements, STARTUP_TIMEOUT, TRIANGLE, Verdicts, wait_for_monitor,
                          wait_for_publishers)
from geometry_msgs.msg import PoseStamped
import pytest
from rclpy.serialization import deserialize_message
from rosbags.interfaces import QosDurability, QosReliability
from rosbags.rosbag2 import Reader
from sensor_msgs.msg import JointState, Range
from std_srvs.srv import Trigger
from throwmap import load_scene
from visualization_msgs.msg import MarkerArray
import yaml

N = 20
# topic -> (type, expected count with N triggered cycles; None: at least one)
EXPECTED = {
    '/feeder/proximity': (Range, N),
    '/feeder/cycle_status': (CycleStatus, N),
    '/feeder/joint_states': (JointState, 2 * N),
    '/feeder/predicted/state': (PredictedState, N),
    '/feeder/predicted/part_pose': (PoseStamped, N),
    '/feeder/predicted/limit_set': (LimitSet, 1),               # latched, once
    '/feeder/predicted/analysis': (Analysis, 1),                # latched, once
    '/feeder/markers': (MarkerArray, None),     # latched + at most one per markers_period
    '/feeder/cycle_fired': (CycleStatus, N),                    # one per fired cycle
    # latched statement + one per cycle (N cycles are all within the settling: never ready, so
    # no "cycling" statement either)
    '/feeder/edge1_ready': (Verdict, N + 1),
    '/feeder/edge1_verdict': (Verdict, N),                      # one per cycle
    '/diagnostics': (DiagnosticArray, None),
}
LATCHED_TOPICS = {'/feeder/predicted/limit_set', '/feeder/predicted/analysis', '/feeder/markers',
                  '/feeder/edge1_ready'}


def type_name(cls):
    module = cls.__module__.split('.')
    return f'{module[0]}/{module[1]}/{cls.__name__}'


def check_mcap_as_rosbag2_writes_it(path, meta):
    """
    Read the MCAP file with the mcap library (not with our writer's code) and check it.

    Channels carry offered_qos_profiles and topic_type_hash (the RIHS01 hash of the type:
    the one in the .json type description that ships with the message package); messages
    have publish_time = the publisher's send time, before log_time = receive time (a latched
    message reaches a late subscriber long after it was sent: only volatile ones are bounded).
    """
    from mcap.reader import make_reader
    with open(path, 'rb') as fh:
        reader = make_reader(fh)
        header = reader.get_header()
        summary = reader.get_summary()
        assert header.profile == 'ros2'
        channels = summary.channels
        by_topic = {c.topic: c for c in channels.values()}
        for topic, (cls, _) in EXPECTED.items():
            ch = by_topic[topic]
            assert ch.message_encoding == 'cdr'
            assert summary.schemas[ch.schema_id].encoding == 'ros2msg'
            assert summary.schemas[ch.schema_id].name == type_name(cls)
            assert 'offered_qos_profiles' in ch.metadata
            assert ch.metadata['topic_type_hash'] == shipped_type_hash(cls), topic
        metas = list(reader.iter_metadata())
        assert [m.name for m in metas] == ['rosbag2']
        inner = yaml.safe_load(metas[0].metadata['serialized_metadata'])
        assert inner['ros_distro'] == 'kilted' and inner['message_count'] == \
            meta['message_count']
        delays = {'/feeder/proximity': [], '/feeder/edge1_ready': []}
        for _, channel, message in reader.iter_messages():
            if channel.topic in delays:
                delays[channel.topic].append(message.log_time - message.publish_time)
        assert all(delays.values())
        assert all(0 < d < 5e9 for d in delays['/feeder/proximity'])
        assert all(d > 0 for d in delays['/feeder/edge1_ready']), \
            'publish_time must be the send time, not log_time'


# The schema text of each of our types names every type it nests (rosbag2's concatenated
# .msg definitions, one "MSG: pkg/Type" section per nested type).
NESTED = {
    'feeder_interfaces/msg/CycleStatus': {'builtin_interfaces/Time'},
    'feeder_interfaces/msg/PredictedState': {'builtin_interfaces/Time'},
    'feeder_interfaces/msg/LimitSet': {'feeder_interfaces/EdgeBand'},
    'feeder_interfaces/msg/Analysis': {
        'feeder_interfaces/LimitSet', 'feeder_interfaces/EdgeBand', 'feeder_interfaces/EdgeDesign',
        'feeder_interfaces/Escape', 'feeder_interfaces/BasinOutcome'},
    'feeder_interfaces/msg/Verdict': {'builtin_interfaces/Time'},
}


def same_fields(msg, decoded, path=''):
    """
    Assert that the independent reader's ``decoded`` message equals rclpy's ``msg``.

    Field by field as rclpy names them, recursing into nested messages and their sequences
    (NaN equals NaN; a uint8[] compares as bytes, a byte as its value).
    """
    for name in msg.get_fields_and_field_types():
        a, b = getattr(msg, name), getattr(decoded, name)
        where = f'{path}.{name}'
        if hasattr(a, 'get_fields_and_field_types'):
            same_fields(a, b, where)
        elif isinstance(a, (list, tuple)) and a and hasattr(a[0], 'get_fields_and_field_types'):
            assert len(a) == len(b), where
            for k, (x, y) in enumerate(zip(a, b)):
                same_fields(x, y, f'{where}[{k}]')
        elif isinstance(a, float):
            assert a == b or (math.isnan(a) and math.isnan(b)), (where, a, b)
        elif isinstance(a, bytes) and isinstance(b, int):     # a byte field: rclpy's b'\x01'
            assert a == bytes([b]), (where, a, b)
        elif isinstance(a, (bytes, bytearray)) or getattr(a, 'typecode', None) == 'B':
            assert bytes(a) == bytes(b), where
        elif not isinstance(a, (str, int, bool)):
            assert list(a) == pytest.approx(list(b), nan_ok=True), where
        else:
            assert a == b, (where, a, b)


def check_mcap_decodes_every_message(path, meta, msgs):
    """
    Decode every message of the bag with mcap-ros2-support, from the bag's schemas alone.

    The count is the bag's; each message equals what rclpy deserialized (``msgs``: by topic,
    in order); our types' schemas carry their nested definitions; and the typed topics come
    out with their fields as the contract reads them.
    """
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    decoded = {}
    with open(path, 'rb') as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        schemas = reader.get_summary().schemas
        for name, nested in NESTED.items():
            (schema,) = [sc for sc in schemas.values() if sc.name == name]
            text = schema.data.decode()
            assert {line[len('MSG: '):].strip() for line in text.splitlines()
                    if line.startswith('MSG: ')} == nested, (name, text)
        count = 0
        for _, channel, _, message in reader.iter_decoded_messages():
            decoded.setdefault(channel.topic, []).append(message)
            count += 1
    assert count == meta['message_count']
    for topic, live in msgs.items():
        assert len(decoded[topic]) == len(live), topic
        for k, (msg, dec) in enumerate(zip(live, decoded[topic])):
            same_fields(msg, dec, f'{topic}[{k}]')

    # The typed topics, as read by the independent reader.
    statuses = decoded['/feeder/cycle_status']
    assert [d.seq for d in statuses] == list(range(1, N + 1))
    assert all(d.outcome == 'completed' and d.sensor in (0, 1) and d.reason == ''
               and d.hardware_id == 'sim' and len(d.mac) == 32 for d in statuses)
    assert all(d.stamp.sec > 0 for d in statuses)
    fired = decoded['/feeder/cycle_fired']
    assert [(d.seq, d.outcome, d.sensor) for d in fired] == \
        [(k, 'fired', -1) for k in range(1, N + 1)]
    states = decoded['/feeder/predicted/state']
    assert [d.seq for d in states] == list(range(1, N + 1))
    assert all(d.edge >= 0 and 0 < d.r < 1 and d.throw_kind in ('jog', 'flip') for d in states)
    assert [(d.stamp.sec, d.stamp.nanosec) for d in states] == \
        [(d.stamp.sec, d.stamp.nanosec) for d in statuses]
    (ls,) = decoded['/feeder/predicted/limit_set']
    (an,) = decoded['/feeder/predicted/analysis']
    assert len(ls.pattern) >= 2 and list(an.limit_set.pattern) == list(ls.pattern)
    assert [(b.edge, b.r_min, b.r_max, b.jogs_min, b.jogs_max) for b in an.limit_set.bands] == \
        [(b.edge, b.r_min, b.r_max, b.jogs_min, b.jogs_max) for b in ls.bands]
    assert sorted(b.edge for b in ls.bands) == sorted(set(ls.pattern))
    assert all(0 < b.r_min <= b.r_max for b in ls.bands)
    assert an.goal_edge == 1 and an.sensor_feasible and an.edges
    assert all(e.r_min <= e.r_flip for e in an.edges)
    for topic in ('/feeder/edge1_ready', '/feeder/edge1_verdict'):
        assert all(len(d.mac) == 32 and d.sent.sec > 0 for d in decoded[topic]), topic
    return decoded


def shipped_type_hash(cls):
    """RIHS01 hash from the type description (.json) installed with the message package."""
    import json
    import pathlib
    import sys
    pkg, kind = cls.__module__.split('.')[:2]
    path = pathlib.Path(sys.prefix) / 'share' / pkg / kind / f'{cls.__name__}.json'
    if not path.is_file():      # a ROS install rather than the wheels: look it up there
        from ament_index_python.packages import get_package_share_directory
        path = pathlib.Path(get_package_share_directory(pkg)) / kind / f'{cls.__name__}.json'
    return json.loads(path.read_text())['type_hashes'][0]['hash_string']


def recorder_subscribed(ros, topic, name='feeder_bag_recorder'):
    return any(i.node_name == name for i in ros.node.get_subscriptions_info_by_topic(topic))


def test_bag_of_the_graph_reads_back(graph, ros, tmp_path):
    bag = tmp_path / 'run'
    sim_as_hardware(graph, 'joint_states_rate:=0')     # joint states at release and rest only
    predictor(graph)
    monitor(graph, 'ready_deadline:=60')       # no idle republishing within the test
    ready = Statements(ros)
    verdicts = Verdicts(ros)
    statuses = CycleStatuses(ros)
    wait_for_monitor(ros, ready)
    verdicts.wait_matched()
    wait_for_publishers(ros, '/feeder/predicted/state', 1)
    rec = graph.start('feeder_monitor', 'bag_recorder', bag, '--ros-args', '-r',
                      '__ns:=/feeder', name='recorder')
    # Two more: selected topics until 10 messages; everything but /diagnostics for 6 s.
    few = graph.start('feeder_monitor', 'bag_recorder', tmp_path / 'few', '--topics',
                      'proximity', '/feeder/cycle_status', '--max-messages', '10',
                      '--ros-args', '-r', '__ns:=/feeder', '-r', '__node:=few_recorder',
                      name='few')
    timed = graph.start('feeder_monitor', 'bag_recorder', tmp_path / 'timed', '--duration', '6',
                        '--exclude', '^/diagnostics$', '--ros-args', '-r', '__ns:=/feeder',
                        '-r', '__node:=timed_recorder', name='timed')
    ros.spin_until(lambda: all(recorder_subscribed(ros, t) for t in EXPECTED), STARTUP_TIMEOUT,
                   'the recorder on every topic')
    ros.spin_until(lambda: all(recorder_subscribed(ros, t, 'few_recorder') for t in
                               ('/feeder/proximity', '/feeder/cycle_status')), STARTUP_TIMEOUT,
                   'the second recorder')
    ros.spin_for(1.0)       # latched messages reach the recorder
    for k in range(N):
        res = ros.call(Trigger, '/feeder/feeder_driver/trigger_cycle', Trigger.Request())
        assert res.success, res.message
        assert res.message.startswith(f'fired cycle seq {k + 1}')
    ros.spin_until(lambda: len(statuses) == N and len(ready) == N + 1 and len(verdicts) == N,
                   20.0, 'all cycles')
    ros.spin_for(1.2)       # and /diagnostics once more
    rec.send_signal(signal.SIGTERM)     # (the demo stops its recorder with SIGINT)
    assert rec.wait(timeout=10) == 0
    assert f'in {bag}' in graph.log(rec)
    assert 'stopped: interrupted (SIGTERM)' in graph.log(rec)
    assert few.wait(timeout=10) == 0 and 'stopped: 10 messages;' in graph.log(few)
    assert timed.wait(timeout=20) == 0 and 'stopped: 6.0 s;' in graph.log(timed)
    with Reader(tmp_path / 'few') as reader:
        assert {c.topic: c.msgcount for c in reader.connections} == {
            '/feeder/proximity': 5, '/feeder/cycle_status': 5}
    with Reader(tmp_path / 'timed') as reader:
        topics = {c.topic for c in reader.connections}
        assert '/diagnostics' not in topics and '/feeder/edge1_ready' in topics

    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['storage_identifier'] == 'mcap' and meta['version'] == 9
    assert meta['ros_distro'] == 'kilted'
    assert [f['path'] for f in meta['files']] == ['run.mcap']
    check_mcap_as_rosbag2_writes_it(bag / 'run.mcap', meta)

    with Reader(bag) as reader:
        conns = {c.topic: c for c in reader.connections}
        for topic, (cls, count) in EXPECTED.items():
            assert topic in conns, f'{topic} not recorded'
            assert conns[topic].msgtype == type_name(cls)
            if count is None:
                assert conns[topic].msgcount >= 1, topic
            else:
                assert conns[topic].msgcount == count, (topic, conns[topic].msgcount)
            qos = conns[topic].ext.offered_qos_profiles
            assert qos, f'{topic}: no offered QoS recorded'
            durability = (QosDurability.TRANSIENT_LOCAL if topic in LATCHED_TOPICS
                          else QosDurability.VOLATILE)
            assert all(q.durability == durability for q in qos), (topic, qos)
            assert all(q.reliability == QosReliability.RELIABLE for q in qos), (topic, qos)
        assert meta['message_count'] == sum(c.msgcount for c in reader.connections)
        msgs = {}
        last_t = {}
        for conn, t, raw in reader.messages():
            if conn.topic not in EXPECTED:
                continue
            assert t >= last_t.get(conn.topic, 0)
            last_t[conn.topic] = t
            msgs.setdefault(conn.topic, []).append(
                deserialize_message(raw, EXPECTED[conn.topic][0]))

    # Every message, decoded by an independent reader from the bag's schemas alone.
    check_mcap_decodes_every_message(bag / 'run.mcap', meta, msgs)

    # Contents: what the test saw live, and what the interface promises.
    reports = [parse_cycle_status(s) for s in msgs['/feeder/cycle_status']]
    bits = [r.sensor for r in reports]
    assert bits == [s.sensor for s in statuses.parsed]
    assert [r.range == -math.inf for r in msgs['/feeder/proximity']] == bits
    assert all(math.isinf(r.range) for r in msgs['/feeder/proximity'])
    assert [r.seq for r in reports] == list(range(1, N + 1))
    assert all(r.ok and r.reason == '' and len(r.mac) == 32 for r in reports)
    # The signed statements and verdicts read back as sent: every one still verifies under the
    # run's key (a bag is evidence), seq by seq as the test saw them live.

    def fields(v):
        return (v.seq, v.stamp.sec, v.stamp.nanosec, v.ready, v.state, v.anomaly, v.session,
                v.sent.sec, v.sent.nanosec, bytes(v.mac))
    for topic, live in (('/feeder/edge1_ready', ready), ('/feeder/edge1_verdict', verdicts)):
        assert [fields(v) for v in msgs[topic]] == [fields(v) for v in live.msgs], topic
        assert all(check_verdict(v, ros.key, MONITOR, 0, max_age_s=1e12).authentic
                   for v in msgs[topic]), topic
    assert (msgs['/feeder/edge1_ready'][0].seq, msgs['/feeder/edge1_ready'][0].ready) == \
        (0, False)
    assert [v.seq for v in msgs['/feeder/edge1_verdict']] == list(range(1, N + 1))
    assert not any(v.ready for v in msgs['/feeder/edge1_verdict'])
    fired = [parse_cycle_fired(m) for m in msgs['/feeder/cycle_fired']]
    assert [f.seq for f in fired] == list(range(1, N + 1))
    assert all(len(f.mac) == 32 for f in fired)
    velocities = [js.velocity[0] for js in msgs['/feeder/joint_states']]
    assert velocities[1::2] == [0.0] * N and all(v > 0 for v in velocities[::2])
    (ls,) = msgs['/feeder/predicted/limit_set']
    assert len(ls.bands) >= 2 and all(b.r_min <= b.r_max for b in ls.bands)
    assert [b.edge for b in ls.bands] == sorted(set(ls.pattern))
    (analysis,) = msgs['/feeder/predicted/analysis']
    scene = load_scene(TRIANGLE)
    assert analysis.scene == scene.name and analysis.goal_edge == 1
    with open(TRIANGLE, 'rb') as scene_file:
        digest = hashlib.sha256(scene_file.read()).digest()
    assert analysis.scene_hash == int.from_bytes(digest[:8], 'big')
    assert analysis.limit_set == ls       # the latched limit set is the analysis' own
    assert 2 <= len(msgs['/feeder/markers']) <= N + 1
    markers = msgs['/feeder/markers'][-1].markers
    assert {'arm', 'part', 'sensor', 'limit_set'} <= {m.ns for m in markers}
    assert all(m.header.frame_id == 'feeder_base' and m.color.a > 0 for m in markers)
    # The last markers show the last predicted state, upright in feeder_base (REP 103: the
    # library's plane x-y is x-z).
    outline = next(m for m in markers if (m.ns, m.id) == ('part', 0))
    states = [parse_predicted_state(m) for m in msgs['/feeder/predicted/state']]
    assert [p.seq for p in states] == list(range(1, N + 1))
    assert [p.stamp_ns for p in states] == [r.stamp_ns for r in reports]
    edge, R = states[-1].edge, states[-1].R
    expected = scene.part.pose_vertices(edge, R, scene.h)
    got = [c for p in outline.points[:-1] for c in (p.x, p.z)]
    assert got == pytest.approx(expected.ravel().tolist())
    assert all(p.y == 0.0 for p in outline.points)
    poses = msgs['/feeder/predicted/part_pose']
    assert [p.pose.position.x for p in poses] == [p.R for p in states]
    names = {s.name for a in msgs['/diagnostics'] for s in a.status}
    assert {'feeder/feeder_driver: actuator', 'feeder/feeder_monitor: readiness'} <= names
