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

"""The key file and the MACs of feeder_common.auth (ROS-free)."""

import hashlib
import hmac
import math
import multiprocessing
import os
import stat

from feeder_common import auth
import pytest


def test_a_new_key_file_is_private_and_reads_back(tmp_path):
    path = tmp_path / 'sub' / 'hmac.key'
    key = auth.ensure_key(path)
    assert len(key) == auth.KEY_BYTES
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o600
    assert stat.S_IMODE(os.stat(path.parent).st_mode) == 0o700
    assert auth.load_key(path) == key
    assert auth.ensure_key(path) == key         # an existing key is kept


def _make_key(path, queue):
    queue.put(auth.ensure_key(path))


def test_processes_that_start_at_once_share_one_key(tmp_path):
    path = tmp_path / 'hmac.key'
    queue = multiprocessing.get_context('fork').Queue()
    procs = [multiprocessing.get_context('fork').Process(target=_make_key, args=(path, queue))
             for _ in range(6)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(30)
    keys = {queue.get(timeout=5) for _ in procs}
    assert len(keys) == 1
    assert sorted(os.listdir(tmp_path)) == ['hmac.key']     # no temporary file left


@pytest.mark.parametrize('mode', [0o640, 0o604, 0o666])
def test_a_key_others_can_read_is_refused_with_the_fix(tmp_path, mode):
    path = tmp_path / 'hmac.key'
    auth.ensure_key(path)
    os.chmod(path, mode)
    with pytest.raises(auth.KeyFileError, match='chmod 600'):
        auth.load_key(path)


@pytest.mark.parametrize('content, match', [
    (b'not hex at all\n', 'hex'),
    (b'abcd\n', 'at least 32'),
    (b'\xff\xfe' * 10, 'hex'),
    (b'0' * 5000, 'one key in hex'),
])
def test_a_malformed_key_file_is_refused(tmp_path, content, match):
    path = tmp_path / 'hmac.key'
    path.write_bytes(content)
    os.chmod(path, 0o600)
    with pytest.raises(auth.KeyFileError, match=match):
        auth.load_key(path)


def test_a_fifo_a_folder_a_link_and_nothing_are_refused_at_once(tmp_path):
    fifo = tmp_path / 'fifo'
    os.mkfifo(fifo, 0o600)
    with pytest.raises(auth.KeyFileError, match='not a regular file'):
        auth.load_key(fifo)         # O_NONBLOCK: no writer, no hang
    folder = tmp_path / 'folder'
    folder.mkdir(mode=0o700)
    with pytest.raises(auth.KeyFileError):
        auth.load_key(folder)
    real = tmp_path / 'real.key'
    auth.ensure_key(real)
    link = tmp_path / 'link.key'
    link.symlink_to(real)
    with pytest.raises(auth.KeyFileError, match='symbolic link'):
        auth.load_key(link)
    with pytest.raises(auth.KeyFileError, match='does not exist'):
        auth.load_key(tmp_path / 'absent.key')


def test_the_default_key_lives_under_ros_home():
    assert auth.default_key_path({'ROS_HOME': '/x/y'}) == '/x/y/feeder/hmac.key'
    assert auth.default_key_path({}).endswith('/.ros/feeder/hmac.key')


def test_the_mac_is_hmac_sha256_of_length_prefixed_fields():
    key = bytes(range(32))
    fields = auth.cycle_fields('/feeder/feeder_driver', 'ab12', 7, None, 'completed', '1', '',
                               5.5851)
    data = (b'15:feeder-cycle-v2' b'21:/feeder/feeder_driver' b'4:ab12' b'1:7' b'4:none'
            b'9:completed' b'1:1' b'0:' b'6:5.5851')
    assert auth.mac(key, auth.CYCLE_LABEL, fields) == \
        hmac.new(key, data, hashlib.sha256).digest()
    # No setpoint (the controller's own speed), NaN alike: 'none'.
    for none in (None, math.nan):
        assert auth.cycle_fields('n', 's', 1, 2, 'failed', 'none', 'x', none)[-1] == 'none'
    setpoint = auth.setpoint_fields('/feeder/feeder_monitor', 'cd', 8, '', 6.0, 123)
    data = (b'18:feeder-setpoint-v1' b'22:/feeder/feeder_monitor' b'2:cd' b'1:8' b'0:'
            b'3:6.0' b'3:123')
    assert auth.mac(key, auth.SETPOINT_LABEL, setpoint) == \
        hmac.new(key, data, hashlib.sha256).digest()


def test_a_mac_does_not_verify_another_statement_key_or_field():
    key, other = bytes(32), bytes([1]) * 32
    f = auth.cycle_fields('/feeder/feeder_driver', 's', 3, 10, 'completed', '1', '', 6.25)
    tag = auth.mac(key, auth.CYCLE_LABEL, f)
    assert auth.mac_ok(key, auth.CYCLE_LABEL, f, tag)
    assert not auth.mac_ok(other, auth.CYCLE_LABEL, f, tag)
    assert not auth.mac_ok(key, auth.VERDICT_LABEL, f, tag)
    for i in range(len(f)):
        changed = list(f)
        changed[i] = str(changed[i]) + '0'
        assert not auth.mac_ok(key, auth.CYCLE_LABEL, changed, tag)
    # Field boundaries are part of what is signed: moving a character across one fails.
    assert not auth.mac_ok(key, auth.CYCLE_LABEL, ('/feeder/feeder_drive', 'rs', *f[2:]), tag)
    assert not auth.mac_ok(key, auth.CYCLE_LABEL, f, tag[:-1])
    assert not auth.mac_ok(key, auth.CYCLE_LABEL, f, b'')
    assert not auth.mac_ok(key, auth.CYCLE_LABEL, f, 'not bytes')
