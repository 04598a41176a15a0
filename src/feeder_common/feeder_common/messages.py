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
Builders and parsers of the messages the driver (or the sim standing in for it) sends.

``cycle_status`` (diagnostic_msgs/DiagnosticStatus): one per fired cycle, ``name = 'cycle'``,
level OK (completed) or ERROR (failed, the reason in ``message``), ``hardware_id`` = who ran
it, values ``seq``, ``sensor`` (``1``/``0``/``none``), ``stamp`` (the sample time,
:mod:`feeder_common.stamps`). ``proximity`` (sensor_msgs/Range, REP 117 fixed-distance ranger):
``-inf`` part detected, ``+inf`` not. ``joint_states``: the arm joint ``feeder_arm_joint``.
``edge1_verdict`` (DiagnosticStatus, the monitor's verdict of each judged cycle): ``name =
'edge1_verdict'``, level OK (ERROR: the cycle revealed an anomaly, its reason in ``message``),
values ``seq`` and ``stamp`` of the cycle, ``ready`` (``true``/``false``), ``state``.
``predicted/state`` (DiagnosticStatus, the predictor's state after each followed cycle): ``name =
'predicted_state'``, level OK, values ``seq`` and ``stamp`` of the cycle, ``edge`` (-1: no part
on the arm), ``R`` (m, ``none`` without a part), ``throw_kind`` (``jog``/``flip``/``lost``).
Every stamp is integer nanoseconds here; :func:`time_msg` and :func:`time_ns` convert.

Every parser takes exactly what its builder writes (the wire is hostile: anyone on the graph
can publish anything): the status's ``name`` and level, each value it reads given once, a
``seq`` in ASCII decimal digits (no sign, space, underscore, other scripts' digits or leading
zero) below 2**63, a stamp as :mod:`feeder_common.stamps` writes it, an ``R`` that is the
``repr`` of a finite float, texts at most :data:`MAX_TEXT` characters long. Anything else is a
ValueError naming the problem; no other exception escapes a parser, whatever the message holds.
"""

from dataclasses import dataclass
import math
from typing import Optional

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from feeder_interfaces.msg import Verdict
from sensor_msgs.msg import JointState, Range

from . import auth
from .frames import ARM_JOINT, SENSOR_FRAME
from .stamps import is_decimal, NS, parse_stamp_text, stamp_text

CYCLE_STATUS_NAME = 'cycle'
CYCLE_FIRED_NAME = 'cycle_fired'
VERDICT_NAME = 'edge1_verdict'
PREDICTED_STATE_NAME = 'predicted_state'
# A follower of cycle_status replays at most this many missed cycles; a longer jump of seq is
# implausible (a forged or corrupt seq, or a driver that ran unseen for minutes): an anomaly.
MAX_SEQ_JUMP = 1000
# A seq is below 2**63 (an int64 holds it), so its text has at most 19 digits.
MAX_SEQ = 2**63 - 1
# An edge of a part (-1: none) fits an int32.
MAX_EDGE = 2**31 - 1
# The longest message, hardware_id or state text a parser takes (a port path, a reason).
MAX_TEXT = 4096
# The longest repr of a finite float ('-2.2250738585072014e-308' is 24 characters).
_MAX_FLOAT_TEXT = 32
_SENSOR_TEXT = {True: '1', False: '0', None: 'none'}
_HEX = frozenset('0123456789abcdef')
_SENSOR_BIT = {'1': True, '0': False, 'none': None}
_READY_TEXT = {True: 'true', False: 'false'}
_READY_BIT = {'true': True, 'false': False}
THROW_KINDS = ('jog', 'flip', 'lost')
_LEVELS = {DiagnosticStatus.OK: True, DiagnosticStatus.ERROR: False}


def time_msg(stamp_ns):
    """Convert integer nanoseconds to builtin_interfaces/Time."""
    sec, nsec = divmod(int(stamp_ns), NS)
    return Time(sec=sec, nanosec=nsec)


def time_ns(stamp):
    """
    Convert builtin_interfaces/Time to integer nanoseconds.

    ValueError for a Time no sample clock writes: ``sec`` negative (before 1970) or
    ``nanosec`` outside [0, 1e9) (the field's documented range).
    """
    sec, nanosec = stamp.sec, stamp.nanosec
    if sec < 0 or not 0 <= nanosec < NS:
        raise ValueError(f'stamp sec={sec} nanosec={nanosec} is not a time from 1970 on with '
                         'nanosec in [0, 1e9)')
    return sec * NS + nanosec


def _text(what, text, limit=MAX_TEXT):
    """Return ``text`` if it is at most ``limit`` characters long; else ValueError."""
    if len(text) > limit:
        raise ValueError(f'{what} is {len(text)} characters long; at most {limit} are accepted')
    return text


def _clip(text):
    """Return ``str(text)`` cut to MAX_TEXT characters (its end an ellipsis when cut)."""
    text = str(text)
    return text if len(text) <= MAX_TEXT else text[:MAX_TEXT - 1] + '\u2026'


def parse_seq(text, what='seq'):
    """
    Parse a ``seq`` as the builders write it: ASCII decimal digits, below 2**63.

    ValueError naming the problem for anything else (a sign, spaces, ``_``, digits of other
    scripts, a leading zero, too many digits).
    """
    if not isinstance(text, str):
        raise ValueError(f'{what} is text, not {type(text).__name__}')
    if len(text) > len(str(MAX_SEQ)):
        raise ValueError(f'{what} is {len(text)} characters long; a seq has at most '
                         f'{len(str(MAX_SEQ))} digits')
    if not is_decimal(text):
        raise ValueError(f'{what} {text!r} is not a non-negative integer in ASCII decimal '
                         'digits without a leading zero')
    seq = int(text)
    if seq > MAX_SEQ:
        raise ValueError(f'{what} {seq} is beyond {MAX_SEQ}')
    return seq


def _parse_edge(text, what):
    """Parse an edge index: ``-1`` (no part) or ASCII decimal digits up to MAX_EDGE."""
    if text == '-1':
        return -1
    if len(text) > len(str(MAX_EDGE)) or not is_decimal(text) or int(text) > MAX_EDGE:
        raise ValueError(f'{what} {text[:40]!r} is not -1 or an edge index in ASCII decimal '
                         f'digits up to {MAX_EDGE}')
    return int(text)


def _parse_float(text, what):
    """Parse a finite float written as its ``repr`` (the shortest text that reads back)."""
    try:
        value = float(text) if len(text) <= _MAX_FLOAT_TEXT else None
    except ValueError:
        value = None
    if value is None or not math.isfinite(value) or repr(value) != text:
        raise ValueError(f'{what} {text[:40]!r} is not a finite float written as its repr')
    return value


def _optional_stamp(text, what):
    """Parse ``none`` (no usable stamp) or a stamp (:mod:`feeder_common.stamps`)."""
    if text == 'none':
        return None
    try:
        return parse_stamp_text(text)
    except ValueError as exc:
        raise ValueError(f'{what}: {exc}') from None


def _values(msg, what, name, keys):
    """
    Return the values ``keys`` of status ``msg``, each given once; else ValueError naming why.

    Checks the status's ``name``, that it is OK or ERROR, and the length of its texts; values
    of other keys are ignored (a later field must not break an older reader).
    """
    if msg.name != name:
        raise ValueError(f'{what} named {msg.name[:40]!r}, not {name!r}')
    if msg.level not in _LEVELS:
        raise ValueError(f'{what} level {msg.level!r} is neither OK nor ERROR')
    _text(f'{what} message', msg.message)
    _text(f'{what} hardware_id', msg.hardware_id)
    found = {}
    for kv in msg.values:
        if kv.key in keys:
            if kv.key in found:
                raise ValueError(f'{what} gives {kv.key} twice')
            found[kv.key] = kv.value
    missing = [k for k in keys if k not in found]
    if missing:
        raise ValueError(f'{what} without a {", ".join(missing)} value')
    return found


@dataclass(frozen=True)
class CycleStatus:
    """
    A parsed ``cycle_status``.

    ``sensor`` None: no bit (a failed cycle); ``stamp_ns`` the sample time, ns.
    """

    seq: int
    ok: bool
    sensor: Optional[bool]
    stamp_ns: int
    message: str
    hardware_id: str
    session: str = ''       # the reporting run (CycleSigner); '' unsigned
    mac: bytes = b''        # HMAC-SHA256 of the report (feeder_common.auth); b'' unsigned


def cycle_status(seq, ok, message, sensor, stamp_ns, hardware_id):
    """
    Build a ``cycle_status``; ``sensor`` True/False, or None for a failed cycle.

    ``message`` and ``hardware_id`` are cut to MAX_TEXT characters (what a parser takes).
    """
    return DiagnosticStatus(
        level=DiagnosticStatus.OK if ok else DiagnosticStatus.ERROR, name=CYCLE_STATUS_NAME,
        message=_clip(message), hardware_id=_clip(hardware_id),
        values=[KeyValue(key='seq', value=str(int(seq))),
                KeyValue(key='sensor', value=_SENSOR_TEXT[sensor]),
                KeyValue(key='stamp', value=stamp_text(stamp_ns))])


def parse_cycle_status(msg):
    """Parse a ``cycle_status`` as :func:`cycle_status` writes it; ValueError naming a fault."""
    what = 'cycle_status'
    values = _values(msg, what, CYCLE_STATUS_NAME, ('seq', 'sensor', 'stamp'))
    seq = parse_seq(values['seq'], f'{what} seq')
    if values['sensor'] not in _SENSOR_BIT:
        raise ValueError(f'{what} sensor {values["sensor"][:40]!r} is not 1, 0 or none')
    try:
        stamp = parse_stamp_text(values['stamp'])
    except ValueError as exc:
        raise ValueError(f'{what}: {exc}') from None
    session, tag = _signature(msg.values)
    return CycleStatus(seq, _LEVELS[msg.level], _SENSOR_BIT[values['sensor']], stamp,
                       msg.message, msg.hardware_id, session, tag)


@dataclass(frozen=True)
class EdgeVerdict:
    """A parsed ``edge1_verdict``: the monitor's answer for cycle ``seq``."""

    seq: int
    stamp_ns: Optional[int]
    ready: bool
    state: str
    anomaly: str            # '' unless the cycle revealed an anomaly


def edge_verdict(seq, stamp_ns, ready, state, anomaly=None, hardware_id=''):
    """
    Build an ``edge1_verdict``; ``stamp_ns`` None: the cycle had no usable stamp.

    Its texts are cut to MAX_TEXT characters (an anomaly can quote a failed cycle's reason).
    """
    return DiagnosticStatus(
        level=DiagnosticStatus.ERROR if anomaly else DiagnosticStatus.OK, name=VERDICT_NAME,
        message=_clip(anomaly or state), hardware_id=_clip(hardware_id),
        values=[KeyValue(key='seq', value=str(int(seq))),
                KeyValue(key='stamp', value='none' if stamp_ns is None
                         else stamp_text(stamp_ns)),
                KeyValue(key='ready', value=_READY_TEXT[bool(ready)]),
                KeyValue(key='state', value=_clip(state))])


def parse_edge_verdict(msg):
    """Parse an ``edge1_verdict`` as :func:`edge_verdict` writes it; ValueError naming a fault."""
    what = 'edge1_verdict'
    values = _values(msg, what, VERDICT_NAME, ('seq', 'stamp', 'ready', 'state'))
    seq = parse_seq(values['seq'], f'{what} seq')
    stamp = _optional_stamp(values['stamp'], what)
    if values['ready'] not in _READY_BIT:
        raise ValueError(f'{what} ready {values["ready"][:40]!r} is not true or false')
    state = _text(f'{what} state', values['state'])
    ok = _LEVELS[msg.level]
    if not state:
        raise ValueError(f'{what} with an empty state')
    if ok and msg.message != state:
        raise ValueError(f'{what} of level OK whose message is not its state')
    if not ok and not msg.message:
        raise ValueError(f'{what} of level ERROR without the anomaly in its message')
    return EdgeVerdict(seq, stamp, _READY_BIT[values['ready']], state,
                       '' if ok else msg.message)


@dataclass(frozen=True)
class PredictedState:
    """A parsed ``predicted/state``: where the predictor has the part after cycle ``seq``."""

    seq: int
    stamp_ns: Optional[int]
    edge: int               # -1: no part on the arm
    R: Optional[float]      # m; None without a part on the arm
    throw_kind: str         # 'jog', 'flip' or 'lost'


def predicted_state(seq, stamp_ns, edge, R, throw_kind):
    """Build a ``predicted/state``; ``R`` None when no part is on the arm (edge -1)."""
    return DiagnosticStatus(
        level=DiagnosticStatus.OK, name=PREDICTED_STATE_NAME, message=str(throw_kind),
        values=[KeyValue(key='seq', value=str(int(seq))),
                KeyValue(key='stamp', value='none' if stamp_ns is None
                         else stamp_text(stamp_ns)),
                KeyValue(key='edge', value=str(int(edge))),
                # repr: the shortest text that reads back as the same float
                KeyValue(key='R', value='none' if R is None else repr(float(R))),
                KeyValue(key='throw_kind', value=str(throw_kind))])


def parse_predicted_state(msg):
    """Parse a ``predicted/state`` as :func:`predicted_state` writes it; ValueError if not."""
    what = 'predicted/state'
    keys = ('seq', 'stamp', 'edge', 'R', 'throw_kind')
    values = _values(msg, what, PREDICTED_STATE_NAME, keys)
    if msg.level != DiagnosticStatus.OK:
        raise ValueError(f'{what} of a level other than OK')
    seq = parse_seq(values['seq'], f'{what} seq')
    stamp = _optional_stamp(values['stamp'], what)
    edge = _parse_edge(values['edge'], f'{what} edge')
    R = None if values['R'] == 'none' else _parse_float(values['R'], f'{what} R')
    kind = values['throw_kind']
    if kind not in THROW_KINDS:
        raise ValueError(f'{what} throw_kind {kind[:40]!r} is not one of {", ".join(THROW_KINDS)}')
    if msg.message != kind:
        raise ValueError(f'{what} whose message is not its throw_kind')
    if len({edge == -1, R is None, kind == 'lost'}) != 1:
        raise ValueError(f'{what} edge {edge}, R {values["R"]!r}, throw_kind {kind!r}: edge -1, '
                         'R none and throw_kind lost go together (no part on the arm)')
    return PredictedState(seq, stamp, edge, R, kind)


def proximity(stamp_ns, detected, range_m, frame_id=SENSOR_FRAME):
    """Build a ``proximity`` Range: a fixed-distance ranger (REP 117), -inf = part detected."""
    rng = Range()
    rng.header.stamp = time_msg(stamp_ns)
    rng.header.frame_id = frame_id
    rng.radiation_type = Range.INFRARED
    rng.field_of_view = 0.0
    rng.min_range = rng.max_range = float(range_m)
    rng.range = -math.inf if detected else math.inf
    return rng


def proximity_detected(msg):
    """
    Sensor bit of a ``proximity`` Range (REP 117), or None for NaN (no reading).

    ``-inf`` detected, ``+inf`` not; a finite reading is a detection within ``[min_range,
    max_range]``, and needs limits that are finite, not negative and in order (else
    ValueError: such a Range says nothing). Never any other exception, whatever the floats.
    """
    r = msg.range
    if math.isnan(r):
        return None
    if math.isinf(r):
        return r < 0
    lo, hi = msg.min_range, msg.max_range
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 <= lo <= hi):
        raise ValueError(f'proximity range {r!r} with limits [{lo!r}, {hi!r}] that are not '
                         'finite, non-negative and in order')
    return lo <= r <= hi


def joint_state(stamp_ns, position, velocity):
    """Build a ``joint_states`` message of the arm joint (rad, rad/s; no effort)."""
    js = JointState()
    js.header.stamp = time_msg(stamp_ns)
    js.name = [ARM_JOINT]
    js.position = [float(position)]
    js.velocity = [float(velocity)]
    js.effort = []
    return js


# ---- signed statements (feeder_common.auth; docs/security.md) ------------------------------

def signed_verdict(key, monitor, session, seq, stamp_ns, ready, state, anomaly, sent_ns):
    """
    Build a signed ``Verdict`` of monitor ``monitor`` (its fully qualified node name).

    ``seq`` 0 and ``stamp_ns`` None: no cycle judged yet.
    """
    msg = Verdict(seq=int(seq), ready=bool(ready), state=_clip(str(state)),
                  anomaly=_clip(str(anomaly or '')), session=str(session))
    if stamp_ns is not None:
        msg.stamp = time_msg(stamp_ns)
    msg.sent = time_msg(sent_ns)
    msg.mac = list(auth.mac(key, auth.VERDICT_LABEL, auth.verdict_fields(
        monitor, session, seq, stamp_ns, ready, msg.state, msg.anomaly, sent_ns)))
    return msg


@dataclass(frozen=True)
class VerdictCheck:
    """What a consumer may conclude from one ``Verdict`` (:func:`check_verdict`)."""

    ready_now: bool         # signed, fresh, and the part is proven on the goal edge
    authentic: bool         # the MAC verifies for this monitor under this key
    seq: int
    stamp_ns: Optional[int]
    sent_age_s: Optional[float]
    reason: str             # why not ready now ('' when ready_now)


def check_verdict(msg, key, monitor, now_ns, max_age_s=1.0):
    """
    The one-call check of an ``edge1_ready`` / ``edge1_verdict`` message for a consumer.

    ``ready_now`` only when the MAC verifies for ``monitor`` (e.g. '/feeder/feeder_monitor')
    under ``key`` (:func:`feeder_common.auth.node_key`), ``ready`` is true, and the monitor
    sent it at most ``max_age_s`` ago (so a dead or stalled monitor, or a replayed message,
    reads as not ready). ``now_ns``: the consumer's clock, e.g. node.get_clock().now().
    """
    try:
        stamp_ns = time_ns(msg.stamp) if (msg.stamp.sec or msg.stamp.nanosec) else None
        sent_ns = time_ns(msg.sent)
    except ValueError as exc:       # no monitor writes such a time: not authentic
        return VerdictCheck(False, False, int(msg.seq), None, None, f'malformed verdict: {exc}')
    fields = auth.verdict_fields(monitor, msg.session, msg.seq, stamp_ns, msg.ready, msg.state,
                                 msg.anomaly, sent_ns)
    authentic = auth.mac_ok(key, auth.VERDICT_LABEL, fields, bytes(msg.mac))
    age = (int(now_ns) - sent_ns) * 1e-9
    if not authentic:
        reason = (f'not signed by {monitor} under this key (key id {auth.key_id(key)})'
                  if len(msg.mac) else 'unsigned verdict')
    elif abs(age) > max_age_s:
        reason = (f'sent {age:.3f} s ago, more than {max_age_s:g} s: the monitor stalled, '
                  'died, or this is a replay' if age > 0 else
                  f'sent {-age:.3f} s in the future: clocks apart')
    elif not msg.ready:
        reason = f'not ready: {msg.state}' + (f' ({msg.anomaly})' if msg.anomaly else '')
    else:
        reason = ''
    return VerdictCheck(not reason, authentic, int(msg.seq), stamp_ns, age, reason)



def _signature(values):
    """
    The ``session`` and ``mac`` of a signed status (a list of KeyValue); ('', b'') unsigned.

    Either may be absent (an unsigned report still parses, so that the monitor can say it was
    unsigned); given twice, or not as CycleSigner writes them, is a ValueError.
    """
    found = {}
    for kv in values:
        if kv.key in ('session', 'mac'):
            if kv.key in found:
                raise ValueError(f'a status gives {kv.key} twice')
            found[kv.key] = kv.value
    session, text = found.get('session', ''), found.get('mac', '')
    if len(session) > 64 or not all(c in _HEX for c in session):
        raise ValueError(f'session {session[:40]!r} is not up to 64 lowercase hex digits')
    if text and (len(text) != 2 * auth.MAC_BYTES or not all(c in _HEX for c in text)):
        raise ValueError(f'mac {text[:40]!r} is not {2 * auth.MAC_BYTES} lowercase hex digits')
    return session, bytes.fromhex(text)


@dataclass(frozen=True)
class CycleFired:
    """A parsed ``cycle_fired``: cycle ``seq`` was being fired at ``stamp_ns``."""

    seq: int
    stamp_ns: int
    session: str
    mac: bytes


def parse_cycle_fired(msg):
    """Parse a ``cycle_fired`` as CycleSigner writes it; ValueError naming a fault."""
    what = 'cycle_fired'
    values = _values(msg, what, CYCLE_FIRED_NAME, ('seq', 'stamp'))
    seq = parse_seq(values['seq'], f'{what} seq')
    try:
        stamp = parse_stamp_text(values['stamp'])
    except ValueError as exc:
        raise ValueError(f'{what}: {exc}') from None
    session, tag = _signature(msg.values)
    return CycleFired(seq, stamp, session, tag)


class CycleSigner:
    """
    Signs the cycle reports of one driver run (the driver, or the sim standing in for it).

    ``node``: the fully qualified name of the reporting node (the monitor's ``driver_node``);
    every run has a new random ``session``, so its reports cannot be replayed into another run.
    """

    def __init__(self, key, node, session=None):
        self.key = key
        self.node = node
        self.session = session or auth.new_session()

    def cycle_status(self, seq, ok, message, sensor, stamp_ns, hardware_id):
        """A signed ``cycle_status`` (values ``session`` and ``mac`` besides the usual)."""
        msg = cycle_status(seq, ok, message, sensor, stamp_ns, hardware_id)
        tag = auth.mac(self.key, auth.CYCLE_LABEL, auth.cycle_fields(
            self.node, self.session, seq, stamp_ns, 'completed' if ok else 'failed',
            _SENSOR_TEXT[sensor], message))
        msg.values += [KeyValue(key='session', value=self.session),
                       KeyValue(key='mac', value=tag.hex())]
        return msg

    def cycle_fired(self, seq, stamp_ns, hardware_id):
        """A signed ``cycle_fired``: cycle ``seq`` is being fired (sent before the actuator moves)."""
        tag = auth.mac(self.key, auth.FIRED_LABEL,
                       auth.fired_fields(self.node, self.session, seq, stamp_ns))
        return DiagnosticStatus(
            level=DiagnosticStatus.OK, name=CYCLE_FIRED_NAME, message='firing',
            hardware_id=hardware_id,
            values=[KeyValue(key='seq', value=str(int(seq))),
                    KeyValue(key='stamp', value=stamp_text(stamp_ns)),
                    KeyValue(key='session', value=self.session),
                    KeyValue(key='mac', value=tag.hex())])
