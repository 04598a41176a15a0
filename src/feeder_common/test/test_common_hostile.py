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
Issue 20 (attack 3, deliverable 5) at the parsers: hostile input is a ValueError, never more.

The cycle reports (``cycle_status``, ``cycle_fired``: feeder_interfaces/CycleStatus) and
``predicted/state`` (PredictedState) are typed (issue 22), but a node on the graph can still
publish any value each field holds: a seq up to 2**64 - 1, a Time before 1970 or with nanosec
up to 2**32 - 1, any int8 sensor code, any outcome, texts, session and MAC. Each parser of
feeder_common.messages takes exactly what its builder writes: for any such message (drawn
here, sent through the wire as a subscriber receives it) it returns a record that its builder
writes back to the same message, or raises ValueError; never another exception. Every rule a
parser enforces has its own test, with the words of the refusal.
"""

import copy
import math
import struct

from builtin_interfaces.msg import Time
from feeder_common import auth, messages
from feeder_interfaces.msg import CycleStatus as CycleStatusMsg
from feeder_interfaces.msg import PredictedState as PredictedStateMsg
# tests/ (test support in no package) is on sys.path by pytest.ini
from hostile_messages import (ranges, REPORT_FIELDS, STATE_FIELDS, TIMES, verdicts,
                              wire)
from hypothesis import example, given, settings, strategies as st
import pytest

SETTINGS = settings(max_examples=400, deadline=None)
KEY = bytes(range(32))
MONITOR = '/feeder/feeder_monitor'
DRIVER = '/feeder/feeder_driver'
SESSION = 'ab12cd34ef56ab78'
SIGNER = messages.CycleSigner(KEY, DRIVER, SESSION)
STAMP = 1795362335_204302396
NS = messages.NS
MAX_SEQ = messages.MAX_SEQ
MAX_TEXT = messages.MAX_TEXT

# ---- strategies: any value each field holds (tests/hostile_messages.py), builders' often --

BUILT_TEXT = st.one_of(st.text(max_size=30), st.text(max_size=3).map(lambda t: t * 2000))


@st.composite
def built_reports(draw):
    """Draw a cycle report a builder writes: unsigned or signed cycle_status, cycle_fired."""
    kind = draw(st.sampled_from(('unsigned', 'signed', 'fired')))
    seq, stamp = draw(st.integers(0, MAX_SEQ)), draw(st.integers(0, messages.MAX_STAMP_NS))
    hardware_id = draw(BUILT_TEXT)
    if kind == 'fired':
        return SIGNER.cycle_fired(seq, stamp, hardware_id)
    ok = draw(st.booleans())
    build = messages.cycle_status if kind == 'unsigned' else SIGNER.cycle_status
    speed = draw(st.one_of(st.none(), st.floats(1e-3, 1e3)))
    return build(seq, ok, draw(BUILT_TEXT), draw(st.booleans()) if ok else None, stamp,
                 hardware_id, speed)


@st.composite
def built_states(draw):
    """Draw a ``predicted/state`` the builder writes."""
    edge = draw(st.integers(-1, 2**31 - 1))
    lost = edge == PredictedStateMsg.EDGE_LOST
    return messages.predicted_state(
        draw(st.integers(0, MAX_SEQ)), draw(st.none() | st.integers(0, messages.MAX_STAMP_NS)),
        edge, None if lost else draw(st.floats(allow_nan=False, allow_infinity=False)),
        'lost' if lost else draw(st.sampled_from(('jog', 'flip'))))


def _hostile(built, msg_type, fields):
    @st.composite
    def draw_message(draw):
        # A builder's message with up to three fields set to anything (none in some), or a
        # message of which every field is drawn.
        if draw(st.integers(0, 3)) == 0:
            msg, names = msg_type(), list(fields)
        else:
            msg = draw(built)
            names = draw(st.lists(st.sampled_from(sorted(fields)), max_size=3, unique=True))
        for name in names:
            setattr(msg, name, draw(fields[name]))
        return wire(msg)
    return draw_message()


def cycle_reports():
    """Draw any CycleStatus a node can publish, as a subscriber receives it."""
    return _hostile(built_reports(), CycleStatusMsg, REPORT_FIELDS)


def predicted_states():
    """Draw any PredictedState a node can publish, as a subscriber receives it."""
    return _hostile(built_states(), PredictedStateMsg, STATE_FIELDS)


def sent(text):
    """Return ``text`` as the builders send it: NUL as U+FFFD, cut to MAX_TEXT characters."""
    text = text.replace('\x00', '\ufffd')
    return text if len(text) <= MAX_TEXT else text[:MAX_TEXT - 1] + '\u2026'


def same_float(a, b):
    """Whether ``a`` and ``b`` are the same double to the bit, or both NaN."""
    return (math.isnan(a) and math.isnan(b)) or struct.pack('<d', a) == struct.pack('<d', b)


def same_report(a, b):
    """Whether two CycleStatus messages are equal, a NaN release speed equal to a NaN."""
    if not same_float(a.release_speed, b.release_speed):
        return False
    a, b = copy.copy(a), copy.copy(b)
    a.release_speed = b.release_speed = 0.0
    return a == b


def signed_ok(rec, outcome):
    """Whether the MAC of a parsed report verifies (what the monitor's trust checks)."""
    if outcome == CycleStatusMsg.OUTCOME_FIRED:
        return auth.mac_ok(KEY, auth.FIRED_LABEL,
                           auth.fired_fields(DRIVER, rec.session, rec.seq, rec.stamp_ns),
                           rec.mac)
    return auth.mac_ok(KEY, auth.CYCLE_LABEL, auth.cycle_fields(
        DRIVER, rec.session, rec.seq, rec.stamp_ns, outcome,
        {True: '1', False: '0', None: 'none'}[rec.sensor], rec.reason, rec.release_speed),
        rec.mac)


# ---- each rule of the parsers, broken alone ------------------------------------------------

def report(kind, **change):
    """Return a signed report of outcome ``kind`` (fired, completed, failed) with ``change``."""
    if kind == 'fired':
        msg = SIGNER.cycle_fired(7, STAMP, 'emu 1.0')
    else:
        ok = kind == 'completed'
        msg = SIGNER.cycle_status(7, ok, 'no ACK', True if ok else None, STAMP, 'emu 1.0',
                                  6.25)
    for name, value in change.items():
        setattr(msg, name, value)
    return wire(msg)


def parser_of(outcome):
    return messages.parse_cycle_fired if outcome == 'fired' else messages.parse_cycle_status


@pytest.mark.parametrize('outcome', ['completed', 'failed', 'fired'])
def test_the_builders_reports_parse_and_verify(outcome):
    # The reports every rule below breaks one field of, unbroken: read and authentic.
    rec = parser_of(outcome)(report(outcome))
    assert (rec.seq, rec.stamp_ns, rec.session) == (7, STAMP, SESSION)
    assert signed_ok(rec, outcome)


@pytest.mark.parametrize('outcome, parse, words', [
    ('fired', messages.parse_cycle_status,
     "cycle_status outcome 'fired' is not 'completed' or 'failed'"),
    ('completed', messages.parse_cycle_fired, "cycle_fired outcome 'completed' is not 'fired'"),
    ('failed', messages.parse_cycle_fired, "cycle_fired outcome 'failed' is not 'fired'")])
def test_a_report_of_the_other_topic_is_refused(outcome, parse, words):
    with pytest.raises(ValueError, match=words):
        parse(report(outcome))


@pytest.mark.parametrize('outcome', ['completed', 'failed', 'fired'])
@pytest.mark.parametrize('value', ['Completed', 'completed ', 'FIRED', ' failed', '', 'ok',
                                   'x' * 5000])
def test_an_outcome_no_builder_writes_is_refused(outcome, value):
    with pytest.raises(ValueError, match=r'outcome .* is not'):
        parser_of(outcome)(report(outcome, outcome=value))


@pytest.mark.parametrize('outcome', ['completed', 'failed', 'fired'])
@pytest.mark.parametrize('code', [2, -2, 127, -128])
def test_a_sensor_code_outside_none_clear_detected_is_refused(outcome, code):
    with pytest.raises(ValueError, match=f'sensor {code} is not SENSOR_NONE'):
        parser_of(outcome)(report(outcome, sensor=code))


@pytest.mark.parametrize('outcome, code', [('completed', -1), ('failed', 0), ('failed', 1),
                                           ('fired', 0), ('fired', 1)])
def test_a_sensor_code_that_does_not_go_with_the_outcome_is_refused(outcome, code):
    with pytest.raises(ValueError, match=f'{outcome} with sensor {code}: a completed cycle has a '
                                         'bit'):
        parser_of(outcome)(report(outcome, sensor=code))


@pytest.mark.parametrize('outcome', ['completed', 'failed', 'fired'])
@pytest.mark.parametrize('seq', [MAX_SEQ + 1, 2**64 - 1])
def test_a_seq_beyond_2_63_is_refused(outcome, seq):
    with pytest.raises(ValueError, match=f'seq {seq} is beyond {MAX_SEQ}'):
        parser_of(outcome)(report(outcome, seq=seq))


@pytest.mark.parametrize('outcome', ['completed', 'failed', 'fired'])
@pytest.mark.parametrize('sec, nanosec', [(-1, 0), (-2**31, 0), (0, NS), (5, 2**32 - 1),
                                          (-1, 2**32 - 1)])
def test_a_stamp_before_1970_or_with_nanosec_past_1e9_is_refused(outcome, sec, nanosec):
    with pytest.raises(ValueError,
                       match=f'stamp sec={sec} nanosec={nanosec} is not a time from 1970 on'):
        parser_of(outcome)(report(outcome, stamp=Time(sec=sec, nanosec=nanosec)))


@pytest.mark.parametrize('outcome', ['completed', 'fired'])
@pytest.mark.parametrize('reason', ['no ACK', ' ', 'x' * 5000])
def test_a_reason_on_a_report_that_did_not_fail_is_refused(outcome, reason):
    with pytest.raises(ValueError, match=f'{outcome} with a reason: only a failed cycle has one'):
        parser_of(outcome)(report(outcome, reason=reason))


@pytest.mark.parametrize('outcome, field', [('failed', 'reason'), ('completed', 'hardware_id'),
                                            ('failed', 'hardware_id'), ('fired', 'hardware_id')])
@pytest.mark.parametrize('length', [MAX_TEXT + 1, 10**6])
def test_a_text_longer_than_max_text_is_refused_with_its_length(outcome, field, length):
    at_most = parser_of(outcome)(report(outcome, **{field: '\u00e9' * MAX_TEXT}))
    assert at_most.seq == 7      # MAX_TEXT characters (of two bytes each) are still taken
    with pytest.raises(ValueError, match=f'{field} is {length} characters long; at most '
                                         f'{MAX_TEXT} are accepted'):
        parser_of(outcome)(report(outcome, **{field: 'r' * length}))


@pytest.mark.parametrize('outcome', ['completed', 'failed', 'fired'])
@pytest.mark.parametrize('session', ['AB12', 'ab12 ', 'g', '\u0661\u0662', '0x12', 'a' * 65,
                                     '-1'])
def test_a_session_not_of_up_to_64_lowercase_hex_digits_is_refused(outcome, session):
    with pytest.raises(ValueError, match='session .* is not up to 64 lowercase hex digits'):
        parser_of(outcome)(report(outcome, session=session))


@pytest.mark.parametrize('outcome', ['completed', 'failed', 'fired'])
@pytest.mark.parametrize('size', [1, 16, 31, 33, 64])
def test_a_mac_of_neither_0_nor_32_bytes_is_refused(outcome, size):
    with pytest.raises(ValueError, match=f'mac of {size} bytes; a MAC has 32'):
        parser_of(outcome)(report(outcome, mac=[7] * size))


@pytest.mark.parametrize('outcome', ['completed', 'failed', 'fired'])
def test_the_boundaries_of_every_rule_are_still_taken(outcome):
    # The largest seq, the last nanosecond a Time holds, MAX_TEXT characters, a session of 64
    # hex digits, no session and no MAC (unsigned: the monitor then says so) all parse.
    texts = {'hardware_id': 'h' * MAX_TEXT}
    if outcome == 'failed':
        texts['reason'] = 'r' * MAX_TEXT
    msg = report(outcome, seq=MAX_SEQ, stamp=Time(sec=2**31 - 1, nanosec=NS - 1), **texts)
    rec = parser_of(outcome)(msg)
    assert (rec.seq, rec.stamp_ns) == (MAX_SEQ, messages.MAX_STAMP_NS)
    assert parser_of(outcome)(report(outcome, stamp=Time())).stamp_ns == 0
    assert parser_of(outcome)(report(outcome, session='f' * 64)).session == 'f' * 64
    unsigned = parser_of(outcome)(report(outcome, session='', mac=[]))
    assert (unsigned.session, unsigned.mac) == ('', b'')


@pytest.mark.parametrize('speed', [0.0, -1.0, math.inf, -math.inf, -0.0])
def test_a_release_speed_no_builder_writes_is_refused(speed):
    with pytest.raises(ValueError, match='release speed .* is not a finite speed > 0'):
        messages.parse_cycle_status(report('completed', release_speed=speed))
    with pytest.raises(ValueError, match='is not a finite speed > 0'):
        SIGNER.cycle_status(7, True, '', True, STAMP, 'emu', speed)


def test_a_changed_report_no_longer_verifies():
    # The parsers read the signature; whether it signs the fields is the monitor's check.
    for outcome, change in (('completed', {'sensor': 0}), ('completed', {'seq': 8}),
                            ('failed', {'reason': 'other'}), ('fired', {'seq': 8}),
                            ('fired', {'stamp': Time(sec=1795362335, nanosec=0)}),
                            ('completed', {'session': 'ab12'}),
                            ('completed', {'release_speed': 6.5}),
                            ('failed', {'release_speed': math.nan})):
        rec = parser_of(outcome)(report(outcome, **change))
        assert not signed_ok(rec, outcome), (outcome, change)


def state(**change):
    """Return a ``predicted/state`` of the builder (edge 1 at 0.25 m, jog) with ``change``."""
    msg = messages.predicted_state(5, STAMP, 1, 0.25, 'jog')
    for name, value in change.items():
        setattr(msg, name, value)
    return wire(msg)


def test_the_builders_predicted_states_parse():
    assert messages.parse_predicted_state(state()) == messages.PredictedState(
        5, STAMP, 1, 0.25, 'jog')
    lost = messages.parse_predicted_state(state(edge=-1, r=math.nan, throw_kind='lost'))
    assert (lost.edge, lost.R, lost.throw_kind) == (-1, None, 'lost')
    far = messages.parse_predicted_state(state(edge=2**31 - 1, seq=MAX_SEQ, stamp=Time()))
    assert (far.edge, far.seq, far.stamp_ns) == (2**31 - 1, MAX_SEQ, None)   # zero: no stamp


@pytest.mark.parametrize('edge', [-2, -3, -2**31])
def test_a_predicted_edge_below_edge_lost_is_refused(edge):
    with pytest.raises(ValueError, match=f'predicted/state edge {edge} is neither EDGE_LOST'):
        messages.parse_predicted_state(state(edge=edge))


@pytest.mark.parametrize('r', [math.inf, -math.inf])
def test_an_infinite_predicted_r_is_refused(r):
    with pytest.raises(ValueError, match=f'predicted/state r {r!r} is not a finite contact'):
        messages.parse_predicted_state(state(r=r))


@pytest.mark.parametrize('kind', ['Jog', 'jog ', 'hop', '', 'none', 'x' * 5000])
def test_an_unknown_throw_kind_is_refused(kind):
    with pytest.raises(ValueError, match=r'predicted/state throw_kind .* is not one of '
                                         'jog, flip, lost'):
        messages.parse_predicted_state(state(throw_kind=kind))


@pytest.mark.parametrize('edge, r, kind', [
    (-1, 0.25, 'lost'), (-1, math.nan, 'jog'), (-1, 0.25, 'flip'), (1, math.nan, 'lost'),
    (1, math.nan, 'jog'), (1, 0.25, 'lost'), (0, math.nan, 'flip')])
def test_edge_lost_r_nan_and_kind_lost_come_only_together(edge, r, kind):
    with pytest.raises(ValueError, match='edge -1, r NaN and throw_kind lost go together'):
        messages.parse_predicted_state(state(edge=edge, r=r, throw_kind=kind))


@pytest.mark.parametrize('change, words', [
    ({'seq': MAX_SEQ + 1}, f'predicted/state seq {MAX_SEQ + 1} is beyond'),
    ({'seq': 2**64 - 1}, f'predicted/state seq {2**64 - 1} is beyond'),
    ({'stamp': Time(sec=-1)}, 'predicted/state: stamp sec=-1 nanosec=0 is not a time'),
    ({'stamp': Time(sec=3, nanosec=NS)}, 'predicted/state: stamp sec=3 nanosec=1000000000')])
def test_a_predicted_seq_or_stamp_no_builder_writes_is_refused(change, words):
    with pytest.raises(ValueError, match=words):
        messages.parse_predicted_state(state(**change))


# ---- other messages' rules -----------------------------------------------------------------

def test_a_verdict_changed_in_any_field_is_not_authentic():
    good = messages.signed_verdict(KEY, MONITOR, 'ab12', 7, 5, True, 'ready', '', 10**18)
    assert messages.check_verdict(good, KEY, MONITOR, 10**18).ready_now
    for field, value in (('seq', 8), ('ready', False), ('state', 'tracking'), ('anomaly', 'x'),
                         ('session', 'ab13')):
        msg = messages.signed_verdict(KEY, MONITOR, 'ab12', 7, 5, True, 'ready', '', 10**18)
        setattr(msg, field, value)
        c = messages.check_verdict(msg, KEY, MONITOR, 10**18)
        assert not c.authentic and not c.ready_now, field
    for stamp in ('stamp', 'sent'):
        msg = messages.signed_verdict(KEY, MONITOR, 'ab12', 7, 5, True, 'ready', '', 10**18)
        getattr(msg, stamp).nanosec += 1
        assert not messages.check_verdict(msg, KEY, MONITOR, 10**18).authentic, stamp


@pytest.mark.parametrize('sec, nanosec', [(-1, 0), (0, 10**9), (5, 2**32 - 1), (-2**31, 0)])
def test_a_time_no_clock_writes_is_a_value_error(sec, nanosec):
    msg = messages.proximity(0, True, 0.02)
    msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
    with pytest.raises(ValueError, match='nanosec'):
        messages.time_ns(msg.header.stamp)


@pytest.mark.parametrize('lo, hi', [(math.nan, 0.02), (0.02, math.inf), (-1.0, 0.02),
                                    (0.03, 0.02), (-math.inf, math.inf)])
def test_a_finite_reading_with_unusable_limits_is_a_value_error(lo, hi):
    msg = messages.proximity(0, True, 0.02)
    msg.range, msg.min_range, msg.max_range = 0.02, lo, hi
    with pytest.raises(ValueError, match='limits'):
        messages.proximity_detected(msg)


# ---- properties: any message ---------------------------------------------------------------

@SETTINGS
@given(cycle_reports())
@example(report('completed', seq=2**64 - 1))
@example(report('completed', stamp=Time(sec=-2**31, nanosec=2**32 - 1)))
@example(report('failed', reason='r' * (MAX_TEXT + 1), session='AB'))
def test_any_cycle_status_parses_to_what_the_builder_writes_or_is_a_value_error(msg):
    try:
        rec = messages.parse_cycle_status(msg)
    except ValueError:
        return
    again = messages.cycle_status(rec.seq, rec.ok, rec.reason, rec.sensor, rec.stamp_ns,
                                  rec.hardware_id, rec.release_speed)
    again.session, again.mac = rec.session, list(rec.mac)
    assert same_report(again, msg)
    assert 0 <= rec.seq <= MAX_SEQ and 0 <= rec.stamp_ns <= messages.MAX_STAMP_NS


@SETTINGS
@given(cycle_reports())
@example(report('fired', seq=2**64 - 1))
@example(report('fired', sensor=1))
def test_any_cycle_fired_parses_to_what_the_builder_writes_or_is_a_value_error(msg):
    try:
        rec = messages.parse_cycle_fired(msg)
    except ValueError:
        return
    again = SIGNER.cycle_fired(rec.seq, rec.stamp_ns, msg.hardware_id)
    again.session, again.mac = rec.session, list(rec.mac)
    assert same_report(again, msg)
    assert 0 <= rec.seq <= MAX_SEQ and 0 <= rec.stamp_ns <= messages.MAX_STAMP_NS


@SETTINGS
@given(predicted_states())
@example(state(r=math.inf))
@example(state(edge=-1, r=math.nan, throw_kind='lost', stamp=Time(nanosec=2**32 - 1)))
def test_any_predicted_state_parses_to_what_the_builder_writes_or_is_a_value_error(msg):
    try:
        s = messages.parse_predicted_state(msg)
    except ValueError:
        return
    again = messages.predicted_state(s.seq, s.stamp_ns, s.edge, s.R, s.throw_kind)
    assert (again.seq, again.stamp, again.edge, again.throw_kind) == \
        (msg.seq, msg.stamp, msg.edge, msg.throw_kind)
    assert same_float(again.r, msg.r)
    assert s.R is None or math.isfinite(s.R)
    assert s.throw_kind in messages.THROW_KINDS and s.edge >= PredictedStateMsg.EDGE_LOST


@SETTINGS
@given(verdicts())
def test_any_verdict_is_checked_without_an_exception_and_never_ready_unsigned(msg):
    # A consumer's one call: whatever arrives, an answer; ready only when our monitor signed.
    c = messages.check_verdict(msg, KEY, MONITOR, 10**18)
    assert isinstance(c.ready_now, bool) and isinstance(c.reason, str)
    assert not c.authentic and not c.ready_now


@SETTINGS
@given(ranges())
def test_any_range_is_a_bit_none_or_a_value_error(msg):
    try:
        bit = messages.proximity_detected(msg)
    except ValueError:
        return
    assert bit in (True, False, None)
    assert (bit is None) == math.isnan(msg.range)


@SETTINGS
@given(TIMES)
def test_any_time_is_nanoseconds_or_a_value_error(stamp):
    try:
        ns = messages.time_ns(stamp)
    except ValueError:
        assert stamp.sec < 0 or stamp.nanosec >= messages.NS
        return
    assert 0 <= ns <= messages.MAX_STAMP_NS


# ---- and what the builders write still reads back ------------------------------------------

def test_a_builder_cuts_a_text_too_long_for_the_parser():
    # A failed cycle's reason goes into the verdict's anomaly; neither may be unreadable.
    reason = 'r' * (MAX_TEXT + 10)
    st = messages.parse_cycle_status(
        wire(messages.cycle_status(3, False, reason, None, 0, 'x' * 10**5)))
    assert len(st.reason) == len(st.hardware_id) == MAX_TEXT
    assert st.reason.startswith('r' * 100) and st.reason.endswith('\u2026')
    v = messages.signed_verdict(KEY, MONITOR, 'ab12', 3, 0, False, 'anomaly',
                                f'cycle 3 failed: {st.reason}', 10**18)
    assert len(v.anomaly) == MAX_TEXT and v.anomaly.startswith('cycle 3 failed: r')
    assert messages.check_verdict(wire(v), KEY, MONITOR, 10**18).authentic
    fired = messages.parse_cycle_fired(wire(SIGNER.cycle_fired(3, 0, 'x' * 10**5)))
    assert fired.seq == 3


@SETTINGS
@given(seq=st.integers(0, MAX_SEQ), ok=st.booleans(), bit=st.booleans(),
       stamp=st.integers(0, messages.MAX_STAMP_NS), reason=BUILT_TEXT, hardware_id=BUILT_TEXT,
       signed=st.booleans(),
       speed=st.one_of(st.none(), st.floats(min_value=5e-324, allow_infinity=False)))
def test_every_cycle_status_the_builder_writes_reads_back(seq, ok, bit, stamp, reason,
                                                          hardware_id, signed, speed):
    sensor = bit if ok else None
    build = SIGNER.cycle_status if signed else messages.cycle_status
    rec = messages.parse_cycle_status(wire(build(seq, ok, reason, sensor, stamp, hardware_id,
                                                 speed)))
    assert rec == messages.CycleStatus(
        seq, ok, sensor, stamp, '' if ok else sent(reason), sent(hardware_id),
        SESSION if signed else '', rec.mac if signed else b'', speed)
    outcome = 'completed' if ok else 'failed'
    assert signed_ok(rec, outcome) == signed      # the MAC signs what the parser read


@SETTINGS
@given(seq=st.integers(0, MAX_SEQ), stamp=st.integers(0, messages.MAX_STAMP_NS),
       hardware_id=BUILT_TEXT)
def test_every_cycle_fired_the_builder_writes_reads_back(seq, stamp, hardware_id):
    rec = messages.parse_cycle_fired(wire(SIGNER.cycle_fired(seq, stamp, hardware_id)))
    assert (rec.seq, rec.stamp_ns, rec.session) == (seq, stamp, SESSION)
    assert signed_ok(rec, 'fired')
    with pytest.raises(ValueError, match='outcome'):        # and never as a cycle_status
        messages.parse_cycle_status(wire(SIGNER.cycle_fired(seq, stamp, hardware_id)))


@SETTINGS
@given(seq=st.integers(0, MAX_SEQ),
       stamp=st.one_of(st.none(), st.integers(0, messages.MAX_STAMP_NS)),
       edge=st.one_of(st.just(-1), st.integers(0, 2**31 - 1)),
       R=st.floats(allow_nan=False, allow_infinity=False),
       kind=st.sampled_from(['jog', 'flip']), ready=st.booleans(),
       verdict_state=st.text(min_size=1, max_size=30), anomaly=st.text(max_size=30))
def test_every_prediction_and_verdict_the_builders_write_reads_back(
        seq, stamp, edge, R, kind, ready, verdict_state, anomaly):
    lost = edge == -1
    p = wire(messages.predicted_state(seq, stamp, edge, None if lost else R,
                                      'lost' if lost else kind))
    assert messages.parse_predicted_state(p) == messages.PredictedState(
        seq, stamp or None, edge, None if lost else R, 'lost' if lost else kind)
    v = wire(messages.signed_verdict(KEY, MONITOR, 'ab12', seq, stamp, ready, verdict_state,
                                     anomaly, messages.MAX_STAMP_NS))
    c = messages.check_verdict(v, KEY, MONITOR, messages.MAX_STAMP_NS)
    assert c.authentic and (c.seq, c.stamp_ns) == (seq, stamp or None)     # 0: no stamp
    # Texts as the wire carries them: a NUL is sent (and signed) as U+FFFD.
    assert (v.ready, v.state, v.anomaly) == \
        (ready, verdict_state.replace('\x00', '\ufffd'), anomaly.replace('\x00', '\ufffd'))
