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

"""(c) A bag of the running graph, recorded by bag_recorder and read back."""

import json
import math
import signal

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from feeder_common.messages import check_verdict, parse_cycle_fired, parse_predicted_state
from feeder_common.stamps import parse_stamp_text
from feeder_interfaces.msg import Verdict
from feeder_nodes import (Collector, MONITOR, monitor, predictor, sim_as_hardware, Statements,
                          STARTUP_TIMEOUT, status_values, TRIANGLE, Verdicts, wait_for_monitor,
                          wait_for_publishers)
from geometry_msgs.msg import PoseStamped
import pytest
from rclpy.serialization import deserialize_message
from rosbags.interfaces import QosDurability, QosReliability
from rosbags.rosbag2 import Reader
from sensor_msgs.msg import JointState, Range
from std_msgs.msg import Float64MultiArray, String
from std_srvs.srv import Trigger
from throwmap import load_scene
from visualization_msgs.msg import MarkerArray
import yaml

N = 20
# topic -> (type, expected count with N triggered cycles; None: at least one)
EXPECTED = {
    '/feeder/proximity': (Range, N),
    '/feeder/cycle_status': (DiagnosticStatus, N),
    '/feeder/joint_states': (JointState, 2 * N),
    '/feeder/predicted/state': (DiagnosticStatus, N),
    '/feeder/predicted/part_pose': (PoseStamped, N),
    '/feeder/predicted/limit_set': (Float64MultiArray, 1),      # latched, once
    '/feeder/predicted/analysis': (String, 1),                  # latched, once
    '/feeder/markers': (MarkerArray, None),     # latched + at most one per markers_period
    '/feeder/cycle_fired': (DiagnosticStatus, N),               # one per fired cycle
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
    statuses = Collector(ros, DiagnosticStatus, '/feeder/cycle_status')
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

    # Contents: what the test saw live, and what the interface promises.
    bits = [status_values(s)['sensor'] == '1' for s in msgs['/feeder/cycle_status']]
    assert bits == [status_values(s)['sensor'] == '1' for s in statuses.msgs]
    assert [r.range == -math.inf for r in msgs['/feeder/proximity']] == bits
    assert all(math.isinf(r.range) for r in msgs['/feeder/proximity'])
    assert [int(status_values(s)['seq']) for s in msgs['/feeder/cycle_status']] == \
        list(range(1, N + 1))
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
    ls = msgs['/feeder/predicted/limit_set'][0]
    assert [d.label for d in ls.layout.dim] == ['edges', 'fields']
    rows, fields = ls.layout.dim[0].size, ls.layout.dim[1].size
    assert fields == 5 and len(ls.data) == rows * fields and rows >= 2
    for r in range(rows):
        assert ls.data[r * 5 + 1] <= ls.data[r * 5 + 2]
    analysis = json.loads(msgs['/feeder/predicted/analysis'][0].data)
    assert analysis['sensor']['goal_edge'] == 1
    assert sorted(int(e) for e in analysis['limit_set']['bands']) == \
        [int(ls.data[r * 5]) for r in range(rows)]
    assert 2 <= len(msgs['/feeder/markers']) <= N + 1
    markers = msgs['/feeder/markers'][-1].markers
    assert {'arm', 'part', 'sensor', 'limit_set'} <= {m.ns for m in markers}
    assert all(m.header.frame_id == 'feeder_base' and m.color.a > 0 for m in markers)
    # The last markers show the last predicted state, upright in feeder_base (REP 103: the
    # library's plane x-y is x-z).
    outline = next(m for m in markers if (m.ns, m.id) == ('part', 0))
    states = [parse_predicted_state(m) for m in msgs['/feeder/predicted/state']]
    assert [p.seq for p in states] == list(range(1, N + 1))
    assert [p.stamp_ns for p in states] == \
        [parse_stamp_text(status_values(s)['stamp']) for s in msgs['/feeder/cycle_status']]
    edge, R = states[-1].edge, states[-1].R
    scene = load_scene(TRIANGLE)
    expected = scene.part.pose_vertices(edge, R, scene.h)
    got = [c for p in outline.points[:-1] for c in (p.x, p.z)]
    assert got == pytest.approx(expected.ravel().tolist())
    assert all(p.y == 0.0 for p in outline.points)
    poses = msgs['/feeder/predicted/part_pose']
    assert [p.pose.position.x for p in poses] == [p.R for p in states]
    names = {s.name for a in msgs['/diagnostics'] for s in a.status}
    assert {'feeder/feeder_driver: actuator', 'feeder/feeder_monitor: readiness'} <= names
