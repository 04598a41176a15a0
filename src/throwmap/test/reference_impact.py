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
Independent reference for a planar frictional impact: Routh's method in small impulse steps.

Written apart from the library's impact law (which finds every phase change in closed form):
here the impact is followed by brute force, in many equal increments dp of the normal impulse.
In each increment the tangential impulse follows Coulomb's law as it stands at the start of the
increment: -mu sign(u_t) dp while the contact slips; while it sticks, whatever keeps u_t = 0 if
that lies within the cone (else slip starts at the cone's edge). The contact velocity changes by
K (dp_t, dp) with the planar collision matrix K of a rigid lamina. Compression ends when u_n
reaches 0; restitution (Stronge's energetic coefficient e) goes on until the normal impulse has
done total work (1 - e^2) W_c, W_c being the (negative) work of compression. Nothing special is
done when no normal impulse can stop the approach while slipping: the steps simply go on, the
slip dies out, and compression ends later. The error is O(dp); ``steps`` sets dp from the
impulse scale of the impact.

All quantities are per unit mass; the contact normal is +y; r = (rx, ry) is the contact point
from the centre of mass; rho2 the squared radius of gyration.
"""

import math

try:
    from numba import njit
except ImportError:  # pragma: no cover
    def njit(fn):
        """Run as plain Python when numba is absent."""
        return fn


@njit(cache=True)
def _routh_steps(rx, ry, vx, vy, om, rho2, e, mu, steps):
    """Step the impact in ``steps`` equal normal-impulse increments of its impulse scale."""
    inv = 1.0 / rho2
    ktt = 1.0 + ry * ry * inv
    knn = 1.0 + rx * rx * inv
    ktn = -rx * ry * inv
    ut = vx - om * ry
    un = vy + om * rx
    if un >= 0.0:
        return vx, vy, om, 0.0, 0.0
    # Impulse scale: what a frictionless impact needs to stop the approach, and what stopping
    # the slip needs; the impact ends within a small multiple of their sum.
    scale = -un / knn + abs(ut) / ktt + 1e-300
    dp = scale / steps
    pt = 0.0
    pn = 0.0
    work = 0.0
    compressing = True
    target = 0.0
    stuck = False
    for _ in range(100 * steps):
        if stuck:
            lam = -ktn / ktt
            if abs(lam) <= mu:
                rate = lam
            else:
                rate = mu if lam > 0.0 else -mu
                stuck = False
        else:
            rate = -mu if ut > 0.0 else mu
        dpt = rate * dp
        ut_new = ut + ktt * dpt + ktn * dp
        un_new = un + ktn * dpt + knn * dp
        if not stuck and ut != 0.0 and ut_new * ut <= 0.0:
            # The slip dies out within this increment: stick from here (the cone test above
            # decides at the next increment whether sticking can last).
            ut_new = 0.0
            stuck = True
        step_work = 0.5 * (un + un_new) * dp
        if compressing and un_new >= 0.0:
            # Compression ends inside this increment: take the part of it up to u_n = 0.
            frac = -un / (un_new - un)
            work += 0.5 * un * frac * dp
            pt += frac * dpt
            pn += frac * dp
            ut = ut + frac * (ut_new - ut)
            un = 0.0
            compressing = False
            target = work * (1.0 - e * e)
            if e == 0.0:
                break
            continue
        if not compressing and work + step_work >= target:
            # Restitution work reached: the fraction of this increment that completes it.
            a = 0.5 * (un_new - un) / dp
            rem = target - work
            if abs(a) > 0.0:
                disc = un * un + 4.0 * a * rem
                s = (-un + math.sqrt(max(disc, 0.0))) / (2.0 * a)
            else:
                s = rem / un if un > 0.0 else 0.0
            frac = min(max(s / dp, 0.0), 1.0)
            pt += frac * dpt
            pn += frac * dp
            break
        work += step_work
        pt += dpt
        pn += dp
        ut = ut_new
        un = un_new
    return vx + pt, vy + pn, om + (rx * pn - ry * pt) * inv, pt, pn


def routh_impact(rx, ry, vx, vy, om, rho2, e, mu, steps=200_000):
    """
    Return the post-impact (vx, vy, omega) and the impulse (p_t, p_n), by brute force.

    ``mu`` may be large (1e6) but not infinite; the result converges as O(1 / steps).
    """
    vx1, vy1, om1, pt, pn = _routh_steps(float(rx), float(ry), float(vx), float(vy), float(om),
                                         float(rho2), float(e), float(mu), int(steps))
    return (vx1, vy1, om1), (pt, pn)


def sticking_impulse(rx, ry, vx, vy, om, rho2):
    """Impulse (p_t, p_n) of the sticking impact of eqs 7-9 (the contact point stops)."""
    inv = 1.0 / rho2
    ktt = 1.0 + ry * ry * inv
    knn = 1.0 + rx * rx * inv
    ktn = -rx * ry * inv
    ut = vx - om * ry
    un = vy + om * rx
    det = ktt * knn - ktn * ktn
    return -(knn * ut - ktn * un) / det, -(-ktn * ut + ktt * un) / det


def kinetic_energy(vx, vy, om, rho2):
    """Kinetic energy per unit mass of a lamina moving at (vx, vy, omega)."""
    return 0.5 * (vx * vx + vy * vy + rho2 * om * om)
