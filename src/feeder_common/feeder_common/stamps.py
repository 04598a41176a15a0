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
The stamp format of ``cycle_status`` (ROS-free): exact seconds as text, ``'<sec>.<9 digits>'``.

A float would lose the last nanoseconds of a stamp near 1.8e9 s, so the value ``stamp`` carries
the integer nanoseconds of the sample, written and parsed here only. The parser takes exactly
what :func:`stamp_text` writes and nothing else: ASCII digits, ``sec`` without a sign, a space,
an underscore or a leading zero, within what builtin_interfaces/Time holds (int32 seconds,
never before 1970), and nine digits of nanoseconds. Anything else is refused with a ValueError
that names the problem, so that no text a subscriber receives can become a number that later
overflows (``'1'`` followed by 400 zeros once did, in :func:`ns_seconds`).
"""

NS = 1_000_000_000
# builtin_interfaces/Time: int32 sec; a sample stamp is never before 1970 (sec >= 0).
MAX_SEC = 2**31 - 1
MAX_STAMP_NS = MAX_SEC * NS + NS - 1
# The longest text a stamp can have: 10 digits, a point, 9 digits.
MAX_STAMP_TEXT = len(str(MAX_SEC)) + 1 + 9
_DIGITS = frozenset('0123456789')


def is_decimal(text):
    """Whether ``text`` is ASCII decimal digits without a redundant leading zero."""
    return (isinstance(text, str) and text != '' and set(text) <= _DIGITS
            and (text == '0' or text[0] != '0'))


def stamp_text(stamp_ns):
    """Write integer nanoseconds as exact seconds, ``'<sec>.<9 digits>'``."""
    sec, nsec = divmod(int(stamp_ns), NS)
    return f'{sec}.{nsec:09d}'


def check_stamp_ns(stamp_ns):
    """Return ``stamp_ns`` if it is a stamp builtin_interfaces/Time can hold; else ValueError."""
    if not 0 <= stamp_ns <= MAX_STAMP_NS:
        raise ValueError(f'stamp {stamp_ns} ns is outside [0, {MAX_STAMP_NS}] ns (what '
                         'builtin_interfaces/Time holds from 1970 on)')
    return stamp_ns


def parse_stamp_text(text):
    """
    Parse ``'<sec>.<9 digits>'`` (what :func:`stamp_text` writes) into integer nanoseconds.

    ValueError naming the problem for anything else: not a string, too long, a sign, spaces,
    underscores, non-ASCII digits, a missing or shorter or longer fraction, a leading zero, or
    seconds beyond what builtin_interfaces/Time holds.
    """
    if not isinstance(text, str):
        raise ValueError(f'a stamp is text, not {type(text).__name__}')
    if len(text) > MAX_STAMP_TEXT:
        raise ValueError(f'stamp is {len(text)} characters long; a stamp has at most '
                         f'{MAX_STAMP_TEXT} (<sec>.<9 digits>)')
    whole, point, frac = text.partition('.')
    if not point or not is_decimal(whole) or len(frac) != 9 or not set(frac) <= _DIGITS:
        raise ValueError(f'stamp {text!r} is not <sec>.<9 digits> in ASCII digits')
    sec = int(whole)
    if sec > MAX_SEC:
        raise ValueError(f'stamp {text!r}: {sec} s is beyond what builtin_interfaces/Time holds '
                         f'({MAX_SEC} s)')
    return sec * NS + int(frac)


def ns_seconds(stamp_ns):
    """Convert nanoseconds to float seconds (for comparisons within a tolerance)."""
    return stamp_ns * 1e-9
