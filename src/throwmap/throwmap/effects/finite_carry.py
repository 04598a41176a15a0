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
Effect finite_carry: a non-impulsive throw along an arm profile theta(t).

Physics: the arm starts horizontal and at rest and turns counterclockwise with constant angular
acceleration a = w^2 / (2 theta_r) until it reaches the release angle theta_r at speed w (the
release speed), after T_c = 2 theta_r / w. During the carry the part must stay in a dynamic
grasp: at every instant the wrench of section III.A.1,
w = theta'' (-(h+d), R, rho^2) + theta'^2 (-R, -(h+d), 0) + (-g sin theta, -g cos theta, 0),
must lie in the contact wrench cone W^i (all four w^T (w_j x w_k) <= 0); it is checked at
accuracy.carry_samples + 1 evenly spaced instants, end points included. A state that fails
is outside the domain (DomainError 'carry_grasp' naming the instant and the constraint).
The cone needs the friction coefficient: contact.mu is required.

At release the part leaves with the arm's rigid motion: CM at Rot(theta_r) (R, h + d), velocity
w z x CM, rotation theta_r and rate w; flight is ballistic (closed form from that state).

The arm's return: with return_time T_r the arm goes from (theta_r, w) back to (0, 0) along
the cubic Hermite curve; the part must clear the moving arm at every sampled instant of
[0, T_r] and may not reach the horizontal arm before T_r (else the throw fails with 'arm_strike':
the model has no impacts with a moving arm). Without return_time the arm is back at once (the
base model's assumption). The catch is on the horizontal arm, unchanged.

Limit: theta_r -> 0 gives the impulsive throw: the release state tends to eqs 5-6 and the
grasp test to the impulse-cone bounds (1)-(4) (both tested).

Scene: throw: {release_speed_deg: 320, carry: {profile: constant_acceleration,
release_angle_deg: 5, return_time: 0.05}}; contact: {mu: 0.8}; effects: [finite_carry].
"""

from dataclasses import dataclass
import math

from ._common import check_keys, number
from ..errors import InputError

NAME = 'finite_carry'
PROFILES = ('constant_acceleration',)
KEYS = {'profile', 'release_angle', 'release_angle_deg', 'return_time'}


@dataclass(frozen=True)
class FiniteCarry:
    profile: str
    release_angle: float    # rad
    return_time: float      # s; 0 means the arm is back at once

    def carry_time(self, w):
        return 2.0 * self.release_angle / w


def parse(carry, mu):
    if carry is None:
        raise InputError('throw.carry', 'missing (effect finite_carry needs it)',
                         'give throw: {carry: {profile: constant_acceleration, '
                         'release_angle_deg: 5}}')
    check_keys(carry, KEYS, 'throw.carry')
    profile = carry.get('profile', 'constant_acceleration')
    if profile not in PROFILES:
        raise InputError('throw.carry.profile', f'unknown profile {profile!r}',
                         f'use one of {", ".join(PROFILES)}')
    theta = number(carry, 'release_angle', 'throw.carry', 'the release angle theta_r > 0',
                   lo=0.0, lo_open=True, hi=math.radians(60),
                   scale_keys=[('release_angle', 1.0),
                               ('release_angle_deg', math.pi / 180.0)])
    if theta is None:
        raise InputError('throw.carry.release_angle_deg', 'missing',
                         'give the release angle theta_r > 0, e.g. release_angle_deg: 5')
    ret = number(carry, 'return_time', 'throw.carry', 'the return time in s (> 0)', lo=0.0,
                 lo_open=True, default=0.0)
    if mu is None:
        raise InputError('contact.mu', 'missing (effect finite_carry checks the wrench cone of '
                         'section III.A.1, which needs the friction coefficient)',
                         'give contact: {mu: ...}, the part/arm Coulomb coefficient')
    return FiniteCarry(profile, theta, ret)
