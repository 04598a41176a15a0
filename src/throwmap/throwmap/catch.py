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
The catch in closed form: sticking impact, flat landing, rolling, settling, and the outcome.

Impacts are sticking (eqs 7-9): angular momentum about the contact vertex is conserved and the
vertex stops. Rolling about a vertex is a rigid pendulum, so which edge lands next and how fast
follows from energy conservation; no time integration is needed. A landing edge E with the old
pivot P and the new contact Q scales omega by k = (rho^2 + r_P . r_Q) / (rho^2 + |r_Q|^2);
k <= 0 means the part stops flat on E (Q cannot turn back through the arm).

The pieces the event simulator (throwmap.event_sim) shares live here once: the flat-landing
test (:func:`flat_landing_edge`), the pivot a part tips over from rest (:func:`tip_pivot`), the
settling rule (:func:`stays_on_edge`), and the jog/flip classifier (:func:`is_jog`,
:func:`throw_kind`).
"""

import math

from .bracket import make_crossing, parabola_exit
from .jit import njit
from .status import (ERR_SETTLE_CAP, EV_FLAT_LANDING, EV_FLIGHT_IMPACT, EV_LANDING,
                     EV_LIFTOFF, EV_TIP_FROM_REST, OK)

HALF_PI = 0.5 * math.pi


# --------------------------------------------------------------------------------- outcome
def is_jog(edge0, edge, net_rotation):
    """
    Jog: the same edge after a net rotation of less than half a turn (section III.C).

    Anything else that lands is a flip. Works on scalars and on numpy arrays alike.
    """
    return (edge == edge0) & (abs(net_rotation) < math.pi)


def throw_kind(edge0, edge, net_rotation):
    """Return 'jog' or 'flip' for one throw."""
    return 'jog' if is_jog(edge0, edge, net_rotation) else 'flip'


# --------------------------------------------------------------------------------- pieces
@njit
def sticking_impact(rx, ry, xdot, ydot, omega, rho2):
    """
    Return the post-impact (xdot, ydot, omega) of a sticking impact (eqs 7-9).

    The vertex at r = (rx, ry) from the CM stops and angular momentum about it is conserved.
    """
    omega_new = (rho2 * omega - (rx * ydot - ry * xdot)) / (rho2 + rx * rx + ry * ry)
    return ry * omega_new, -rx * omega_new, omega_new


@njit
def flat_landing_edge(alpha, k, flat_tol, part):
    """
    Return the edge that lies flat when vertex k reaches the arm at angle alpha, else -1.

    alpha is the angle of (CM - V^k) from the arm; the edges on either side of V^k are flat at
    the ends of its rolling range, acw[k] (edge k) and accw[k] (edge k - 1). Within flat_tol
    (accuracy.flat_landing_tol) of an end the edge lands flat: a two-point impact.
    """
    if alpha - part.acw[k] <= flat_tol:
        return k
    if part.accw[k] - alpha <= flat_tol:
        return (k - 1) % part.n
    return -1


@njit
def tip_pivot(j, part):
    """
    Return the vertex a part at rest flat on unstable edge j tips over: the one past its CM.

    Returns (pivot, its offset along the edge from the left vertex, angle of CM - pivot).
    """
    if part.u_r[j] <= 0.0:
        p = (j + 1) % part.n
        return p, part.edge_len[j], part.accw[p]
    return j, 0.0, part.acw[j]


@njit
def stays_on_edge(ke, lq, lp, d_j, g_abs):
    """
    Tell whether, after a landing on stable edge j, the part can never leave it (settling rule).

    Energy only falls from here: with kinetic energy ke (per unit mass) below both tip-over
    barriers, g (l - d_j) over the landing vertex (distance lq from the CM) and the old pivot
    (lp), the part cannot roll over either vertex of j.
    """
    return ke <= g_abs * (lq - d_j) and ke <= g_abs * (lp - d_j)


@njit
def record(rec, nrec, kind, vertex, edge, x, w0, w1, e0, e1, pivot, a0, om0, a1, px):
    """Write one event row (status.REC_*) if there is room; return the count of events."""
    if nrec < rec.shape[0]:
        rec[nrec, 0] = kind
        rec[nrec, 1] = vertex
        rec[nrec, 2] = edge
        rec[nrec, 3] = x
        rec[nrec, 4] = w0
        rec[nrec, 5] = w1
        rec[nrec, 6] = e0
        rec[nrec, 7] = e1
        rec[nrec, 8] = pivot
        rec[nrec, 9] = a0
        rec[nrec, 10] = om0
        rec[nrec, 11] = a1
        rec[nrec, 12] = px
    return nrec + 1


# --------------------------------------------------------------------------------- rolling
@njit
def settle(p, alpha, omega, xp, g_abs, part, knobs, rec, nrec):
    """
    Roll about vertex p from angle alpha with rate omega until the part settles.

    alpha is the angle of (CM - V^p) from the arm, omega its rate (CCW positive); xp the
    arm coordinate of V^p. Returns (status, edge, R, rotation during settling, impacts, records
    written, lowest and highest arm coordinate a vertex touched).
    """
    n = part.n
    d = part.d
    acw = part.acw
    accw = part.accw
    vrad = part.vrad
    rho2 = part.rho2
    first_stable = knobs.first_stable
    rotation = 0.0
    impacts = 0
    flat_edge = -1
    flat_left_x = 0.0
    x_lo = xp
    x_hi = xp
    while True:
        if flat_edge >= 0:
            # Resting flat on an unstable edge: tip over the vertex the CM lies beyond.
            j = flat_edge
            p, offset, alpha = tip_pivot(j, part)
            xp = flat_left_x + offset
            omega = 0.0
            e_rest = g_abs * d[j]
            nrec = record(rec, nrec, EV_TIP_FROM_REST, p, j, xp, 0.0, 0.0, e_rest, e_rest,
                          p, alpha, 0.0, alpha, xp)
            x_lo = min(x_lo, xp)
            x_hi = max(x_hi, xp)
            flat_edge = -1
        if impacts > knobs.max_impacts:
            return ERR_SETTLE_CAP, -1, math.nan, rotation, impacts, nrec, x_lo, x_hi
        lp = vrad[p]
        inertia = rho2 + lp * lp
        if omega < 0.0:
            s = -1
        elif omega > 0.0:
            s = 1
        else:
            c = math.cos(alpha)
            if c > 0.0:
                s = -1
            elif c < 0.0:
                s = 1
            else:   # balanced exactly over the pivot: leave the end it sits at
                s = 1 if alpha <= acw[p] else -1
        target = acw[p] if s < 0 else accw[p]
        lo = min(alpha, target)
        hi = max(alpha, target)
        top = 1.0 if (lo <= HALF_PI <= hi) else max(math.sin(alpha), math.sin(target))
        ke = 0.5 * inertia * omega * omega
        need = g_abs * lp * (top - math.sin(alpha))
        if not (need <= 0.0 or ke > need):
            s = -s   # turns back before the top: falls the other way (no well in between)
            target = acw[p] if s < 0 else accw[p]
        w2 = omega * omega + 2.0 * g_abs * lp * (math.sin(alpha) - math.sin(target)) / inertia
        if w2 < 0.0:
            w2 = 0.0
        omega_land = s * math.sqrt(w2)
        rotation += target - alpha
        e_before = 0.5 * inertia * w2 + g_abs * lp * math.sin(target)
        if s < 0:
            j = p
            q = (p + 1) % n
            xq = xp + part.edge_len[j]
            k = part.kcw[p]
            left_x = xp
        else:
            j = (p - 1) % n
            q = j
            xq = xp - part.edge_len[j]
            k = part.kccw[p]
            left_x = xq
        x_lo = min(x_lo, xq)
        x_hi = max(x_hi, xq)
        omega_new = k * omega_land
        impacts += 1
        lq = vrad[q]
        continues = omega_new * s > 0.0
        e_after = g_abs * d[j]
        if continues:
            e_after += 0.5 * (rho2 + lq * lq) * omega_new * omega_new
        nrec = record(rec, nrec, EV_LANDING, q, j, xq, omega_land,
                      omega_new if continues else 0.0, e_before, e_after, p, alpha, omega,
                      target, xp)
        R = left_x - part.u_l[j]
        if first_stable and part.stable[j]:
            return OK, j, R, rotation, impacts, nrec, x_lo, x_hi
        if not continues:
            if part.stable[j]:
                return OK, j, R, rotation, impacts, nrec, x_lo, x_hi
            flat_edge = j
            flat_left_x = left_x
            continue
        if part.stable[j] and stays_on_edge(0.5 * (rho2 + lq * lq) * omega_new * omega_new, lq,
                                            lp, d[j], g_abs):
            return OK, j, R, rotation, impacts, nrec, x_lo, x_hi
        alpha = accw[q] if s < 0 else acw[q]
        omega = omega_new
        p = q
        xp = xq


@njit
def catch_at_contact(k, rot0, rx, ry, x_cm, xdot, ydot, om, e_flight, g_abs, part, knobs, rec):
    """
    Catch the part whose vertex k has just reached the arm at the end of a flight.

    (rx, ry): that vertex from the CM; (xdot, ydot, om): the CM velocity and spin; x_cm the CM's
    arm coordinate; e_flight the energy per unit mass; rot0 the rotation so far. Sticking
    impact (or a flat two-point landing), then rolling until the part settles. Returns
    (status, edge, R, net rotation, impacts, records written, lowest and highest arm coordinate
    a vertex touched).
    """
    omega = sticking_impact(rx, ry, xdot, ydot, om, part.rho2)[2]
    alpha = math.atan2(-ry, -rx)
    a_lo = part.acw[k]
    a_hi = part.accw[k]
    xk = x_cm + rx
    nrec = 0
    j = flat_landing_edge(alpha, k, knobs.flat_landing_tol, part)
    if j >= 0:
        # The edge on one side of V^k is flat at impact: both of its vertices stick at once.
        if j == k:
            left_x = xk
            rot = a_lo - alpha
        else:
            left_x = xk - part.edge_len[j]
            rot = a_hi - alpha
        e_rest = g_abs * part.d[j]
        nrec = record(rec, nrec, EV_FLAT_LANDING, k, j, xk, om, 0.0, e_flight, e_rest,
                      -1, 0.0, 0.0, 0.0, xk)
        x_lo = min(xk, left_x)
        x_hi = max(xk, left_x + part.edge_len[j])
        if part.stable[j]:
            return OK, j, left_x - part.u_l[j], rot0 + rot, 1, nrec, x_lo, x_hi
        p, offset, alpha = tip_pivot(j, part)
        xp = left_x + offset
        nrec = record(rec, nrec, EV_TIP_FROM_REST, p, j, xp, 0.0, 0.0, e_rest, e_rest, p,
                      alpha, 0.0, alpha, xp)
        status, j1, r1, rot2, imp, nrec, lo, hi = settle(p, alpha, 0.0, xp, g_abs, part, knobs,
                                                         rec, nrec)
        return (status, j1, r1, rot0 + rot + rot2, imp + 1, nrec, min(x_lo, lo),
                max(x_hi, hi))
    if alpha < a_lo:
        alpha = a_lo
    elif alpha > a_hi:
        alpha = a_hi
    lk = part.vrad[k]
    e_after = 0.5 * (part.rho2 + lk * lk) * omega * omega + g_abs * lk * math.sin(alpha)
    nrec = record(rec, nrec, EV_FLIGHT_IMPACT, k, -1, xk, om, omega, e_flight, e_after,
                  -1, 0.0, 0.0, 0.0, xk)
    status, j1, r1, rot, imp, nrec, x_lo, x_hi = settle(k, alpha, omega, xk, g_abs, part, knobs,
                                                        rec, nrec)
    return status, j1, r1, rot0 + rot, imp + 1, nrec, x_lo, x_hi


# --------------------------------------------------------------------------------- pivot force
# Rolling about a pinned vertex P at distance l from the CM (inertia I = rho^2 + l^2 per unit
# mass about P), the energy constant K = omega^2 + 2 |g| l sin(alpha) / I fixes omega at every
# angle. The arm's normal force on the part per unit mass is then (docs/physics.md derives it)
#     N(s) = |g| (1 - l^2 / I) + 3 |g| l^2 s^2 / I - l K s,     s = sin(alpha),
# a convex quadratic in s: its smallest value over a segment is exact in closed form.


@njit
def pivot_normal(s, energy_k, lp, inertia, g_abs):
    """Return the normal force per unit mass at the pivot when sin(alpha) = s (see above)."""
    return (g_abs * (1.0 - lp * lp / inertia) + 3.0 * g_abs * lp * lp * s * s / inertia
            - lp * energy_k * s)


@njit
def roll_force_rates(g, om, lp, inertia):
    """
    Return bounds on |dN/dalpha| and |dFt/dalpha| over a roll about a pinned vertex.

    N and Ft: the arm's normal and tangential force per unit mass (above), as functions of the
    roll angle from a state spinning at om (the CM at lp from the pivot, inertia = rho^2 +
    lp^2 about it). With c, s the cosine and sine of alpha,
    N = |g| - |g| lp^2 c^2 / inertia - om^2 lp s and Ft = |g| lp^2 c s / inertia - om^2 lp c,
    and om^2 = om0^2 - 2 |g| lp (s - s0) / inertia: so |dN/dalpha| <= 2 |g| + om_max^2 lp and
    |dFt/dalpha| <= 3 |g| + om_max^2 lp, om_max^2 <= om0^2 + 4 |g| lp / inertia. A margin
    divided by its bound is a turn within which the force cannot reach zero.
    """
    g_abs = abs(g)
    om2_max = om * om + 4.0 * g_abs * lp / inertia
    return 2.0 * g_abs + om2_max * lp, 3.0 * g_abs + om2_max * lp


@njit
def cone_margin(n, ft, mu, rate_n, rate_ft):
    """
    Return the turn within which a roll's contact stays in the cone |Ft| <= mu N; <= 0 outside.

    The margins N and mu N - |Ft| over bounds on their rates (roll_force_rates): continuous,
    so its zero can be bracketed.
    """
    if math.isinf(mu):
        return n / rate_n
    return min(n / rate_n, (mu * n - abs(ft)) / (mu * rate_n + rate_ft))


@njit
def roll_cone_forces(theta, energy_k, lp, inertia, g_abs):
    """
    Return (N, Ft, dN/dalpha, dFt/dalpha) of a roll about a pinned vertex, no body force.

    N(s) as :func:`pivot_normal` and Ft = l cos(alpha) (3 |g| l s / I - K) (both per unit
    mass, K the energy constant), s = sin(alpha); their second derivatives in alpha are
    bounded by 2 B + |l K| and 4 B + |l K|, B = 3 |g| l^2 / I (:func:`first_cone_exit`).
    """
    s = math.sin(theta)
    c = math.cos(theta)
    b3 = 3.0 * g_abs * lp * lp / inertia
    k = lp * energy_k
    ft = c * (b3 * s - k)
    return (pivot_normal(s, energy_k, lp, inertia, g_abs), ft, c * (2.0 * b3 * s - k),
            b3 * (c * c - s * s) + k * s)


@njit
def _cone_value(u, args):
    # The cone's margin mu N - |Ft| (N for mu = inf) at arc u of a monotone roll.
    theta0, sd, energy_k, lp, inertia, g_abs, mu = args
    n, ft, _, _ = roll_cone_forces(theta0 + sd * u, energy_k, lp, inertia, g_abs)
    return n if math.isinf(mu) else mu * n - abs(ft)


_cone_crossing = make_crossing(_cone_value)


@njit
def first_cone_exit(theta0, sd, length, energy_k, lp, inertia, g_abs, mu, floor, tol):
    """
    Return the first arc u in [0, length] where a roll leaves the cone |Ft| <= mu N, else -1.

    The roll about a pinned vertex without body force runs from alpha = theta0 in the sense sd
    (alpha = theta0 + sd u) along one rate's sign (no turning point inside); N < 0 is outside
    the cone for every mu, and mu = inf asks for N < 0 only. Steps are safe: mu N -+ Ft with
    their derivatives and the bounds on their second derivatives (:func:`roll_cone_forces`)
    bound each margin from below by a parabola, which stays positive for the step. Steps are at
    least ``floor`` (an excursion narrower than that may go unseen); a sign change is refined
    by Illinois regula falsi to ``tol`` (returned: the bracket's right end).
    """
    k = abs(lp * energy_k)
    b3 = abs(3.0 * g_abs * lp * lp / inertia)
    finite = not math.isinf(mu)
    bound_n = 2.0 * b3 + k
    bound = mu * bound_n + 4.0 * b3 + k if finite else bound_n
    args = (theta0, sd, energy_k, lp, inertia, g_abs, mu)
    a = 0.0
    fa = 0.0
    b = 0.0
    while True:
        n, ft, dn, dft = roll_cone_forces(theta0 + sd * b, energy_k, lp, inertia, g_abs)
        fb = mu * n - abs(ft) if finite else n
        if fb <= 0.0:
            if b == 0.0:
                return 0.0
            return _cone_crossing(a, b, fa, fb, tol, 200, args)
        if b >= length:
            return -1.0
        a = b
        fa = fb
        if finite:
            h = min(parabola_exit(mu * n - ft, sd * (mu * dn - dft), bound),
                    parabola_exit(mu * n + ft, sd * (mu * dn + dft), bound))
        else:
            h = parabola_exit(n, sd * dn, bound)
        # (at least a few ulps: a floor below them, a tiny roll_step, must not stall the walk)
        b = min(length, a + max(h, floor, 1e-15 * (1.0 + a)))


@njit
def roll_pieces(alpha, omega, target, lp, inertia, g_abs):
    """
    Split a roll from alpha (rate omega) to target into pieces along which sin(alpha) is monotone.

    Returns (energy constant K, peak sin, whether there is a second piece, the rate's sign on
    the first piece and on the second): the first piece runs from sin(alpha) to the peak, the
    second from the peak down to sin(target). A roll that turns back (omega against the
    direction of target: settle's fall the other way) peaks where omega = 0.
    """
    energy_k = omega * omega + 2.0 * g_abs * lp * math.sin(alpha) / inertia
    direction = 1.0 if target > alpha else -1.0
    s0 = math.sin(alpha)
    s1 = math.sin(target)
    if omega * direction < 0.0:
        peak = min(energy_k * inertia / (2.0 * g_abs * lp), 1.0)
        return energy_k, peak, True, -direction, direction
    if min(alpha, target) <= HALF_PI <= max(alpha, target):
        return energy_k, 1.0, True, direction, direction
    if s1 >= s0:
        return energy_k, s1, False, direction, direction
    return energy_k, s0, True, direction, direction


@njit
def roll_min_normal(alpha, omega, target, lp, rho2, g_abs):
    """Return the smallest normal force per unit mass at the pivot over a roll (exact)."""
    inertia = rho2 + lp * lp
    energy_k, peak, _, _, _ = roll_pieces(alpha, omega, target, lp, inertia, g_abs)
    s_lo = min(math.sin(alpha), math.sin(target))
    s_v = energy_k * inertia / (6.0 * g_abs * lp)    # the parabola's vertex
    s = min(max(s_v, s_lo), peak)
    return pivot_normal(s, energy_k, lp, inertia, g_abs)


@njit
def roll_liftoff(alpha, omega, target, lp, rho2, g_abs):
    """
    Return (alpha, omega) where a roll first needs a pulling force (N < 0), else (nan, nan).

    Along each monotone piece (roll_pieces) the first root of N(s) = 0 in the direction of
    travel; a roll that needs a pull at its start lifts off there.
    """
    inertia = rho2 + lp * lp
    energy_k, peak, two, sg1, sg2 = roll_pieces(alpha, omega, target, lp, inertia, g_abs)
    s0 = math.sin(alpha)
    s1 = math.sin(target)    # (a single piece ends at its peak, sin(target))
    if pivot_normal(s0, energy_k, lp, inertia, g_abs) < 0.0:
        return alpha, omega
    a2 = 3.0 * g_abs * lp * lp / inertia
    c0 = g_abs * (1.0 - lp * lp / inertia)
    disc = lp * lp * energy_k * energy_k - 4.0 * a2 * c0
    if disc <= 0.0:
        return math.nan, math.nan
    root = math.sqrt(disc)
    r1 = (lp * energy_k - root) / (2.0 * a2)
    r2 = (lp * energy_k + root) / (2.0 * a2)
    s_lift = math.nan
    first = True
    if s0 < r1 <= peak:
        s_lift = r1
    elif two and s1 <= r2 < peak:
        s_lift = r2
        first = False
    if math.isnan(s_lift):
        return math.nan, math.nan
    # Which side of the top: the first piece lies on alpha's side, the second on target's.
    side = alpha if first else target
    a_lift = math.asin(min(s_lift, 1.0))
    if side > HALF_PI:
        a_lift = math.pi - a_lift
    w2 = max(energy_k - 2.0 * g_abs * lp * s_lift / inertia, 0.0)
    return a_lift, (sg1 if first else sg2) * math.sqrt(w2)


@njit
def records_min_normal(rec, nrec, vrad, rho2, g_abs):
    """
    Return the smallest pivot normal force over the rolls in a catch's records, inf if none.

    A roll is a landing or liftoff row that names its pivot (the closed-form catch's; the event
    simulator's rows carry none).
    """
    low = math.inf
    for i in range(min(nrec, rec.shape[0])):
        kind = rec[i, 0]
        if kind != EV_LANDING and kind != EV_LIFTOFF:
            continue
        p = rec[i, 8]
        if not p >= 0.0:
            continue
        n = roll_min_normal(rec[i, 9], rec[i, 10], rec[i, 11], vrad[int(p)], rho2, g_abs)
        low = min(low, n)
    return low
