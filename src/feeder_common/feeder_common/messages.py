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
Builders and parsers of the feeder's messages (feeder_interfaces; docs/interfaces.md).

``cycle_status`` (feeder_interfaces/CycleStatus): one per fired cycle, outcome ``completed``
(with the sensor bit) or ``failed`` (SENSOR_NONE, the ``reason``), ``hardware_id`` = who ran
it, ``stamp`` the sample time. ``cycle_fired`` (the same type, outcome ``fired``) announces
each cycle before it fires. A driver signs both (``session``, ``mac``: :class:`CycleSigner`,
feeder_common.auth). ``proximity`` (sensor_msgs/Range, REP 117 fixed-distance ranger): ``-inf``
part detected, ``+inf`` not. ``joint_states``: the arm joint ``feeder_arm_joint``. The
monitor's ``edge1_ready`` / ``edge1_verdict`` are ``feeder_interfaces/Verdict``, signed
(:func:`signed_verdict`); a consumer checks one in one call (:func:`check_verdict`).
``predicted/state`` (feeder_interfaces/PredictedState): the predictor's state after each
followed cycle (edge -1 and r NaN: no part on the arm); ``predicted/limit_set`` and
``predicted/analysis`` (LimitSet, Analysis): the scene's analysis, field by field.
Every stamp is integer nanoseconds here; :func:`time_msg` and :func:`time_ns` convert.

