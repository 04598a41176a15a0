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
Compiled core of the throw map: flight, first contact, sticking impacts, rolling, settling.

Written in the subset of Python that numba compiles; with numba absent (or
NUMBA_DISABLE_JIT=1) the very same functions run as plain Python, only slower.

Method (docs/physics.md has the derivations):
* Flight (eqs 5-6) is closed form. The first contact of vertex k is the first root t > 0 of
  F_k(t) = y_k(t) - h. Because |F_k''| <= |g| + w^2 s_k (s_k = distance of V^k from the CM),
  F_k(a) + F_k'(a) tau - M tau^2 / 2 is a lower bound of F_k(a + tau); stepping to its first
  root can never jump over a root of F_k ("conservative advancement"). Steps shrink near a root
  (quadratic convergence) and near a graze; a graze that misses the arm by more than
  M * tol_t^2 / 2 (about 1e-23 m at the default) is stepped over, never taken for a contact.
  The shortest step is tol_t or two units in the last place of t, whichever is longer, so the
  advancement always moves (a tiny tol_t, or a flight of hours, cannot stall it).
* Impacts are sticking (eqs 7-9): angular momentum about the contact vertex is conserved and
  the vertex stops.
* Rolling about a vertex is a rigid pendulum, so which edge lands next and how fast follows from
  energy conservation; no time integration is needed. A landing edge E with the old pivot P and
  the new contact Q scales omega by k = (rho^2 + r_P . r_Q) / (rho^2 + |r_Q|^2); k <= 0 means the
  part stops flat on E (Q cannot turn back through the arm).
