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
A bag_recorder killed with SIGKILL at random moments (issue 10, item 6).

It used to leave no metadata.yaml and, after 5 s at 200 Hz, a 0-byte .mcap. Now the bag as the
kill leaves it is read by two independent readers (rosbags and the mcap library) and holds
every message published up to a second before the kill, without a gap; bag_reindex then gives
the .mcap its summary, and both readers read the same messages again.

The second is counted from the recorder's first flushed message: seeing the recorder's
subscription in the test's graph does not mean the recorder has discovered the test's writer
yet (DDS discovery is not symmetric in time; a missed announcement can delay it by seconds),
and what the recorder never received is no loss of the recorder's.
"""

import os
import random
import signal
import time

from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosbags.rosbag2 import Reader
from std_msgs.msg import Int32
import yaml

TOPIC = '/kill_test/counter'
PERIOD = 0.005                  # 200 Hz
LOSS_BOUND = 1.0                # s of messages a kill may lose


def read_counters(bag):
    """Return the values in the bag by rosbags and by the mcap library (they must agree)."""
    from mcap.reader import make_reader
    with Reader(bag) as reader:
        by_rosbags = [int.from_bytes(raw[4:8], 'little') for c, _, raw in reader.messages()
                      if c.topic == TOPIC]
    with open(bag / f'{bag.name}.mcap', 'rb') as fh:
        by_mcap = [int.from_bytes(m.data[4:8], 'little')
                   for _, ch, m in make_reader(fh).iter_messages() if ch.topic == TOPIC]
    assert by_rosbags == by_mcap
    return by_rosbags


def test_sigkill_at_random_moments_loses_at_most_a_second(graph, ros, tmp_path):
    seed = int.from_bytes(os.urandom(4), 'little')
    rng = random.Random(seed)
    pub = ros.node.create_publisher(Int32, TOPIC,
                                    QoSProfile(depth=1000,
                                               reliability=ReliabilityPolicy.RELIABLE))
    sent = []                   # monotonic send time of value k at index k - 1

    def tick():
        sent.append(time.monotonic())
        pub.publish(Int32(data=len(sent)))

    timer = ros.node.create_timer(PERIOD, tick)
    try:
        _kill_trials(graph, ros, tmp_path, rng, seed, sent)
    finally:
        # Stopped before the fixture's teardown destroys the node (no timer firing into it).
        ros.node.destroy_timer(timer)
        ros.node.destroy_publisher(pub)


def _first_flush_count(bag):
    try:
        meta = yaml.safe_load((bag / 'metadata.yaml').read_text())
        return meta['rosbag2_bagfile_information']['message_count']
    except (OSError, yaml.YAMLError, KeyError, TypeError):
        return 0


def _kill_trials(graph, ros, tmp_path, rng, seed, sent):
    # Early (within the first flush periods of its receiving), mid, and the 5 s of the report.
    for trial, after in enumerate([rng.uniform(0.05, 0.6), rng.uniform(0.6, 3.0),
                                   rng.uniform(5.0, 6.0)]):
        bag = tmp_path / f'bag{trial}'
        name = f'kill_test_recorder{trial}'
        rec = graph.start('feeder_monitor', 'bag_recorder', bag, '--topics', TOPIC,
                          '--ros-args', '-r', f'__node:={name}', name=name)
        ros.spin_until(lambda: any(i.node_name == name for i in
                                   ros.node.get_subscriptions_info_by_topic(TOPIC)),
                       60.0, 'the recorder')
        ros.spin_until(lambda: _first_flush_count(bag) > 0, 30.0,
                       "the recorder's first flushed message")
        matched = len(sent)
        kill_at = time.monotonic() + after
        ros.spin_until(lambda: time.monotonic() >= kill_at, after + 5.0, 'the kill moment')
        rec.send_signal(signal.SIGKILL)
        killed = time.monotonic()
        assert rec.wait(timeout=10) == -signal.SIGKILL
        published = len(sent)
        what = f'seed {seed}, trial {trial}, killed {after:.3f} s after the match'

        # As the kill left it: metadata.yaml and an .mcap that both readers read.
        meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
        got = read_counters(bag)
        gaps = [(a, b) for a, b in zip(got, got[1:]) if b != a + 1]
        assert not gaps, f'{what}: gaps (before, after) {gaps[:5]} in {got[0]}..{got[-1]}'
        assert meta['message_count'] <= len(got), what
        # Every value published more than LOSS_BOUND before the kill is in the bag.
        must = [k for k in range(matched + 50, published + 1) if sent[k - 1] < killed - LOSS_BOUND]
        if must:
            assert got and got[0] <= must[0] and got[-1] >= must[-1], (
                f'{what}: bag {got[:1]}..{got[-1:]} misses some of {must[0]}..{must[-1]}')

        lost = (killed - sent[got[-1] - 1]) if got else None
        print(f'{what}: {len(got)} messages in the bag of {published} published, '
              + (f'last one sent {lost:.3f} s before the kill' if got else 'none'))

        reindex = graph.start('feeder_monitor', 'bag_reindex', bag, name=f'reindex{trial}')
        assert reindex.wait(timeout=60) == 0, graph.log(reindex)
        assert f'{len(got)} messages on' in graph.log(reindex), (what, graph.log(reindex))
        assert read_counters(bag) == got, what
        meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
        assert meta['message_count'] == len(got), what
