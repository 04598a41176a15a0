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
Closed-form throws from any ballistic release state (effects that keep flight ballistic).

kernel.throw_one starts every flight from the impulsive release of eqs 5-6 at theta = 0. The
effects finite_carry (release at theta_r > 0 along an arm profile), release_noise (per-throw w
and h) and finite_arm (a range check) keep the flight ballistic and the catch unchanged, so they
reuse the same machinery from a general release state (x0, y0, phi0, vx, vy, omega):
F_k(t) = y0 - h + vy t + g t^2 / 2 + u_k sin(phi0 + omega t) + v_k cos(phi0 + omega t), with the
same bound |F_k''| <= |g| + omega^2 s_k. The catch is kernel.catch_at_contact, unchanged.

``method`` picks the contact finder: 0 = conservative advancement (exact, never misses), 1 = a
fixed-step scan at ``scan_step`` with bisection to ``root_tol`` (misses any graze shorter than a
step; kept to show what that costs, docs/accuracy.md).
"""

import math

from . import _jitcache  # noqa: F401  (drops stale compiled code first)

from .kernel import catch_at_contact, ERR_FLIGHT_CAP, ERR_NONFINITE, njit, TIME_RESOLUTION

METHOD_ADVANCEMENT = 0
METHOD_SCAN = 1


@njit
def _height(t, f0, vy, g, phi0, om, u, v):
    """
    Return F(t), the vertex height over the arm, as f0 plus terms that vanish at t = 0.

    As kernel.flight_height: a short hop keeps its relative precision instead of being rounded
    to units of the last place of d.
    """
    b = 0.5 * om * t
    sb = math.sin(b)
    mid = phi0 + b
    return f0 + ((vy * t + 2.0 * u * math.cos(mid) * sb)
                 + (0.5 * g * t * t - 2.0 * v * math.sin(mid) * sb))


@njit
def _rate(t, vy, g, phi0, om, u, v):
    ph = phi0 + om * t
    return vy + g * t + om * (u * math.cos(ph) - v * math.sin(ph))


@njit
def advance_contact(f0, vy, g, phi0, om, u, v, t_limit, tol_t, max_steps):
    """
    Return the first t in (0, t_limit) where F falls through 0 (conservative advancement).

    f0 = F(0) >= 0. Returns inf if there is none, -1 at the step cap.
    """
    s = math.sqrt(u * u + v * v)
    m = abs(g) + om * om * s
    a = 0.0
    f = f0
    for _ in range(max_steps):
        if a >= t_limit:
            return math.inf
        fp = _rate(a, vy, g, phi0, om, u, v)
        # as kernel.first_vertex_contact: a step must move a (at least two ulps)
        t_min = max(tol_t, a * TIME_RESOLUTION)
        if f <= 0.0 and a > 0.0:
            if fp < 0.0:
                return a
            a += t_min
            f = _height(a, f0, vy, g, phi0, om, u, v)
            continue
        sq = math.sqrt(fp * fp + 2.0 * m * f)
        if fp >= 0.0:
            tau = (fp + sq) / m
        else:
            tau = 2.0 * f / (sq - fp)
        if tau <= t_min:
            if fp < 0.0:
                return a + tau
            tau = t_min
        a += tau
        f = _height(a, f0, vy, g, phi0, om, u, v)
    return -1.0


@njit
def scan_contact(f0, vy, g, phi0, om, u, v, t_limit, step, root_tol, max_steps):
    """
    Return the first sampled downward crossing of F through 0, refined by bisection.

    Samples every ``step`` seconds, so a dip below the arm shorter than a step goes unseen.
    """
    a = 0.0
    fa = f0
    for _ in range(max_steps):
        if a >= t_limit:
            return math.inf
        b = a + step
        fb = _height(b, f0, vy, g, phi0, om, u, v)
        if fb <= 0.0 and fa > 0.0:
            lo = a
            hi = b
            while hi - lo > root_tol:
                mid = 0.5 * (lo + hi)
                if _height(mid, f0, vy, g, phi0, om, u, v) <= 0.0:
                    hi = mid
                else:
                    lo = mid
            return hi
        a = b
        fa = fb
    return -1.0


@njit
def release_state(edge, R, w, h, theta_r, d):
    """
    Return the release state (x0, y0, phi0, vx, vy, omega) in frame F.

    The part rests on ``edge`` at radius R of an arm at angle theta_r turning at w about the
    pivot (theta_r = 0 is eq 5 at t = 0).
    """
    c = math.cos(theta_r)
    s = math.sin(theta_r)
    px = c * R - s * (h + d[edge])
    py = s * R + c * (h + d[edge])
    return px, py, theta_r, -w * py, w * px, w


@njit
def ballistic_throw(edge, x0, y0, phi0, vx, vy, om, g, h, n, rho2, d, u_l, u_r, stable,
                    edge_len, vrad, acw, accw, kcw, kccw, U, V, first_stable, tol_t, flat_tol,
                    max_steps, max_impacts, method, scan_step, root_tol, rec):
    """
    Flight from a release state, first contact, then kernel.catch_at_contact.

    Returns (status, edge, R, flight time, net rotation, impacts, first contact vertex,
    records written); the records' REC_X columns give every arm coordinate touched.
    """
    g_abs = -g
    t_best = math.inf
    k_best = -1
    yr = y0 - h
    right = (edge + 1) % n
    s0 = math.sin(phi0)
    c0 = math.cos(phi0)
    for k in range(n):
        if phi0 == 0.0 and (k == edge or k == right):
            f0 = 0.0    # the resting edge's vertices start exactly on the arm
        else:
            f0 = max(yr + U[edge, k] * s0 + V[edge, k] * c0, 0.0)
        if method == METHOD_SCAN:
            t = scan_contact(f0, vy, g, phi0, om, U[edge, k], V[edge, k], t_best, scan_step,
                             root_tol, max_steps)
        else:
            t = advance_contact(f0, vy, g, phi0, om, U[edge, k], V[edge, k], t_best, tol_t,
                                max_steps)
        if t < 0.0:
            return ERR_FLIGHT_CAP, -1, math.nan, math.nan, math.nan, 0, -1, 0
        if t < t_best:
            t_best = t
            k_best = k
    T = t_best
    if not math.isfinite(T):
        return ERR_NONFINITE, -1, math.nan, math.nan, math.nan, 0, -1, 0
    phi = phi0 + om * T
    c = math.cos(phi)
    sn = math.sin(phi)
    uk = U[edge, k_best]
    vk = V[edge, k_best]
    rx = c * uk - sn * vk
    ry = sn * uk + c * vk
    x_cm = x0 + vx * T
    xdot = vx
    ydot = vy + g * T
    y_rel = yr + vy * T + 0.5 * g * T * T
    e_flight = 0.5 * (xdot * xdot + ydot * ydot + rho2 * om * om) + g_abs * y_rel
    status, j1, r1, rot, imp, nrec = catch_at_contact(
        k_best, phi, rx, ry, x_cm, xdot, ydot, om, e_flight, n, rho2, g_abs, d, u_l, u_r,
        stable, edge_len, vrad, acw, accw, kcw, kccw, first_stable, flat_tol, max_impacts, rec)
    return status, j1, r1, T, rot, imp, k_best, nrec
