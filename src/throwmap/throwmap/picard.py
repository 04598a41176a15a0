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
The event simulator's ``flight_method: picard``: flight as a series about the ballistic flight.

The flight ODE is x'' = (fx, g + fy), phi'' = tq / rho^2 with the body force (fx, fy, tq)
depending on the velocities and phi only. Without the force the flight is the closed-form
ballistic one; the plate's drag is 1.8 % of gravity. So the flight is taken in pieces, and on
each piece the accelerations are sought at NODES Gauss-Legendre nodes: positions and
velocities are the start's plus the twice (once) integrated interpolant of the node
accelerations, exact for the ballistic part. Each sweep evaluates the force along the current
motion: a Picard iteration, the perturbation series about the ballistic flight term by term,
from a predictor (the acceleration and its rate at the previous piece's end). It
contracts by about L h (L the force's Lipschitz constant in the velocities, h the piece). The
last sweep's increment at the piece's end (positions and velocities times h in m, phi times
the part's size), times q / (1 - q) with q its ratio to the increment before, is the series'
remainder: sweeps stop when it is at most ``flight_tol``, and ``fly`` reports the largest over
the pieces. On a piece's first sweep q is not measured yet: Q_SAFETY times the last piece's,
and at least Q_FLOOR (the contraction changes slowly along a flight; the flight's first piece
always takes two sweeps). Stopping on the increment itself would take one sweep more for an
iterate already q times closer. A piece whose sweeps do not contract is quartered.

Converged, a piece is Gauss collocation, of order 2 NODES at its end and NODES + 2 inside it
(positions). The quadrature needs a smooth force: the plate's drag has a kink where the
instantaneous centre of the velocity field crosses the outline (docs/effects.md), so a piece
ends where the centre crosses an edge: looked for at KINK_SAMPLES points of the predicted
motion (there interpolated linearly), then located by regula falsi on the first sweep's
motion. A piece is at most ``flight_step``
long. The error that remains is measured against the rk4 reference (docs/accuracy.md): the
drag is not kinked but goes as d^2 ln|d| in the centre's distance d from an edge, so a piece
that ends at a crossing, or passes close to the outline, is only third order whatever its
nodes. With ``flight_grade`` > 0 the pieces are graded: at most flight_grade times the time
the centre would take to reach the outline at its speed (at KINK_SAMPLES points of the
predicted motion, :func:`first_kink`), not split at a kink until within flight_step / GRADE
of it, each at most 4x the last; and the piece in which a contact falls is solved again to
end at it (inside a piece collocation is of order 7 in positions and 6 in velocities, at its
end of order 10: on the plate the spin at the impact was 1.8e-6 rad/s off the reference's,
3.2e-7 after at grade 3).

Contacts are looked for on the piece's polynomial motion: at points at least
``integrator_step`` apart, farther where every vertex's height, normal velocity and a bound on
its downward acceleration prove that it cannot reach the arm sooner (:func:`safe_step`), and
located by regula falsi (the earliest of the vertices below the arm) to ``contact_root_tol``.

Compiled code may not allocate, so a sweep is generated as straight-line code over the nodes
(:func:`sweep_source`).
"""

import math

import numpy as np

from .bracket import make_crossing, make_first_event, parabola_exit
from .jit import njit
from .status import ERR_NONFINITE, ERR_SIM_CAP, OK

NODES = 5           # Gauss-Legendre nodes per piece (collocation order 10 at a piece's end)
KINK_SAMPLES = 8    # points per piece at which the centre's crossing of an edge is looked for
KINK_MARGIN = 0.1   # a crossing of an edge's line this far (times the edge) past its ends counts
MAX_SWEEPS = 12     # sweeps before a piece is quartered
KINK_SKIP = 1e-3    # a kink this close (times the piece) after a piece's start is not split at
KINK_REACH = 0.25   # how far about the predicted kink the first sweep's motion is searched
KINK_TOL = 1e-5     # s, how exactly a kink is located (a piece's end off it by dt costs ~dt^3)
EPS = 2.220446049250313e-16
Q_SAFETY = 2.0      # a piece's first sweep: its contraction taken as this times the last piece's
Q_FLOOR = 0.01      # ... and at least this (a lucky small ratio must not pass a first sweep)
GRADE = 16.0        # flight_grade > 0: the shortest piece about a kink is flight_step / GRADE


def tables(n=NODES):
    """
    Return the nodes c, the node integrals A1, A2 and the interpolant's monomial matrix VINV.

    On [0, 1] with nodes c_i: l_j the Lagrange basis, l_j(s) = sum_k VINV[k, j] s^k;
    A1[i, j] = int_0^c_i l_j, A2[i, j] = int_0^c_i (c_i - s) l_j(s) ds.
    """
    c, _ = np.polynomial.legendre.leggauss(n)
    c = 0.5 * (c + 1.0)
    vinv = np.linalg.inv(np.vander(c, n, increasing=True))
    k = np.arange(n)
    a1 = np.array([[np.sum(vinv[:, j] * ci ** (k + 1) / (k + 1)) for j in range(n)] for ci in c])
    a2 = np.array([[np.sum(vinv[:, j] * ci ** (k + 2) / ((k + 1) * (k + 2))) for j in range(n)]
                   for ci in c])
    return c, a1, a2, vinv


def _log_moment(k, x):
    """int_0^x s^k ln s ds (x > 0)."""
    return x ** (k + 1) / (k + 1) * (math.log(x) - 1.0 / (k + 1))


def _log_moment_end(k, x):
    """int_0^x s^k ln(1 - s) ds (0 < x <= 1): (1 - u)^k expanded in u = 1 - s."""
    total = 0.0
    for m in range(k + 1):
        coef = math.comb(k, m) * (-1.0) ** m
        # int_{1-x}^{1} u^m ln u du
        lo = 1.0 - x
        f_lo = 0.0 if lo == 0.0 else _log_moment(m, lo)
        total += coef * (_log_moment(m, 1.0) - f_lo)
    return total


def log_tables(n=NODES, at_end=False):
    """
    Return (D1, D2, E1, E2): a piece's corrections for a logarithmic acceleration term.

    On a piece [0, h] with a(t) = G(t) + B(t) ln|t - t_k|, t_k at its start (``at_end``: at
    its end), G and B smooth: interpolating G and B at the nodes (G_j = a_j - B_j ln|t_j -
    t_k|) and integrating B's interpolant against the logarithm exactly gives, at node i,
    int_0^{c_i h} a = h (A1 a + D1 B)_i and int_0^{c_i h} (c_i h - t) a = h^2 (A2 a + D2 B)_i,
    and at the piece's end h (w . a + E1 . B), h^2 (w (1 - c) . a + E2 . B) (A1, A2, w:
    :func:`tables`' and the Gauss weights). ln h cancels: the tables do not depend on h.
    (The drag's B: throwmap.effects.backplate_friction.crossing_log_coefficient.)
    """
    c, a1, a2, vinv = tables(n)
    w = 0.5 * np.polynomial.legendre.leggauss(n)[1]
    mom = _log_moment_end if at_end else _log_moment
    node_log = np.log(1.0 - c) if at_end else np.log(c)
    l1 = np.zeros((n, n))
    l2 = np.zeros((n, n))
    for i, ci in enumerate(c):
        for j in range(n):
            l1[i, j] = sum(vinv[k, j] * mom(k, ci) for k in range(n))
            l2[i, j] = sum(vinv[k, j] * (ci * mom(k, ci) - mom(k + 1, ci)) for k in range(n))
    e1 = np.array([sum(vinv[k, j] * mom(k, 1.0) for k in range(n)) for j in range(n)])
    e2 = np.array([sum(vinv[k, j] * (mom(k, 1.0) - mom(k + 1, 1.0)) for k in range(n))
                   for j in range(n)])
    return (l1 - a1 * node_log, l2 - a2 * node_log, e1 - w * node_log,
            e2 - w * (1.0 - c) * node_log)


def sweep_source(n=NODES):
    """
    Return the source of ``sweep`` and ``dense`` over n nodes (straight-line code).

    sweep(phi, vx, vy, om, h, ax, ay, ao, g, rho2, edge, prm) -> (ax, ay, ao): the
    accelerations at the nodes of the motion whose node accelerations are (ax, ay, ao) (tuples
    of n). dense(q, v, h, a) -> the coefficients (n + 2) of the position in s = t / h.
    linear(a, b, h): a + b t at the nodes of a piece of h.
    increment(new, old, hh): the end value and d/ds of dense(0, 0, h, new - old), hh = h^2.
    """
    c, a1, a2, vinv = tables(n)
    r = repr
    lines = ['def sweep(phi, vx, vy, om, h, ax, ay, ao, g, rho2, edge, prm):',
             '    hh = h * h']
    for i in range(n):
        for name, base, comp in (('u', 'vx', 'ax'), ('v', 'vy', 'ay'), ('o', 'om', 'ao')):
            terms = ' + '.join(f'{r(float(a1[i, j]))} * {comp}[{j}]' for j in range(n))
            lines.append(f'    {name}{i} = {base} + h * ({terms})')
        terms = ' + '.join(f'{r(float(a2[i, j]))} * ao[{j}]' for j in range(n))
        lines.append(f'    p{i} = phi + h * {r(float(c[i]))} * om + hh * ({terms})')
        lines.append(f'    x{i}, y{i}, z{i} = rhs(u{i}, v{i}, o{i}, p{i}, g, rho2, edge, prm)')
    for name, comp in (('x', 'nx'), ('y', 'ny'), ('z', 'nz')):
        lines.append(f'    {comp} = (' + ', '.join(f'{name}{i}' for i in range(n)) + ',)')
    lines.append('    return nx, ny, nz')
    lines.append('')
    lines.append('def dense(q, v, h, a):')
    lines.append('    hh = h * h')
    coefs = ['q', 'h * v']
    for k in range(n):
        terms = ' + '.join(f'{r(float(vinv[k, j]))} * a[{j}]' for j in range(n))
        coefs.append(f'hh * ({terms}) / {float((k + 1) * (k + 2))!r}')
    lines.append('    return (' + ', '.join(coefs) + ',)')
    lines.append('')
    lines.append('def linear(a, b, h):')
    nodes = ', '.join(f'a + b * h * {float(c[i])!r}' for i in range(n))
    lines.append(f'    return ({nodes},)')
    lines.append('')
    # the end values of dense(0, 0, h, new - old) and of its d/ds: the Gauss weights w_j and
    # w_j (1 - c_j), exact as the interpolant's integrals are
    w = 0.5 * np.polynomial.legendre.leggauss(n)[1]
    lines.append('def increment(new, old, hh):')
    for j in range(n):
        lines.append(f'    d{j} = new[{j}] - old[{j}]')
    pos = ' + '.join(f'{r(float(w[j] * (1.0 - c[j])))} * d{j}' for j in range(n))
    vel = ' + '.join(f'{r(float(w[j]))} * d{j}' for j in range(n))
    lines.append(f'    return hh * ({pos}), hh * ({vel})')
    return '\n'.join(lines) + '\n'


@njit
def poly_at(c, s):
    """Value and d/ds of the polynomial sum c[k] s^k."""
    q = 0.0
    dq = 0.0
    for k in range(len(c) - 1, -1, -1):
        dq = dq * s + q
        q = q * s + c[k]
    return q, dq


@njit
def dense_state(cx, cy, cp, s, h):
    """State (x, y, phi, vx, vy, om) at s = t / h of a piece's polynomials."""
    x, dx = poly_at(cx, s)
    y, dy = poly_at(cy, s)
    p, dp = poly_at(cp, s)
    return x, y, p, dx / h, dy / h, dp / h


@njit
def body_velocity(vx, vy, phi):
    """Return the CM's velocity in the body frame of the start edge."""
    c = math.cos(phi)
    s = math.sin(phi)
    return c * vx + s * vy, -s * vx + c * vy


@njit(inline=True)
def body_centre_side(bx, by, om, bu, bv, k):
    """
    Return om times the side of edge k's line (k to k + 1) on which the instantaneous centre lies.

    (bx, by): the CM's velocity in the body frame of the start edge (where bu, bv are); the
    centre is z x v / om from the CM. Times om the value is smooth in the state and changes
    sign where the centre crosses the line (or om changes sign).
    """
    kn = (k + 1) % bu.shape[0]
    return (bu[kn] - bu[k]) * (bx - om * bv[k]) - (bv[kn] - bv[k]) * (-by - om * bu[k])


@njit
def centre_edge(bx, by, om, bu, bv, k):
    """
    Return om times (the side of edge k's line, the position along edge k) of the centre.

    (bx, by): the CM's velocity in the body frame of the start edge (where bu, bv are). The
    instantaneous centre is z x v / om from the CM; the side is the cross product of the edge
    with (centre - vertex k), the position the dot product over the edge's squared length (0
    and 1 at its ends): both times om, so smooth in the state.
    """
    kn = (k + 1) % bu.shape[0]
    ex = bu[kn] - bu[k]
    ey = bv[kn] - bv[k]
    qx = -by - om * bu[k]
    qy = bx - om * bv[k]
    return body_centre_side(bx, by, om, bu, bv, k), (ex * qx + ey * qy) / (ex * ex + ey * ey)


@njit
def centre_side_at(cx, cy, cp, tau, h, bu, bv, k):
    """Return om times (side, position along edge k) of the centre at time tau of a piece."""
    _, _, p, u, v, o = dense_state(cx, cy, cp, tau / h, h)
    bx, by = body_velocity(u, v, p)
    return centre_edge(bx, by, o, bu, bv, k)


@njit(inline=True)
def signed_centre_side(tau, args):
    """Return om times the centre's side of edge k at tau, times ``sign``."""
    cx, cy, cp, h, bu, bv, k, sign = args
    return sign * centre_side_at(cx, cy, cp, tau, h, bu, bv, k)[0]


centre_side_crossing = make_crossing(signed_centre_side)


@njit
def side_root(cx, cy, cp, h, bu, bv, k, a, b, fa, fb, tol):
    """
    Return a time within ``tol`` after the centre crosses edge k's line in [a, b], or -1.

    fa, fb: om times the side at a and b (a sign change: else -1). Regula falsi, Illinois
    (throwmap.bracket), on the side signed to start positive.
    """
    if not ((fa > 0.0 and fb <= 0.0) or (fa < 0.0 and fb >= 0.0)):
        return -1.0
    sign = 1.0 if fa > 0.0 else -1.0
    return centre_side_crossing(a, b, sign * fa, sign * fb, tol, 200,
                                (cx, cy, cp, h, bu, bv, k, sign))


@njit(inline=True)
def turned_velocity(cx, cy, cp, s, h, cl, sl):
    """
    Return the CM's velocity in the body frame, and om, at s = t / h of a piece's polynomials.

    (cl, sl): cos and sin of the phase's linear part cp[0] + cp[1] s. The rest (the body
    force's turn, small over a piece) turns them by its series to the 7th order; beyond 0.1
    rad the cosine and sine are taken whole.
    """
    _, _, p, u, v, o = dense_state(cx, cy, cp, s, h)
    d = p - (cp[0] + cp[1] * s)
    if abs(d) <= 0.1:
        d2 = d * d
        cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0 - d2 / 720.0))
        sd = d * (1.0 - d2 * (1.0 / 6.0 - d2 / 120.0))
        c = cl * cd - sl * sd
        sn = sl * cd + cl * sd
    else:
        c = math.cos(p)
        sn = math.sin(p)
    return c * u + sn * v, -sn * u + c * v, o


@njit
def first_kink(cx, cy, cp, h, bu, bv, t_min, tol, exact=True, reach=0.0, h_min=0.0):
    """
    Return (time, edge) of the centre's first crossing of an edge in (t_min, h), else (h, -1).

    Sampled at KINK_SAMPLES points; a sign change of an edge's side counts where the crossing
    (interpolated linearly between the samples, then, if ``exact``, located to ``tol`` by
    regula falsi) lies on the edge, within KINK_MARGIN of its length. The samples' phases
    turn by a fixed rotation from one to the next (:func:`turned_velocity`).

    ``reach`` > 0 (flight_grade): the time returned is also at most max(h_min, reach r), r
    the least time the centre takes to reach the outline at its speed between two samples so
    far (edge -1 when it ends there).
    """
    n = bu.shape[0]
    p0 = cp[0]
    cl = math.cos(p0)
    sl = math.sin(p0)
    turn = cp[1] / KINK_SAMPLES
    ct = math.cos(turn)
    st = math.sin(turn)
    bxa, bya, oa = turned_velocity(cx, cy, cp, 0.0, h, cl, sl)
    if reach > 0.0:
        pxa, pya, da = centre_distance(bxa, bya, oa, bu, bv)
    r_min = math.inf
    lo = 0.0
    for i in range(1, KINK_SAMPLES + 1):
        hi = h * i / KINK_SAMPLES
        cl, sl = cl * ct - sl * st, sl * ct + cl * st
        bxb, byb, ob = turned_velocity(cx, cy, cp, i / KINK_SAMPLES, h, cl, sl)
        end = hi
        if reach > 0.0:
            pxb, pyb, db = centre_distance(bxb, byb, ob, bu, bv)
            moved = math.sqrt((pxb - pxa) ** 2 + (pyb - pya) ** 2)
            if moved > 0.0:
                r_min = min(r_min, min(da, db) * (hi - lo) / moved)
            end = max(h_min, reach * r_min)
            if end <= lo:
                return end, -1
            if end < hi:
                # the graded end: the crossings looked for up to it
                _, _, pe, ue, ve, ob = dense_state(cx, cy, cp, end / h, h)
                bxb, byb = body_velocity(ue, ve, pe)
            else:
                end = hi
            pxa, pya, da = pxb, pyb, db
        best = end
        best_k = -1
        for k in range(n):
            sa = body_centre_side(bxa, bya, oa, bu, bv, k)
            sb = body_centre_side(bxb, byb, ob, bu, bv, k)
            if not ((sa > 0.0 and sb <= 0.0) or (sa < 0.0 and sb >= 0.0)):
                continue
            _, la = centre_edge(bxa, bya, oa, bu, bv, k)
            _, lb = centre_edge(bxb, byb, ob, bu, bv, k)
            w = sa / (sa - sb)
            along = ((1.0 - w) * la + w * lb) / ((1.0 - w) * oa + w * ob)
            if not (-0.5 <= along <= 1.5):
                continue        # clearly off the edge: the force is smooth there
            if exact:
                b = side_root(cx, cy, cp, h, bu, bv, k, lo, end, sa, sb, tol)
                _, _, p, u, v, o = dense_state(cx, cy, cp, b / h, h)
                bx, by = body_velocity(u, v, p)
                _, along = centre_edge(bx, by, o, bu, bv, k)
                along /= o if o != 0.0 else 1.0
            else:
                b = lo + w * (end - lo)
            if b > t_min and -KINK_MARGIN <= along <= 1.0 + KINK_MARGIN and b < best:
                best = b
                best_k = k
        if best_k >= 0 or end < hi:
            return best, best_k
        lo = hi
        oa = ob
        bxa, bya = bxb, byb
    return h, -1


@njit
def centre_distance(bx, by, om, bu, bv):
    """Return the instantaneous centre (body frame; inf at om 0) and its distance to the edges."""
    if om == 0.0:
        return math.inf, math.inf, math.inf
    px = -by / om
    py = bx / om
    n = bu.shape[0]
    best = math.inf
    for k in range(n):
        kn = (k + 1) % n
        ex = bu[kn] - bu[k]
        ey = bv[kn] - bv[k]
        wx = px - bu[k]
        wy = py - bv[k]
        t = min(max((wx * ex + wy * ey) / (ex * ex + ey * ey), 0.0), 1.0)
        dx = wx - t * ex
        dy = wy - t * ey
        best = min(best, dx * dx + dy * dy)
    return px, py, math.sqrt(best)


@njit
def jerk_at_end(c, h):
    """Return the third derivative in time at s = 1 of sum c[k] s^k, s = t / h."""
    d3 = 0.0
    for k in range(3, len(c)):
        d3 += k * (k - 1) * (k - 2) * c[k]
    return d3 / (h * h * h)


@njit
def acc_at_end(c, h):
    """Return the second derivative in time at s = 1 of sum c[k] s^k, s = t / h."""
    d2 = 0.0
    for k in range(2, len(c)):
        d2 += k * (k - 1) * c[k]
    return d2 / (h * h)


@njit
def safe_step(y, phi, vy, om, bu, bv, skip, acc):
    """
    Return a time within which no vertex (but ``skip``) can reach the arm.

    Vertex k at height h_k >= 0 rising at u_k stays above h_k + u_k t - acc t^2 / 2 while its
    downward acceleration stays below ``acc``: until t = (u_k + sqrt(u_k^2 + 2 acc h_k)) / acc.
    """
    c = math.cos(phi)
    s = math.sin(phi)
    best = math.inf
    for k in range(bu.shape[0]):
        if k == skip:
            continue
        hk = max(y + s * bu[k] + c * bv[k], 0.0)
        uk = vy + om * (c * bu[k] - s * bv[k])
        best = min(best, parabola_exit(hk, uk, acc))
    return best


@njit
def vertex_height(cx, cy, cp, tau, h, bu_k, bv_k):
    """Height over the arm of the vertex (bu_k, bv_k) at time tau of a piece."""
    y, _ = poly_at(cy, tau / h)
    p, _ = poly_at(cp, tau / h)
    return y + math.sin(p) * bu_k + math.cos(p) * bv_k


@njit(inline=True)
def vertex_height_of(tau, args):
    """Return the height over the arm of the vertex (bu_k, bv_k) at tau of a piece."""
    cx, cy, cp, h, bu_k, bv_k = args
    return vertex_height(cx, cy, cp, tau, h, bu_k, bv_k)


vertex_height_crossing = make_crossing(vertex_height_of)


@njit
def vertex_crossing(cx, cy, cp, h, lo, hi, bu_k, bv_k, root, floor=0.0):
    """
    Return a time in (lo, hi] within ``root`` after the vertex's height crosses zero, or -1.

    The height is above ``floor`` at lo and at or below zero at hi (else -1: the caller
    bisects); Illinois regula falsi (throwmap.bracket) keeps the crossing bracketed. A height
    within rounding of zero at lo (a vertex that has just bounced off the arm) is no bracket:
    its rounding noise holds crossings of its own, where regula falsi would stop.
    """
    fa = vertex_height(cx, cy, cp, lo, h, bu_k, bv_k)
    fb = vertex_height(cx, cy, cp, hi, h, bu_k, bv_k)
    if not (fa > floor and fb <= 0.0):
        return -1.0
    return vertex_height_crossing(lo, hi, fa, fb, root, 100, (cx, cy, cp, h, bu_k, bv_k))


@njit
def contact_near_end(cx, cy, cp, h, bu_k, bv_k, root):
    """
    Return the time the vertex (bu_k, bv_k) reaches the arm near the end h of a piece, or -1.

    Bracketed within w = max(1e-6 s, 4 root) of h (the polynomials reach a little past the
    piece), then 10 w; -1 if neither holds the crossing (the caller keeps the piece before).
    """
    w = max(1e-6, 4.0 * root)
    for _ in range(2):
        a = max(0.0, h - w)
        b = h + w
        if (vertex_height(cx, cy, cp, a, h, bu_k, bv_k) > 0.0
                and vertex_height(cx, cy, cp, b, h, bu_k, bv_k) <= 0.0):
            return vertex_crossing(cx, cy, cp, h, a, b, bu_k, bv_k, root)
        w *= 10.0
    return -1.0


def make_flight(rhs, lowest_approaching, arm_contact, n=NODES, graded=False):
    """
    Return the compiled Picard flight over the accelerations ``rhs`` (event_sim.build's).

    ``lowest_approaching`` and ``arm_contact`` are the event simulator's contact tests
    (throwmap.event_sim). ``graded``: the flight of flight_grade > 0 (graded pieces, the contact
    piece solved again), else flight_grade is not read. Two flights, not one with a branch on
    the knob: the graded code in the ungraded flight's loop made it 7-9 % slower (session 39).

    ``fly(x, y, phi, vx, vy, om, t, sep, sep_rising, g, rho2, bu, bv, ou, ov, size, edge, prm,
    knobs, steps)`` flies until a vertex (bu, bv: the hull's, in the start edge's frame) meets
    the arm moving down; its pieces end where the instantaneous centre crosses an edge of the
    outline (ou, ov: the part's outline, whose notches the hull skips) and, graded, where it
    nears one. Returns (status, vertex, x, y, phi, vx, vy, om, t, steps, evaluations, remainder):
    the state at the crossing, the force evaluations made and the largest remainder estimate
    of a piece's series (m).
    """
    space = {'rhs': rhs}
    exec(compile(sweep_source(n), '<picard sweep>', 'exec'), space)  # noqa: S102
    sweep = njit(cache=False)(space['sweep'])
    dense = njit(cache=False)(space['dense'])
    increment = njit(cache=False)(space['increment'])
    linear = njit(cache=False)(space['linear'])

    @njit(cache=False, inline=True)
    def contact_at(tau, args):
        """Return the vertex at or below the arm and moving down at tau of a piece, if any."""
        cx, cy, cp, h, bu, bv, sep = args
        xs, ys, ps, us, vs, os_ = dense_state(cx, cy, cp, tau / h, h)
        k, _ = lowest_approaching(xs, ys, ps, us, vs, os_, bu, bv, sep)
        return (1 if k >= 0 else 0), k

    contact_in_piece = make_first_event(contact_at)

    @njit(cache=False)
    def piece(x, y, phi, vx, vy, om, h, a0x, a0y, a0o, dax, day, dao, g, rho2, ou, ov, size,
              edge, prm, tol, root, q_prev, reach, h_min):
        """
        Solve one piece from its start state, from the predictor a0 + da t of the accelerations.

        Returns (ok, h, cx, cy, cp, evaluations, remainder, q): the piece, ended at the first
        kink of the force, where the centre crosses an edge of the outline (ou, ov; found on
        the predicted motion, then located on the first sweep's);
        ok False when the sweeps did not converge; q the sweeps' contraction measured on this
        piece (q_prev, the last piece's, when it took one sweep).
        """
        ax = linear(a0x, dax, h)
        ay = linear(a0y, day, h)
        ao = linear(a0o, dao, h)
        t_min = max(64.0 * root, KINK_SKIP * h)
        kink_tol = max(root, KINK_TOL)
        h_max = h
        cx = dense(x, vx, h, ax)
        cy = dense(y, vy, h, ay)
        cp = dense(phi, om, h, ao)
        # the predicted motion's end: a kink, or (graded) the graded end
        h_end, kink = first_kink(cx, cy, cp, h, ou, ov, t_min, kink_tol, False,
                                 reach if graded else 0.0, h_min)
        if graded and reach > 0.0 and kink >= 0 and h_end > (1.0 + 1.0 / reach) * h_min:
            # graded towards the kink: end where the rest is 1 / reach of the piece
            h_end = h_end * reach / (1.0 + reach)
            kink = -1
        if h_end < h:
            # the predicted accelerations at the shorter piece's nodes
            h = h_end
            ax = linear(a0x, dax, h)
            ay = linear(a0y, day, h)
            ao = linear(a0o, dao, h)
        evals = 0
        prev = math.inf
        rem = math.inf
        for it in range(MAX_SWEEPS):
            nx, ny, no = sweep(phi, vx, vy, om, h, ax, ay, ao, g, rho2, edge, prm)
            evals += n
            # the sweep's increment at the piece's end: positions, and velocities times h
            hh = h * h
            ex, evx = increment(nx, ax, hh)
            ey, evy = increment(ny, ay, hh)
            ep, evp = increment(no, ao, hh)
            inc = abs(ex) + abs(ey) + abs(evx) + abs(evy) + size * (abs(ep) + abs(evp))
            ax, ay, ao = nx, ny, no
            if not (math.isfinite(inc)):
                return (False, h, dense(x, vx, h, ax), dense(y, vy, h, ay),
                        dense(phi, om, h, ao), evals, inc, q_prev)
            if it == 0 and kink >= 0:
                # the predicted kink, located again on the first sweep's motion (near it; the
                # motion's polynomials reach a little past the piece)
                h_ext = min(h_max, (1.0 + KINK_REACH) * h)
                ex_x = dense(x, vx, h_ext, ax)
                ex_y = dense(y, vy, h_ext, ay)
                ex_p = dense(phi, om, h_ext, ao)
                a = (1.0 - KINK_REACH) * h
                fa, _ = centre_side_at(ex_x, ex_y, ex_p, a, h_ext, ou, ov, kink)
                fb, _ = centre_side_at(ex_x, ex_y, ex_p, h_ext, h_ext, ou, ov, kink)
                hk = side_root(ex_x, ex_y, ex_p, h_ext, ou, ov, kink, a, h_ext, fa, fb, kink_tol)
                if hk >= 0.0:
                    _, _, p, u, v, o = dense_state(ex_x, ex_y, ex_p, hk / h_ext, h_ext)
                    bx, by = body_velocity(u, v, p)
                    _, along = centre_edge(bx, by, o, ou, ov, kink)
                    along /= o if o != 0.0 else 1.0
                    if not -KINK_MARGIN <= along <= 1.0 + KINK_MARGIN:
                        hk = -1.0
                if hk < 0.0:
                    hk, kink = first_kink(ex_x, ex_y, ex_p, h_ext, ou, ov, t_min, kink_tol)
                if abs(hk - h) > kink_tol:
                    h = hk
                    prev = math.inf
                    continue
            measured = prev < math.inf and prev > 0.0
            q = inc / prev if measured else max(Q_SAFETY * q_prev, Q_FLOOR)
            rem = inc * q / (1.0 - q) if q < 1.0 else (0.0 if inc == 0.0 else math.inf)
            if rem <= tol:
                return (True, h, dense(x, vx, h, ax), dense(y, vy, h, ay),
                        dense(phi, om, h, ao), evals, rem, q if measured else q_prev)
            if it >= 3 and inc > 0.5 * prev:
                return (False, h, dense(x, vx, h, ax), dense(y, vy, h, ay),
                        dense(phi, om, h, ao), evals, inc, q_prev)
            prev = inc
        return (False, h, dense(x, vx, h, ax), dense(y, vy, h, ay), dense(phi, om, h, ao),
                evals, rem, q_prev)

    @njit(cache=False)
    def fly(x, y, phi, vx, vy, om, t, sep, sep_rising, g, rho2, bu, bv, ou, ov, size, edge, prm,
            knobs, steps):
        H = knobs.flight_step
        dts = knobs.integrator_step
        root = knobs.contact_root_tol
        tol = knobs.flight_tol
        a0x, a0y, a0o = rhs(vx, vy, om, phi, g, rho2, edge, prm)
        dax = 0.0
        day = 0.0
        dao = 0.0
        evals = 1
        worst = 0.0
        h_try = H
        q_prev = 1.0
        reach = knobs.flight_grade if graded else 0.0
        h_min = H / GRADE
        hit = -1
        first = -1
        hi = -1.0
        # graded: the piece that holds the contact is solved again to end at it (to_contact);
        # the first solution is kept in case that fails
        to_contact = -1.0
        kept = dense(0.0, 0.0, 1.0, linear(0.0, 0.0, 1.0))
        kept_x, kept_y, kept_p, kept_h = kept, kept, kept, 1.0
        while True:
            steps += 1
            if steps > knobs.max_sim_steps:
                return ERR_SIM_CAP, -1, x, y, phi, vx, vy, om, t, steps, evals, worst
            ok, h, cx, cy, cp, ne, rem, q_prev = piece(
                x, y, phi, vx, vy, om, h_try, a0x, a0y, a0o, dax, day, dao, g, rho2, ou, ov, size,
                edge, prm, tol, root, q_prev, reach if to_contact < 0.0 else 0.0, h_min)
            evals += ne
            if graded and to_contact >= 0.0:
                if ok and h == to_contact:
                    hi2 = contact_near_end(cx, cy, cp, h, bu[first], bv[first], root)
                    if hi2 > 0.0:
                        hi = hi2
                        worst = max(worst, rem)
                        break
                cx, cy, cp, h = kept_x, kept_y, kept_p, kept_h
                break
            if not ok:
                if not math.isfinite(rem) and h_try <= 64.0 * root:
                    return ERR_NONFINITE, -1, x, y, phi, vx, vy, om, t, steps, evals, worst
                h_try = 0.25 * h
                if h_try <= 64.0 * root:
                    return ERR_NONFINITE, -1, x, y, phi, vx, vy, om, t, steps, evals, worst
                continue
            worst = max(worst, rem)
            # graded: a piece at most 4x the last, so that its samples resolve where to end
            h_try = min(H, 4.0 * h) if graded else H
            x1, y1, p1, vx1, vy1, om1 = dense_state(cx, cy, cp, 1.0, h)
            if not (math.isfinite(y1) and math.isfinite(om1) and math.isfinite(x1)):
                return ERR_NONFINITE, -1, x, y, phi, vx, vy, om, t, steps, evals, worst
            # Contact on the piece's motion: samples at least integrator_step apart, farther
            # where every vertex's height, normal velocity and a bound on its downward
            # acceleration prove that it cannot reach the arm sooner (safe_step).
            acc = 1.25 * max(abs(a0y) + abs(a0o) * size + om * om * size,
                             abs(acc_at_end(cy, h)) + abs(acc_at_end(cp, h)) * size
                             + om1 * om1 * size) + 1e-9
            tau = 0.0
            hit = -1
            lo = 0.0
            xs, ys, ps, us, vs, os_ = x, y, phi, vx, vy, om
            while tau < h:
                lo = tau
                tau = min(h, tau + max(safe_step(ys, ps, vs, os_, bu, bv, sep, acc), dts))
                xs, ys, ps, us, vs, os_ = dense_state(cx, cy, cp, tau / h, h)
                k, sep = arm_contact(xs, ys, ps, us, vs, os_, bu, bv, sep, sep_rising)
                if k >= 0:
                    hit = k
                    break
            if hit < 0:
                x, y, phi, vx, vy, om = x1, y1, p1, vx1, vy1, om1
                t += h
                # the predictor: the piece's acceleration and its slope at its end
                a0x = acc_at_end(cx, h)
                a0y = acc_at_end(cy, h)
                a0o = acc_at_end(cp, h)
                dax = jerk_at_end(cx, h)
                day = jerk_at_end(cy, h)
                dao = jerk_at_end(cp, h)
                continue
            # the earliest crossing of the vertices below the arm at tau (two may cross within
            # one sample interval: a nearly flat landing)
            hi = -1.0
            first = -1
            noise = 16.0 * EPS * (abs(y) + size)     # a height's rounding
            for kv in range(bu.shape[0]):
                if kv == sep or vertex_height(cx, cy, cp, tau, h, bu[kv], bv[kv]) > 0.0:
                    continue
                tk = vertex_crossing(cx, cy, cp, h, lo, tau, bu[kv], bv[kv], root, noise)
                if tk < 0.0:
                    hi = -1.0
                    break
                if hi < 0.0 or tk < hi:
                    hi = tk
                    first = kv
            if hi < 0.0:
                hi, _, hit = contact_in_piece(lo, tau, root, 1, hit, (cx, cy, cp, h, bu, bv, sep))
                first = hit
            if graded and first >= 0 and KINK_SKIP * h < hi < h:
                # graded: the piece again, ending at the contact, where collocation is of
                # order 10 (positions and velocities) where inside it is of order 7 and 6
                kept_x, kept_y, kept_p, kept_h = cx, cy, cp, h
                to_contact = hi
                h_try = hi
                continue
            break
        xe, ye, pe, vxe, vye, ome = dense_state(cx, cy, cp, hi / h, h)
        k2, _ = lowest_approaching(xe, ye, pe, vxe, vye, ome, bu, bv, sep)
        if k2 >= 0:
            hit = k2
        return OK, hit, xe, ye, pe, vxe, vye, ome, t + hi, steps, evals, worst

    return fly
