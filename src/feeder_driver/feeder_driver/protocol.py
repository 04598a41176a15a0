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

r"""
Feeder controller protocol (docs/serial-protocol.md): framing, checksum, messages, parser.

ROS-free. A frame is ``$BODY*HH\r\n`` where BODY is ``CMD[,field...]`` in printable ASCII
and HH is the XOR of the BODY bytes as two hex digits (sent uppercase, accepted in either
case). :class:`Parser` takes arbitrary byte chunks and returns decoded messages and
:class:`Rejected` events; it keeps a bounded buffer, resynchronises on the next ``$`` and
counts every byte and line it drops.
"""

from dataclasses import dataclass
import re
from typing import Optional

# Longest frame accepted, from '$' up to and including the final '\n'.
MAX_LINE = 96
# Sequence numbers on the wire are 0 .. SEQ_MODULO - 1.
SEQ_MODULO = 65536
UINT32_MAX = 2 ** 32 - 1
MAX_SPEED_MRAD_S = 10 ** 7

_TOKEN_RE = re.compile(r'[A-Za-z0-9_-]{1,16}\Z')
_BOOT_RE = re.compile(r'[A-Za-z0-9]{1,16}\Z')
_WORD_RE = re.compile(r'[A-Z][A-Z0-9_]{0,11}\Z')
# What each pattern allows, for the error messages.
_RULES = {_TOKEN_RE: '1-16 of [A-Za-z0-9_-]', _BOOT_RE: '1-16 of [A-Za-z0-9]',
          _WORD_RE: '1-12 of [A-Z0-9_], starting A-Z'}
_UINT_RE = re.compile(r'[0-9]{1,10}\Z')
_INT_RE = re.compile(r'-?[0-9]{1,10}\Z')
_HEX = b'0123456789ABCDEFabcdef'

# Error codes a controller sends in ERR (docs/serial-protocol.md, section 'Error codes').
ERROR_CODES = ('BADSUM', 'BADFRAME', 'OVERLONG', 'BADCMD', 'BADARG', 'BUSY', 'ABORTED',
               'FAULT')
# Controller states reported in HB.
STATES = ('IDLE', 'BUSY', 'FAULT')


class ProtocolError(ValueError):
    """A value cannot be encoded, or a received field is invalid; the text says which."""


def checksum(body):
    """XOR of the bytes of ``body`` (everything between '$' and '*')."""
    if isinstance(body, str):
        body = body.encode('ascii')
    value = 0
    for byte in body:
        value ^= byte
    return value


def _check_text(name, value, max_len, allow_empty=False):
    if not isinstance(value, str):
        raise ProtocolError(f'{name}: must be a str, got {type(value).__name__}')
    if not value and not allow_empty:
        raise ProtocolError(f'{name}: must not be empty')
    if len(value) > max_len:
        raise ProtocolError(f'{name}: longer than {max_len} characters ({len(value)})')
    for ch in value:
        if not ' ' <= ch <= '~' or ch in '$*,':
            raise ProtocolError(f'{name}: character {ch!r} not allowed (printable ASCII '
                                'except $ * and comma)')
    return value


def _check_match(name, value, pattern):
    """Return ``value`` if it is a str that ``pattern`` matches; else raise ProtocolError."""
    if not isinstance(value, str) or not pattern.match(value):
        raise ProtocolError(f'{name}: {value!r} must be {_RULES[pattern]}')
    return value


def _check_seq(name, value):
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < SEQ_MODULO:
        raise ProtocolError(f'{name}: must be an integer 0..{SEQ_MODULO - 1}, got {value!r}')
    return value


def frame(fields):
    """Encode string fields (command name first) as the bytes of one wire line."""
    if not fields:
        raise ProtocolError('frame: needs at least the command name')
    for k, field in enumerate(fields):
        _check_text(f'field {k}', field, MAX_LINE, allow_empty=k > 0)
    body = ','.join(fields).encode('ascii')
    line = b'$' + body + b'*%02X\r\n' % checksum(body)
    if len(line) > MAX_LINE:
        raise ProtocolError(f'frame: {len(line)} bytes, longer than MAX_LINE={MAX_LINE}; '
                            'shorten the text fields')
    return line


