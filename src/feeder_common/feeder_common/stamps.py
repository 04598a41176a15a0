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
the integer nanoseconds of the sample, written and parsed here only.
"""

NS = 1_000_000_000


def stamp_text(stamp_ns):
    """Write integer nanoseconds as exact seconds, ``'<sec>.<9 digits>'``."""
    sec, nsec = divmod(int(stamp_ns), NS)
    return f'{sec}.{nsec:09d}'


def parse_stamp_text(text):
    """
    Parse ``'<sec>[.<fraction>]'`` into integer nanoseconds, exactly; ValueError if malformed.

    Digits past the ninth are dropped (sub-nanosecond).
    """
    whole, _, frac = str(text).strip().partition('.')
    if not whole.isdigit() or (frac and not frac.isdigit()):
        raise ValueError(f'not a time in seconds: {text!r}')
    return int(whole) * NS + int((frac + '000000000')[:9])


def ns_seconds(stamp_ns):
    """Convert nanoseconds to float seconds (for comparisons within a tolerance)."""
    return stamp_ns * 1e-9
