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

"""The arm's swing between cycle events (feeder_common.arm; issue 23, item 5)."""

from feeder_common import arm
import pytest

W = 5.585       # rad/s, the triangle's release speed


def test_the_swing_passes_release_and_rest_continuously():
    wind, follow = 0.04, 0.06
    assert arm.swing(-wind, 0.0, W, wind, follow) == pytest.approx((0.0, 0.0))
    assert arm.swing(-1e-12, 0.0, W, wind, follow) == pytest.approx((0.0, W), abs=1e-9)
    assert arm.swing(0.0, 0.0, W, wind, follow) == pytest.approx((0.0, W))
    assert arm.swing(follow, 0.0, W, wind, follow) == pytest.approx((0.0, 0.0))
    assert arm.swing(-1.0, 0.0, W, wind, follow) == (0.0, 0.0)
    assert arm.swing(1.0, 0.0, W, wind, follow) == (0.0, 0.0)
    # Lowest in the wind-up, highest in the follow-through, as documented.
    ts = [k / 10000 * (wind + follow) - wind for k in range(10001)]
    angles = [arm.swing(t, 0.0, W, wind, follow)[0] for t in ts]
    assert min(angles) == pytest.approx(-4 / 27 * W * wind, rel=1e-3)
    assert max(angles) == pytest.approx(4 / 27 * W * follow, rel=1e-3)
    # The velocity is the angle's derivative (no jumps in between).
    h = 1e-6
    for t in (-0.03, -0.01, 0.01, 0.03, 0.05):
        numeric = (arm.swing(t + h, 0.0, W, wind, follow)[0] -
                   arm.swing(t - h, 0.0, W, wind, follow)[0]) / (2 * h)
        assert arm.swing(t, 0.0, W, wind, follow)[1] == pytest.approx(numeric, rel=1e-4)


def test_the_motion_learns_its_phases_from_the_cycle_events():
    ms = 1_000_000
    m = arm.ArmMotion()
    assert m.at(0) == (0.0, 0.0)                # never fired: at rest
    m.fired(1000 * ms)
    m.released(1030 * ms, W)                    # REL 30 ms after FIRE
    assert m.wind == pytest.approx(0.030)
    assert m.at(1030 * ms) == pytest.approx((0.0, W))
    assert m.at(1040 * ms)[0] > 0
    m.rested(1100 * ms)                         # SENS 70 ms after REL
    assert m.follow == pytest.approx(0.070)
    assert m.at(1100 * ms) == m.at(1200 * ms) == (0.0, 0.0)
    m.fired(2000 * ms)                          # the next cycle: REL expected 30 ms later
    assert m.at(2015 * ms)[0] < 0               # winding up
    assert m.at(2030 * ms) == pytest.approx((0.0, W))
    m.rested(2010 * ms)                         # failed before its REL: at rest, phases kept
    assert m.at(2020 * ms) == (0.0, 0.0) and m.follow == pytest.approx(0.070)


def test_the_stand_in_shows_the_follow_through_only():
    m = arm.ArmMotion(wind=0.0)
    period = 1.0
    m.released(0, W, follow=arm.stand_in_follow(period))
    assert arm.stand_in_follow(period) == 0.5 and arm.stand_in_follow(0.02) == 0.01
    assert m.at(-1) == (0.0, 0.0)
    top = max(m.at(k * 1_000_000)[0] for k in range(0, 600))
    assert top == pytest.approx(4 / 27 * W * 0.5, rel=1e-3)
    assert m.at(500_000_000) == pytest.approx((0.0, 0.0))
