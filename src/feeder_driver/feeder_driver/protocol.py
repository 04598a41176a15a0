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
Feeder controller protocol (docs/serial-protocol.md): framing, frame check, messages, parser.

ROS-free. Protocol version 2: a frame is ``$BODY*HHHH\r\n`` where BODY is ``CMD[,field...]``
in printable ASCII and HHHH is the CRC-16/CCITT-FALSE of the BODY bytes (polynomial 0x1021,
initial value 0xFFFF, no reflection, no final XOR: ``binascii.crc_hqx(body, 0xFFFF)``) as
four uppercase hex digits. :class:`Parser` takes arbitrary byte chunks and returns decoded
messages and :class:`Rejected` events; it keeps a bounded buffer, resynchronises on the next
``$`` and counts every byte and line it drops. A frame of protocol 1 (``*HH``, the XOR of the
body) is recognised and refused as ``legacy``, so an old controller is named as such.
"""

import binascii
import dataclasses
from dataclasses import dataclass
import re
from typing import Optional

# Longest frame accepted, from '$' up to and including the final '\n'.
MAX_LINE = 96
# The version of this protocol: 1 framed with an 8-bit XOR, 2 with CRC-16/CCITT-FALSE.
PROTOCOL_VERSION = 2
# Hex digits of the frame check (uppercase on the wire).
CHECK_DIGITS = 4
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
_HEX = b'0123456789ABCDEF'
_LEGACY_HEX = b'0123456789ABCDEFabcdef'

# Error codes a controller sends in ERR (docs/serial-protocol.md, section 'Error codes').
ERROR_CODES = ('BADSUM', 'BADFRAME', 'OVERLONG', 'BADCMD', 'BADARG', 'BUSY', 'ABORTED',
               'FAULT')
# Controller states reported in HB.
STATES = ('IDLE', 'BUSY', 'FAULT')


class ProtocolError(ValueError):
    """A value cannot be encoded, or a received field is invalid; the text says which."""


def checksum(body):
    """
    Frame check of ``body`` (everything between '$' and '*'): CRC-16/CCITT-FALSE.

    Polynomial 0x1021, initial value 0xFFFF, bits not reflected, no final XOR; the CRC of
    ``b'123456789'`` is 0x29B1. A generator of degree 16 detects every burst of up to 16
    bits, every odd number of bit errors (it has the factor x + 1) and every two-bit error
    within 32767 bits, far more than the 96 bytes of a frame (docs/serial-protocol.md).
    """
    if isinstance(body, str):
        body = body.encode('ascii')
    return binascii.crc_hqx(body, 0xFFFF)


def legacy_checksum(body):
    """XOR of the bytes of ``body``: the frame check of protocol 1, only to recognise it."""
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
    line = b'$' + body + b'*%04X\r\n' % checksum(body)
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


def _check_int(name, value, low, high, rule):
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ProtocolError(f'{name}: must be an integer {rule}, got {value!r}')
    return value


def _parse_speed(text):
    if not _INT_RE.match(text) or abs(int(text)) > MAX_SPEED_MRAD_S:
        raise ProtocolError(f'speed: {text!r} is not an integer within +-{MAX_SPEED_MRAD_S} '
                            'mrad/s')
    return int(text)


def _parse_bit(text):
    if text not in ('0', '1'):
        raise ProtocolError(f'bit: {text!r} must be 0 or 1')
    return int(text)


class _Field:
    """
    One wire field: its place in the usage line, and its codec both ways.

    ``encode(value)`` checks a value and returns its text; ``decode(text)`` checks a received
    field and returns the value; both raise ProtocolError naming the field.
    """

    def __init__(self, usage, encode, decode):
        self.usage, self.encode, self.decode = usage, encode, decode


def _matching(name, pattern, usage):
    def check(value):
        return _check_match(name, value, pattern)
    return _Field(usage, check, check)


def _text(name, max_len, usage, allow_empty=False, check_received=True):
    def check(value):
        return _check_text(name, value, max_len, allow_empty)
    return _Field(usage, check, check if check_received else str)


_SEQ = _Field('<seq>', lambda v: str(_check_seq('seq', v)), _parse_seq)
_SEQ_OR_NONE = _Field('<seq|->', lambda v: '-' if v is None else str(_check_seq('seq', v)),
                      lambda t: None if t == '-' else _parse_seq(t))
_BIT = _Field('<0|1>', lambda v: str(_check_int('bit', v, 0, 1, '0 or 1')), _parse_bit)


def _speed(usage):
    return _Field(usage, lambda v: str(_check_int('speed', v, -MAX_SPEED_MRAD_S,
                                                  MAX_SPEED_MRAD_S,
                                                  f'within +-{MAX_SPEED_MRAD_S} mrad/s')),
                  _parse_speed)


_SPEED = _speed('<speed mrad/s>')
_UPTIME = _Field('<uptime_ms>', lambda v: str(_check_int('uptime_ms', v, 0, UINT32_MAX,
                                                         f'0..{UINT32_MAX}')),
                 lambda t: _parse_uint('uptime_ms', t, UINT32_MAX))
_TOKEN = _matching('token', _TOKEN_RE, '<token>')
# The capability a CAP announces; protocol 2 knows one, SPEED (the release-speed setpoint).
CAPABILITIES = ('SPEED',)


def _check_capability(value):
    if value not in CAPABILITIES:
        raise ProtocolError(f'capability: {value!r} must be one of {", ".join(CAPABILITIES)}')
    return value


_CAPABILITY = _Field('SPEED', _check_capability, _check_capability)
_BOOT_ID = _matching('boot_id', _BOOT_RE, '<boot_id>')
_CODE = _matching('code', _WORD_RE, '<CODE>')
_STATE = _matching('state', _WORD_RE, '<STATE>')
_FIRMWARE = _text('firmware', 32, '<firmware>')
# A received ERR text is taken as framed: the controller's text is for people, not parsed.
_ERR_TEXT = _text('text', 48, '<text>', allow_empty=True, check_received=False)


class _Message:
    """
    The codec every message shares, driven by its table ``FIELDS``.

    ``FIELDS`` lists the dataclass fields in wire order, each with its ``_Field``; the usage
    line of an error (``SENS,<seq>,<0|1>``) is made from the same table.
    """

    NAME = ''
    FIELDS = ()
    # How many of the last FIELDS may be left off the wire (trailing; absent, they are None).
    OPTIONAL = 0

    @classmethod
    def usage(cls):
        """Return the usage line, e.g. ``FIRE,<seq>[,<speed mrad/s>]``."""
        required = len(cls.FIELDS) - cls.OPTIONAL
        head = ','.join([cls.NAME] + [field.usage for _, field in cls.FIELDS[:required]])
        tail = ''.join(f'[,{field.usage}' for _, field in cls.FIELDS[required:])
        return head + tail + ']' * cls.OPTIONAL

    def fields(self):
        """Return the wire fields, command name first (raises ProtocolError)."""
        values = [getattr(self, attr) for attr, _ in self.FIELDS]
        least = len(values) - self.OPTIONAL
        n = len(values)
        # Trailing optional fields that are None are not sent; none may be left out before
        # one that is sent (the wire has no placeholder for a missing field).
        while n > least and values[n - 1] is None:
            n -= 1
        for attr, _ in self.FIELDS[least:n]:
            if getattr(self, attr) is None:
                raise ProtocolError(f'{attr}: None, but a later optional field is given '
                                    f'({self.usage()})')
        return [self.NAME] + [field.encode(value)
                              for (_, field), value in zip(self.FIELDS[:n], values[:n])]

    @classmethod
    def from_fields(cls, fields):
        """Decode the received fields that follow the command name."""
        most = len(cls.FIELDS)
        least = most - cls.OPTIONAL
        if not least <= len(fields) <= most:
            count = (str(most) if least == most else
                     f'{least} or {most}' if least + 1 == most else f'{least} to {most}')
            raise ProtocolError(f'expected {count} field(s) ({cls.usage()}), '
                                f'got {len(fields)}')
        return cls(*[field.decode(text) for (_, field), text in zip(cls.FIELDS, fields)])


def _message(cls_name, name, doc, *fields, optional=0, **namespace):
    """
    One message class: a frozen dataclass of ``fields`` with the table codec.

    Each of ``fields`` is ``(attribute, type, _Field)`` or ``(attribute, type, _Field,
    default)``; the last ``optional`` of them may be left off the wire (each must default to
    None, its value when absent); ``namespace`` adds properties (and may add a
    ``__post_init__`` that checks the fields together, raising ProtocolError).
    """
    if not 0 <= optional <= len(fields) or \
            any(len(f) < 4 or f[3] is not None for f in fields[len(fields) - optional:]):
        raise ValueError(f'{name}: the {optional} optional field(s) must be the last ones and '
                         'default to None')
    spec = [(f[0], f[1]) if len(f) == 3 else (f[0], f[1], dataclasses.field(default=f[3]))
            for f in fields]
    namespace.update(NAME=name, FIELDS=tuple((f[0], f[2]) for f in fields), OPTIONAL=optional,
                     __doc__=doc, __module__=__name__)
    return dataclasses.make_dataclass(cls_name, spec, bases=(_Message,), namespace=namespace,
                                      frozen=True)


def _speed_rad_s(mrad_s):
    return None if mrad_s is None else mrad_s / 1000.0


def speed_mrad_s(speed_rad_s):
    """Return a speed in rad/s as the wire carries it: whole mrad/s (REL, FIRE, CAP)."""
    return int(round(speed_rad_s * 1000.0))


def _check_cap(self):
    """Check a CAP's range: 0 < min <= max (raises ProtocolError; types are checked later)."""
    low, high = self.min_mrad_s, self.max_mrad_s
    if all(isinstance(v, int) and not isinstance(v, bool) for v in (low, high)) and \
            not 0 < low <= high:
        raise ProtocolError(f'CAP,SPEED: the range must be 0 < min <= max mrad/s, got '
                            f'{low}..{high}')


