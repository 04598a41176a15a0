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

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from feeder_common import frames, messages, stamps
from feeder_common.params import check_scene, ParamSpec
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

def test_stamp_text_is_exact_to_the_nanosecond():
    ns = 1795362335_204302396
    assert stamps.stamp_text(ns) == '1795362335.204302396'
    assert stamps.parse_stamp_text('1795362335.204302396') == ns
    assert float('1795362335.204302396') * 1e9 != ns     # what a float parser would lose
    assert stamps.parse_stamp_text('3.000000007') == 3_000_000_007
    # only what stamp_text writes (test_common_hostile.py has the rest)
    for bad in ('', '-1.5', '1.2e3', 'x', '1.x', '12.5', '7'):
        with pytest.raises(ValueError):
            stamps.parse_stamp_text(bad)


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
    msg = messages.cycle_status(42, True, 'completed', True, 1795362335_204302396, 'sim')
    assert msg.level == DiagnosticStatus.OK and msg.name == 'cycle'
    assert {kv.key: kv.value for kv in msg.values} == {
        'seq': '42', 'sensor': '1', 'stamp': '1795362335.204302396'}
    st = messages.parse_cycle_status(msg)
    assert (st.seq, st.ok, st.sensor, st.stamp_ns, st.hardware_id) == \
        (42, True, True, 1795362335_204302396, 'sim')
    failed = messages.parse_cycle_status(
        messages.cycle_status(43, False, 'no ACK', None, 5, '/dev/ttyACM0'))
    assert (failed.ok, failed.sensor, failed.message) == (False, None, 'no ACK')


@pytest.mark.parametrize('values, words', [
    ({}, 'without a seq'), ({'seq': 'x'}, "seq 'x' is not a non-negative integer"),
    ({'seq': '-3'}, "seq '-3' is not a non-negative integer")])
def test_a_cycle_status_without_a_usable_seq_is_refused(values, words):
    values = {'sensor': '1', 'stamp': '1.000000000', **values}
    msg = DiagnosticStatus(name='cycle',
                           values=[KeyValue(key=k, value=v) for k, v in values.items()])
    with pytest.raises(ValueError, match=words):
        messages.parse_cycle_status(msg)


def test_a_bad_stamp_is_a_bad_status():
    # The stamp pairs the status with its proximity: a status without a usable one is refused.
    msg = DiagnosticStatus(name='cycle', values=[KeyValue(key='seq', value='1'),
                                                 KeyValue(key='sensor', value='1'),
                                                 KeyValue(key='stamp', value='soon')])
    with pytest.raises(ValueError, match="stamp 'soon' is not <sec>.<9 digits>"):
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


def test_edge_verdict_round_trip():
    msg = messages.edge_verdict(7, 1795362335_204302396, True, 'ready', None, 'triangle')
    assert msg.name == 'edge1_verdict' and msg.level == DiagnosticStatus.OK
    v = messages.parse_edge_verdict(msg)
    assert (v.seq, v.stamp_ns, v.ready, v.state, v.anomaly) == \
        (7, 1795362335_204302396, True, 'ready', '')
    bad = messages.parse_edge_verdict(messages.edge_verdict(8, None, False, 'anomaly', 'why'))
    assert (bad.stamp_ns, bad.ready, bad.anomaly) == (None, False, 'why')
    with pytest.raises(ValueError, match='without a stamp, ready, state value'):
        messages.parse_edge_verdict(DiagnosticStatus(name='edge1_verdict',
                                                     values=[KeyValue(key='seq', value='1')]))


def test_predicted_state_round_trip_keeps_R_to_the_bit():
    R = 0.1 + 0.2       # a float whose short decimal forms read back as another float
    msg = messages.predicted_state(12, 1795362335_204302396, 1, R, 'flip')
    assert msg.name == 'predicted_state' and msg.level == DiagnosticStatus.OK
    s = messages.parse_predicted_state(msg)
    assert (s.seq, s.stamp_ns, s.edge, s.R, s.throw_kind) == \
        (12, 1795362335_204302396, 1, R, 'flip')
    lost = messages.parse_predicted_state(messages.predicted_state(13, None, -1, None, 'lost'))
    assert (lost.stamp_ns, lost.edge, lost.R, lost.throw_kind) == (None, -1, None, 'lost')
    with pytest.raises(ValueError, match='without a stamp, edge, R, throw_kind value'):
        messages.parse_predicted_state(DiagnosticStatus(
            name='predicted_state', values=[KeyValue(key='seq', value='1')]))


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


def test_the_publisher_guard_trusts_one_node_and_its_writer(domain_id):
    import rclpy
    from rclpy.context import Context
    from feeder_common.graph import PublisherGuard
    ctx = Context()
    rclpy.init(context=ctx, domain_id=domain_id)
    try:
        me = rclpy.create_node('feeder_monitor', namespace='/feeder', context=ctx)
        driver = rclpy.create_node('feeder_driver', namespace='/feeder', context=ctx)
        guard = PublisherGuard(me, ('/feeder/cycle_status',), '/feeder/feeder_driver')
        assert 'no publisher on /feeder/cycle_status' in guard.check()
        pub = driver.create_publisher(DiagnosticStatus, 'cycle_status', 10)
        assert guard.check() is None and guard.crowded() is None
        forger = rclpy.create_node('forger', context=ctx)
        forged = forger.create_publisher(DiagnosticStatus, '/feeder/cycle_status', 10)
        assert '2 publishers on /feeder/cycle_status' in guard.crowded()
        assert '/forger besides or instead of /feeder/feeder_driver' in guard.check()
        forger.destroy_publisher(forged)
        assert guard.check() is None
        # The driver's writer replaced (a restart, or a node that took its name): said once.
        driver.destroy_publisher(pub)
        driver.create_publisher(DiagnosticStatus, 'cycle_status', 10)
        assert 'changed (GID' in guard.check()
        assert guard.check() is None
    finally:
        rclpy.shutdown(context=ctx)