"""

import math
import os

import numpy as np

try:  # pragma: no cover - exercised by whichever environment runs the tests
    if os.environ.get('THROWMAP_NO_NUMBA'):
        raise ImportError
    from numba import njit as _njit

    def njit(fn):
        return _njit(cache=True, nogil=True)(fn)

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    def njit(fn):
        return fn

    HAVE_NUMBA = False

# Status codes returned by the kernels (see throwmap.throw.STATUS_MESSAGES).
OK = 0
ERR_EDGE_INDEX = 1
ERR_UNSTABLE_EDGE = 2
ERR_GRASP = 3
ERR_TOE_STUB = 4
ERR_FLIGHT_CAP = 5
ERR_SETTLE_CAP = 6
ERR_NONFINITE = 7

# Columns of the impact record (one row per impact or event).
REC_KIND, REC_VERTEX, REC_EDGE, REC_X, REC_W_BEFORE, REC_W_AFTER, REC_E_BEFORE, REC_E_AFTER, \
    REC_PIVOT, REC_ALPHA0, REC_OMEGA0, REC_ALPHA1, REC_PIVOT_X = range(13)
REC_COLS = 13
EV_FLIGHT_IMPACT = 0      # a vertex hits the arm at the end of flight
EV_LANDING = 1            # rolling brings an edge down; sticking impact at its other vertex
EV_FLAT_LANDING = 2       # an edge lands flat from flight (two-point impact): the part stops
EV_TIP_FROM_REST = 3      # stopped on an unstable edge, the part tips over from rest

HALF_PI = 0.5 * math.pi
# a * TIME_RESOLUTION is at least two units in the last place of a (a > 0 normal), so
# a + a * TIME_RESOLUTION > a always.
TIME_RESOLUTION = 2.0 ** -51


@njit
def flight_height(t, R, w, g, f0, u, v):
    """
    F(t): height over the arm of a vertex at (u, v) in F^i during flight (eqs 5-6).

    f0 = F(0) = d + v, exactly 0 for the two vertices of the resting edge. Written as f0 plus
    terms that vanish at t = 0 (v cos(wt) = v - 2 v sin^2(wt / 2)), so that a short hop keeps
    full relative precision instead of being rounded to units of the last place of d.
    """
    wt = w * t
    sh = math.sin(0.5 * wt)
    return f0 + ((R * w * t + u * math.sin(wt)) + (0.5 * g * t * t - 2.0 * v * sh * sh))


@njit
def _flight_height_rate(t, R, w, g, u, v):
    wt = w * t
    return R * w + g * t + w * (u * math.cos(wt) - v * math.sin(wt))


@njit
def first_vertex_contact(R, w, g, f0, u, v, t_limit, tol_t, max_steps):
    """
    First t in (0, t_limit) with F(t) = 0 and F decreasing, or inf; negative on cap.

    f0 = F(0) >= 0: 0 for the resting edge's vertices, d + v for the others.
    """
    s = math.sqrt(u * u + v * v)
    m = abs(g) + w * w * s
    a = 0.0
    f = f0
    for _ in range(max_steps):
        if a >= t_limit:
            return math.inf
        fp = _flight_height_rate(a, R, w, g, u, v)
        # Shortest step: tol_t, or the spacing of doubles at a when that is coarser (a + tau
        # must move a, else the loop stalls until the cap; late in a long flight, or with a
        # tiny tol_t, the safe step can be smaller than the time resolution).
        t_min = max(tol_t, a * TIME_RESOLUTION)
        if f <= 0.0 and a > 0.0:
            if fp < 0.0:
                return a
            a += t_min   # touching while not approaching: a graze, not an impact
            f = flight_height(a, R, w, g, f0, u, v)
            continue
        sq = math.sqrt(fp * fp + 2.0 * m * f)
        if fp >= 0.0:
            tau = (fp + sq) / m
        else:
            tau = 2.0 * f / (sq - fp)
        if tau <= t_min:
            if fp < 0.0:
                return a + tau
            tau = t_min  # at a tangency the vertex is not approaching: step past it
        a += tau
        f = flight_height(a, R, w, g, f0, u, v)
    return -1.0


@njit
def sticking_impact(rx, ry, xdot, ydot, omega, rho2):
    """
    Return the post-impact (xdot, ydot, omega) of a sticking impact (eqs 7-9).

    The vertex at r = (rx, ry) from the CM stops and angular momentum about it is conserved.
    """
    omega_new = (rho2 * omega - (rx * ydot - ry * xdot)) / (rho2 + rx * rx + ry * ry)
    return ry * omega_new, -rx * omega_new, omega_new


@njit
def _settle_ke_barrier(rho2, lv, d_edge, g_abs):
    return g_abs * (lv - d_edge)


@njit
def _record(rec, nrec, kind, vertex, edge, x, w0, w1, e0, e1, pivot, a0, om0, a1, px):
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


@njit
def settle(p, alpha, omega, xp, n, rho2, g_abs, d, u_l, u_r, stable, edge_len, vrad,
           acw, accw, kcw, kccw, first_stable, max_impacts, rec, nrec):
    """
    Roll about vertex p from angle alpha with rate omega until the part settles.

    alpha is the angle of (CM - V^p) from the arm, omega its rate (CCW positive); xp the
    arm coordinate of V^p. Returns (status, edge, R, rotation during settling, impacts, nrec).
    """
    rotation = 0.0
    impacts = 0
    flat_edge = -1
    flat_left_x = 0.0
    while True:
        if flat_edge >= 0:
            # Resting flat on an unstable edge: tip over the vertex the CM lies beyond.
            j = flat_edge
            if u_r[j] <= 0.0:
                p = (j + 1) % n
                xp = flat_left_x + edge_len[j]
                alpha = accw[p]
            else:
                p = j
                xp = flat_left_x
                alpha = acw[p]
            omega = 0.0
            e_rest = g_abs * d[j]
            nrec = _record(rec, nrec, EV_TIP_FROM_REST, p, j, xp, 0.0, 0.0, e_rest, e_rest,
                           p, alpha, 0.0, alpha, xp)
            flat_edge = -1
        if impacts > max_impacts:
            return ERR_SETTLE_CAP, -1, math.nan, rotation, impacts, nrec
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
            xq = xp + edge_len[j]
            k = kcw[p]
            left_x = xp
        else:
            j = (p - 1) % n
            q = j
            xq = xp - edge_len[j]
            k = kccw[p]
            left_x = xq
        omega_new = k * omega_land
        impacts += 1
        lq = vrad[q]
        continues = omega_new * s > 0.0
        e_after = g_abs * d[j]
        if continues:
            e_after += 0.5 * (rho2 + lq * lq) * omega_new * omega_new
        nrec = _record(rec, nrec, EV_LANDING, q, j, xq, omega_land,
                       omega_new if continues else 0.0, e_before, e_after, p, alpha, omega,
                       target, xp)
        if first_stable and stable[j]:
            return OK, j, left_x - u_l[j], rotation, impacts, nrec
        if not continues:
            if stable[j]:
                return OK, j, left_x - u_l[j], rotation, impacts, nrec
            flat_edge = j
            flat_left_x = left_x
            continue
        if stable[j]:
            # Energy only falls from here; below both tip-over barriers the part cannot leave.
            ke_new = 0.5 * (rho2 + lq * lq) * omega_new * omega_new
            b_q = _settle_ke_barrier(rho2, lq, d[j], g_abs)
            b_p = _settle_ke_barrier(rho2, lp, d[j], g_abs)
            if ke_new <= b_q and ke_new <= b_p:
                return OK, j, left_x - u_l[j], rotation, impacts, nrec
        alpha = accw[q] if s < 0 else acw[q]
        omega = omega_new
        p = q
        xp = xq


@njit
def catch_at_contact(k_best, rot0, rx, ry, x_cm, xdot, ydot, om, e_flight, n, rho2, g_abs, d,
                     u_l, u_r, stable, edge_len, vrad, acw, accw, kcw, kccw, first_stable,
                     flat_tol, max_impacts, rec):
    """
    Catch the part whose vertex k_best has just reached the arm at the end of a flight.

    (rx, ry): that vertex from the CM; (xdot, ydot, om): the CM velocity and spin; x_cm the CM's
    arm coordinate; e_flight the energy per unit mass; rot0 the rotation so far. Sticking
    impact (or a flat two-point landing), then rolling until the part settles. Returns
    (status, edge, R, net rotation, impacts, records written).
    """
    lk = vrad[k_best]
    omega = sticking_impact(rx, ry, xdot, ydot, om, rho2)[2]
    alpha = math.atan2(-ry, -rx)
    a_lo = acw[k_best]
    a_hi = accw[k_best]
    xk = x_cm + rx
    nrec = 0
    if alpha - a_lo <= flat_tol or a_hi - alpha <= flat_tol:
        # The edge on one side of V^k is flat at impact: both of its vertices stick at once.
        if alpha - a_lo <= flat_tol:
            j = k_best
            left_x = xk
            rot = a_lo - alpha
        else:
            j = (k_best - 1) % n
            left_x = xk - edge_len[j]
            rot = a_hi - alpha
        e_rest = g_abs * d[j]
        nrec = _record(rec, nrec, EV_FLAT_LANDING, k_best, j, xk, om, 0.0, e_flight, e_rest,
                       -1, 0.0, 0.0, 0.0, xk)
        if stable[j]:
            return OK, j, left_x - u_l[j], rot0 + rot, 1, nrec
        if u_r[j] <= 0.0:
            p = (j + 1) % n
            xp = left_x + edge_len[j]
            alpha = accw[p]
        else:
            p = j
            xp = left_x
            alpha = acw[p]
        nrec = _record(rec, nrec, EV_TIP_FROM_REST, p, j, xp, 0.0, 0.0, e_rest, e_rest, p,
                       alpha, 0.0, alpha, xp)
        status, j1, r1, rot2, imp, nrec = settle(
            p, alpha, 0.0, xp, n, rho2, g_abs, d, u_l, u_r, stable, edge_len, vrad, acw, accw,
            kcw, kccw, first_stable, max_impacts, rec, nrec)
        return status, j1, r1, rot0 + rot + rot2, imp + 1, nrec
    if alpha < a_lo:
        alpha = a_lo
    elif alpha > a_hi:
        alpha = a_hi
    e_after = 0.5 * (rho2 + lk * lk) * omega * omega + g_abs * lk * math.sin(alpha)
    nrec = _record(rec, nrec, EV_FLIGHT_IMPACT, k_best, -1, xk, om, omega, e_flight, e_after,
                   -1, 0.0, 0.0, 0.0, xk)
    status, j1, r1, rot, imp, nrec = settle(
        k_best, alpha, omega, xk, n, rho2, g_abs, d, u_l, u_r, stable, edge_len, vrad, acw,
        accw, kcw, kccw, first_stable, max_impacts, rec, nrec)
    return status, j1, r1, rot0 + rot, imp + 1, nrec


@njit
def throw_one(edge, R, w, g, h, n, rho2, d, u_l, u_r, stable, edge_len, vrad, acw, accw,
              kcw, kccw, U, V, r_grasp, first_stable, tol_t, flat_tol, max_steps,
              max_impacts, rec):
    """
    One evaluation of the throw map f(edge, R).

    Returns (status, new edge, new R, flight time, net rotation, impacts, first contact vertex,
    records written).
    """
    if edge < 0 or edge >= n:
        return ERR_EDGE_INDEX, -1, math.nan, math.nan, math.nan, 0, -1, 0
    if not stable[edge]:
        return ERR_UNSTABLE_EDGE, -1, math.nan, math.nan, math.nan, 0, -1, 0
    if not (r_grasp[edge] <= R < math.inf):    # (an infinite R: model.domain_error says so)
        return ERR_GRASP, -1, math.nan, math.nan, math.nan, 0, -1, 0
    if not (R + u_l[edge] > 0.0):
        return ERR_TOE_STUB, -1, math.nan, math.nan, math.nan, 0, -1, 0
    g_abs = -g
    di = d[edge]
    t_best = math.inf
    k_best = -1
    right = (edge + 1) % n
    for k in range(n):
        # The resting edge's vertices start exactly on the arm (d + v there is only rounding,
        # up to an ulp of d, which would dominate a short hop); the others strictly above it.
        f0 = 0.0 if (k == edge or k == right) else max(di + V[edge, k], 0.0)
        t = first_vertex_contact(R, w, g, f0, U[edge, k], V[edge, k], t_best, tol_t, max_steps)
        if t < 0.0:
            return ERR_FLIGHT_CAP, -1, math.nan, math.nan, math.nan, 0, -1, 0
        if t < t_best:
            t_best = t
            k_best = k
    T = t_best
    if not math.isfinite(T):
        return ERR_NONFINITE, -1, math.nan, math.nan, math.nan, 0, -1, 0
    phi = w * T
    c = math.cos(phi)
    sn = math.sin(phi)
    uk = U[edge, k_best]
    vk = V[edge, k_best]
    rx = c * uk - sn * vk
    ry = sn * uk + c * vk
    x_cm = R - (h + di) * w * T
    xdot = -(h + di) * w
    ydot = R * w + g * T
    y_rel = di + R * w * T + 0.5 * g * T * T           # CM height over the arm
    e_flight = 0.5 * (xdot * xdot + ydot * ydot + rho2 * w * w) + g_abs * y_rel
    status, j1, r1, rot, imp, nrec = catch_at_contact(
        k_best, phi, rx, ry, x_cm, xdot, ydot, w, e_flight, n, rho2, g_abs, d, u_l, u_r, stable,
        edge_len, vrad, acw, accw, kcw, kccw, first_stable, flat_tol, max_impacts, rec)
    return status, j1, r1, T, rot, imp, k_best, nrec


@njit
def throw_many(edges, radii, w, g, h, n, rho2, d, u_l, u_r, stable, edge_len, vrad, acw, accw,
               kcw, kccw, U, V, r_grasp, first_stable, tol_t, flat_tol, max_steps, max_impacts,
               out_edge, out_r, out_status, out_t, out_rot):
    """Vectorised f over many states (loops compile to machine code; no Python per state)."""
    rec = np.empty((0, REC_COLS))
    for idx in range(edges.shape[0]):
        status, j, r1, t, rot, _, _, _ = throw_one(
            edges[idx], radii[idx], w, g, h, n, rho2, d, u_l, u_r, stable, edge_len, vrad,
            acw, accw, kcw, kccw, U, V, r_grasp, first_stable, tol_t, flat_tol, max_steps,
            max_impacts, rec)
        out_edge[idx] = j
        out_r[idx] = r1
        out_status[idx] = status
        out_t[idx] = t
        out_rot[idx] = rot


@njit
def orbit(edge, R, steps, w, g, h, n, rho2, d, u_l, u_r, stable, edge_len, vrad, acw, accw,
          kcw, kccw, U, V, r_grasp, first_stable, tol_t, flat_tol, max_steps, max_impacts,
          out_edge, out_r, out_rot):
    """Iterate f from (edge, R); returns (status, number of throws done)."""
    rec = np.empty((0, REC_COLS))
    out_edge[0] = edge
    out_r[0] = R
    out_rot[0] = 0.0
    for idx in range(steps):
        status, j, r1, t, rot, _, _, _ = throw_one(
            edge, R, w, g, h, n, rho2, d, u_l, u_r, stable, edge_len, vrad, acw, accw, kcw,
            kccw, U, V, r_grasp, first_stable, tol_t, flat_tol, max_steps, max_impacts, rec)
        if status != OK:
            return status, idx
        out_edge[idx + 1] = j
        out_r[idx + 1] = r1
        out_rot[idx + 1] = rot
        edge = j
        R = r1
    return OK, steps


@njit
def orbit_many(edges, radii, steps, w, g, h, n, rho2, d, u_l, u_r, stable, edge_len, vrad, acw,
               accw, kcw, kccw, U, V, r_grasp, first_stable, tol_t, flat_tol, max_steps,
               max_impacts, out_edge, out_r, out_rot, out_status, out_done):
    """Many orbits at once (basins): out_* have shape (starts, steps + 1)."""
    for s in range(edges.shape[0]):
        status, done = orbit(edges[s], radii[s], steps, w, g, h, n, rho2, d, u_l, u_r, stable,
                             edge_len, vrad, acw, accw, kcw, kccw, U, V, r_grasp, first_stable,
                             tol_t, flat_tol, max_steps, max_impacts, out_edge[s], out_r[s],
                             out_rot[s])
        out_status[s] = status
        out_done[s] = done
