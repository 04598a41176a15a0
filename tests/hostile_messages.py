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
replaced and cut at a NUL, numbers have their field's width). The texts mix what the builders
write with the forms issue 20 found accepted (``' 12 '``, Arabic-Indic digits, ``999999_0``,
a ``1`` followed by 400 zeros), boundaries (2**31 s, 2**63), floats' spellings (``1e400``,
``nan``) and arbitrary unicode, some of it huge.
"""

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from feeder_common import messages as m
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
KEYS = ('seq', 'sensor', 'stamp', 'ready', 'state', 'edge', 'R', 'throw_kind')
NAMES = ('cycle', 'edge1_verdict', 'predicted_state', 'Cycle', 'cycle ', '')
LEVELS = (DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR,
          DiagnosticStatus.STALE)
INT32 = st.integers(-2**31, 2**31 - 1)
UINT32 = st.integers(0, 2**32 - 1)

# Values the builders write, to make near-valid messages frequent.
VALID_TEXT = st.one_of(
    st.integers(0, 2**63 - 1).map(str),
    st.integers(0, 2**31 * 10**9 - 1).map(lambda ns: f'{ns // 10**9}.{ns % 10**9:09d}'),
    st.sampled_from(('1', '0', 'none', 'true', 'false', 'jog', 'flip', 'lost', '-1')),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.integers(-1, 5).map(str))
# Numbers beyond every bound: a seq past 2**63, a stamp past what a Time holds (issue 20's
# stamp is '1' and 400 zeros).
BEYOND_TEXT = st.one_of(
    st.integers(2**63 - 2, 10**420).map(str),
    st.integers(2**31 - 2, 10**420).map(lambda sec: f'{sec}.000000000'),
    st.integers(2**31 - 2, 10**420).map(str))
HUGE_TEXT = st.builds(lambda c, n: c * n, st.characters(), st.integers(0, 20_000))
TEXT = st.one_of(st.sampled_from(TRICKY), VALID_TEXT, BEYOND_TEXT, st.text(max_size=40),
                 st.text(alphabet='0123456789.-+_ eEnaif\u0661\u0663', max_size=30), HUGE_TEXT)
KEY = st.one_of(st.sampled_from(KEYS), st.sampled_from(KEYS).map(lambda k: k + ' '),
                st.text(max_size=12))
# Per key: the builder's form of a value beyond what a parser may take (a seq past 2**63, a
# stamp past Time's int32 seconds, an edge past int32, R past the largest float).
BEYOND = {
    'seq': st.integers(2**63, 10**420).map(str),
    'stamp': st.integers(2**31, 10**420).map(lambda sec: f'{sec}.000000000'),
    'edge': st.integers(2**31, 10**420).map(str),
    'R': st.sampled_from(('1e400', '-1e400', '1' + '0' * 400 + '.0', 'inf', 'nan')),
}
VALUES = st.lists(st.builds(KeyValue, key=KEY, value=TEXT), max_size=9)


def wire(msg):
    """Return ``msg`` as a subscriber receives it: serialized and deserialized."""
    return deserialize_message(serialize_message(msg), type(msg))


SEQS = st.integers(0, 2**63 - 1)
STAMPS = st.integers(0, 2**31 * 10**9 - 1)
KINDS = st.sampled_from(('jog', 'flip'))


@st.composite
def canonical(draw):
    """Draw a status one of feeder_common.messages' builders writes, with any valid fields."""
    which = draw(st.sampled_from(('cycle', 'verdict', 'predicted')))
    if which == 'cycle':
        ok = draw(st.booleans())
        return m.cycle_status(draw(SEQS), ok, draw(st.text(max_size=30)),
                              draw(st.sampled_from((True, False))) if ok else None,
                              draw(STAMPS), draw(st.text(max_size=30)))
    stamp = draw(st.one_of(st.none(), STAMPS))
    if which == 'verdict':
        return m.edge_verdict(draw(SEQS), stamp, draw(st.booleans()),
                              draw(st.text(min_size=1, max_size=20)),
                              draw(st.text(max_size=20)), draw(st.text(max_size=20)))
    edge = draw(st.integers(-1, 5))
    return m.predicted_state(draw(SEQS), stamp, edge,
                             None if edge < 0 else draw(st.floats(allow_nan=False,
                                                                  allow_infinity=False)),
                             'lost' if edge < 0 else draw(KINDS))


@st.composite
def mutated(draw):
    """Draw a builder's status with up to three hostile changes (none in about a quarter)."""
    msg = draw(canonical())
    values = list(msg.values)
    for _ in range(draw(st.integers(0, 3))):
        op = draw(st.sampled_from(('value', 'value', 'beyond', 'beyond', 'drop', 'twice', 'add',
                                   'name', 'level', 'message')))
        k = draw(st.integers(0, max(0, len(values) - 1)))
        if op == 'value' and values:
            values[k] = KeyValue(key=values[k].key, value=draw(TEXT))
        elif op == 'beyond' and values:
            key = values[k].key
            values[k] = KeyValue(key=key, value=draw(BEYOND.get(key, TEXT)))
        elif op == 'drop' and values:
            del values[k]
        elif op == 'twice' and values:
            values.append(KeyValue(key=values[k].key, value=draw(TEXT)))
        elif op == 'add':
            values.append(draw(st.builds(KeyValue, key=KEY, value=TEXT)))
        elif op == 'name':
            msg.name = draw(st.one_of(st.sampled_from(NAMES), st.text(max_size=20)))
        elif op == 'level':
            msg.level = draw(st.one_of(st.sampled_from(LEVELS),
                                       st.binary(min_size=1, max_size=1)))
        elif op == 'message':
            msg.message = draw(TEXT)
    msg.values = values
    return wire(msg)


@st.composite
def arbitrary(draw, names=NAMES):
    """Draw a DiagnosticStatus of any name, level, texts and values (the keys often known)."""
    keys = draw(st.permutations(KEYS))[:draw(st.integers(0, len(KEYS)))]
    values = [KeyValue(key=k, value=draw(TEXT)) for k in keys] + draw(VALUES)
    values = draw(st.permutations(values))
    return wire(DiagnosticStatus(
        level=draw(st.one_of(st.sampled_from(LEVELS), st.binary(min_size=1, max_size=1))),
        name=draw(st.one_of(st.sampled_from(names), st.text(max_size=20))),
        message=draw(TEXT), hardware_id=draw(TEXT), values=values))


def statuses():
    """Draw any DiagnosticStatus: mostly a builder's with hostile changes, else arbitrary."""
    return st.one_of(mutated(), arbitrary())


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


TIMES = st.builds(Time, sec=INT32, nanosec=UINT32).map(wire)

LABELS = st.one_of(st.sampled_from(('active', 'inactive', 'unconfigured', 'finalized',
                                    'deactivate', 'shutdown', '')), st.text(max_size=20))
TRANSITION_EVENTS = st.builds(
    TransitionEvent, timestamp=st.integers(0, 2**64 - 1),
    transition=st.builds(Transition, id=st.integers(0, 255), label=LABELS),
    start_state=st.builds(State, id=st.integers(0, 255), label=LABELS),
    goal_state=st.builds(State, id=st.integers(0, 255), label=LABELS)).map(wire)
