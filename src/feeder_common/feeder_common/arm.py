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
The arm joint's angle over a cycle, for ``joint_states`` between cycle events (ROS-free).

The controller reports two moments of a cycle: the release (REL, at the release speed w) and
the rest (SENS); the arm is horizontal (angle 0) at both and still between cycles. In between,
the driver and the hardware stand-in publish ``joint_states`` at a steady rate
(``joint_states_rate``) along this profile, so robot_state_publisher and RViz animate the arm.
It is illustrative (the controller reports no angles), and continuous in angle and velocity:

* wind-up, W s before the release: the arm dips back and swings up through 0 at w,
  ``theta = w W (tau^3 - tau^2)``, ``tau = (t - t_release + W) / W`` in [0, 1]; lowest
  ``-4/27 w W`` at tau = 2/3;
* follow-through, F s after it: it rises, stops and comes back to 0 to catch the part,
  ``theta = w F s (1 - s)^2``, ``s = (t - t_release) / F`` in [0, 1]; highest ``4/27 w F`` at
  s = 1/3, velocity w at s = 0 and 0 at s = 1;
* 0 before the wind-up, after the follow-through, and from the rest report on.

The driver takes W and F from the previous cycle (FIRE to REL, REL to SENS; the first cycle
assumes :data:`DEFAULT_PHASE_S` each) and the release speed from REL (until then, the last
one). The stand-in's cycle is instantaneous (release and rest share one stamp): it shows the
follow-through after it, ``F = min(STAND_IN_FOLLOW_S, cycle_period / 2)`` (no wind-up; with the
default 1 s period and the triangle's 5.585 rad/s the arm rises to 0.41 rad and is back at 0
half a second after the release).
"""

DEFAULT_PHASE_S = 0.05      # s: the emulator's default cycle (0.1 s, REL at half)
STAND_IN_FOLLOW_S = 0.5     # s: the longest follow-through the stand-in shows


def stand_in_follow(cycle_period):
    """Return the stand-in's follow-through (s) for its ``cycle_period``."""
    return min(STAND_IN_FOLLOW_S, cycle_period / 2)


def swing(t, release, speed, wind, follow):
    """
    Return (angle rad, velocity rad/s) of the arm at ``t`` (s) for a release at ``release``.

    ``speed`` is the release speed (rad/s), ``wind`` and ``follow`` the lengths (s) of the
    phases before and after it (0: none).
    """
    dt = t - release
    if wind > 0 and -wind <= dt < 0:
        tau = (dt + wind) / wind
        return speed * wind * (tau ** 3 - tau ** 2), speed * (3 * tau ** 2 - 2 * tau)
    if follow > 0 and 0 <= dt <= follow:
        s = dt / follow
        return speed * follow * s * (1 - s) ** 2, speed * (1 - 4 * s + 3 * s ** 2)
    return 0.0, 0.0


class ArmMotion:
    """
    The arm's motion as the cycle events report it; :meth:`at` gives its angle at a time.

    Times are nanoseconds (message stamps). ``fired`` (FIRE sent), ``released`` (REL) and
    ``rested`` (SENS, or the cycle's end) may come in any subset: a missing event leaves the
    arm on the profile's estimate, a rest ends the motion.
    """

    def __init__(self, wind=DEFAULT_PHASE_S, follow=DEFAULT_PHASE_S):
        self.wind = wind
        self.follow = follow
        self.speed = 0.0
        self._fired = None
        self._release = None        # ns of the (expected) release
        self._reported = False      # the release was reported (not only expected)
        self._rest = None

    def fired(self, t_ns):
        """Start a cycle at ``t_ns`` (FIRE): the release is expected ``wind`` s later."""
        self._fired = t_ns
        self._release = t_ns + int(self.wind * 1e9)
        self._reported = False
        self._rest = None

    def released(self, t_ns, speed, follow=None):
        """Release the part at ``t_ns`` at ``speed`` rad/s (REL; ``follow``: its phase, s)."""
        if self._fired is not None and self._rest is None and t_ns > self._fired:
            self.wind = (t_ns - self._fired) / 1e9
        self.speed = float(speed)
        self._release = t_ns
        self._reported = True
        self._rest = None
        if follow is not None:
            self.follow = follow

    def rested(self, t_ns):
        """End the cycle at ``t_ns`` (back at 0); measure the follow-through for the next."""
        if self._reported and self._rest is None and t_ns > self._release:
            self.follow = (t_ns - self._release) / 1e9
        self._rest = t_ns
        self._fired = None

    def at(self, t_ns):
        """Return (angle rad, velocity rad/s) at ``t_ns``."""
        if self._release is None or (self._rest is not None and t_ns >= self._rest):
            return 0.0, 0.0
        return swing(t_ns / 1e9, self._release / 1e9, self.speed, self.wind, self.follow)