def _parse_uint(name, text, maximum):
    if not _UINT_RE.match(text):
        raise ProtocolError(f'{name}: {text!r} is not an unsigned decimal integer')
    value = int(text)
    if value > maximum:
        raise ProtocolError(f'{name}: {value} exceeds {maximum}')
    return value


def _parse_seq(text):
    return _parse_uint('seq', text, SEQ_MODULO - 1)


def _expect(fields, count, usage):
    if len(fields) != count:
        raise ProtocolError(f'expected {count} field(s) ({usage}), got {len(fields)}')


class _SeqOnly:
    """Codec of the messages whose one field is a seq (``FIRE``, ``ACK``)."""

    def fields(self):
        return [self.NAME, str(_check_seq('seq', self.seq))]

    @classmethod
    def from_fields(cls, fields):
        _expect(fields, 1, f'{cls.NAME},<seq>')
        return cls(_parse_seq(fields[0]))


class _TokenOnly:
    """Codec of the messages whose one field is a token (``PING``, ``PONG``)."""

    def fields(self):
        return [self.NAME, _check_match('token', self.token, _TOKEN_RE)]

    @classmethod
    def from_fields(cls, fields):
        _expect(fields, 1, f'{cls.NAME},<token>')
        return cls(_check_match('token', fields[0], _TOKEN_RE))


# ---- host -> controller ------------------------------------------------------------------

@dataclass(frozen=True)
class Fire(_SeqOnly):
    """``FIRE,<seq>``: run one throw-catch cycle tagged ``seq``."""

    seq: int
    NAME = 'FIRE'


@dataclass(frozen=True)
class Stop:
    """``STOP``: abort the cycle in progress (if any); the arm returns to rest."""

    NAME = 'STOP'

    def fields(self):
        return [self.NAME]

    @classmethod
    def from_fields(cls, fields):
        _expect(fields, 0, 'STOP')
        return cls()


@dataclass(frozen=True)
class Ping(_TokenOnly):
    """``PING,<token>``: the controller answers ``PONG,<token>``."""

    token: str
    NAME = 'PING'


# ---- controller -> host ------------------------------------------------------------------

@dataclass(frozen=True)
class Hello:
    """``HELLO,<firmware>,<boot_id>``: banner after power-up or reset, and answer to ID."""

    firmware: str
    boot_id: str
    NAME = 'HELLO'

    def fields(self):
        _check_text('firmware', self.firmware, 32)
        return [self.NAME, self.firmware, _check_match('boot_id', self.boot_id, _BOOT_RE)]

    @classmethod
    def from_fields(cls, fields):
        _expect(fields, 2, 'HELLO,<firmware>,<boot_id>')
        _check_text('firmware', fields[0], 32)
        return cls(fields[0], _check_match('boot_id', fields[1], _BOOT_RE))


@dataclass(frozen=True)
class Ack(_SeqOnly):
    """``ACK,<seq>``: FIRE accepted, the cycle has started."""

    seq: int
    NAME = 'ACK'


@dataclass(frozen=True)
class Rel:
    """``REL,<seq>,<speed>``: the arm released the part at ``speed`` mrad/s."""

    seq: int
    speed_mrad_s: int
    NAME = 'REL'

    def fields(self):
        s = self.speed_mrad_s
        if isinstance(s, bool) or not isinstance(s, int) or abs(s) > MAX_SPEED_MRAD_S:
            raise ProtocolError(f'speed: must be an integer within +-{MAX_SPEED_MRAD_S} mrad/s,'
                                f' got {s!r}')
        return [self.NAME, str(_check_seq('seq', self.seq)), str(s)]

    @classmethod
    def from_fields(cls, fields):
        _expect(fields, 2, 'REL,<seq>,<speed mrad/s>')
        if not _INT_RE.match(fields[1]) or abs(int(fields[1])) > MAX_SPEED_MRAD_S:
            raise ProtocolError(f'speed: {fields[1]!r} is not an integer within '
                                f'+-{MAX_SPEED_MRAD_S} mrad/s')
        return cls(_parse_seq(fields[0]), int(fields[1]))

    @property
    def speed_rad_s(self):
        return self.speed_mrad_s / 1000.0


