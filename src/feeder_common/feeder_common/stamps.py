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
Stamps as integer nanoseconds (ROS-free): the range builtin_interfaces/Time holds from 1970 on.

Every stamp in feeder_common is integer nanoseconds (a float would lose the last nanoseconds
of a stamp near 1.8e9 s); feeder_common.messages converts to and from builtin_interfaces/Time
and refuses a Time no sample clock writes (before 1970, or nanosec of 1e9 or more).
"""

NS = 1_000_000_000
# builtin_interfaces/Time: int32 sec; a sample stamp is never before 1970 (sec >= 0).
MAX_SEC = 2**31 - 1
MAX_STAMP_NS = MAX_SEC * NS + NS - 1


def check_stamp_ns(stamp_ns):
    """Return ``stamp_ns`` if it is a stamp builtin_interfaces/Time can hold; else ValueError."""
    if not 0 <= stamp_ns <= MAX_STAMP_NS:
        raise ValueError(f'stamp {stamp_ns} ns is outside [0, {MAX_STAMP_NS}] ns (what '
                         'builtin_interfaces/Time holds from 1970 on)')
    return stamp_ns


def ns_seconds(stamp_ns):
    """Convert nanoseconds to float seconds (for comparisons within a tolerance)."""
    return stamp_ns * 1e-9
