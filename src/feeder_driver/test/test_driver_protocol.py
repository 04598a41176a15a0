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

"""Protocol codec: round trips, the worked CRC example, defensive decoding."""

import random
from typing import Optional

from feeder_driver import protocol as p
from hypothesis import given, settings
from hypothesis import strategies as st
import pytest

ALL = [p.Fire(0), p.Fire(65535), p.Fire(17, 6283), p.Stop(), p.Ping('h1'), p.Ident(), p.Caps(),
       p.Cap('SPEED', 1047, 12566), p.Cap('SPEED', 1, p.MAX_SPEED_MRAD_S),
       p.Hello('feeder-emu-1.0', '0A1B'), p.Ack(7), p.Rel(7, 5585), p.Rel(7, -12),
       p.Sens(7, 1), p.Sens(65535, 0),
       p.Err(7, 'BUSY', 'cycle 6 in progress'), p.Err(None, 'BADSUM', ''), p.Pong('h1'),
       p.Hb(0, 'IDLE'), p.Hb(2 ** 32 - 1, 'BUSY')]
TABLE = dict(p.HOST_MESSAGES, **p.CONTROLLER_MESSAGES)


def bitwise_crc(data):
    """CRC-16/CCITT-FALSE as docs/serial-protocol.md writes it for firmware, bit by bit."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def test_crc_worked_example():
    # docs/serial-protocol.md, section 3: the check value of the standard and the running CRC
    # of PING,42 byte by byte.
    assert p.checksum(b'123456789') == bitwise_crc(b'123456789') == 0x29B1
    running = [bitwise_crc(b'PING,42'[:k]) for k in range(1, 8)]
    assert running == [0xBB05, 0xCA5D, 0x8C0C, 0x6427, 0xEECC, 0xA637, 0xF43D]
    assert p.checksum(b'PING,42') == 0xF43D
    assert p.encode(p.Ping('42')) == b'$PING,42*F43D\r\n'
    assert p.encode(p.Sens(17, 1)) == b'$SENS,17,1*2A61\r\n'
    for msg in ALL:
        line = p.encode(msg)
        assert line[-7:-6] == b'*' and int(line[-6:-2], 16) == bitwise_crc(line[1:-7])


def test_doc_example_frames_are_exact():
    # The example frames of docs/serial-protocol.md, section 5.
    examples = {
        p.Hello('feeder-emu-1.0', '1A2B0001'): b'$HELLO,feeder-emu-1.0,1A2B0001*92F3',
        p.Ident(): b'$ID*A21B', p.Ping('h1'): b'$PING,h1*8F8C', p.Pong('h1'): b'$PONG,h1*026D',
        p.Fire(17): b'$FIRE,17*AF2A', p.Ack(17): b'$ACK,17*2D2E',
        p.Rel(17, 5585): b'$REL,17,5585*84A5', p.Sens(17, 1): b'$SENS,17,1*2A61',
        p.Hb(123456, 'IDLE'): b'$HB,123456,IDLE*0802',
        p.Hb(123456, 'BUSY'): b'$HB,123456,BUSY*A2BE',
        p.Err(18, 'BUSY', 'cycle 17 in progress'): b'$ERR,18,BUSY,cycle 17 in progress*F585',
        p.Stop(): b'$STOP*AF2E', p.Err(18, 'ABORTED', 'stopped by host'):
        b'$ERR,18,ABORTED,stopped by host*A4EF',
        p.Err(None, 'BADSUM', 'checksum'): b'$ERR,-,BADSUM,checksum*4028',
        p.Err(19, 'FAULT', 'arm stalled'): b'$ERR,19,FAULT,arm stalled*5F27',
        # The release-speed setpoint (section 5): the handshake's CAPS and its two answers,
        # FIRE with a setpoint and its refusal.
        p.Caps(): b'$CAPS*3F34', p.Cap('SPEED', 1047, 12566): b'$CAP,SPEED,1047,12566*57BD',
        p.Err(None, 'BADCMD', 'unknown'): b'$ERR,-,BADCMD,unknown*5036',
        p.Fire(17, 6283): b'$FIRE,17,6283*B95E', p.Rel(17, 6283): b'$REL,17,6283*FA2F',
        p.Fire(18, 20000): b'$FIRE,18,20000*4CD4',
        p.Err(18, 'BADARG', 'speed out of range'): b'$ERR,18,BADARG,speed out of range*C214',
        p.Err(None, 'BADARG', 'fields'): b'$ERR,-,BADARG,fields*A98F',
    }
    for msg, line in examples.items():
        assert p.encode(msg) == line + b'\r\n'


@pytest.mark.parametrize('msg', ALL, ids=lambda m: m.NAME)
def test_round_trip(msg):
    parser = p.Parser(TABLE)
    line = p.encode(msg)
    assert line.startswith(b'$') and line.endswith(b'\r\n') and len(line) <= p.MAX_LINE
    assert parser.feed(line) == [msg]
    assert parser.stats['lines'] == 1 and parser.dropped_frames == 0


def test_bare_newline_is_accepted():
    parser = p.Parser()
    line = b'$HELLO,fw,AB*%04X\n' % p.checksum(b'HELLO,fw,AB')
    assert parser.feed(line) == [p.Hello('fw', 'AB')]


def test_every_split_of_a_stream_gives_the_same_messages():
    stream = b''.join(p.encode(m) for m in ALL)
    for cut in range(1, len(stream)):
        parser = p.Parser(TABLE)
        assert parser.feed(stream[:cut]) + parser.feed(stream[cut:]) == ALL


def test_byte_by_byte():
    stream = b''.join(p.encode(m) for m in ALL)
    parser = p.Parser(TABLE)
    out = []
    for b in stream:
        out += parser.feed(bytes([b]))
    assert out == ALL


@pytest.mark.parametrize('raw, kind', [
    (b'$SENS,7,1*0000\r\n', 'checksum'),
    (b'$SENS,7,1\r\n', 'frame'),
    (b'$SENS,7,1*G100\r\n', 'frame'),
    (b'$SENS,7,1*00\r\n', 'frame'),
    (b'$SENS,7,1*%02X\r\n' % p.legacy_checksum(b'SENS,7,1'), 'legacy'),
    (b'$SENS,7,\xff1*0000\r\n', 'frame'),
    (b'$SE\x00NS,7,1*0000\r\n', 'frame'),
    (b'$FOO,1*%04X\r\n' % p.checksum(b'FOO,1'), 'unknown'),
    (b'$SENS,7,2*%04X\r\n' % p.checksum(b'SENS,7,2'), 'fields'),
    (b'$SENS,70000,1*%04X\r\n' % p.checksum(b'SENS,70000,1'), 'fields'),
    (b'$ACK,7,8*%04X\r\n' % p.checksum(b'ACK,7,8'), 'fields'),
    (b'$ACK,-1*%04X\r\n' % p.checksum(b'ACK,-1'), 'fields'),
    (b'$ACK,7', 'truncated'),
    (b'$' + b'A' * 200 + b'\r\n', 'overlong'),
])
def test_defective_frames_are_dropped_counted_and_the_next_frame_survives(raw, kind):
    parser = p.Parser()
    good = p.encode(p.Ack(9))
    events = parser.feed(raw) + parser.feed(good)
    assert events[-1] == p.Ack(9)
    rejected = [e for e in events if isinstance(e, p.Rejected)]
    assert [r.kind for r in rejected] == [kind]
    assert rejected[0].detail
    assert parser.stats[kind] == 1 and parser.dropped_frames == 1


def test_garbage_outside_frames_is_counted_not_reported():
    parser = p.Parser()
    assert parser.feed(b'\xff\xfe\r\nnoise*12\n') == []
    assert parser.stats['garbage_bytes'] == 13
    assert parser.feed(p.encode(p.Ack(1))) == [p.Ack(1)]


def test_buffer_stays_bounded_under_endless_input():
    parser = p.Parser()
    for _ in range(1000):
        parser.feed(b'$' + b'x' * 1000)
        assert len(parser._buf) <= p.MAX_LINE
    assert parser.feed(b'\n' + p.encode(p.Ack(3))) == [p.Ack(3)]
    assert parser.stats['overlong'] >= 1


def test_a_frame_of_exactly_max_line_is_accepted_and_one_more_byte_is_not():
    text = 'x' * (p.MAX_LINE - len('$ERR,1,FAULT,*HHHH\r\n'))
    with pytest.raises(p.ProtocolError):
        p.encode(p.Err(1, 'FAULT', text))       # text longer than 48
    fields = ['HELLO', 'f' * 32, 'A' * 16]
    line = p.frame(fields)
    parser = p.Parser(max_line=len(line))
    assert parser.feed(line) == [p.Hello('f' * 32, 'A' * 16)]
    parser = p.Parser(max_line=len(line) - 1)
    assert [e.kind for e in parser.feed(line)] == ['overlong']


@pytest.mark.parametrize('bad', [
    lambda: p.Fire(-1), lambda: p.Fire(65536), lambda: p.Fire(True), lambda: p.Ping(''),
    lambda: p.Ping('a,b'), lambda: p.Hello('fw$', 'AB'), lambda: p.Hello('fw', 'A-B'),
    lambda: p.Sens(1, 2), lambda: p.Sens(1, 1.0),
    lambda: p.Err(1, 'busy', ''), lambda: p.Err(1, 'BUSY', 'a*b'),
    lambda: p.Hb(-1, 'IDLE'), lambda: p.Rel(1, 10 ** 8), lambda: p.Rel(1, 1.5),
    lambda: p.Fire(1, 10 ** 8), lambda: p.Fire(1, 6.283), lambda: p.Cap('TURBO', 1, 2),
    lambda: p.Cap('SPEED', 0, 5), lambda: p.Cap('SPEED', 6, 5), lambda: p.Cap('SPEED', 1, 2.5),
])
def test_encoding_invalid_values_raises_a_clear_error(bad):
    with pytest.raises(p.ProtocolError) as info:
        p.encode(bad())
    assert ':' in str(info.value)


def test_random_noise_never_raises_and_never_forges_a_message():
    rng = random.Random(1)
    parser = p.Parser(TABLE)
    for _ in range(300):
        chunk = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 64)))
        for event in parser.feed(chunk):
            # Random bytes could pass the CRC (1 in 65536), but only as a valid message.
            assert isinstance(event, (p.Rejected,) + tuple(TABLE.values()))
    assert parser.stats['bytes'] > 0


@settings(max_examples=200, deadline=None)
@given(noise=st.lists(st.binary(max_size=40), max_size=6),
       seqs=st.lists(st.integers(0, 65535), min_size=1, max_size=6),
       cuts=st.lists(st.integers(1, 30), max_size=20))
def test_messages_between_noise_survive_any_chunking(noise, seqs, cuts):
    # Noise may end in a cut frame; a real frame always starts with $, so it resyncs.
    msgs = [p.Sens(s, s % 2) for s in seqs]
    stream = b''
    for k, m in enumerate(msgs):
        junk = noise[k] if k < len(noise) else b''
        stream += junk.replace(b'\n', b' ') + p.encode(m)
    parser = p.Parser()
    out, i = [], 0
    for c in cuts:
        out += parser.feed(stream[i:i + c])
        i += c
    out += parser.feed(stream[i:])
    got = [e for e in out if isinstance(e, p.Sens)]
    assert got == msgs


def test_parser_rejects_a_tiny_max_line():
    with pytest.raises(ValueError, match='max_line'):
        p.Parser(max_line=3)


def test_reject_codes_cover_every_kind():
    parser = p.Parser()
    assert set(p.REJECT_CODES) == set(parser.STAT_KEYS) - {'bytes', 'lines', 'garbage_bytes'}
    assert set(p.REJECT_CODES.values()) <= set(p.ERROR_CODES)


def test_fire_takes_an_optional_speed_field():
    parser = p.Parser(p.HOST_MESSAGES)
    assert parser.feed(p.frame(['FIRE', '17'])) == [p.Fire(17)]
    assert parser.feed(p.frame(['FIRE', '17', '6283'])) == [p.Fire(17, 6283)]
    assert p.Fire(17).speed_rad_s is None and p.Fire(17, 6283).speed_rad_s == 6.283
    assert p.Fire(17).fields() == ['FIRE', '17']
    for fields, text in [(['FIRE'], 'expected 1 or 2 field(s) (FIRE,<seq>[,<speed mrad/s>]), '
                          'got 0'),
                         (['FIRE', '1', '2', '3'], 'expected 1 or 2 field(s)'),
                         (['FIRE', '1', ''], 'speed'), (['FIRE', '1', 'x'], 'speed'),
                         (['FIRE', '1', '10000001'], 'speed')]:
        (event,) = parser.feed(p.frame(fields))
        assert event.kind == 'fields' and text in event.detail, event
    assert p.Fire.usage() == 'FIRE,<seq>[,<speed mrad/s>]'
    assert p.Cap.usage() == 'CAP,SPEED,<min mrad/s>,<max mrad/s>'


def test_cap_range_and_name_are_checked_on_receipt():
    parser = p.Parser()
    for fields, text in [(['CAP', 'SPEED', '0', '5'], '0 < min <= max'),
                         (['CAP', 'SPEED', '6', '5'], '0 < min <= max'),
                         (['CAP', 'SPEED', '-5', '5'], '0 < min <= max'),
                         (['CAP', 'TURBO', '1', '5'], 'capability'),
                         (['CAP', 'SPEED', '5'], 'expected 3 field(s)')]:
        (event,) = parser.feed(p.frame(fields))
        assert event.kind == 'fields' and text in event.detail, event
    (cap,) = parser.feed(p.frame(['CAP', 'SPEED', '1047', '12566']))
    assert (cap.min_rad_s, cap.max_rad_s) == (1.047, 12.566)


def test_only_trailing_fields_may_be_optional():
    with pytest.raises(ValueError, match='optional'):
        p._message('Bad', 'BAD', 'doc', ('a', int, p._SEQ, None), ('b', int, p._SEQ),
                   optional=2)
    with pytest.raises(ValueError, match='optional'):
        p._message('Bad', 'BAD', 'doc', ('a', int, p._SEQ), optional=1)
    two = p._message('Two', 'TWO', 'doc', ('a', int, p._SEQ),
                     ('b', Optional[int], p._SEQ, None), ('c', Optional[int], p._SEQ, None),
                     optional=2)
    assert two.usage() == 'TWO,<seq>[,<seq>[,<seq>]]'
    assert two(1).fields() == ['TWO', '1'] and two(1, 2).fields() == ['TWO', '1', '2']
    with pytest.raises(p.ProtocolError, match='later optional field'):
        two(1, None, 3).fields()
    assert two.from_fields(['1', '2']) == two(1, 2)