@dataclass(frozen=True)
class Sens:
    """``SENS,<seq>,<0|1>``: sensor bit sampled after the part settled; ends the cycle."""

    seq: int
    bit: int
    NAME = 'SENS'

    def fields(self):
        if self.bit not in (0, 1) or isinstance(self.bit, bool):
            raise ProtocolError(f'bit: must be 0 or 1, got {self.bit!r}')
        return [self.NAME, str(_check_seq('seq', self.seq)), str(self.bit)]

    @classmethod
    def from_fields(cls, fields):
        _expect(fields, 2, 'SENS,<seq>,<0|1>')
        if fields[1] not in ('0', '1'):
            raise ProtocolError(f'bit: {fields[1]!r} must be 0 or 1')
        return cls(_parse_seq(fields[0]), int(fields[1]))


@dataclass(frozen=True)
class Err:
    """``ERR,<seq|->,<CODE>,<text>``: a refused or failed command."""

    seq: Optional[int]
    code: str
    text: str = ''
    NAME = 'ERR'

    def fields(self):
        seq = '-' if self.seq is None else str(_check_seq('seq', self.seq))
        _check_match('code', self.code, _WORD_RE)
        _check_text('text', self.text, 48, allow_empty=True)
        return [self.NAME, seq, self.code, self.text]

    @classmethod
    def from_fields(cls, fields):
        _expect(fields, 3, 'ERR,<seq|->,<CODE>,<text>')
        seq = None if fields[0] == '-' else _parse_seq(fields[0])
        return cls(seq, _check_match('code', fields[1], _WORD_RE), fields[2])


@dataclass(frozen=True)
class Pong(_TokenOnly):
    """``PONG,<token>``: answer to PING."""

    token: str
    NAME = 'PONG'


@dataclass(frozen=True)
class Hb:
    """``HB,<uptime_ms>,<STATE>``: heartbeat, once a second."""

    uptime_ms: int
    state: str
    NAME = 'HB'

    def fields(self):
        u = self.uptime_ms
        if isinstance(u, bool) or not isinstance(u, int) or not 0 <= u <= UINT32_MAX:
            raise ProtocolError(f'uptime_ms: must be an integer 0..{UINT32_MAX}, got {u!r}')
        return [self.NAME, str(u), _check_match('state', self.state, _WORD_RE)]

    @classmethod
    def from_fields(cls, fields):
        _expect(fields, 2, 'HB,<uptime_ms>,<STATE>')
        uptime = _parse_uint('uptime_ms', fields[0], UINT32_MAX)
        return cls(uptime, _check_match('state', fields[1], _WORD_RE))


@dataclass(frozen=True)
class Ident:
    """``ID``: the controller answers with its banner ``HELLO,<firmware>,<boot_id>``."""

    NAME = 'ID'

    def fields(self):
        return [self.NAME]

    @classmethod
    def from_fields(cls, fields):
        _expect(fields, 0, 'ID')
        return cls()


HOST_MESSAGES = {cls.NAME: cls for cls in (Fire, Stop, Ping, Ident)}
CONTROLLER_MESSAGES = {cls.NAME: cls for cls in (Hello, Ack, Rel, Sens, Err, Pong, Hb)}


def encode(message):
    """Wire bytes of one message object (raises ProtocolError on an invalid value)."""
    return frame(message.fields())


@dataclass(frozen=True)
class Rejected:
    """
    A frame the parser dropped.

    ``kind``: ``checksum``, ``frame`` (malformed: no ``*HH``, bad hex, control or non-ASCII
    byte), ``overlong``, ``truncated`` (a new ``$`` came before the line ended), ``unknown``
    (command not in the table) or ``fields`` (known command, bad fields). ``command`` is the
    command name when it could be read. ``raw``: the dropped bytes (at most MAX_LINE).
    """

    kind: str
    detail: str
    raw: bytes = b''
    command: Optional[str] = None


# What a receiving controller answers to each kind of rejected frame (docs/serial-protocol.md).
REJECT_CODES = {'checksum': 'BADSUM', 'frame': 'BADFRAME', 'overlong': 'OVERLONG',
                'truncated': 'BADFRAME', 'unknown': 'BADCMD', 'fields': 'BADARG'}


