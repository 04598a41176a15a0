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
The frame check catches what a serial line does (issue 20, item 2; attack 4).

Theory: the CRC-16/CCITT-FALSE generator G = x^16 + x^12 + x^5 + 1 has degree 16 and a
non-zero constant term, so it divides no error polynomial x^i * B(x) with B of degree < 16:
every burst of up to 16 bits is detected. G = (x + 1) * P(x) with P primitive of degree 15,
so every odd number of bit errors is detected and two bit errors are detected when they are
less than 32767 bits apart: every double-bit error in a frame (at most 96 bytes). The tests
below check these claims on the parser itself, not on the theory: the bit errors hit the
whole line (``$``, body, ``*``, hex digits, CR LF), where the theory says nothing.
"""

import itertools
import random

from feeder_driver import protocol as p
import numpy as np
import pytest

# A line of exactly MAX_LINE bytes (its ERR text is longer than a controller may send; a
# received text is taken as framed), and the longest message a controller may send.
LONGEST_TEXT = ''.join(chr(0x20 + (7 * k) % 95) for k in range(200)).replace(
    '$', 'D').replace('*', 'S').replace(',', 'C')
FULL_LINE = p.frame(['ERR', '1', 'FAULT', LONGEST_TEXT[:p.MAX_LINE - 20]])
LONGEST_MSG = p.Err(65535, 'ABCDEFGHIJKL', LONGEST_TEXT[:48])
SENTINEL = p.Ack(9)
SENTINEL_LINE = p.encode(SENTINEL)
# Kinds that mean the frame check passed: a corrupted frame must never get that far.
PASSED_CHECK = ('unknown', 'fields')


def flip(line, *bits):
    """``line`` with the given bits inverted (bit ``8 * i + j``: bit j of byte i)."""
    out = bytearray(line)
    for b in bits:
        out[b // 8] ^= 1 << (b % 8)
    return bytes(out)


def refused(parser, line, original=None, bits=()):
    """
    Whether ``line``, followed by a good frame, yields nothing but that good frame.

    The one exception: an error confined to the line end (CR LF; e.g. CR turned into LF) may
    still deliver the ``original`` frame's message, unchanged.
    """
    parser.reset()
    events = parser.feed(line + SENTINEL_LINE)
    messages = [e for e in events if not isinstance(e, p.Rejected)]
    kinds = [e.kind for e in events if isinstance(e, p.Rejected)]
    if set(kinds) & set(PASSED_CHECK):
        return False
    if messages == [SENTINEL]:
        return True
    if original is None or not all(b // 8 >= len(original) - 2 for b in bits):
        return False
    return messages == p.Parser(p.CONTROLLER_MESSAGES).feed(original) + [SENTINEL]


def test_frames_are_of_protocol_length():
    assert len(FULL_LINE) == p.MAX_LINE
    line = p.encode(LONGEST_MSG)
    assert p.Parser(p.CONTROLLER_MESSAGES).feed(line) == [LONGEST_MSG]
    (full,) = p.Parser(p.CONTROLLER_MESSAGES).feed(FULL_LINE)
    assert isinstance(full, p.Err) and len(full.text) == p.MAX_LINE - 20


@pytest.mark.parametrize('seq', range(96))
def test_attack_4_sensor_bit_and_check_digit_flipped_is_refused(seq):
    # Issue 20, attack 4: flip the sensor-bit character and bit 0 of the check's last digit.
    # With the 8-bit XOR both flips cancel: 96 of 96 such replies were accepted.
    line = p.encode(p.Sens(seq, seq % 2))
    sensor_char = line.index(b'*') - 1
    last_digit = len(line) - 3
    bad = flip(line, 8 * sensor_char, 8 * last_digit)
    assert bad != line
    parser = p.Parser()
    assert refused(parser, bad), bad
    assert parser.stats['checksum'] == 1


@pytest.mark.parametrize('line', [FULL_LINE, p.encode(LONGEST_MSG), p.encode(p.Sens(17, 1)),
                                  p.encode(p.Hb(123456, 'IDLE'))],
                         ids=['max_line', 'longest_err', 'sens', 'hb'])
def test_every_single_and_double_bit_error_is_refused(line):
    parser = p.Parser()
    nbits = 8 * len(line)
    escaped = [b for b in range(nbits) if not refused(parser, flip(line, b), line, [b])]
    assert escaped == []
    escaped = [pair for pair in itertools.combinations(range(nbits), 2)
               if not refused(parser, flip(line, *pair), line, pair)]
    assert escaped == [], f'{len(escaped)} double-bit errors accepted, e.g. {escaped[:5]}'


def _syndromes(nbytes, order):
    """CRC change of each single bit flip of an ``nbytes`` body, bits listed in ``order``."""
    body = bytes(range(0x30, 0x30 + nbytes)) if nbytes <= 0x4e else b'A' * nbytes
    base = p.checksum(body)
    bits = [(k, 7 - j) for k in range(nbytes) for j in range(8)]     # the CRC reads MSB first
    if order == 'wire':
        bits = [(k, j) for k in range(nbytes) for j in range(8)]     # a UART sends LSB first
    out = []
    for k, j in bits:
        body2 = bytearray(body)
        body2[k] ^= 1 << j
        out.append(p.checksum(bytes(body2)) ^ base)
    return np.array(out, dtype=np.uint16)


@pytest.mark.parametrize('order', ['crc', 'wire'])
def test_every_burst_of_up_to_16_bits_in_a_body_is_detected_exhaustively(order):
    # The CRC is affine: check(body ^ e) ^ check(body) depends on e alone (and e's distance
    # from the end), so a burst goes undetected exactly when the XOR of the changes of its
    # bits is 0. Every burst (first bit at each position, any pattern of the next 15 bits) of
    # the longest body a frame can carry (MAX_LINE - 8 bytes, which covers every shorter
    # body too: leading zeros do not change the change) is checked, in the CRC's bit order
    # and in the order a UART sends (LSB first: there a 16-bit burst can span 3 bytes).
    syn = _syndromes(p.MAX_LINE - 8, order)
    # Linearity, checked on the real function for a few multi-bit errors.
    rng = random.Random(3)
    body = bytes(rng.randrange(0x20, 0x7f) for _ in range(p.MAX_LINE - 8))
    for _ in range(50):
        bits = rng.sample(range(len(syn)), rng.randint(2, 9))
        err = bytearray(len(body))
        for b in bits:
            k, j = divmod(b, 8)
            err[k] ^= 1 << ((7 - j) if order == 'crc' else j)
        change = p.checksum(bytes(x ^ y for x, y in zip(body, err))) ^ p.checksum(body)
        assert change == np.bitwise_xor.reduce(syn[bits])
    undetected = 0
    for start in range(len(syn)):
        window = syn[start:start + 16]
        changes = np.zeros(1 << len(window), dtype=np.uint16)
        for i, value in enumerate(window):
            changes[1 << i:2 << i] = changes[:1 << i] ^ value
        undetected += int(np.count_nonzero(changes[1::2] == 0))    # first bit always set
    assert undetected == 0


@pytest.mark.parametrize('line', [FULL_LINE, p.encode(p.Sens(17, 1))], ids=['max_line', 'sens'])
def test_bursts_of_up_to_16_bits_anywhere_on_the_line_are_refused(line):
    # On the whole line (framing characters and hex digits included), through the parser:
    # every start bit, every length 1..16, all-ones plus 6 seeded patterns per length.
    rng = random.Random(20)
    parser = p.Parser()
    nbits = 8 * len(line)
    escaped = []
    for start in range(nbits):
        for length in range(1, 17):
            if start + length > nbits:
                break
            patterns = {(1 << length) - 1} | {
                1 | (1 << (length - 1)) | (rng.getrandbits(length) if length > 2 else 0)
                for _ in range(6)}
            for pattern in patterns:
                bits = [start + i for i in range(length) if pattern >> i & 1]
                if not refused(parser, flip(line, *bits), line, bits):
                    escaped.append((start, length, pattern))
    assert escaped == []


def test_a_protocol_1_frame_is_refused_as_legacy_with_the_fix():
    body = b'HELLO,feeder-fw-0.9,1A2B'
    old = b'$' + body + b'*%02X\r\n' % p.legacy_checksum(body)
    parser = p.Parser()
    (event,) = parser.feed(old)
    assert event.kind == 'legacy' and parser.stats['legacy'] == 1
    assert 'protocol 1' in event.detail and 'update the controller firmware' in event.detail
    # A two-digit check that is not the XOR is just a malformed frame.
    (event,) = parser.feed(b'$' + body + b'*00\r\n')
    assert event.kind == 'frame' and '*HHHH' in event.detail
    assert p.REJECT_CODES['legacy'] == 'BADFRAME'


def test_lowercase_check_digits_are_refused():
    # A lowercase digit is one bit away from its uppercase form: accepting both would let a
    # single bit error through (harmlessly, but undetected). Senders send uppercase.
    line = b'$HELLO,fw,AB*%04x\r\n' % p.checksum(b'HELLO,fw,AB')
    assert line != line.upper()
    (event,) = p.Parser().feed(line)
    assert event.kind == 'frame' and 'uppercase' in event.detail