Every parser takes exactly what its builder writes (the wire is hostile: anyone on the graph
can publish anything): an outcome and a sensor code the topic carries and that go together,
a ``seq`` below 2**63, a stamp from 1970 on with nanosec below 1e9, a finite ``r`` or NaN with
edge -1 and kind ``lost``, texts at most :data:`MAX_TEXT` characters long, a session of lower
case hex and a MAC of 32 bytes or none. Anything else is a ValueError naming the problem; no
other exception escapes a parser, whatever the message holds.
"""

from dataclasses import dataclass
import math
from typing import Optional

from builtin_interfaces.msg import Time
from feeder_interfaces.msg import Analysis as AnalysisMsg
from feeder_interfaces.msg import BasinOutcome, EdgeBand, EdgeDesign, Escape
from feeder_interfaces.msg import CycleStatus as CycleStatusMsg
from feeder_interfaces.msg import LimitSet as LimitSetMsg
from feeder_interfaces.msg import PredictedState as PredictedStateMsg
from feeder_interfaces.msg import SpeedSetpoint
from feeder_interfaces.msg import Verdict
from sensor_msgs.msg import JointState, Range

from . import auth
from .frames import ARM_JOINT, SENSOR_FRAME

# A follower of cycle_status replays at most this many missed cycles; a longer jump of seq is
# implausible (a forged or corrupt seq, or a driver that ran unseen for minutes): an anomaly.
MAX_SEQ_JUMP = 1000
NS = 1_000_000_000
# builtin_interfaces/Time holds int32 sec; a sample stamp is never before 1970 (sec >= 0).
MAX_STAMP_NS = (2**31 - 1) * NS + NS - 1
# A seq is below 2**63 (an int64 holds it: a consumer in any language can count with it).
MAX_SEQ = 2**63 - 1
# The longest message, hardware_id or state text a parser takes (a port path, a reason).
MAX_TEXT = 4096
_SENSOR_TEXT = {True: '1', False: '0', None: 'none'}
_HEX = frozenset('0123456789abcdef')
_SENSOR_CODE = {True: CycleStatusMsg.SENSOR_DETECTED, False: CycleStatusMsg.SENSOR_CLEAR,
                None: CycleStatusMsg.SENSOR_NONE}
_SENSOR_OF_CODE = {code: bit for bit, code in _SENSOR_CODE.items()}
THROW_KINDS = (PredictedStateMsg.THROW_JOG, PredictedStateMsg.THROW_FLIP,
               PredictedStateMsg.THROW_LOST)


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


def _wire_text(text):
    """
    Return ``text`` as a DDS string carries it, cut to MAX_TEXT characters.

    A NUL ends a string on the wire, so it is sent (and signed) as U+FFFD instead.
    """
    return _clip(str(text).replace('\x00', '\ufffd'))


def _clip(text):
    """Return ``str(text)`` cut to MAX_TEXT characters (its end an ellipsis when cut)."""
    text = str(text)
    return text if len(text) <= MAX_TEXT else text[:MAX_TEXT - 1] + '\u2026'


def _seq_field(seq, what):
    """Return ``seq`` if a cycle number an int64 holds (uint64 on the wire); else ValueError."""
    if seq > MAX_SEQ:
        raise ValueError(f'{what} {seq} is beyond {MAX_SEQ}')
    return int(seq)


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
    reason: str             # why the cycle failed ('' when it completed)
    hardware_id: str
    session: str = ''       # the reporting run (CycleSigner); '' unsigned
    mac: bytes = b''        # HMAC-SHA256 of the report (feeder_common.auth); b'' unsigned
    release_speed: Optional[float] = None   # rad/s, the cycle's setpoint; None: none


def _speed(speed):
    """Return a setpoint (rad/s) as sent: a float > 0, or NaN for none; ValueError else."""
    if speed is None:
        return math.nan
    speed = float(speed)
    if not (math.isfinite(speed) and speed > 0.0):
        raise ValueError(f'release speed {speed!r} is not a finite speed > 0 rad/s')
    return speed


def cycle_status(seq, ok, reason, sensor, stamp_ns, hardware_id, release_speed=None):
    """
    Build an unsigned ``cycle_status``; ``sensor`` True/False, or None for a failed cycle.

    ``reason`` (why a cycle failed) is only sent for a failed cycle; it and ``hardware_id``
    are cut to MAX_TEXT characters (what a parser takes), a NUL sent as U+FFFD.
    ``release_speed``: the setpoint the cycle was fired at (rad/s; None: the controller's own
    fixed speed, sent as NaN).
    """
    return CycleStatusMsg(
        seq=int(seq), stamp=time_msg(stamp_ns),
        outcome=CycleStatusMsg.OUTCOME_COMPLETED if ok else CycleStatusMsg.OUTCOME_FAILED,
        sensor=_SENSOR_CODE[sensor], reason='' if ok else _wire_text(reason),
        hardware_id=_wire_text(hardware_id), release_speed=_speed(release_speed))


def _report_fields(msg, what, outcomes):
    """
    Check the fields every cycle report has; return (seq, outcome, sensor, stamp_ns).

    ``outcomes``: the outcomes this topic carries. A bit goes with a completed cycle only.
    """
    if msg.outcome not in outcomes:
        raise ValueError(f'{what} outcome {msg.outcome[:40]!r} is not '
                         + ' or '.join(repr(o) for o in outcomes))
    seq = _seq_field(msg.seq, f'{what} seq')
    if msg.sensor not in _SENSOR_OF_CODE:
        raise ValueError(f'{what} sensor {msg.sensor} is not SENSOR_NONE (-1), SENSOR_CLEAR (0) '
                         'or SENSOR_DETECTED (1)')
    sensor = _SENSOR_OF_CODE[msg.sensor]
    if (msg.outcome == CycleStatusMsg.OUTCOME_COMPLETED) != (sensor is not None):
        raise ValueError(f'{what} {msg.outcome} with sensor {msg.sensor}: a completed cycle has '
                         'a bit (0 or 1), a fired or failed one SENSOR_NONE')
    try:
        stamp = time_ns(msg.stamp)
    except ValueError as exc:
        raise ValueError(f'{what}: {exc}') from None
    if msg.outcome != CycleStatusMsg.OUTCOME_FAILED and msg.reason:
        raise ValueError(f'{what} {msg.outcome} with a reason: only a failed cycle has one')
    _text(f'{what} reason', msg.reason)
    _text(f'{what} hardware_id', msg.hardware_id)
    return seq, sensor, stamp


def parse_cycle_status(msg):
    """
    Parse a ``cycle_status`` (feeder_interfaces/CycleStatus, outcome completed or failed).

    ValueError naming the fault for anything :func:`cycle_status` (signed or not) does not
    write.
    """
    what = 'cycle_status'
    seq, sensor, stamp = _report_fields(
        msg, what, (CycleStatusMsg.OUTCOME_COMPLETED, CycleStatusMsg.OUTCOME_FAILED))
    session, tag = _signature(msg, what)
    speed = msg.release_speed
    if not math.isnan(speed):
        try:
            _speed(speed)
        except ValueError as exc:
            raise ValueError(f'{what}: {exc} (NaN: none)') from None
    return CycleStatus(seq, msg.outcome == CycleStatusMsg.OUTCOME_COMPLETED, sensor, stamp,
                       msg.reason, msg.hardware_id, session, tag,
                       None if math.isnan(speed) else float(speed))


@dataclass(frozen=True)
class PredictedState:
    """A parsed ``predicted/state``: where the predictor has the part after cycle ``seq``."""

    seq: int
    stamp_ns: Optional[int]
    edge: int               # -1: no part on the arm
    R: Optional[float]      # m; None without a part on the arm
    throw_kind: str         # 'jog', 'flip' or 'lost'


def predicted_state(seq, stamp_ns, edge, R, throw_kind):
    """
    Build a ``predicted/state``; ``R`` None when no part is on the arm (edge -1).

    ``stamp_ns`` None (no cycle stamp known) is sent as the zero time.
    """
    msg = PredictedStateMsg(seq=int(seq), edge=int(edge),
                            r=math.nan if R is None else float(R), throw_kind=str(throw_kind))
    if stamp_ns:
        msg.stamp = time_msg(stamp_ns)
    return msg


def parse_predicted_state(msg):
    """Parse a ``predicted/state`` as :func:`predicted_state` writes it; ValueError if not."""
    what = 'predicted/state'
    seq = _seq_field(msg.seq, f'{what} seq')
    try:
        stamp = time_ns(msg.stamp) or None
    except ValueError as exc:
        raise ValueError(f'{what}: {exc}') from None
    edge = msg.edge
    if edge < PredictedStateMsg.EDGE_LOST:
        raise ValueError(f'{what} edge {edge} is neither EDGE_LOST (-1) nor an edge index')
    R = msg.r
    if math.isinf(R):
        raise ValueError(f'{what} r {R!r} is not a finite contact point (NaN: no part)')
    R = None if math.isnan(R) else R
    kind = msg.throw_kind
    if kind not in THROW_KINDS:
        raise ValueError(f'{what} throw_kind {kind[:40]!r} is not one of {", ".join(THROW_KINDS)}')
    if len({edge == PredictedStateMsg.EDGE_LOST, R is None, kind == 'lost'}) != 1:
        raise ValueError(f'{what} edge {edge}, r {msg.r!r}, throw_kind {kind!r}: edge -1, r NaN '
                         'and throw_kind lost go together (no part on the arm)')
    return PredictedState(seq, stamp, edge, R, kind)


def limit_set_msg(limit_set):
    """
    Build a ``predicted/limit_set`` from a limit set's ``as_dict()`` (throwmap.LimitSet).

    An edge without a jog count (none seen) has ``jogs_min`` = ``jogs_max`` = -1.
    """
    jogs = limit_set['jogs']
    cycle = limit_set['cycle_length']
    return LimitSetMsg(
        pattern=[int(e) for e in limit_set['pattern']],
        bands=[EdgeBand(edge=int(edge), r_min=float(lo), r_max=float(hi),
                        jogs_min=int(jogs.get(edge, (-1, -1))[0]),
                        jogs_max=int(jogs.get(edge, (-1, -1))[1]))
               for edge, (lo, hi) in sorted(limit_set['bands'].items(),
                                            key=lambda band: int(band[0]))],
        periodic=bool(limit_set['periodic']), transient=int(limit_set['transient']),
        cycle_length_min=float(cycle['min']), cycle_length_mean=float(cycle['mean']),
        cycle_length_max=float(cycle['max']))


def analysis_msg(analysis, scene, scene_hash):
    """
    Build a ``predicted/analysis`` from an analysis' ``as_dict()`` (throwmap.Analysis).

    ``scene``: the scene's name; ``scene_hash``: the first 8 bytes of the SHA-256 of its file,
    as an integer. Without a pull sample (``pull`` None) the counts are 0 and the worst normal
    force NaN.
    """
    design, sensor = analysis['design'], analysis['sensor']
    pull = analysis.get('pull') or {'throws': 0, 'pulling': 0, 'worst': math.nan}
    return AnalysisMsg(
        scene=_wire_text(scene), scene_hash=int(scene_hash),
        start_edge=int(analysis['start']['edge']), start_r=float(analysis['start']['R']),
        limit_set=limit_set_msg(analysis['limit_set']),
        edges=[EdgeDesign(edge=int(row['edge']), r_grasp=float(row['R_grasp']),
                          r_min=float(row['R_min']), r_flip=float(row['R_flip']),
                          r_max=float(row['R_max'])) for row in design['edges']],
        r_max_all=float(design['R_max_all']), invariant=bool(design['invariant']),
        escapes=[Escape(edge=int(edge), to_edge=int(to_edge), r=float(r))
                 for edge, to_edge, r in design.get('escapes', ())],
        basin=[BasinOutcome(pattern=_wire_text(pattern), starts=int(starts))
               for pattern, starts in sorted(analysis['basin'].items())],
        goal_edge=int(sensor['goal_edge']), sensor_radius=float(sensor['radius']),
        sensor_footprint=float(sensor['footprint']),
        guarantee_radius=float(sensor['guarantee_radius']),
        reach_radius=float(sensor['reach_radius']),
        detection_rate=float(sensor['detection_rate']),
        warmup_throws=int(sensor['warmup_throws']), sensor_feasible=bool(sensor['feasible']),
        pull_throws=int(pull['throws']), pulling_throws=int(pull['pulling']),
        worst_normal_force=float(pull['worst']))


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

    ``seq`` 0 and ``stamp_ns`` None: no cycle judged yet. A zero stamp is "none" on the wire
    (Verdict's stamp field), so it is signed as none.
    """
    stamp_ns = stamp_ns or None
    msg = Verdict(seq=int(seq), ready=bool(ready), state=_wire_text(state),
                  anomaly=_wire_text(anomaly or ''), session=_wire_text(session))
    if stamp_ns is not None:
        msg.stamp = time_msg(stamp_ns)
    msg.sent = time_msg(sent_ns)
    msg.mac = list(auth.mac(key, auth.VERDICT_LABEL, auth.verdict_fields(
        monitor, session, seq, stamp_ns, ready, msg.state, msg.anomaly, sent_ns)))
    return msg


