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

"""The contract as code: parameter specs, stamps, frames, message builders and parsers."""

import math

from builtin_interfaces.msg import Time
from feeder_common import frames, messages
from feeder_common.params import check_scene, ParamSpec
from feeder_interfaces.msg import CycleStatus, PredictedState
import pytest


# ---- parameter specs ----------------------------------------------------------------------

DOUBLE = ParamSpec('cycle_period', 1.0, 'd', minimum=0.005, maximum=60.0)
INT = ParamSpec('warmup_cycles', -1, 'i', minimum=-1, maximum=1000)
STRING = ParamSpec('scene', '', 's')
BOOL = ParamSpec('autostart', True, 'b')


@pytest.mark.parametrize('spec, given, expected', [
    (DOUBLE, 1, 1.0), (DOUBLE, 2.5, 2.5), (INT, 3, 3), (STRING, 'x.yaml', 'x.yaml'),
    (BOOL, False, False)])
def test_a_value_of_the_type_or_an_integer_for_a_double_is_taken(spec, given, expected):
    value, reason = spec.validate(given)
    assert reason is None and value == expected and type(value) is type(expected)


@pytest.mark.parametrize('spec, given, words', [
    (DOUBLE, 'abc', ('cycle_period must be a double, got string', 'write a number')),
    (DOUBLE, True, ('must be a double, got bool',)),
    (INT, 1.5, ('warmup_cycles must be an integer, got double 1.5',)),
    (INT, 2.0, ('must be an integer', 'write 2')),
    (STRING, 5, ('scene must be a string, got integer 5', "-p scene:=\"'5'\"")),
    (BOOL, 1, ('autostart must be a bool', 'true or false')),
    (DOUBLE, 0.001, ('cycle_period = 0.001 is outside [0.005, 60.0]',)),
    (DOUBLE, math.nan, ('must be finite',)),
    (INT, -2, ('outside [-1, 1000]',)),
])
def test_every_other_mismatch_is_one_line_naming_the_fix(spec, given, words):
    value, reason = spec.validate(given)
    assert value is None and '\n' not in reason
    for w in words:
        assert w in reason, reason


def test_choices_and_one_sided_ranges():
    baud = ParamSpec('baud_rate', 115200, 'b', choices=(9600, 115200))
    assert 'not one of the allowed values: 9600, 115200' in baud.check(1234)
    low = ParamSpec('x', 1.0, 'x', minimum=0.0)
    assert 'below the minimum 0.0' in low.check(-1.0)
    assert low.check(1e9) is None


def test_check_scene_reports_the_loaders_reason(tmp_path):
    def loader(path):
        if path.endswith('bad.yaml'):
            raise ValueError('bogus: unknown key')
        open(path).close()

    assert 'not set' in check_scene('', loader)
    assert 'cannot read' in check_scene(str(tmp_path / 'missing.yaml'), loader)
    assert check_scene(str(tmp_path / 'bad.yaml'), loader) == 'scene: bogus: unknown key'
    (tmp_path / 'ok.yaml').write_text('x')
    assert check_scene(str(tmp_path / 'ok.yaml'), loader) is None


# ---- stamps -------------------------------------------------------------------------------

def test_a_stamp_is_integer_nanoseconds_within_what_a_time_holds():
    ns = 1795362335_204302396
    assert messages.time_ns(messages.time_msg(ns)) == ns
    assert float(ns) != ns          # what a float would lose
    top = Time(sec=2**31 - 1, nanosec=messages.NS - 1)    # the last nanosecond a Time holds
    assert messages.time_ns(top) == messages.MAX_STAMP_NS
    assert messages.time_msg(messages.MAX_STAMP_NS) == top
    for outside in (Time(sec=-1, nanosec=0), Time(sec=0, nanosec=messages.NS)):
        with pytest.raises(ValueError, match='not a time from 1970 on'):
            messages.time_ns(outside)


# ---- frames (REP 103) ---------------------------------------------------------------------

def _rotate(q, v):
    """Rotate v by the unit quaternion q = (x, y, z, w)."""
    x, y, z, w = q
    u = (x, y, z)

    def cross(a, b):
        return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])

    t = tuple(2 * c for c in cross(u, v))
    c2 = cross(u, t)
    return tuple(v[i] + w * t[i] + c2[i] for i in range(3))


def test_the_plane_is_upright_in_feeder_base():
    assert frames.plane_point(0.2, 0.05) == (0.2, 0.0, 0.05)       # F's y is up: base z
    assert frames.plane_scale(0.4, 0.004, 0.01) == (0.4, 0.01, 0.004)


