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
A disk that refuses writes (ENOSPC, EDQUOT, EFBIG, EIO) under the bag writer and bag_reindex.

The files are opened through a stand-in for ``open`` whose writes take their new bytes from a
budget shared by every file of the bag (a disk with N bytes free): a write that goes past it
writes what fits, and the next one raises the error, as write(2) does. Writes within a file's
size and truncation need no new space (truncation gives it back). For budgets that end in every
part of the writing (the header, a chunk, the channel records, metadata.yaml, the summary at
close) the bag must end up readable by rosbags and by the mcap library with every message
flushed before the fault, exactly the ones the writer says it holds (issue 20, attack 9).
"""

import errno
import os

from feeder_monitor import bag as bagmod
from feeder_monitor.bag import BagError, BagWriter, McapLog, qos, reindex, reindex_main
import pytest
from rosbags.rosbag2 import Reader
import yaml

VOLATILE = qos(1, 10, 1, 2)
TOPICS = ('/disk/a', '/disk/b')


class Disk:
    """A disk with ``free`` bytes left; files opened through ``open_file`` draw on it."""

    def __init__(self, free, err=errno.ENOSPC, dead=False):
        self.free = free
        self.err = err
        self.dead = dead        # True: once full, no write at all succeeds (a failed device)
        self.refused = 0

    def open_file(self, path, mode='r', *args, **kwargs):
        """Open ``path`` as ``open`` does, its writes drawing on this disk."""
        return DiskFile(self, open(path, mode, *args, **kwargs))


class DiskFile:
    """A binary file whose writes past its end take space from its ``Disk``."""

    def __init__(self, disk, raw):
        self.disk = disk
        self.raw = raw
        self.size = os.fstat(raw.fileno()).st_size

    def write(self, data):
        data = memoryview(data).cast('B')
        pos = self.raw.tell()
        room = max(0, self.size - pos) + self.disk.free
        if self.disk.dead and self.disk.refused:
            room = 0
        if room == 0 and len(data):
            self.disk.refused += 1
            raise OSError(self.disk.err, os.strerror(self.disk.err))
        n = self.raw.write(data[:room])
        grown = max(0, pos + n - self.size)
        self.disk.free -= grown
        self.size += grown
        return n

    def truncate(self, size=None):
        size = self.raw.tell() if size is None else size
        if size < self.size:
            self.disk.free += self.size - size
        self.size = size
        return self.raw.truncate(size)

    def __getattr__(self, name):
        return getattr(self.raw, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.raw.close()


def payload(k):
    """CDR of a std_msgs/Int32 ``k`` with some padding bytes so chunks have some size."""
    return b'\x00\x01\x00\x00' + k.to_bytes(4, 'little') + bytes(200)


def record(path, disk=None, monkeypatch=None, flushes=6, per_flush=40):
    """
    Write ``flushes`` flushes of messages (the second topic appears in the third), then close.

    With ``disk``, every write draws on it (the bag's creation included). Returns the writer,
    the values written, and how many of them the last flush before the fault put on disk.
    """
    if disk is not None:
        monkeypatch.setattr(bagmod, 'open', disk.open_file, raising=False)
    writer = BagWriter(path)
    writer.add_topic(TOPICS[0], 'std_msgs/msg/Int32', [VOLATILE])
    written = []
    flushed = 0
    for f in range(flushes):
        if f == 2:
            writer.add_topic(TOPICS[1], 'std_msgs/msg/Int32', [VOLATILE])
        for _ in range(per_flush):
            k = len(written) + 1
            written.append(k)
            writer.write(TOPICS[k % 2 if f >= 2 else 0], 1000 * k, payload(k))
        writer.flush()
        if writer.fault is None:
            flushed = len(written)
    writer.close()
    if disk is not None:
        monkeypatch.undo()
    return writer, written, flushed


def read_both(bag):
    """Return the values in the bag by rosbags and by the mcap library (they agree)."""
    from mcap.reader import make_reader
    with Reader(bag) as reader:
        by_rosbags = [int.from_bytes(raw[4:8], 'little') for _, _, raw in reader.messages()]
    with open(bag / f'{bag.name}.mcap', 'rb') as fh:
        by_mcap = [int.from_bytes(m.data[4:8], 'little')
                   for _, _, m in make_reader(fh).iter_messages()]
    assert by_rosbags == by_mcap
    return by_rosbags


def test_the_fault_free_run_is_the_reference(tmp_path):
    writer, written, flushed = record(tmp_path / 'bag')
    assert writer.fault is None and flushed == len(written) == 240
    assert read_both(tmp_path / 'bag') == written


def _needed(tmp_path):
    """Bytes the bag's creation takes, and the whole recording (.mcap and metadata.yaml)."""
    disk = Disk(1 << 30)
    mp = pytest.MonkeyPatch()
    mp.setattr(bagmod, 'open', disk.open_file, raising=False)
    BagWriter(tmp_path / 'probe0')
    created = (1 << 30) - disk.free
    record(tmp_path / 'probe', disk, mp)
    return created, (1 << 30) - disk.free - 2 * created


@pytest.mark.parametrize('err', [errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO])
def test_a_refused_write_anywhere_leaves_a_readable_bag_of_what_was_flushed(
        tmp_path, monkeypatch, err):
    created, needed = _needed(tmp_path)
    # The first chunk, the channel record of the second topic, mid-chunks, the summary
    # (a few hundred bytes at the end), metadata.yaml after each of them.
    budgets = sorted(created + n for n in {
        0, 1, 13, 49, 50, 51, 400, 5000, 9000, 11000, needed - 600, needed - 200,
        needed - 60, needed - 1, *range(0, needed, max(1, needed // 23))})
    seen = set()
    for free in budgets:
        bag = tmp_path / f'bag{free}'
        disk = Disk(free, err)
        writer, written, flushed = record(bag, disk, monkeypatch)
        what = f'{errno.errorcode[err]} with {free} of {needed} bytes free'
        assert writer.fault is not None, what
        assert writer.fault.errno == err and writer.fault.intact, what
        got = read_both(bag)
        assert got == written[:len(got)], what
        assert len(got) >= flushed, f'{what}: {len(got)} read, {flushed} were flushed'
        assert len(got) == writer.fault.flushed, what
        assert len(got) <= writer.fault.received <= len(written), what
        meta = yaml.safe_load((bag / 'metadata.yaml').read_text())
        assert meta['rosbag2_bagfile_information']['message_count'] <= len(got), what
        assert not (bag / 'metadata.yaml.tmp').exists(), what
        seen.add(writer.fault.finished)
        # bag_reindex (space again) gives it its summary and the same messages.
        assert 'metadata.yaml rebuilt' in reindex(bag), what
        assert read_both(bag) == got, what
    # Some faults left room for the summary at close, some did not.
    assert seen == {True, False}


def test_the_fault_line_names_cause_file_counts_and_fix(tmp_path, monkeypatch):
    disk = Disk(25000)
    writer, written, _ = record(tmp_path / 'bag', disk, monkeypatch)
    line = writer.fault.line()
    assert '\n' not in line
    assert line.startswith(f'disk full (ENOSPC) writing {tmp_path / "bag"}/')
    assert f'after {writer.fault.received} messages' in line
    assert writer.fault.flushed < writer.fault.received <= len(written)
    assert f'holds the {writer.fault.flushed} messages flushed before' in line
    assert 'free space, then record again' in line


@pytest.mark.parametrize('err, fix', [(errno.EDQUOT, 'quota'), (errno.EFBIG, 'file size'),
                                      (errno.EIO, 'dmesg')])
def test_each_cause_has_its_fix(tmp_path, monkeypatch, err, fix):
    writer, _, _ = record(tmp_path / 'bag', Disk(8000, err), monkeypatch)
    assert errno.errorcode[err] in writer.fault.line() and fix in writer.fault.line()


def test_a_device_that_fails_for_good_is_said_and_reindex_recovers_what_was_flushed(
        tmp_path, monkeypatch):
    created, needed = _needed(tmp_path)
    cut = 0
    for free in range(created, created + needed, needed // 11):
        bag = tmp_path / f'bag{free}'
        writer, written, flushed = record(bag, Disk(free, errno.EIO, dead=True), monkeypatch)
        line = writer.fault.line()
        if writer.fault.intact:
            # The last metadata.yaml at close, after the summary: nothing to undo.
            assert writer.fault.path.name == 'metadata.yaml' and writer.fault.finished
            assert f'holds the {writer.fault.flushed} messages flushed before' in line, line
            assert read_both(bag) == written[:writer.fault.flushed]
            continue
        cut += 1
        assert not writer.fault.finished
        assert line.startswith(f'I/O error (EIO) writing {bag}/'), line
        assert f'may end in a cut-off record: bag_reindex {bag} finishes it' in line, line
        assert 'check the device (dmesg)' in line, line
        assert 'metadata.yaml rebuilt' in reindex(bag)
        got = read_both(bag)
        assert got == written[:len(got)] and len(got) >= flushed, (free, len(got), flushed)
    assert cut >= 5


def _killed_bag(path, cut=0):
    """Make a bag whose writer was killed after 3 flushes (and ``cut`` bytes into a 4th)."""
    writer = BagWriter(path)
    writer.add_topic(TOPICS[0], 'std_msgs/msg/Int32', [VOLATILE])
    for k in range(1, 121):
        writer.write(TOPICS[0], 1000 * k, payload(k))
        if k % 40 == 0:
            writer.flush()
    writer._log.close()
    mcap = path / f'{path.name}.mcap'
    if cut:
        with open(mcap, 'r+b') as fh:
            fh.seek(-50, os.SEEK_END)
            fh.write(bytes(range(256)) * (cut // 256 + 1))
            fh.truncate(os.fstat(fh.fileno()).st_size - 50 + cut)
    return mcap


def _readable(bag):
    try:
        return read_both(bag)
    except Exception:           # noqa: B902 - any reader's refusal
        return None


@pytest.mark.parametrize('cut', [0, 30, 5000])
def test_reindex_on_a_full_disk_works_in_place_or_leaves_the_bag_as_it_was(
        tmp_path, monkeypatch, capsys, cut):
    outcomes = set()
    for free in (0, 40, 400, 4000, 1 << 20):
        bag = tmp_path / f'bag{cut}_{free}'
        mcap = _killed_bag(bag, cut)
        before = mcap.read_bytes()
        meta_before = (bag / 'metadata.yaml').read_bytes()
        readable_before = _readable(bag)
        disk = Disk(free)
        monkeypatch.setattr(bagmod, 'open', disk.open_file, raising=False)
        status = reindex_main([str(bag)])
        monkeypatch.undo()
        out, err = capsys.readouterr()
        what = f'cut {cut}, {free} bytes free: {out}{err}'
        outcomes.add(status)
        assert not (bag / 'metadata.yaml.tmp').exists(), what
        if status == 0:
            assert '120 messages on 1 topics' in out and not err, what
            assert read_both(bag) == list(range(1, 121)), what
            assert yaml.safe_load((bag / 'metadata.yaml').read_text())[
                'rosbag2_bagfile_information']['message_count'] == 120
            continue
        assert status == 3 and not out and err.count('\n') == 1, what
        assert err.startswith(f'bag_reindex: disk full (ENOSPC) writing {bag}/'), what
        assert 'free space, then run bag_reindex' in err, what
        assert (bag / 'metadata.yaml').read_bytes() == meta_before, what
        # Never worse: unchanged, or readable after its last whole record (a cut record
        # replaced by a provisional end, the summary written when it fit).
        if mcap.read_bytes() == before:
            assert 'is as it was' in err, what
            assert _readable(bag) == readable_before, what
        else:
            assert read_both(bag) == list(range(1, 121)), what
            log, _, dropped = McapLog.recover(mcap)
            log.close()
            assert dropped == 0, what
    assert 0 in outcomes and (cut == 5000 or 3 in outcomes)


def test_reindex_with_no_byte_free_says_so(tmp_path, monkeypatch):
    bag = tmp_path / 'bag'
    mcap = _killed_bag(bag)
    before = mcap.read_bytes()
    monkeypatch.setattr(bagmod, 'open', Disk(0).open_file, raising=False)
    with pytest.raises(BagError, match=r'^disk full \(ENOSPC\) writing .*no room for its '
                       r'summary and footer; bag.mcap is as it was \(readable as it is\)'):
        reindex(bag)
    assert mcap.read_bytes() == before


@pytest.mark.parametrize('free', [0, 100, 560])
def test_a_disk_full_at_creation_is_one_line_exit_3_and_leaves_nothing(
        tmp_path, monkeypatch, capsys, free):
    from feeder_monitor import bag_recorder
    bag = tmp_path / 'bag'
    monkeypatch.setattr(bagmod, 'open', Disk(free).open_file, raising=False)
    assert bag_recorder.main(['bag_recorder', str(bag)]) == 3
    out, err = capsys.readouterr()
    assert not out and err == (f'bag_recorder: error: disk full (ENOSPC) creating the bag {bag} '
                               '(nothing recorded, nothing left there); free space, then record '
                               'again\n')
    assert not bag.exists()