def _age_reason(age, max_age_s, who):
    """Say why a statement sent ``age`` s ago (negative: ahead) is not fresh."""
    if age > 0:
        return (f'sent {age:.3f} s ago, more than {max_age_s:g} s: {who} stalled, died, or '
                'this is a replay')
    return f'sent {-age:.3f} s in the future: clocks apart'


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
    Check an ``edge1_ready`` / ``edge1_verdict`` message in one call, for a consumer.

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
        reason = _age_reason(age, max_age_s, 'the monitor')
    elif not msg.ready:
        reason = f'not ready: {msg.state}' + (f' ({msg.anomaly})' if msg.anomaly else '')
    else:
        reason = ''
    return VerdictCheck(not reason, authentic, int(msg.seq), stamp_ns, age, reason)


@dataclass(frozen=True)
class SetpointCheck:
    """What a driver may conclude from one ``SpeedSetpoint`` (:func:`check_setpoint`)."""

    usable: bool            # signed by the sender under the key, fresh, a valid speed
    seq: int
    driver_session: str
    speed: float            # rad/s (NaN when not a valid speed)
    reason: str             # why not usable ('' when usable)
    sent_ns: Optional[int] = None   # when the sender sent it (None: malformed)


def signed_setpoint(key, sender, session, seq, driver_session, speed, sent_ns):
    """
    Build a signed ``SpeedSetpoint`` of ``sender`` (its fully qualified node name).

    ``speed`` rad/s for cycle ``seq`` of the driver run ``driver_session`` ('' : the first
    cycle of a run not seen yet).
    """
    msg = SpeedSetpoint(seq=int(seq), driver_session=_wire_text(driver_session),
                        speed=_speed(speed), session=_wire_text(session))
    msg.sent = time_msg(sent_ns)
    msg.mac = list(auth.mac(key, auth.SETPOINT_LABEL, auth.setpoint_fields(
        sender, session, seq, msg.driver_session, speed, sent_ns)))
    return msg


