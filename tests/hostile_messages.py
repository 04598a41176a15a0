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
Hypothesis strategies of hostile messages: anything a node on the graph can publish.

Every message goes through :func:`wire` (serialize, deserialize) before a test hands it to a
parser or a callback: a subscriber sees exactly that (strings are UTF-8 with invalid bytes
replaced and cut at a NUL, numbers have their field's width). The typed reports
(feeder_interfaces/CycleStatus on cycle_status and cycle_fired, PredictedState on
predicted/state) get every value their fields hold: a seq up to 2**64 - 1, stamps before 1970
or with nanosec past 1e9, outcome and sensor codes no driver writes, NaN and infinite contact
points, edges past int32's middle, MACs of any length, sessions that are not hex, and texts
that mix what the builders write with the forms issue 20 found accepted (``' 12 '``,
Arabic-Indic digits, ``999999_0``, a ``1`` followed by 400 zeros), boundaries, floats'
spellings and arbitrary unicode, some of it huge.
"""

import math

from builtin_interfaces.msg import Time
from feeder_common import messages as m
from feeder_interfaces.msg import CycleStatus, PredictedState, Verdict
from hypothesis import strategies as st
from lifecycle_msgs.msg import State, Transition, TransitionEvent
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import Range

KILLER_STAMP = '1' + '0' * 400          # issue 20, attack 3: OverflowError in the monitor
TRICKY = (
    KILLER_STAMP, KILLER_STAMP + '.000000000', ' 12 ', '\u0661\u0662', '999999_0', '+5', '-0',
    '-1', '-2', '007', '0', '1e3', '0x10', '12\n', '', ' ', 'none', 'None', 'true', 'True',
    'false', '1', '0.5', '12.5', '7', '1.', '.5', '1.000000000', '1.0000000001', '01.000000000',
    '2147483647.999999999', '2147483648.000000000', '-1.000000000', '1_0.000000000',
    '\u0663.000000000', '1.00000000\u0663', '1.000000000 ', str(2**63 - 1), str(2**63),
    str(2**64), '9' * 5000, 'nan', 'NaN', 'inf', '-inf', 'Infinity', '1e400', '-1e400',
    '1e-400', '0.1', '0.30000000000000004', '1_0.5', '0.30000000000000004 ', '1E5', '1e5',
    'jog', 'flip', 'lost', 'Jog', 'ready', 'anomaly', 'cycle', '\x00', '1\x002', '\ufffd',
    '\U0001f600', '\u00df', '\u212a', 'x' * 100_000,
)
def wire(msg):
    """Return ``msg`` as a subscriber receives it: serialized and deserialized."""
    return deserialize_message(serialize_message(msg), type(msg))


INT8 = st.integers(-2**7, 2**7 - 1)
INT32 = st.integers(-2**31, 2**31 - 1)
UINT32 = st.integers(0, 2**32 - 1)
UINT64 = st.integers(0, 2**64 - 1)

# Texts the builders write, to make near-valid messages frequent.
VALID_TEXT = st.one_of(
    st.integers(0, 2**63 - 1).map(str),
    st.sampled_from(('completed', 'failed', 'fired', 'jog', 'flip', 'lost', 'sim', '', '1',
                     '0', 'none', 'aborted: interrupted (SIGTERM)', 'no reply from the board')),
    st.text(alphabet='0123456789abcdef', max_size=64))
HUGE_TEXT = st.builds(lambda c, n: c * n, st.characters(codec='utf-8'), st.integers(0, 20_000))
TEXT = st.one_of(st.sampled_from(TRICKY), VALID_TEXT, st.text(max_size=40),
                 st.text(alphabet='0123456789.-+_ eEnaif\u0661\u0663', max_size=30), HUGE_TEXT)
# Outcomes: the three a topic may carry, their near misses and anything else.
OUTCOMES = st.one_of(
    st.sampled_from((CycleStatus.OUTCOME_FIRED, CycleStatus.OUTCOME_COMPLETED,
                     CycleStatus.OUTCOME_FAILED, 'Completed', 'completed ', ' fired', 'FAILED',
                     'ok', 'complete', 'completed\x00', 'fired\x00x', '')),
    TEXT)
# Sensor codes: the three valid ones often, any int8 else.
SENSORS = st.one_of(st.sampled_from((CycleStatus.SENSOR_NONE, CycleStatus.SENSOR_CLEAR,
                                     CycleStatus.SENSOR_DETECTED)), INT8)
# Seqs: the valid range, its ends, and what only a uint64 holds (>= 2**63, up to 2**64 - 1).
SEQS_ANY = st.one_of(st.sampled_from((0, 1, 2**63 - 1, 2**63, 2**64 - 1)), UINT64)
# Times: any sec (negative: before 1970; 2**31 - 1: the end) and any nanosec (>= 1e9 invalid).
TIMES = st.builds(Time, sec=st.one_of(st.sampled_from((-1, -2**31, 0, 2**31 - 1)), INT32),
                  nanosec=st.one_of(st.sampled_from((0, 999_999_999, 10**9, 2**32 - 1)),
                                    UINT32)).map(wire)
# Sessions: lowercase hex of the signer's lengths and beyond, and any text.
SESSIONS = st.one_of(st.text(alphabet='0123456789abcdef', max_size=80),
                     st.sampled_from(('ABCDEF', 'g', ' ab', 'ab\x00cd', '0x12')), TEXT)
# MACs: 32 bytes (the right length), none, or any other length.
MACS = st.one_of(st.binary(min_size=32, max_size=32), st.just(b''), st.binary(max_size=100))
# Contact points: any float64, infinities and NaN often.
FLOATS = st.one_of(st.sampled_from((math.nan, math.inf, -math.inf, -0.0, 1e308, 5e-324)),
                   st.floats())
KINDS_ANY = st.one_of(st.sampled_from((PredictedState.THROW_JOG, PredictedState.THROW_FLIP,
                                       PredictedState.THROW_LOST, 'Jog', 'lost ', '')), TEXT)
EDGES_ANY = st.one_of(st.integers(-3, 6), INT32)

# What a hostile change may set, per field of CycleStatus.
REPORT_FIELDS = {
    'seq': SEQS_ANY, 'stamp': TIMES, 'outcome': OUTCOMES, 'sensor': SENSORS, 'reason': TEXT,
    'hardware_id': TEXT, 'release_speed': FLOATS, 'session': SESSIONS, 'mac': MACS.map(list),
}
# ... and of PredictedState.
STATE_FIELDS = {'seq': SEQS_ANY, 'stamp': TIMES, 'edge': EDGES_ANY, 'r': FLOATS,
                'throw_kind': KINDS_ANY}


SEQS = st.integers(0, 2**63 - 1)
STAMPS = st.integers(0, 2**31 * 10**9 - 1)
KINDS = st.sampled_from(('jog', 'flip'))
# A signer of the forger's own (a key no node uses), as a forger can have one.
FORGER = m.CycleSigner(b'forger-key-' * 3, '/feeder/feeder_driver', session='f0f0')


@st.composite
def canonical_report(draw):
    """Draw a cycle report a builder writes (cycle_status or cycle_fired), maybe signed."""
    which = draw(st.sampled_from(('status', 'signed status', 'fired')))
    seq, stamp, hardware_id = draw(SEQS), draw(STAMPS), draw(st.text(max_size=30))
    if which == 'fired':
        return FORGER.cycle_fired(seq, stamp, hardware_id)
    ok = draw(st.booleans())
    args = (seq, ok, draw(st.text(max_size=30)),
            draw(st.sampled_from((True, False))) if ok else None, stamp, hardware_id)
    return FORGER.cycle_status(*args) if which == 'signed status' else m.cycle_status(*args)


@st.composite
def canonical_state(draw):
    """Draw a predicted/state predicted_state writes, with any valid fields."""
    stamp = draw(st.one_of(st.none(), STAMPS))
    edge = draw(st.integers(-1, 5))
    return m.predicted_state(draw(SEQS), stamp, edge,
                             None if edge < 0 else draw(st.floats(allow_nan=False,
                                                                  allow_infinity=False)),
                             'lost' if edge < 0 else draw(KINDS))


def _mutate(draw, msg, fields):
    """Set up to three fields of ``msg`` to hostile values (none in about a quarter)."""
    for _ in range(draw(st.integers(0, 3))):
        name = draw(st.sampled_from(sorted(fields)))
        setattr(msg, name, draw(fields[name]))
    return wire(msg)


@st.composite
def mutated(draw):
    """Draw a builder's CycleStatus with up to three hostile field values."""
    return _mutate(draw, draw(canonical_report()), REPORT_FIELDS)


@st.composite
def arbitrary(draw):
    """Draw a CycleStatus with every field any value it holds."""
    return wire(CycleStatus(**{name: draw(values) for name, values in REPORT_FIELDS.items()}))


def statuses():
    """
    Draw any CycleStatus (what cycle_status and cycle_fired can carry).

    Mostly a builder's report with hostile changes, else arbitrary fields.
    """
    return st.one_of(mutated(), arbitrary())


@st.composite
def mutated_state(draw):
    """Draw a builder's PredictedState with up to three hostile field values."""
    return _mutate(draw, draw(canonical_state()), STATE_FIELDS)


@st.composite
def arbitrary_state(draw):
    """Draw a PredictedState with every field any value it holds."""
    return wire(PredictedState(**{name: draw(values) for name, values in STATE_FIELDS.items()}))


def predicted_states():
    """Draw any PredictedState (what predicted/state can carry)."""
    return st.one_of(mutated_state(), arbitrary_state())


FLOAT32 = st.floats(width=32)


@st.composite
def ranges(draw):
    """Draw a sensor_msgs/Range with any float32 readings and limits and any stamp."""
    rng = Range()
    rng.header.stamp = Time(sec=draw(INT32), nanosec=draw(UINT32))
    rng.header.frame_id = draw(st.text(max_size=20))
    rng.radiation_type = draw(st.integers(0, 255))
    rng.field_of_view = draw(FLOAT32)
    rng.min_range = draw(FLOAT32)
    rng.max_range = draw(FLOAT32)
    rng.range = draw(st.one_of(st.sampled_from([float('inf'), float('-inf'), float('nan')]),
                               FLOAT32))
    return wire(rng)


VERDICT_STATES = st.one_of(st.sampled_from(('ready', 'tracking', 'warming up', 'anomaly',
                                           'cycling')), st.text(max_size=20))


@st.composite
def verdicts(draw):
    """Draw a feeder_interfaces/Verdict with any fields: times, texts and a MAC of any size."""
    return wire(Verdict(seq=draw(st.integers(0, 2**64 - 1)),
                        stamp=Time(sec=draw(INT32), nanosec=draw(UINT32)),
                        ready=draw(st.booleans()), state=draw(VERDICT_STATES),
                        anomaly=draw(st.text(max_size=40)), session=draw(st.text(max_size=20)),
                        sent=Time(sec=draw(INT32), nanosec=draw(UINT32)),
                        mac=list(draw(st.binary(max_size=40)))))


LABELS = st.one_of(st.sampled_from(('active', 'inactive', 'unconfigured', 'finalized',
                                    'deactivate', 'shutdown', '')), st.text(max_size=20))
TRANSITION_EVENTS = st.builds(
    TransitionEvent, timestamp=st.integers(0, 2**64 - 1),
    transition=st.builds(Transition, id=st.integers(0, 255), label=LABELS),
    start_state=st.builds(State, id=st.integers(0, 255), label=LABELS),
    goal_state=st.builds(State, id=st.integers(0, 255), label=LABELS)).map(wire)