# The message table (docs/serial-protocol.md). Host -> controller:
Fire = _message('Fire', 'FIRE', '``FIRE,<seq>[,<speed>]``: run one throw-catch cycle tagged '
                '``seq``, at the release-speed setpoint ``speed`` mrad/s if given (only to a '
                'controller that announced ``CAP,SPEED``).',
                ('seq', int, _SEQ), ('speed_mrad_s', Optional[int], _SPEED, None), optional=1,
                speed_rad_s=property(lambda self: _speed_rad_s(self.speed_mrad_s)))
Caps = _message('Caps', 'CAPS', '``CAPS``: which optional capabilities the controller has; a '
                'controller that can set the release speed answers ``CAP,SPEED,<min>,<max>``, '
                'one without answers ``ERR,-,BADCMD``.')
Stop = _message('Stop', 'STOP',
                '``STOP``: abort the cycle in progress (if any); the arm returns to rest.')
Ping = _message('Ping', 'PING', '``PING,<token>``: the controller answers ``PONG,<token>``.',
                ('token', str, _TOKEN))
Ident = _message('Ident', 'ID', '``ID``: the controller answers with its banner '
                 '``HELLO,<firmware>,<boot_id>``.')
# Controller -> host:
Hello = _message('Hello', 'HELLO', '``HELLO,<firmware>,<boot_id>``: banner after power-up or '
                 'reset, and answer to ID.', ('firmware', str, _FIRMWARE),
                 ('boot_id', str, _BOOT_ID))
