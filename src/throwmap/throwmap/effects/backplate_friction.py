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
Effect backplate_friction: Coulomb drag of the part on the inclined back plate.

Physics (paper section V.B): the back plate is inclined at angle beta from horizontal, so the
in-plane gravity is g = -g0 sin(beta) and the part presses on the plate with m g0 cos(beta),
spread as a uniform pressure over its area. Every area element dA slides on the plate at its own
velocity v(r) = v_cm + omega z x r and feels the Coulomb force -mu_p (m g0 cos(beta) / A)
v / |v| dA. Per unit mass, the drag force is -mu_p g_n <v/|v|> and its torque about the CM is
-mu_p g_n <r x v/|v|>, with g_n = g0 cos(beta) and <.> the area average, evaluated by
quadrature (accuracy.plate_quadrature). |v| -> 0 is regularised as
v / sqrt(|v|^2 + v_reg^2) (accuracy.plate_v_reg, default 1e-4 m/s). While rolling about a
fixed vertex P, v(r) = omega z x (r - P), so the drag is the torque -sign(omega) mu_p g_n
<|r - P|> about P (plus a force, which the pivot takes). For the experiment (beta = 80 deg,
mu_p = 0.1) the drag is 0.1 cot(80 deg) = 1.8 % of the in-plane gravity.

Hooks: ``body_force`` (the drag, in flight and in every contact phase) and ``static_hold``
(near the top of a roll the plate's friction can hold the part balanced on a corner: gravity's
torque about the pivot below the drag's largest torque at rest. The regularised drag would let
it creep off over minutes; at such a turning point the part is turned to the edge of the
holding zone on its CM's side and falls from rest, "the feeder's vibration breaks the tie").
Flight is then no longer ballistic: the event simulator integrates it. mu_p = 0 still runs the
event simulator (with zero drag): that is how the simulator is checked against the closed form
(tested: the base model's edges, |dR| < 1e-9 m).

Scene: plate: {inclination_deg: 80, g0: 9.81, mu: 0.1}; effects: [backplate_friction].
"""

from collections import namedtuple
from dataclasses import dataclass
import math

from ..errors import InputError
from ..jit import njit

NAME = 'backplate_friction'
SCHEMA = {'plate': ('mu',)}
KNOBS = {'plate_quadrature': 4, 'plate_v_reg': 1e-4}

# coef = mu_p g_n (m/s^2); vreg: plate_v_reg; QU, QV: quadrature points in every edge frame
# (n, points); QW: weights (sum 1).
PlateParams = namedtuple('PlateParams', ['coef', 'vreg', 'QU', 'QV', 'QW'])


@dataclass(frozen=True)
class BackplateFriction:
    """Parameters: Coulomb coefficient of part on plate, the plate's pressure per unit mass."""

    mu: float
    g_normal: float     # g0 cos(beta), m/s^2

    @property
    def drag(self):
        """mu_p g_n: the largest drag per unit mass (m/s^2)."""
        return self.mu * self.g_normal


def parse(scene):
    """From the scene's plate section (already validated: g0, inclination)."""
    plate = scene.plate
    if plate is None:
        raise InputError('effects.backplate_friction', 'needs the back plate',
                         'give plate: {inclination_deg: 80, g0: 9.81, mu: 0.1} instead of '
                         'gravity')
    if plate.get('mu') is None:
        raise InputError('plate.mu', 'missing (effect backplate_friction needs it)',
                         'give the part/plate Coulomb coefficient, e.g. mu: 0.1')
    return BackplateFriction(plate['mu'], plate['g_normal'])


def slots(params):
    """Fill body_force (the drag in flight and contact) and static_hold."""
    return ('body_force', 'static_hold')


def bundle(params, part, knobs):
    """Return the compiled parameters: the drag coefficient and the area quadrature."""
    qu, qv, qw = part.area_quadrature(knobs.plate_quadrature)
    return PlateParams(float(params.drag), float(knobs.plate_v_reg), qu, qv, qw)


@njit
def plate_drag(vx, vy, om, phi, qu, qv, qw, coef, vreg):
    """
    Force (fx, fy) and torque about the CM per unit mass of the back plate's Coulomb drag.

    coef = mu_p * g_n: the plate pushes with uniform pressure; every area element feels
    -coef * v / sqrt(|v|^2 + vreg^2) at its own velocity v = v_cm + om z x r. qu, qv, qw:
    quadrature points (body frame of the start edge, from the CM) and weights (sum 1).
    """
    if coef == 0.0:
        return 0.0, 0.0, 0.0
    c = math.cos(phi)
    s = math.sin(phi)
    fx = 0.0
    fy = 0.0
    tq = 0.0
    for k in range(qu.shape[0]):
        rx = c * qu[k] - s * qv[k]
        ry = s * qu[k] + c * qv[k]
        px = vx - om * ry
        py = vy + om * rx
        inv = qw[k] / math.sqrt(px * px + py * py + vreg * vreg)
        fx -= px * inv
        fy -= py * inv
        tq -= (rx * py - ry * px) * inv
    return coef * fx, coef * fy, coef * tq


@njit
def body_force(vx, vy, om, phi, edge, prm):
    """Return the drag on the part moving at (vx, vy, om), at phi from rest on ``edge`` (hook)."""
    return plate_drag(vx, vy, om, phi, prm.QU[edge], prm.QV[edge], prm.QW, prm.coef, prm.vreg)


@njit
def plate_hold(phi, om, bu_p, bv_p, qu, qv, qw, g, coef):
    """
    Return (held, turn): whether plate friction holds the part at rest on pivot p.

    ``turn`` is the rotation about p that brings the CM just past the holding zone on the side
    it leans to.
    """
    c = math.cos(phi)
    s = math.sin(phi)
    cx = -(c * bu_p - s * bv_p)
    cy = -(s * bu_p + c * bv_p)
    dmean = 0.0
    for k in range(qu.shape[0]):
        dx = qu[k] - bu_p
        dy = qv[k] - bv_p
        dmean += qw[k] * math.sqrt(dx * dx + dy * dy)
    reach = coef * dmean / abs(g)       # |c_x| below this: friction outweighs gravity
    if abs(cx) > reach:
        return False, 0.0
    lc = math.sqrt(cx * cx + cy * cy)
    side = cx if cx != 0.0 else -om
    target = math.copysign(min(1.01 * reach, lc), side)
    alpha = math.atan2(cy, cx)
    alpha_new = math.acos(target / lc)
    return True, alpha_new - alpha


@njit
def static_hold(phi, om, turned, size, pu, pv, g, edge, prm):
    """
    Tell whether the plate holds the part on its pivot, and the turn that releases it (hook).

    Looked at a turning point of a roll, or in a creep so slow that the drag is in its
    regularised (viscous) zone on the whole part (|omega| 2 size < v_reg).
    """
    if (turned or abs(om) * 2.0 * size < prm.vreg) and prm.coef > 0.0:
        return plate_hold(phi, om, pu, pv, prm.QU[edge], prm.QV[edge], prm.QW, g, prm.coef)
    return False, 0.0