@pytest.mark.parametrize('angle', [0.0, 0.3, -1.2, math.pi / 2, 3.0])
def test_a_rotation_in_the_plane_maps_plane_points_like_the_library(angle):
    # The library turns a plane vector (x, y) counterclockwise by angle (about z_F).
    q = frames.plane_quaternion(angle)
    assert math.isclose(sum(c * c for c in q), 1.0)
    for x, y in ((1.0, 0.0), (0.0, 1.0), (0.3, -0.7)):
        c, s = math.cos(angle), math.sin(angle)
        expected = frames.plane_point(c * x - s * y, s * x + c * y)
        got = _rotate(q, frames.plane_point(x, y))
        assert got == pytest.approx(expected, abs=1e-12)


def test_the_arm_axis_turns_the_tip_up_for_a_positive_angle():
    # A small positive rotation about the arm axis lifts a point on the arm (x > 0) in z.
    angle = 0.1
    half = angle / 2
    ax = frames.ARM_AXIS
    q = (ax[0] * math.sin(half), ax[1] * math.sin(half), ax[2] * math.sin(half),
         math.cos(half))
    tip = _rotate(q, (1.0, 0.0, 0.0))
    assert tip[2] == pytest.approx(math.sin(angle)) and tip[1] == pytest.approx(0.0)


# ---- messages -----------------------------------------------------------------------------

def test_cycle_status_round_trip():
    msg = messages.cycle_status(42, True, 'ignored: only a failed cycle has a reason', True,
                                1795362335_204302396, 'sim')
    assert (msg.seq, msg.stamp.sec, msg.stamp.nanosec, msg.outcome, msg.sensor, msg.reason,
            msg.hardware_id, msg.session, list(msg.mac)) == \
        (42, 1795362335, 204302396, CycleStatus.OUTCOME_COMPLETED, CycleStatus.SENSOR_DETECTED,
         '', 'sim', '', [])
    st = messages.parse_cycle_status(msg)
    assert st == messages.CycleStatus(42, True, True, 1795362335_204302396, '', 'sim')
    clear = messages.parse_cycle_status(messages.cycle_status(44, True, '', False, 6, 'sim'))
    assert (clear.ok, clear.sensor) == (True, False)
    failed = messages.cycle_status(43, False, 'no ACK', None, 5, '/dev/ttyACM0')
    assert (failed.outcome, failed.sensor, failed.reason) == \
        (CycleStatus.OUTCOME_FAILED, CycleStatus.SENSOR_NONE, 'no ACK')
    failed = messages.parse_cycle_status(failed)
    assert (failed.ok, failed.sensor, failed.reason, failed.stamp_ns) == \
        (False, None, 'no ACK', 5)
    for gone in ('parse_seq', 'MAX_EDGE', 'CYCLE_STATUS_NAME'):
        assert not hasattr(messages, gone)


def test_cycle_fired_is_the_same_type_signed_with_its_own_label():
    signer = messages.CycleSigner(b'k' * 32, '/feeder/feeder_driver', 'ab12')
    msg = signer.cycle_fired(9, 1795362335_204302396, 'sim')
    assert (msg.outcome, msg.sensor, msg.reason, msg.hardware_id, msg.session, len(msg.mac)) == \
        (CycleStatus.OUTCOME_FIRED, CycleStatus.SENSOR_NONE, '', 'sim', 'ab12', 32)
    fired = messages.parse_cycle_fired(msg)
    assert (fired.seq, fired.stamp_ns, fired.session, fired.mac) == \
        (9, 1795362335_204302396, 'ab12', bytes(msg.mac))
    status = signer.cycle_status(9, True, '', False, 1795362335_204302396, 'sim')
    assert bytes(status.mac) != fired.mac       # another statement: another MAC
    with pytest.raises(ValueError, match="cycle_status outcome 'fired'"):
        messages.parse_cycle_status(msg)


def test_a_bad_stamp_is_a_bad_status():
    # The stamp pairs the status with its proximity: a status without a usable one is refused.
    msg = messages.cycle_status(1, True, '', True, 5, 'sim')
    msg.stamp = Time(sec=-1, nanosec=0)
    with pytest.raises(ValueError, match='cycle_status: stamp sec=-1 nanosec=0 is not a time'):
        messages.parse_cycle_status(msg)


def test_proximity_is_a_fixed_distance_ranger():
    on = messages.proximity(2_000_000_001, True, 0.02)
    off = messages.proximity(2_000_000_001, False, 0.02)
    assert on.range == -math.inf and off.range == math.inf
    assert on.header.frame_id == frames.SENSOR_FRAME
    assert messages.time_ns(on.header.stamp) == 2_000_000_001
    assert messages.proximity_detected(on) is True and messages.proximity_detected(off) is False
    off.range = math.nan
    assert messages.proximity_detected(off) is None
    off.range = 0.01
    assert messages.proximity_detected(off) is False       # outside [min, max] = 0.02
    off.range = 0.02
    assert messages.proximity_detected(off) is True