def check_setpoint(msg, key, sender, now_ns, max_age_s=1.0):
    """
    Check a ``release_speed_setpoint`` message in one call, for a driver.

    ``usable`` only when the MAC verifies for ``sender`` under ``key``, the speed is finite
    and > 0, and it was sent at most ``max_age_s`` ago. Whether it is for the driver's next
    cycle (``seq``, ``driver_session``) is the driver's to check. Never raises.
    """
    seq, session = int(msg.seq), str(msg.driver_session)
    try:
        sent_ns = time_ns(msg.sent)
        speed = _speed(msg.speed)
        _signature(msg, 'release_speed_setpoint')
    except ValueError as exc:
        return SetpointCheck(False, seq, session, math.nan, f'malformed setpoint: {exc}')
    fields = auth.setpoint_fields(sender, msg.session, seq, session, speed, sent_ns)
    age = (int(now_ns) - sent_ns) * 1e-9
    if not auth.mac_ok(key, auth.SETPOINT_LABEL, fields, bytes(msg.mac)):
        reason = (f'not signed by {sender} under this key (key id {auth.key_id(key)})'
                  if len(msg.mac) else 'unsigned setpoint')
    elif abs(age) > max_age_s:
        reason = _age_reason(age, max_age_s, 'the sender')
    else:
        reason = ''
    return SetpointCheck(not reason, seq, session, speed, reason, sent_ns)


