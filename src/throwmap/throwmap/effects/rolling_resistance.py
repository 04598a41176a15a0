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
Effect rolling_resistance: the foam resists a roll with a torque proportional to the load.

Physics: a corner pressed into the arm's foam dents it; as the part rolls, the dent's front
pushes back harder than its rear, and the normal force's line of action moves ahead of the
corner by a lever b (the coefficient of rolling resistance, a length). The torque about the
corner is b |N| against the roll, whatever the contact's friction does: torque = -b |N|
sign(omega), in every phase with one corner on the arm (rolling or slipping); none flat on an
edge (nothing rolls). At rest on a corner the same torque holds the part while gravity's torque
about the corner is smaller, |g| |c_x| <= b |N| with N = |g| at rest: the CM within b of the
corner's vertical.

Hooks: ``contact_load`` (the simulator solves the contact with this load exactly: it is
affine in N on either side of 0) and ``static_hold`` (the holding zone, left by the turn of
throwmap.effects._common.hold_turn). Limit: b = 0 fills no hook: the base model bit for bit.

Scene: contact: {rolling_resistance_mm: 0.5}; effects: [rolling_resistance].
"""

from collections import namedtuple
from dataclasses import dataclass
import math

from ._common import hold_turn, number
from ..errors import InputError
from ..event_sim import PHASE_FLAT
from ..jit import njit

NAME = 'rolling_resistance'
SCHEMA = {'contact': ('rolling_resistance', 'rolling_resistance_mm')}
KNOBS = {}

RollingParams = namedtuple('RollingParams', ['lever'])


@dataclass(frozen=True)
class RollingResistance:
    """Parameter: the lever b (m) of the normal force ahead of the rolling corner."""

    lever: float


def parse(scene):
    """From the scene's contact section."""
    contact = scene.section('contact')
    lever = number(contact, 'rolling_resistance', 'contact',
                   'the rolling-resistance lever in m (>= 0), e.g. rolling_resistance_mm: 0.5',
                   lo=0.0, scale_keys=[('rolling_resistance', 1.0),
                                       ('rolling_resistance_mm', 1e-3)])
    if lever is None:
        raise InputError('contact.rolling_resistance_mm',
                         'missing (effect rolling_resistance needs it)',
                         'give the lever of the normal force ahead of the rolling corner, '
                         'e.g. rolling_resistance_mm: 0.5')
    return RollingResistance(lever)


def slots(params):
    """Fill contact_load and static_hold, unless the lever is zero."""
    return ('contact_load', 'static_hold') if params.lever > 0.0 else ()


def bundle(params, part, knobs):
    """
    Return the lever; refuse one of the part's own size.

    Below the radius of gyration rho the contact equations stay solvable at every pivot (their
    denominator is at least rho^2 + l^2 - b l > 0); a foam's lever is a fraction of that.
    """
    rho = math.sqrt(part.rho2)
    if params.lever >= rho:
        raise InputError('contact.rolling_resistance_mm',
                         f"{params.lever * 1000:g} mm is not below the part's radius of "
                         f'gyration ({rho * 1000:.3g} mm): that is no rolling resistance',
                         'give the lever of the normal force ahead of the rolling corner, a '
                         'fraction of a millimetre to a few millimetres, e.g. 0.5')
    return RollingParams(float(params.lever))


@njit
def contact_load(phase, n, vslip, om, phi, edge, prm):
    """Return no tangential force and the torque -b |N| sign(omega) about the CM (hook)."""
    if phase == PHASE_FLAT or om == 0.0:
        return 0.0, 0.0
    return 0.0, -math.copysign(prm.lever * abs(n), om)


@njit
def static_hold(phi, om, turned, size, pu, pv, g, edge, prm):
    """Hold the part at a turning point of a roll while its CM is within b of the pivot (hook)."""
    if turned:
        return hold_turn(phi, om, pu, pv, prm.lever)
    return False, 0.0
