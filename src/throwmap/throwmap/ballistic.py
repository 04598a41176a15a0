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
Ballistic flight from any release state, and THE first-contact finder.

A release state is (x0, y0, phi0, vx, vy, omega) in frame F with y0 the CM's height over the
arm surface and phi0 the rotation from the resting pose on the start edge. The impulsive release
of eqs 5-6 is (R, d, 0, -(h + d) w, R w, w); a finite carry (effect finite_carry) releases
elsewhere. In flight, vertex k (at (u, v) in the start edge's frame F^i) is at height

    F(t) = f0 + vy t + g t^2 / 2 + u0 sin(w t) - 2 v0 sin^2(w t / 2),

with (u0, v0) = Rot(phi0) (u, v) its offset from the CM at release and f0 = F(0). Written as f0
plus terms that vanish at t = 0, a short hop keeps its relative precision instead of being
rounded to units of the last place of d; at phi0 = 0 it is the paper's eq 6 term by term.

The first contact of vertex k is the first root t > 0 of F with F decreasing. Because
|F''| <= |g| + w^2 s (s = distance of V^k from the CM), F(a) + F'(a) tau - M tau^2 / 2 is a lower
bound of F(a + tau); stepping to its first root can never jump over a root of F ("conservative
advancement"). Steps shrink near a root (quadratic convergence) and near a graze; a graze that
misses the arm by more than M tol_t^2 / 2 (about 1e-23 m at the default) is stepped over,
never taken for a contact. The shortest step is tol_t or two units in the last place of t,
whichever is longer, so the advancement always moves (a tiny tol_t, or a flight of hours,
cannot stall it).

accuracy.contact_method 'scan' replaces advancement by a fixed-step scan with bisection: it
misses any dip below the arm shorter than a step, and is kept to show what that costs
(docs/accuracy.md).
"""

import math

from .accuracy import METHOD_SCAN
from .jit import njit
from .status import ERR_FLIGHT_CAP, ERR_NONFINITE, OK

# a * TIME_RESOLUTION is at least two units in the last place of a (a > 0 normal), so
# a + a * TIME_RESOLUTION > a always.
TIME_RESOLUTION = 2.0 ** -51


@njit
def impulsive_release(edge, R, w, h, d):
    """Return the release state of eqs 5-6: (x0, y0 over the arm, phi0, vx, vy, omega)."""
    return R, d[edge], 0.0, -(h + d[edge]) * w, R * w, w


@njit
def flight_height(t, f0, vy, g, om, u0, v0):
    """F(t): height over the arm of a vertex at offset (u0, v0) from the CM at release."""
    wt = om * t
    sh = math.sin(0.5 * wt)
    return f0 + ((vy * t + u0 * math.sin(wt)) + (0.5 * g * t * t - 2.0 * v0 * sh * sh))


@njit
def flight_height_rate(t, vy, g, om, u0, v0):
    """Return F'(t)."""
    wt = om * t
    return vy + g * t + om * (u0 * math.cos(wt) - v0 * math.sin(wt))


@njit(inline=True)
def advancement_step(f, fp, m):
    """
    Return the first root tau > 0 of f + fp tau - m tau^2 / 2, a lower bound of F(a + tau).

    f = F(a) >= 0, fp = F'(a), m >= |F''|: no root of F lies in (a, a + tau).
    """
    sq = math.sqrt(fp * fp + 2.0 * m * f)
    if fp >= 0.0:
        return (fp + sq) / m
    return 2.0 * f / (sq - fp)


@njit
def vertex_contact(f0, vy, g, om, u0, v0, s, t_limit, tol_t, max_steps):
    """
    First t in (0, t_limit) with F(t) = 0 and F decreasing, or inf; -1 at the step cap.

    Conservative advancement (module docstring); f0 = F(0) >= 0, s = |(u0, v0)|.
    """
    m = abs(g) + om * om * s
    a = 0.0
    f = f0
    for _ in range(max_steps):
        if a >= t_limit:
            return math.inf
        fp = flight_height_rate(a, vy, g, om, u0, v0)
        # Shortest step: tol_t, or the spacing of doubles at a when that is coarser (a + tau
        # must move a, else the loop stalls until the cap; late in a long flight, or with a
        # tiny tol_t, the safe step can be smaller than the time resolution).
        t_min = max(tol_t, a * TIME_RESOLUTION)
        if f <= 0.0 and a > 0.0:
            if fp < 0.0:
                return a
            a += t_min   # touching while not approaching: a graze, not an impact
            f = flight_height(a, f0, vy, g, om, u0, v0)
            continue
        tau = advancement_step(f, fp, m)
        if tau <= t_min:
            if fp < 0.0:
                return a + tau
            tau = t_min  # at a tangency the vertex is not approaching: step past it
        a += tau
        f = flight_height(a, f0, vy, g, om, u0, v0)
    return -1.0


@njit
def vertex_contact_scan(f0, vy, g, om, u0, v0, t_limit, step, root_tol, max_steps):
    """
    First sampled downward crossing of F through 0, refined by bisection, or inf; -1 at cap.

    Samples every ``step`` seconds, so a dip below the arm shorter than a step goes unseen.
    """
    a = 0.0
    fa = f0
    for _ in range(max_steps):
        if a >= t_limit:
            return math.inf
        b = a + step
        fb = flight_height(b, f0, vy, g, om, u0, v0)
        if fb <= 0.0 and fa > 0.0:
            lo = a
            hi = b
            while hi - lo > root_tol:
                mid = 0.5 * (lo + hi)
                if flight_height(mid, f0, vy, g, om, u0, v0) <= 0.0:
                    hi = mid
                else:
                    lo = mid
            return hi
        a = b
        fa = fb
    return -1.0


@njit
def vertex_first_contact(f0, vy, g, om, u0, v0, s, t_limit, knobs):
    """
    First t in (0, t_limit) at which a vertex meets the arm moving down, inf if none, -1 at cap.

    By the knobs' contact_method: conservative advancement or the scan.
    """
    if knobs.contact_method == METHOD_SCAN:
        return vertex_contact_scan(f0, vy, g, om, u0, v0, t_limit, knobs.contact_scan_step,
                                   knobs.contact_root_tol, knobs.max_flight_steps)
    return vertex_contact(f0, vy, g, om, u0, v0, s, t_limit, knobs.contact_time_tol,
                          knobs.max_flight_steps)


@njit
def first_contact(edge, y0, phi0, vy, om, g, part, knobs):
    """
    Return (status, flight time, first contact vertex) of the flight from a release state.

    The resting edge's vertices of an impulsive release (phi0 = 0) start exactly on the arm
    (d + v there is only rounding, up to an ulp of d, which would dominate a short hop); the
    others strictly above it.
    """
    U = part.U
    V = part.V
    n = part.n
    right = (edge + 1) % n
    s0 = math.sin(phi0)
    c0 = math.cos(phi0)
    t_best = math.inf
    k_best = -1
    for k in range(n):
        u = U[edge, k]
        v = V[edge, k]
        if phi0 == 0.0 and (k == edge or k == right):
            f0 = 0.0
        else:
            f0 = max(y0 + u * s0 + v * c0, 0.0)
        u0 = u * c0 - v * s0
        v0 = u * s0 + v * c0
        t = vertex_first_contact(f0, vy, g, om, u0, v0, math.sqrt(u * u + v * v), t_best,
                                 knobs)
        if t < 0.0:
            return ERR_FLIGHT_CAP, math.nan, -1
        if t < t_best:
            t_best = t
            k_best = k
    if not math.isfinite(t_best):
        return ERR_NONFINITE, math.nan, -1
    return OK, t_best, k_best


@njit
def state_at(t, edge, k, x0, y0, phi0, vx, vy, om, g, part):
    """
    Return the flight's state at time t, seen from vertex k.

    Returns (rx, ry) of V^k from the CM, the CM's arm coordinate x, its velocity (xdot, ydot),
    the rotation phi, and the energy per unit mass over the arm surface.
    """
    phi = phi0 + om * t
    c = math.cos(phi)
    sn = math.sin(phi)
    uk = part.U[edge, k]
    vk = part.V[edge, k]
    rx = c * uk - sn * vk
    ry = sn * uk + c * vk
    x_cm = x0 + vx * t
    ydot = vy + g * t
    y_rel = y0 + vy * t + 0.5 * g * t * t
    energy = 0.5 * (vx * vx + ydot * ydot + part.rho2 * om * om) - g * y_rel
    return rx, ry, x_cm, vx, ydot, phi, energy
