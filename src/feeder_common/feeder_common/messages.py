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
from .stamps import NS, parse_stamp_text, stamp_text

CYCLE_STATUS_NAME = 'cycle'
VERDICT_NAME = 'edge1_verdict'
PREDICTED_STATE_NAME = 'predicted_state'
# A follower of cycle_status replays at most this many missed cycles; a longer jump of seq is
# implausible (a forged or corrupt seq, or a driver that ran unseen for minutes): an anomaly.
MAX_SEQ_JUMP = 1000
_SENSOR_TEXT = {True: '1', False: '0', None: 'none'}
_SENSOR_BIT = {'1': True, '0': False}


def time_msg(stamp_ns):
    """Convert integer nanoseconds to builtin_interfaces/Time."""
    sec, nsec = divmod(int(stamp_ns), NS)
    return Time(sec=sec, nanosec=nsec)


def time_ns(stamp):
    """Convert builtin_interfaces/Time to integer nanoseconds."""
    return stamp.sec * NS + stamp.nanosec


@dataclass(frozen=True)
class CycleStatus:
    """
    A parsed ``cycle_status``.

    ``sensor`` None: no bit (a failed cycle); ``stamp_ns`` None: no usable stamp.
    """

    seq: int
    ok: bool
    sensor: Optional[bool]
    stamp_ns: Optional[int]
    message: str
    hardware_id: str
    session: str = ''       # the reporting run (CycleSigner); '' unsigned
    mac: bytes = b''        # HMAC-SHA256 of the report (feeder_common.auth); b'' unsigned


def cycle_status(seq, ok, message, sensor, stamp_ns, hardware_id):
    """Build a ``cycle_status``; ``sensor`` True/False, or None for a failed cycle."""
    return DiagnosticStatus(
        level=DiagnosticStatus.OK if ok else DiagnosticStatus.ERROR, name=CYCLE_STATUS_NAME,
        message=message, hardware_id=hardware_id,
        values=[KeyValue(key='seq', value=str(int(seq))),
                KeyValue(key='sensor', value=_SENSOR_TEXT[sensor]),
                KeyValue(key='stamp', value=stamp_text(stamp_ns))])


def _optional_stamp(values):
    """Return the ``stamp`` value of a status in ns; None when it is missing or unreadable."""
    # A bad stamp does not make the status unusable: the seq still names the cycle.
    try:
        return parse_stamp_text(values['stamp'])
    except (KeyError, ValueError):
        return None


def parse_cycle_status(msg):
    """Parse a ``cycle_status``; ValueError naming what is wrong when ``seq`` is unusable."""
    values = {kv.key: kv.value for kv in msg.values}
    try:
        seq = int(values['seq'])
    except KeyError:
        raise ValueError('cycle_status without a seq value') from None
    except ValueError:
        raise ValueError(f'cycle_status seq {values["seq"]!r} is not an integer') from None
    if seq < 0:
        raise ValueError(f'cycle_status seq {seq} is negative')
    stamp = _optional_stamp(values)
    session, tag = _signature(values)
    return CycleStatus(seq, msg.level == DiagnosticStatus.OK,
                       _SENSOR_BIT.get(values.get('sensor')), stamp, msg.message,
                       msg.hardware_id, session, tag)


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
    """Parse a ``predicted/state``; ValueError naming what is wrong."""
    values = {kv.key: kv.value for kv in msg.values}
    try:
        seq, edge = int(values['seq']), int(values['edge'])
        R = None if values['R'] == 'none' else float(values['R'])
    except (KeyError, ValueError) as exc:
        raise ValueError(f'predicted/state without a usable seq/edge/R ({exc!r})') from None
    stamp = _optional_stamp(values)
    return PredictedState(seq, stamp, edge, R, values.get('throw_kind', ''))


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
    """Sensor bit of a ``proximity`` Range (REP 117), or None for NaN (no reading)."""
    r = msg.range
    if math.isnan(r):
        return None
    if math.isinf(r):
        return r < 0
    return bool(msg.min_range <= r <= msg.max_range)


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
    msg = Verdict(seq=int(seq), ready=bool(ready), state=str(state), anomaly=str(anomaly or ''),
                  session=str(session))
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
    stamp_ns = time_ns(msg.stamp) if (msg.stamp.sec or msg.stamp.nanosec) else None
    sent_ns = time_ns(msg.sent)
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


CYCLE_FIRED_NAME = 'cycle_fired'


def _signature(values):
    """The ``session`` and ``mac`` of a signed status; ('', b'') when absent or malformed."""
    session, text = values.get('session', ''), values.get('mac', '')
    if len(session) > 64 or len(text) != 2 * auth.MAC_BYTES:
        return session[:64], b''
    try:
        return session, bytes.fromhex(text)
    except ValueError:
        return session, b''


@dataclass(frozen=True)
class CycleFired:
    """A parsed ``cycle_fired``: cycle ``seq`` was being fired at ``stamp_ns``."""

    seq: int
    stamp_ns: Optional[int]
    session: str
    mac: bytes


def parse_cycle_fired(msg):
    """Parse a ``cycle_fired``; ValueError naming what is wrong."""
    values = {kv.key: kv.value for kv in msg.values}
    try:
        seq = int(values['seq'])
    except (KeyError, ValueError) as exc:
        raise ValueError(f'cycle_fired without a usable seq ({exc!r})') from None
    session, tag = _signature(values)
    return CycleFired(seq, _optional_stamp(values), session, tag)


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
