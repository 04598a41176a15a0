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
Keyed MACs of what the feeder's readiness rests on (ROS-free; docs/security.md).

Without DDS security any process on the domain can publish any topic, and who is on the graph
at a given moment proves nothing about a message. So the messages prove themselves: the driver
(or the stand-in) signs each cycle report, the monitor each verdict, with HMAC-SHA256 under a
key that only the feeder's processes can read (a file of mode 0600).

What is signed is a list of fields, each written as ``<byte length>:<UTF-8 bytes>`` after a
label that names the kind of statement (so that a cycle report can never pass as a verdict)
and the fully qualified name of the node that makes it (so that one feeder's report can never
pass as another's). A key file holds the key as hex text (at least 32 bytes); its *key id*,
the first 8 hex digits of the SHA-256 of the key, names it in errors without revealing it.
"""

import errno
import hashlib
import hmac
import os
import secrets
import stat

# v2: the cycle's release-speed setpoint is signed too (issue 25).
CYCLE_LABEL = 'feeder-cycle-v2'
FIRED_LABEL = 'feeder-fired-v1'
VERDICT_LABEL = 'feeder-verdict-v1'
SETPOINT_LABEL = 'feeder-setpoint-v1'
KEY_BYTES = 32                  # a new key; a given key may be longer
MAX_KEY_FILE_BYTES = 4096
MAC_BYTES = 32


class KeyFileError(Exception):
    """A key file is missing, unreadable, too open or malformed; the text says the fix."""


def default_key_path(environ=None):
    """``$ROS_HOME/feeder/hmac.key`` (ROS_HOME defaults to ``~/.ros``, as ROS 2 has it)."""
    env = os.environ if environ is None else environ
    ros_home = env.get('ROS_HOME') or os.path.join(os.path.expanduser('~'), '.ros')
    return os.path.join(ros_home, 'feeder', 'hmac.key')


def key_id(key):
    """Name a key without revealing it: the first 8 hex digits of its SHA-256."""
    return hashlib.sha256(key).hexdigest()[:8]


def _parse_key(text, path):
    body = text.strip()
    try:
        key = bytes.fromhex(body)
    except ValueError:
        raise KeyFileError(f'key file {path} does not hold a key in hex; make a new one with: '
                           f'rm {path} (the nodes and the launch create it again)') from None
    if len(key) < KEY_BYTES:
        raise KeyFileError(f'key file {path} holds {len(key)} bytes; at least {KEY_BYTES} are '
                           f'needed: rm {path} (the nodes and the launch create it again)')
    return key


def load_key(path):
    """Read the key of ``path``; KeyFileError naming the fix if it is not a safe key file."""
    path = os.path.expanduser(str(path))
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, 'O_NOFOLLOW', 0))
    except FileNotFoundError:
        raise KeyFileError(f'key file {path} does not exist; create it with the launch, or give '
                           'key_file:="" to use (and create) the default one') from None
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise KeyFileError(f'key file {path} is a symbolic link; give the file itself') \
                from None
        raise KeyFileError(f'key file {path} cannot be opened: {exc.strerror}') from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise KeyFileError(f'key file {path} is not a regular file')
        if st.st_mode & 0o077:
            raise KeyFileError(f'key file {path} can be read by others (mode '
                               f'{stat.S_IMODE(st.st_mode):04o}); make it private: chmod 600 '
                               f'{path}')
        if st.st_size > MAX_KEY_FILE_BYTES:
            raise KeyFileError(f'key file {path} is {st.st_size} bytes; a key file holds one key '
                               f'in hex (at most {MAX_KEY_FILE_BYTES} bytes)')
        data = os.read(fd, MAX_KEY_FILE_BYTES + 1)
    finally:
        os.close(fd)
    try:
        text = data.decode('ascii')
    except UnicodeDecodeError:
        raise KeyFileError(f'key file {path} does not hold a key in hex') from None
    return _parse_key(text, path)


def ensure_key(path):
    """
    Return the key of ``path``, creating the file (mode 0600, a new random key) when absent.

    Several processes may start at once: the new file is written under a temporary name and
    linked into place, so a reader never sees it half written and exactly one key wins.
    """
    path = os.path.expanduser(str(path))
    if not os.path.lexists(path):
        folder = os.path.dirname(os.path.abspath(path))
        os.makedirs(folder, mode=0o700, exist_ok=True)
        tmp = os.path.join(folder, f'.{os.path.basename(path)}.{secrets.token_hex(8)}')
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        try:
            os.write(fd, (secrets.token_bytes(KEY_BYTES).hex() + '\n').encode('ascii'))
            os.fsync(fd)
        finally:
            os.close(fd)
        try:
            os.link(tmp, path)
        except FileExistsError:
            pass                    # another process made it first: use that one
        finally:
            os.unlink(tmp)
    return load_key(path)


def node_key(path):
    """
    Return the key a node signs or checks with: ``path``'s, or the default file's if it is ''.

    The default file is created when absent (so ``ros2 run`` works without a launch); a given
    path must exist: a mistyped path would otherwise make a key nobody else has.
    """
    if not path:
        try:
            return ensure_key(default_key_path())
        except OSError as exc:
            raise KeyFileError(f'cannot create the key file {default_key_path()}: '
                               f'{exc.strerror}; give key_file:=<a file of mode 0600>') \
                from None
    return load_key(path)


def _encode(label, fields):
    parts = []
    for field in (label, *fields):
        b = str(field).encode('utf-8')
        parts.append(b'%d:%s' % (len(b), b))
    return b''.join(parts)


def mac(key, label, fields):
    """HMAC-SHA256 of ``fields`` (each written as text) under ``key``, for statement ``label``."""
    return hmac.new(key, _encode(label, fields), hashlib.sha256).digest()


def mac_ok(key, label, fields, tag):
    """Whether ``tag`` (bytes) is the MAC of ``fields``; constant-time comparison."""
    if not isinstance(tag, (bytes, bytearray)) or len(tag) != MAC_BYTES:
        return False
    return hmac.compare_digest(mac(key, label, fields), bytes(tag))


def new_session():
    """Return a run's session id: 16 random hex digits, new at every start of a node."""
    return secrets.token_hex(8)


# What each statement signs, in order (docs/security.md gives the same lists for firmware or
# other languages). ``stamp_ns`` None is written 'none'; booleans as 'true'/'false'.
def _opt(value):
    return 'none' if value is None else value


def speed_text(speed):
    """Write a speed (rad/s) as signed: Python's shortest round-trip repr; None or NaN 'none'."""
    return 'none' if speed is None or speed != speed else repr(float(speed))


def cycle_fields(node, session, seq, stamp_ns, outcome, sensor, message, release_speed):
    """
    Fields of a cycle report: ``outcome`` 'completed' or 'failed', ``sensor`` '1'/'0'/'none'.

    ``release_speed``: the setpoint the cycle was fired at, rad/s (None: the controller's own).
    """
    return (node, session, int(seq), _opt(stamp_ns), outcome, sensor, message,
            speed_text(release_speed))


def setpoint_fields(sender, session, seq, driver_session, speed, sent_ns):
    """Fields of a release-speed setpoint of ``sender`` for cycle ``seq`` of a driver run."""
    return (sender, session, int(seq), driver_session, speed_text(speed), int(sent_ns))


def fired_fields(node, session, seq, stamp_ns):
    """Fields of a fired notice: cycle ``seq`` is being fired at ``stamp_ns``."""
    return (node, session, int(seq), _opt(stamp_ns))


def verdict_fields(monitor, session, seq, stamp_ns, ready, state, anomaly, sent_ns):
    """Fields of a verdict of monitor ``monitor`` (its fully qualified node name)."""
    return (monitor, session, int(seq), _opt(stamp_ns), 'true' if ready else 'false', state,
            anomaly, int(sent_ns))
