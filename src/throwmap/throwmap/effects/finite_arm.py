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
Effect finite_arm: the arm occupies 0 <= x <= L; a part that leaves it is lost.

Physics: the arm surface is the segment from the pivot (x = 0) to the arm's end (x = L, the
experiment's arm is 40 cm). The throw is computed as on an unbounded arm, and the part is
**lost** (it falls off; a documented outcome, not an error) when
* its first contact with the arm line is outside [0, L] (it missed the arm),
* any later contact (a landing vertex, a pivot it rolls or slides over, a corner of an edge
  that lands flat) is outside [0, L] (it rolled or slid off: that vertex has no arm under it),
* it comes to rest with its CM outside [0, L].
The flight and catch report the lowest and highest arm coordinate a vertex touched; a catch that
failed numerically after leaving the arm is lost all the same. A lost throw ends an orbit: f
returns (-1, nan, 'lost'), orbits stop there and say so, basins count the start as 'lost',
design radii treat lost states as leaving the invariant set.

Hook: ``check``. Limit: L -> inf is the base model (nothing is ever lost).

Scene: arm: {offset_cm: -0.5, length_cm: 40}; effects: [finite_arm].
"""

from collections import namedtuple
from dataclasses import dataclass

from ..errors import InputError
from ..jit import njit
from ..status import LOST, OK, REC_X

NAME = 'finite_arm'
SCHEMA = {'arm': ('length', 'length_cm')}
KNOBS = {}

ArmParams = namedtuple('ArmParams', ['length'])


@dataclass(frozen=True)
class FiniteArm:
    """Parameter: the arm's length."""

    length: float   # m


def parse(scene):
    """From arm.length (the scene reads it, in m or cm)."""
    length = scene.arm_length
    if length is None:
        raise InputError('arm.length', 'missing (effect finite_arm needs it)',
                         'give the arm length, e.g. length_cm: 40')
    if not length > 0:
        raise InputError('arm.length', f'must be > 0, got {length!r}', 'give the arm length')
    return FiniteArm(float(length))


def slots(params):
    """Fill check: losing parts."""
    return ('check',)


def bundle(params, part, knobs):
    """Return the compiled parameters."""
    return ArmParams(float(params.length))


@njit
def check(outcome, release, edge, ctx, prm):
    """
    Return LOST if a vertex touched the arm line off [0, L] or the part rests off it (hook).

    outcome.x_lo, x_hi: the lowest and highest arm coordinate a vertex touched. A throw that
    failed after a contact off the arm is lost all the same.
    """
    off = outcome.x_lo < 0.0 or outcome.x_hi > prm.length
    if outcome.status == OK:
        off = off or outcome.R < 0.0 or outcome.R > prm.length
    else:
        off = off and outcome.vertex >= 0
    return LOST if off else outcome.status


def lost_reason(rows, R, params):
    """Say how the part was lost, from the throw's event records."""
    L = params.length
    if len(rows) and not 0 <= rows[0][REC_X] <= L:
        return (f'first contact at x = {rows[0][REC_X] * 100:.2f} cm, off the arm [0, '
                f'{L * 100:g} cm]: the part missed the arm')
    return f'the part rolled or slid off the arm [0, {L * 100:g} cm]'
