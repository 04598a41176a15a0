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
Issue 20, attack 3 and deliverable 5 at the parsers: hostile input is a ValueError, never more.

Each parser of feeder_common.messages takes exactly the forms its builder writes: for any
message (tests/hostile_messages.py) it returns a value that its builder writes back to the same
texts, or raises ValueError; never another exception, never a number that overflows later.
"""

import math

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from feeder_common import messages, stamps
from hostile_messages import KILLER_STAMP, ranges, statuses, TEXT, TIMES
from hypothesis import example, given, settings, strategies as st
import pytest

SETTINGS = settings(max_examples=400, deadline=None)
GOOD_STAMP = '1795362335.204302396'


def status(name='cycle', level=DiagnosticStatus.OK, message='completed', **values):
    return DiagnosticStatus(name=name, level=level, message=message,
                            values=[KeyValue(key=k, value=v) for k, v in values.items()])


def good_cycle(**change):
    values = {'seq': '42', 'sensor': '1', 'stamp': GOOD_STAMP, **change}
    return status(**{k: v for k, v in values.items() if v is not None})


# ---- the forms issue 20 found accepted, and their neighbours -------------------------------

@pytest.mark.parametrize('seq', [
    ' 12 ', '12 ', '\u0661\u0662', '999999_0', '+12', '-0', '012', '', '1e3', '0x1f', '12\n',
    str(2**63), '9' * 5000, '\uff11\uff12'])
def test_a_seq_the_builder_never_writes_is_refused(seq):
    with pytest.raises(ValueError, match='seq'):
        messages.parse_cycle_status(good_cycle(seq=seq))


@pytest.mark.parametrize('stamp, words', [
    (KILLER_STAMP, 'characters long'),
    (KILLER_STAMP + '.000000000', 'characters long'),
    ('2147483648.000000000', 'beyond what builtin_interfaces/Time holds'),
    ('12.5', '<sec>.<9 digits>'), ('7', '<sec>.<9 digits>'), ('1.0000000001', '<sec>.<9 dig'),
    (' 1.000000000', '<sec>.<9 digits>'), ('-1.000000000', '<sec>.<9 digits>'),
    ('01.000000000', '<sec>.<9 digits>'), ('1_0.000000000', '<sec>.<9 digits>'),
    ('\u0663.000000000', '<sec>.<9 digits>'), ('1.00000000\u0663', '<sec>.<9 digits>'),
    ('1e3.000000000', '<sec>.<9 digits>'), ('soon', '<sec>.<9 digits>'), ('none', '<sec>')])
def test_a_cycle_status_whose_stamp_is_not_the_builders_is_refused(stamp, words):
    with pytest.raises(ValueError, match=words):
        messages.parse_cycle_status(good_cycle(stamp=stamp))


def test_the_killer_stamp_of_issue_20_never_reaches_arithmetic():
    # The monitor computed ns_seconds(parse(...)): float(10**400 * 1e9) raised OverflowError.
    with pytest.raises(ValueError):
        stamps.parse_stamp_text(KILLER_STAMP)
    top = stamps.parse_stamp_text('2147483647.999999999')
    assert top == stamps.MAX_STAMP_NS and math.isfinite(stamps.ns_seconds(top))
    assert stamps.parse_stamp_text('0.000000000') == 0


@pytest.mark.parametrize('change, words', [
    ({'seq': None}, 'without a seq'), ({'sensor': None}, 'without a sensor'),
    ({'stamp': None}, 'without a stamp'), ({'sensor': 'yes'}, 'sensor'),
    ({'sensor': ' 1'}, 'sensor'), ({'name': 'cycles'}, 'named'),
    ({'level': DiagnosticStatus.WARN}, 'neither OK nor ERROR'),
    ({'message': 'x' * 5000}, 'message is 5000 characters long')])
def test_a_cycle_status_unlike_the_builders_is_refused(change, words):
    fields = {'name': 'cycle', 'level': DiagnosticStatus.OK, 'message': 'completed',
              'seq': '42', 'sensor': '1', 'stamp': GOOD_STAMP, **change}
    with pytest.raises(ValueError, match=words):
        messages.parse_cycle_status(status(**{k: v for k, v in fields.items()
                                              if v is not None}))


def test_a_value_given_twice_is_refused_not_overwritten():
    msg = good_cycle()
    msg.values.append(KeyValue(key='seq', value='43'))
    with pytest.raises(ValueError, match='seq twice'):
        messages.parse_cycle_status(msg)
    msg = good_cycle()
    msg.values.append(KeyValue(key='mac', value='later fields are not read here'))
    assert messages.parse_cycle_status(msg).seq == 42


@pytest.mark.parametrize('R', ['1e400', '-1e400', 'inf', 'nan', '1_0.5', ' 0.1', '0.10',
                               '\u0660.1', '1E-3', '0.3', 'x' * 100])
def test_a_predicted_R_that_is_not_a_finite_floats_repr_is_refused(R):
    msg = messages.predicted_state(5, None, 1, 0.25, 'jog')
    msg.values[3].value = R
    if R == '0.3':      # a repr itself: read back exactly
        assert messages.parse_predicted_state(msg).R == 0.3
        return
    with pytest.raises(ValueError, match='R'):
        messages.parse_predicted_state(msg)


@pytest.mark.parametrize('edge, R, kind', [
    (-1, 0.25, 'lost'), (1, None, 'jog'), (-1, None, 'jog'), (1, 0.25, 'lost'),
    (2**31, 0.25, 'jog'), (-2, 0.25, 'jog'), (1, 0.25, 'hop')])
def test_a_predicted_state_that_contradicts_itself_is_refused(edge, R, kind):
    with pytest.raises(ValueError, match='predicted/state'):
        messages.parse_predicted_state(messages.predicted_state(5, None, edge, R, kind))


def test_a_verdict_unlike_the_builders_is_refused():
    good = messages.edge_verdict(7, None, True, 'ready')
    assert messages.parse_edge_verdict(good).ready is True
    for key, value in (('ready', 'True'), ('ready', '1'), ('seq', '+7'), ('stamp', '12.5'),
                       ('state', '')):
        msg = messages.edge_verdict(7, None, True, 'ready')
        next(kv for kv in msg.values if kv.key == key).value = value
        with pytest.raises(ValueError, match='edge1_verdict'):
            messages.parse_edge_verdict(msg)


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

def _texts(msg, *keys):
    values = {kv.key: kv.value for kv in msg.values}
    return [values[k] for k in keys]


@SETTINGS
@given(statuses())
@example(good_cycle(stamp=KILLER_STAMP))
@example(good_cycle(seq=' 12 '))
def test_any_cycle_status_parses_to_the_builders_form_or_is_a_value_error(msg):
    try:
        st = messages.parse_cycle_status(msg)
    except ValueError:
        return
    again = messages.cycle_status(st.seq, st.ok, st.message, st.sensor, st.stamp_ns,
                                  st.hardware_id)
    assert _texts(again, 'seq', 'sensor', 'stamp') == _texts(msg, 'seq', 'sensor', 'stamp')
    assert (again.level, again.name) == (msg.level, msg.name)
    assert math.isfinite(stamps.ns_seconds(st.stamp_ns)) and 0 <= st.seq <= messages.MAX_SEQ
    messages.time_msg(st.stamp_ns)      # a stamp a Time holds: republishing it cannot fail


@SETTINGS
@given(statuses())
def test_any_verdict_parses_to_the_builders_form_or_is_a_value_error(msg):
    try:
        v = messages.parse_edge_verdict(msg)
    except ValueError:
        return
    again = messages.edge_verdict(v.seq, v.stamp_ns, v.ready, v.state, v.anomaly)
    keys = ('seq', 'stamp', 'ready', 'state')
    assert _texts(again, *keys) == _texts(msg, *keys)
    assert (again.level, again.message) == (msg.level, msg.message)


@SETTINGS
@given(statuses())
def test_any_predicted_state_parses_to_the_builders_form_or_is_a_value_error(msg):
    try:
        s = messages.parse_predicted_state(msg)
    except ValueError:
        return
    again = messages.predicted_state(s.seq, s.stamp_ns, s.edge, s.R, s.throw_kind)
    keys = ('seq', 'stamp', 'edge', 'R', 'throw_kind')
    assert _texts(again, *keys) == _texts(msg, *keys)
    assert s.R is None or math.isfinite(s.R)


@SETTINGS
@given(TEXT)
@example(KILLER_STAMP)
def test_any_text_is_a_stamp_a_time_holds_or_a_value_error(text):
    try:
        ns = stamps.parse_stamp_text(text)
    except ValueError:
        return
    assert stamps.stamp_text(ns) == text and 0 <= ns <= stamps.MAX_STAMP_NS
    messages.time_msg(ns)


@SETTINGS
@given(TEXT)
def test_any_text_is_a_seq_below_2_63_or_a_value_error(text):
    try:
        seq = messages.parse_seq(text)
    except ValueError:
        return
    assert str(seq) == text and 0 <= seq < 2**63


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
        assert stamp.sec < 0 or stamp.nanosec >= stamps.NS
        return
    assert 0 <= ns <= stamps.MAX_STAMP_NS and math.isfinite(stamps.ns_seconds(ns))


# ---- and what the builders write still reads back ------------------------------------------

def test_a_builder_cuts_a_text_too_long_for_the_parser():
    # A failed cycle's reason goes into the verdict's anomaly; neither may be unreadable.
    reason = 'r' * (messages.MAX_TEXT + 10)
    st = messages.parse_cycle_status(messages.cycle_status(3, False, reason, None, 0, 'x' * 10**5))
    assert len(st.message) == len(st.hardware_id) == messages.MAX_TEXT
    assert st.message.startswith('r' * 100) and st.message.endswith('\u2026')
    v = messages.parse_edge_verdict(messages.edge_verdict(3, 0, False, 'anomaly',
                                                          f'cycle 3 failed: {st.message}'))
    assert len(v.anomaly) == messages.MAX_TEXT and v.anomaly.startswith('cycle 3 failed: r')


@SETTINGS
@given(seq=st.integers(0, messages.MAX_SEQ), ok=st.booleans(),
       sensor=st.sampled_from([True, False, None]), stamp=st.integers(0, stamps.MAX_STAMP_NS),
       message=st.text(max_size=50), hardware_id=st.text(max_size=50))
def test_every_cycle_status_the_builder_writes_reads_back(seq, ok, sensor, stamp, message,
                                                          hardware_id):
    msg = messages.cycle_status(seq, ok, message, sensor, stamp, hardware_id)
    assert messages.parse_cycle_status(msg) == messages.CycleStatus(
        seq, ok, sensor, stamp, message, hardware_id)


@SETTINGS
@given(seq=st.integers(0, messages.MAX_SEQ),
       stamp=st.one_of(st.none(), st.integers(0, stamps.MAX_STAMP_NS)),
       state=st.one_of(st.just(-1), st.integers(0, messages.MAX_EDGE)),
       R=st.floats(allow_nan=False, allow_infinity=False),
       kind=st.sampled_from(['jog', 'flip']), ready=st.booleans(),
       verdict_state=st.text(min_size=1, max_size=30), anomaly=st.text(max_size=30))
def test_every_prediction_and_verdict_the_builders_write_reads_back(
        seq, stamp, state, R, kind, ready, verdict_state, anomaly):
    lost = state == -1
    p = messages.predicted_state(seq, stamp, state, None if lost else R,
                                 'lost' if lost else kind)
    assert messages.parse_predicted_state(p) == messages.PredictedState(
        seq, stamp, state, None if lost else R, 'lost' if lost else kind)
    v = messages.parse_edge_verdict(messages.edge_verdict(seq, stamp, ready, verdict_state,
                                                          anomaly))
    assert v == messages.EdgeVerdict(seq, stamp, ready, verdict_state, anomaly)
