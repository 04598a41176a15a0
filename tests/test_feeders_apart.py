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
Two feeders in one domain are told apart (issue 23, item 1): bags and diagnostics.

Two hardware stand-ins, in namespaces ``/left`` and ``/right``, each with its bag_recorder in
its namespace, cycle side by side. Each bag, read with the ``mcap`` package (not rosbags, not
the recorder's own code), holds only its feeder's topics plus ``/diagnostics``; the
``/diagnostics`` statuses of the two feeders have names of their own, in the bag and live.
"""

import pathlib

from diagnostic_msgs.msg import DiagnosticArray
from feeder_nodes import Collector, CycleStatuses, sim_as_hardware, STARTUP_TIMEOUT
from mcap.reader import make_reader
from rclpy.serialization import deserialize_message
from std_srvs.srv import SetBool

SPACES = ('/left', '/right')
SHARED = {'/diagnostics', '/tf', '/tf_static'}


def read_bag(bag_dir):
    """Topics (with message counts) and the /diagnostics status names of a bag's .mcap."""
    files = sorted(pathlib.Path(bag_dir).glob('*.mcap'))
    assert len(files) == 1, files
    counts, names = {}, set()
    with open(files[0], 'rb') as f:
        reader = make_reader(f)
        for _, channel, message in reader.iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            if channel.topic == '/diagnostics':
                msg = deserialize_message(message.data, DiagnosticArray)
                names |= {s.name for s in msg.status}
        summary = reader.get_summary()
        topics = {c.topic for c in summary.channels.values()} if summary else set(counts)
    return topics, counts, names


def test_each_feeders_recorder_takes_only_its_namespace(graph, ros, tmp_path):
    recorders = {}
    statuses = {}
    for ns in SPACES:
        sim_as_hardware(graph, 'cycle_period:=0.05', 'diagnostics_period:=0.2', ns=ns)
        recorders[ns] = graph.start('feeder_monitor', 'bag_recorder', tmp_path / ns[1:],
                                    '--discovery-period', '0.2', '--ros-args', '-r',
                                    f'__ns:={ns}', name=f'recorder_{ns[1:]}')
        statuses[ns] = CycleStatuses(ros, f'{ns}/cycle_status')
    live = Collector(ros, DiagnosticArray, '/diagnostics')
    for ns in SPACES:       # the stand-in's cycle_status matched the recorder's reader and ours
        ros.wait_remote_matched(f'{ns}/feeder_driver', readers={f'{ns}/cycle_status': 2})
    ros.spin_for(1.0)       # the recorders' discovery subscribes to every topic there
    for ns in SPACES:
        assert ros.call(SetBool, f'{ns}/feeder_driver/enable', SetBool.Request(data=True),
                        timeout=STARTUP_TIMEOUT).success
    ros.spin_until(lambda: all(len(statuses[ns]) >= 10 for ns in SPACES), 30.0, 'cycles')
    for ns in SPACES:
        assert ros.call(SetBool, f'{ns}/feeder_driver/enable',
                        SetBool.Request(data=False)).success
    ros.spin_for(0.5)
    for ns in SPACES:
        assert graph.stop(recorders[ns]) == 0, graph.log(recorders[ns])

    live_names = {s.name for m in live.msgs for s in m.status}
    for ns in SPACES:
        other = next(o for o in SPACES if o != ns)
        topics, counts, names = read_bag(tmp_path / ns[1:])
        strays = {t for t in topics if not t.startswith(ns + '/') and t not in SHARED}
        assert not strays, f'{ns} bag holds other topics: {sorted(strays)}'
        assert counts.get(f'{ns}/cycle_status', 0) >= 10, counts
        assert {f'{ns}/proximity', f'{ns}/joint_states', '/diagnostics'} <= topics, topics
        # Both feeders' statuses come on the shared /diagnostics; each has its own names.
        own = {n for n in names if n.startswith(f'{ns[1:]}/feeder_driver: ')}
        assert f'{ns[1:]}/feeder_driver: actuator' in own, sorted(names)
        assert f'{ns[1:]}/feeder_driver: actuator' in live_names, sorted(live_names)
        assert not own & {n.replace(ns[1:], other[1:], 1) for n in own}
    assert 'feeder_driver: actuator' not in live_names, sorted(live_names)