def _signature(msg, what):
    """
    Return the ``session`` and ``mac`` of a cycle report; ('', b'') unsigned.

    Either may be empty (an unsigned report still parses, so that the monitor can say it was
    unsigned); anything CycleSigner does not write is a ValueError.
    """
    session, tag = msg.session, bytes(msg.mac)
    if len(session) > 64 or not all(c in _HEX for c in session):
        raise ValueError(f'{what} session {session[:40]!r} is not up to 64 lowercase hex digits')
    if tag and len(tag) != auth.MAC_BYTES:
        raise ValueError(f'{what} mac of {len(tag)} bytes; a MAC has {auth.MAC_BYTES}')
    return session, tag


@dataclass(frozen=True)
class CycleFired:
    """A parsed ``cycle_fired``: cycle ``seq`` was being fired at ``stamp_ns``."""

    seq: int
    stamp_ns: int
    session: str
    mac: bytes


def parse_cycle_fired(msg):
    """Parse a ``cycle_fired`` (CycleStatus, outcome fired) as CycleSigner writes it."""
    what = 'cycle_fired'
    seq, _, stamp = _report_fields(msg, what, (CycleStatusMsg.OUTCOME_FIRED,))
    if not math.isnan(msg.release_speed):
        raise ValueError(f'{what} release_speed {msg.release_speed!r} is not NaN: a fired '
                         'notice carries no speed (its cycle_status does)')
    session, tag = _signature(msg, what)
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

    def cycle_status(self, seq, ok, reason, sensor, stamp_ns, hardware_id, release_speed=None):
        """Build a signed ``cycle_status`` (:func:`cycle_status` with ``session`` and ``mac``)."""
        msg = cycle_status(seq, ok, reason, sensor, stamp_ns, hardware_id, release_speed)
        return self._signed(msg, auth.CYCLE_LABEL, auth.cycle_fields(
            self.node, self.session, seq, stamp_ns, msg.outcome, _SENSOR_TEXT[sensor],
            msg.reason, release_speed))

    def cycle_fired(self, seq, stamp_ns, hardware_id):
        """Build a signed ``cycle_fired``: cycle ``seq`` is being fired (before the arm moves)."""
        msg = CycleStatusMsg(seq=int(seq), stamp=time_msg(stamp_ns),
                             outcome=CycleStatusMsg.OUTCOME_FIRED,
                             sensor=CycleStatusMsg.SENSOR_NONE,
                             hardware_id=_wire_text(hardware_id), release_speed=math.nan)
        return self._signed(msg, auth.FIRED_LABEL,
                            auth.fired_fields(self.node, self.session, seq, stamp_ns))

    def _signed(self, msg, label, fields):
        msg.session = self.session
        msg.mac = list(auth.mac(self.key, label, fields))
        return msg
