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

import math

import pytest


def test_quaternion_of_a_yaw():
    from feeder_sim.ros_glue import yaw_quaternion
    for yaw in (-3.0, -1.0, 0.0, 0.5, 3.0):
        qx, qy, qz, qw = yaw_quaternion(yaw)
        assert (qx, qy) == (0.0, 0.0)
        assert math.isclose(qz * qz + qw * qw, 1.0)
        assert math.isclose(2 * math.atan2(qz, qw), yaw)


def test_stamp_text_round_trip():
    from feeder_sim.ros_glue import stamp_from_text, stamp_text
    t = stamp_from_text('1795362335.204302396')
    assert (t.sec, t.nanosec) == (1795362335, 204302396)
    assert stamp_text(t) == '1795362335.204302396'
    assert stamp_from_text(stamp_text(stamp_from_text('3.000000007'))).nanosec == 7
    assert stamp_from_text('12.5').nanosec == 500_000_000
    assert stamp_from_text('7').sec == 7
    for bad in ('', '-1.5', '1.2e3', 'x'):
        with pytest.raises(ValueError):
            stamp_from_text(bad)