Ack = _message('Ack', 'ACK', '``ACK,<seq>``: FIRE accepted, the cycle has started.',
               ('seq', int, _SEQ))
Rel = _message('Rel', 'REL', '``REL,<seq>,<speed>``: the arm released the part at ``speed`` '
               'mrad/s.', ('seq', int, _SEQ), ('speed_mrad_s', int, _SPEED),
               speed_rad_s=property(lambda self: self.speed_mrad_s / 1000.0))
Sens = _message('Sens', 'SENS', '``SENS,<seq>,<0|1>``: sensor bit sampled after the part '
                'settled; ends the cycle.', ('seq', int, _SEQ), ('bit', int, _BIT))
Err = _message('Err', 'ERR', '``ERR,<seq|->,<CODE>,<text>``: a refused or failed command.',
               ('seq', Optional[int], _SEQ_OR_NONE), ('code', str, _CODE),
               ('text', str, _ERR_TEXT, ''))
Pong = _message('Pong', 'PONG', '``PONG,<token>``: answer to PING.', ('token', str, _TOKEN))
Hb = _message('Hb', 'HB', '``HB,<uptime_ms>,<STATE>``: heartbeat, once a second.',
              ('uptime_ms', int, _UPTIME), ('state', str, _STATE))
Cap = _message('Cap', 'CAP', '``CAP,SPEED,<min>,<max>``: answer to CAPS: the controller sets '
               'the release speed FIRE asks for, from ``min`` to ``max`` mrad/s.',
               ('capability', str, _CAPABILITY), ('min_mrad_s', int, _speed('<min mrad/s>')),
               ('max_mrad_s', int, _speed('<max mrad/s>')), __post_init__=_check_cap,
               min_rad_s=property(lambda self: _speed_rad_s(self.min_mrad_s)),
               max_rad_s=property(lambda self: _speed_rad_s(self.max_mrad_s)))