def test_joint_state_names_the_arm_joint():
    js = messages.joint_state(7, 0.0, 5.58)
    assert js.name == [frames.ARM_JOINT] and list(js.velocity) == [5.58] and not js.effort


def test_a_consumer_reads_a_signed_verdict_and_checks_it():
    """edge1_ready / edge1_verdict: a Verdict read field by field, and the one-call check."""
    from feeder_interfaces.msg import Verdict
    key, other = b'k' * 32, b'o' * 32
    mon = '/feeder/feeder_monitor'
    sent = 1795362335_300000000
    msg = messages.signed_verdict(key, mon, 'ab12', 7, 1795362335_204302396, True,
                                  Verdict.STATE_READY, '', sent)
    assert (msg.seq, messages.time_ns(msg.stamp), msg.ready, msg.state, msg.anomaly,
            msg.session) == (7, 1795362335_204302396, True, 'ready', '', 'ab12')
    assert messages.time_ns(msg.sent) == sent and len(msg.mac) == 32
    ok = messages.check_verdict(msg, key, mon, sent + 100_000_000)
    assert (ok.ready_now, ok.authentic, ok.seq, ok.stamp_ns, ok.reason) == \
        (True, True, 7, 1795362335_204302396, '')
    assert ok.sent_age_s == pytest.approx(0.1)
    # Another key, another monitor, a stale or a changed message: never ready now.
    assert not messages.check_verdict(msg, other, mon, sent).authentic
    assert not messages.check_verdict(msg, key, '/feeder_2/feeder_monitor', sent).ready_now
    stale = messages.check_verdict(msg, key, mon, sent + 2_000_000_000, max_age_s=1.0)
    assert stale.authentic and not stale.ready_now and 'more than 1 s' in stale.reason
    msg.seq = 8
    assert not messages.check_verdict(msg, key, mon, sent).authentic
    unsigned = Verdict(seq=7, ready=True, state='ready')
    assert messages.check_verdict(unsigned, key, mon, 0).reason == 'unsigned verdict'
    # No cycle judged yet: seq 0, no stamp; an anomaly says why.
    none = messages.signed_verdict(key, mon, 'ab12', 0, None, False, Verdict.STATE_ANOMALY,
                                   'why', sent)
    c = messages.check_verdict(none, key, mon, sent)
    assert (c.authentic, c.ready_now, c.stamp_ns) == (True, False, None)
    assert c.reason == 'not ready: anomaly (why)'
    for gone in ('edge_verdict', 'parse_edge_verdict', 'EdgeVerdict'):
        assert not hasattr(messages, gone)


def test_predicted_state_round_trip_keeps_R_to_the_bit():
    R = 0.1 + 0.2       # a float whose short decimal forms read back as another float
    msg = messages.predicted_state(12, 1795362335_204302396, 1, R, 'flip')
    assert (msg.seq, msg.stamp.sec, msg.stamp.nanosec, msg.edge, msg.r, msg.throw_kind) == \
        (12, 1795362335, 204302396, 1, R, PredictedState.THROW_FLIP)
    s = messages.parse_predicted_state(msg)
    assert (s.seq, s.stamp_ns, s.edge, s.R, s.throw_kind) == \
        (12, 1795362335_204302396, 1, R, 'flip')
    msg = messages.predicted_state(13, None, -1, None, 'lost')
    assert (msg.stamp.sec, msg.stamp.nanosec, msg.edge, math.isnan(msg.r)) == \
        (0, 0, PredictedState.EDGE_LOST, True)
    lost = messages.parse_predicted_state(msg)
    assert (lost.stamp_ns, lost.edge, lost.R, lost.throw_kind) == (None, -1, None, 'lost')
    with pytest.raises(ValueError, match="throw_kind '' is not one of jog, flip, lost"):
        messages.parse_predicted_state(PredictedState(seq=1))     # a default message: no kind


def test_a_string_longer_than_its_bound_is_refused_with_its_length():
    spec = ParamSpec('frame_id', 'feeder_sensor', 'f', max_length=frames.FRAME_ID_MAX_LENGTH)
    assert spec.validate('x' * 256) == ('x' * 256, None)
    value, reason = spec.validate('x' * 1_000_000)
    assert value is None
    assert reason == 'frame_id is 1000000 characters long; at most 256 are accepted'


def test_edge1_ready_promises_deadline_and_liveliness():
    from feeder_common import qos
    from rclpy.qos import DurabilityPolicy, LivelinessPolicy
    p = qos.edge1_ready(0.25)
    assert p.depth == 1 and p.durability == DurabilityPolicy.TRANSIENT_LOCAL
    assert p.deadline.nanoseconds == p.liveliness_lease_duration.nanoseconds == 250_000_000
    assert p.liveliness == LivelinessPolicy.AUTOMATIC
    assert qos.EDGE1_VERDICT.depth >= 1000 and qos.DIAGNOSTICS.depth >= 10
