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
Effect air_drag: quadratic air drag on the part, in flight and while it rolls or slides.

Physics: a part moving at v through still air feels F = -1/2 rho_air C_d A |v| v, with A its
frontal area (for a flat part moving in its own plane: its thickness times its width across
the motion). Per unit mass that is a = -k |v| v with k = rho_air C_d A / (2 m), in 1/m.

Model: drag on the CM velocity plus a rotational drag term. The rotational term is the same
quadratic law applied to the part's area elements spinning about the CM: an element at distance
r moves at |omega| r, so the torque per unit mass is -k <r^3> omega |omega|, with <r^3> the area
average over the outline (a uniform lamina; computed once per scene, to 3e-5). Why not the
distributed law for every motion (each element at its own velocity v + omega z x r): it would
put a quadrature loop into the force the integrator evaluates four times per step, for cross
terms between translation and spin that a single frontal area cannot describe anyway; the
split model is exact for pure translation and pure spin, and costs two multiplications.

Hook: ``body_force`` (flight and every contact phase: the event simulator integrates). Limit:
k = 0 (density or C_d zero) fills no hook: the base model bit for bit (tested); small k
converges to it linearly (tested).

Scene: air: {density: 1.2, drag_coefficient: 1.2, frontal_area_cm2: 4, mass_g: 20};
effects: [air_drag].
"""

from collections import namedtuple
from dataclasses import dataclass
import math

import numpy as np

from ._common import check_keys, number
from ..errors import InputError
from ..jit import njit

NAME = 'air_drag'
SCHEMA = {'air': ('density', 'drag_coefficient', 'frontal_area', 'frontal_area_cm2', 'mass',
                  'mass_g')}
KNOBS = {}
# The rk4 flight step a scene with this force takes unless it sets accuracy.integrator_step:
# the drag is smooth, and at 2 ms the throws' error against the reference (rk4 at 5e-5 s) is
# the same as at 1 ms (max 6.9e-14 m over 1,000 states; docs/accuracy.md).
FLIGHT_STEP = 2e-3
# <r^3>: the outline's area quadrature (centroids of level^2 pieces per triangle, an error
# falling as level^-2) at these two levels, extrapolated (Richardson): 3e-5 relative.
QUADRATURE_LEVELS = (8, 16)

# k (1/m): translation, a = -k |v| v; k_spin (m^2): rotation, torque = -k_spin omega |omega|.
AirParams = namedtuple('AirParams', ['k', 'k_spin'])


@dataclass(frozen=True)
class AirDrag:
    """Parameters: air density, drag coefficient, frontal area, the part's mass."""

    density: float          # kg/m^3
    drag_coefficient: float
    frontal_area: float     # m^2
    mass: float             # kg

    @property
    def k(self):
        """rho_air C_d A / (2 m), 1/m: the drag per unit mass is -k |v| v."""
        return self.density * self.drag_coefficient * self.frontal_area / (2.0 * self.mass)


def parse(scene):
    """From the scene's air section."""
    air = scene.section('air')
    check_keys(air, set(SCHEMA['air']), 'air')
    density = number(air, 'density', 'air', 'the air density in kg/m^3 (>= 0)', lo=0.0,
                     default=1.2)
    cd = number(air, 'drag_coefficient', 'air', 'the drag coefficient C_d (>= 0)', lo=0.0)
    if cd is None:
        raise InputError('air.drag_coefficient', 'missing (effect air_drag needs it)',
                         'give the drag coefficient of the part edge-on, e.g. 1.2')
    area = number(air, 'frontal_area', 'air', 'the frontal area (> 0)', lo=0.0, lo_open=True,
                  scale_keys=[('frontal_area', 1.0), ('frontal_area_cm2', 1e-4)])
    if area is None:
        raise InputError('air.frontal_area_cm2', 'missing (effect air_drag needs it)',
                         'give the area the part shows the air: thickness x width, e.g. '
                         'frontal_area_cm2: 4')
    mass = number(air, 'mass', 'air', "the part's mass (> 0)", lo=0.0, lo_open=True,
                  scale_keys=[('mass', 1.0), ('mass_g', 1e-3)])
    if mass is None:
        raise InputError('air.mass_g', 'missing (effect air_drag needs it)',
                         "give the part's mass, e.g. mass_g: 20")
    return AirDrag(density, cd, area, mass)


def slots(params):
    """Fill body_force, unless the drag is zero."""
    return ('body_force',) if params.k > 0.0 else ()


def bundle(params, part, knobs):
    """Return k and k <r^3> (the area average of r^3 about the CM)."""
    coarse, fine = (float(np.sum(qw * np.hypot(qu[0], qv[0]) ** 3))
                    for qu, qv, qw in (part.area_quadrature(n) for n in QUADRATURE_LEVELS))
    r3 = (4.0 * fine - coarse) / 3.0
    return AirParams(float(params.k), float(params.k) * r3)


@njit
def body_force(vx, vy, om, phi, edge, prm):
    """Return the drag force per unit mass and its torque about the CM (hook)."""
    speed = math.sqrt(vx * vx + vy * vy)
    return -prm.k * speed * vx, -prm.k * speed * vy, -prm.k_spin * om * abs(om)