HOST_MESSAGES = {cls.NAME: cls for cls in (Fire, Stop, Ping, Ident, Caps)}
CONTROLLER_MESSAGES = {cls.NAME: cls for cls in (Hello, Ack, Rel, Sens, Err, Pong, Hb, Cap)}


def encode(message):
    """Wire bytes of one message object (raises ProtocolError on an invalid value)."""
    return frame(message.fields())


@dataclass(frozen=True)
class Rejected:
    """
    A frame the parser dropped.

    ``kind``: ``checksum`` (the CRC does not match), ``frame`` (malformed: no ``*HHHH``, not
    four uppercase hex digits, control or non-ASCII byte), ``legacy`` (a well-formed frame of
    protocol 1, ``*HH`` with its XOR: the peer runs old firmware), ``overlong``,
    ``truncated`` (a new ``$`` came before the line ended), ``unknown`` (command not in the
    table) or ``fields`` (known command, bad fields). ``command`` is the
    command name when it could be read. ``raw``: the dropped bytes (at most MAX_LINE).
    """

    kind: str
    detail: str
    raw: bytes = b''
    command: Optional[str] = None


# What a receiving controller answers to each kind of rejected frame (docs/serial-protocol.md).
REJECT_CODES = {'checksum': 'BADSUM', 'frame': 'BADFRAME', 'legacy': 'BADFRAME',
                'overlong': 'OVERLONG',
                'truncated': 'BADFRAME', 'unknown': 'BADCMD', 'fields': 'BADARG'}


class Parser:
    """
    Incremental frame parser: ``feed(chunk)`` returns messages and Rejected events.

    ``messages`` maps command names to message classes (CONTROLLER_MESSAGES for the host
    side, HOST_MESSAGES for a controller). The buffer never grows beyond ``max_line`` bytes.
    ``stats`` counts received bytes, good lines, garbage bytes (outside any frame, or the
    tail of an overlong frame) and each kind of rejected frame.
    """

    STAT_KEYS = ('bytes', 'lines', 'garbage_bytes', 'checksum', 'frame', 'legacy', 'overlong',
                 'truncated', 'unknown', 'fields')
    REJECT_KINDS = STAT_KEYS[3:]

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
        return sum(self.stats[kind] for kind in self.REJECT_KINDS)

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
        n = CHECK_DIGITS
        if len(line) < n + 2 or line[-n - 1:-n] != b'*':
            if self._is_legacy(line):
                return self._reject('legacy', 'a frame of serial protocol 1 (XOR checksum *HH); '
                                    f'this side speaks protocol {PROTOCOL_VERSION} (CRC-16 '
                                    '*HHHH): update the controller firmware '
                                    '(docs/serial-protocol.md)', line)
            return self._reject('frame', f'no *{"H" * n} CRC at the end of the line', line)
        body, given = line[:-n - 1], line[-n:]
        if any(b not in _HEX for b in given):
            return self._reject('frame', f'CRC {given!r} is not {n} uppercase hex digits', line)
        if any(b < 0x20 or b > 0x7e for b in body):
            return self._reject('frame', 'control or non-ASCII byte inside the frame', line)
        want = checksum(body)
        if int(given, 16) != want:
            return self._reject('checksum', f'CRC {given.decode()} != computed '
                                f'{want:04X}', line)
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

    @staticmethod
    def _is_legacy(line):
        """Whether ``line`` (no '$', no line end) is a valid protocol-1 frame ``BODY*HH``."""
        if len(line) < 4 or line[-3:-2] != b'*':
            return False
        body, given = line[:-3], line[-2:]
        if any(b not in _LEGACY_HEX for b in given) or any(b < 0x20 or b > 0x7e for b in body):
            return False
        return int(given, 16) == legacy_checksum(body)