class Parser:
    """
    Incremental frame parser: ``feed(chunk)`` returns messages and Rejected events.

    ``messages`` maps command names to message classes (CONTROLLER_MESSAGES for the host
    side, HOST_MESSAGES for a controller). The buffer never grows beyond ``max_line`` bytes.
    ``stats`` counts received bytes, good lines, garbage bytes (outside any frame, or the
    tail of an overlong frame) and each kind of rejected frame.
    """

    STAT_KEYS = ('bytes', 'lines', 'garbage_bytes', 'checksum', 'frame', 'overlong',
                 'truncated', 'unknown', 'fields')

    def __init__(self, messages=None, max_line=MAX_LINE):
        if max_line < 8:
            raise ValueError(f'max_line: {max_line} is too small; use at least 8')
        self.messages = CONTROLLER_MESSAGES if messages is None else messages
        self.max_line = max_line
        self._buf = bytearray()
        self._in_frame = False
        self._skipping = False      # inside the tail of an overlong frame
        self.stats = dict.fromkeys(self.STAT_KEYS, 0)

    @property
    def dropped_frames(self):
        """Frames dropped for any reason (sum of the rejection counters)."""
        s = self.stats
        return s['checksum'] + s['frame'] + s['overlong'] + s['truncated'] + s['unknown'] + \
            s['fields']

    def reset(self):
        """Forget a partial frame (e.g. after reopening the port); counters are kept."""
        self._buf.clear()
        self._in_frame = False
        self._skipping = False

    def feed(self, data):
        """Consume a chunk of bytes; return the list of events it completed."""
        data = bytes(data)
        events = []
        self.stats['bytes'] += len(data)
        i, n = 0, len(data)
        while i < n:
            if not self._in_frame:
                j = data.find(b'$', i)
                if j < 0:
                    self.stats['garbage_bytes'] += n - i
                    break
                self.stats['garbage_bytes'] += j - i
                self._skipping = False
                self._in_frame = True
                self._buf.clear()
                i = j + 1
                continue
            k_nl = data.find(b'\n', i)
            k_sync = data.find(b'$', i)
            ends = [k for k in (k_nl, k_sync) if k >= 0]
            k = min(ends) if ends else n
            room = self.max_line - 2 - len(self._buf)   # '$' and '\n' count too
            if k - i > room:
                # Overlong: keep what fits for the report, skip to the next '$'.
                self._buf += data[i:i + max(room, 0)]
                events.append(self._reject('overlong', f'frame longer than {self.max_line} '
                                           'bytes without a line end', bytes(self._buf)))
                self.stats['garbage_bytes'] += (k - i) - max(room, 0)
                self._in_frame = False
                self._buf.clear()
                i = k
                if k < n and data[k:k + 1] == b'\n':
                    self.stats['garbage_bytes'] += 1
                    i = k + 1
                continue
            self._buf += data[i:k]
            if k == n:
                break
            if data[k:k + 1] == b'$':
                events.append(self._reject('truncated', 'a new $ started before the line end',
                                           bytes(self._buf)))
                self._buf.clear()
                i = k + 1           # the new frame starts here; stay in frame
                continue
            events.append(self._decode(bytes(self._buf)))
            self._in_frame = False
            self._buf.clear()
            i = k + 1
        return events

    def _reject(self, kind, detail, raw, command=None):
        self.stats[kind] += 1
        return Rejected(kind, detail, b'$' + raw[:self.max_line], command)

    def _decode(self, line):
        if line.endswith(b'\r'):
            line = line[:-1]
        if len(line) < 4 or line[-3:-2] != b'*':
            return self._reject('frame', 'no *HH checksum at the end of the line', line)
        body, given = line[:-3], line[-2:]
        if any(b not in _HEX for b in given):
            return self._reject('frame', f'checksum {given!r} is not two hex digits', line)
        if any(b < 0x20 or b > 0x7e for b in body):
            return self._reject('frame', 'control or non-ASCII byte inside the frame', line)
        want = checksum(body)
        if int(given, 16) != want:
            return self._reject('checksum', f'checksum {given.decode()} != computed '
                                f'{want:02X}', line)
        fields = body.decode('ascii').split(',')
        name = fields[0]
        cls = self.messages.get(name)
        if cls is None:
            return self._reject('unknown', f'unknown command {name!r}', line, name)
        try:
            message = cls.from_fields(fields[1:])
        except ProtocolError as exc:
            return self._reject('fields', f'{name}: {exc}', line, name)
        self.stats['lines'] += 1
        return message
