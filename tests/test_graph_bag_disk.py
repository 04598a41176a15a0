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
The bag_recorder executable on a filesystem that fills up (issue 20, attack 9).

A 256 KiB tmpfs is mounted (this needs root: CAP_SYS_ADMIN; without it the test is skipped
and says why) and a 2 KB message is published at 200 Hz into a recorder writing there. It used
to end with a traceback and, in one run of two, an .mcap no reader opened. Now it ends by
itself with exit status 3 and one line naming the cause and the fix, and the bag holds, by
rosbags and by the mcap library alike, the messages it says it flushed, without a gap. Then
the filesystem is filled to the last byte and bag_reindex runs in place: it works or says in
one line why not (exit status 3), and the bag reads the same after it; with space again it
rebuilds metadata.yaml. The same with a file size limit (RLIMIT_FSIZE: EFBIG), which needs
no root.
"""

import errno
import os
import shutil
import subprocess

import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosbags.rosbag2 import Reader
from std_msgs.msg import String
import yaml

TOPIC = '/disk_test/blob'
PERIOD = 0.005                  # 200 Hz
PAD = 'x' * 2000


def read_counters(bag):
    """Return the counters in the bag by rosbags and by the mcap library (they must agree)."""
    from mcap.reader import make_reader
    with Reader(bag) as reader:
        by_rosbags = [int(raw[8:16]) for c, _, raw in reader.messages() if c.topic == TOPIC]
    with open(bag / f'{bag.name}.mcap', 'rb') as fh:
        by_mcap = [int(m.data[8:16]) for _, ch, m in make_reader(fh).iter_messages()
                   if ch.topic == TOPIC]
    assert by_rosbags == by_mcap
    return by_rosbags


@pytest.fixture
def small_fs(tmp_path):
    """Mount a 256 KiB tmpfs at tmp_path/disk; skip, saying why, where that is not permitted."""
    where = tmp_path / 'disk'
    where.mkdir()
    if os.geteuid() != 0:
        pytest.skip(f'mounting a tmpfs needs root (CAP_SYS_ADMIN); this runs as uid '
                    f'{os.geteuid()}')
    got = subprocess.run(['mount', '-t', 'tmpfs', '-o', 'size=256k,mode=0755', 'tmpfs',
                          str(where)], capture_output=True, text=True)
    if got.returncode != 0:
        pytest.skip(f'mount -t tmpfs refused here (status {got.returncode}): '
                    f'{got.stderr.strip()}')
    try:
        yield where
    finally:
        subprocess.run(['umount', '-l', str(where)], check=True)


def _fill(where):
    """Write a filler file until the filesystem refuses a single byte; return its path."""
    filler = where / 'filler'
    with open(filler, 'wb', buffering=0) as fh:
        for size in (65536, 4096, 512, 1):
            try:
                while True:
                    fh.write(bytes(size))
            except OSError as exc:
                assert exc.errno == errno.ENOSPC, exc
    return filler


def _one_error_line(log, prog):
    assert 'Traceback' not in log, log
    lines = [ln for ln in log.splitlines() if ln.startswith(f'{prog}: error:')
             or ln.startswith(f'{prog}: disk')]
    assert len(lines) == 1, log
    return lines[0]


def _record_until_refused(graph, ros, bag, cause, wrapper=()):
    """Publish 2 KB messages at 200 Hz into a recorder until the disk stops it; check it."""
    pub = ros.node.create_publisher(String, TOPIC,
                                    QoSProfile(depth=1000,
                                               reliability=ReliabilityPolicy.RELIABLE))
    sent = [0]

    def tick():
        sent[0] += 1
        pub.publish(String(data=f'{sent[0]:08d}{PAD}'))

    timer = ros.node.create_timer(PERIOD, tick)
    try:
        rec = graph.start('feeder_monitor', 'bag_recorder', bag, '--topics', TOPIC,
                          name='disk_recorder', wrapper=wrapper)
        ros.spin_until(lambda: rec.poll() is not None, 25.0, 'the recorder to stop by itself')
    finally:
        ros.node.destroy_timer(timer)
        ros.node.destroy_publisher(pub)
    log = graph.log(rec)
    assert rec.returncode == 3, log
    line = _one_error_line(log, 'bag_recorder')
    assert line.startswith(f'bag_recorder: error: {cause} writing {bag}/'), line
    assert line.endswith(', then record again'), line
    got = read_counters(bag)
    assert got, line
    assert got == list(range(got[0], got[0] + len(got))), f'gaps in {got[0]}..{got[-1]}'
    assert f'holds the {len(got)} messages flushed before' in line, (line, len(got))
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['message_count'] <= len(got)
    print(line)
    return got


def test_a_file_size_limit_ends_the_recorder_with_one_line_and_a_readable_bag(
        graph, ros, tmp_path):
    # RLIMIT_FSIZE (ulimit -f): write(2) fails with EFBIG past it (Python ignores SIGXFSZ).
    if shutil.which('prlimit') is None:
        pytest.skip('prlimit (util-linux) is not installed: it sets the file size limit')
    bag = tmp_path / 'bag'
    got = _record_until_refused(graph, ros, bag, 'file too large (EFBIG)',
                                wrapper=('prlimit', '--fsize=200000'))
    assert (bag / 'bag.mcap').stat().st_size <= 200000
    rx = graph.start('feeder_monitor', 'bag_reindex', bag, name='reindex')
    assert rx.wait(timeout=25) == 0, graph.log(rx)
    assert read_counters(bag) == got


def test_a_full_filesystem_ends_the_recorder_with_one_line_and_a_readable_bag(
        graph, ros, small_fs):
    bag = small_fs / 'bag'
    got = _record_until_refused(graph, ros, bag, 'disk full (ENOSPC)')

    # bag_reindex in place with not one byte free: works, or one line and the bag unharmed.
    filler = _fill(small_fs)
    mcap = bag / 'bag.mcap'
    before = (mcap.read_bytes(), (bag / 'metadata.yaml').read_bytes())
    rx = graph.start('feeder_monitor', 'bag_reindex', bag, name='reindex_full')
    assert rx.wait(timeout=25) in (0, 3), graph.log(rx)
    rx_log = graph.log(rx)
    print(rx_log)
    if rx.returncode == 3:
        rx_line = _one_error_line(rx_log, 'bag_reindex')
        assert rx_line.startswith(f'bag_reindex: disk full (ENOSPC) writing {bag}/'), rx_line
        assert 'run bag_reindex' in rx_line, rx_line
        assert (bag / 'metadata.yaml').read_bytes() == before[1]
    else:
        assert 'Traceback' not in rx_log and f'{len(got)} messages on 1 topics' in rx_log
    assert not (bag / 'metadata.yaml.tmp').exists()
    assert read_counters(bag) == got

    # Space again: bag_reindex rebuilds metadata.yaml (and the summary if it was missing).
    filler.unlink()
    rx = graph.start('feeder_monitor', 'bag_reindex', bag, name='reindex_free')
    assert rx.wait(timeout=25) == 0, graph.log(rx)
    assert read_counters(bag) == got
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['message_count'] == len(got)
