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
-mu_p g_n <r x v/|v|>, with g_n = g0 cos(beta) and <.> the area average. The averages are
exact (accuracy.plate_quadrature 0, the default): the velocity field is a rotation about the
instantaneous centre, and in polar coordinates about it each outline edge's triangle integrates
in closed form (:func:`polar_moments`; checked against an independent implementation and 4M-point
sampling). plate_quadrature >= 1 evaluates them by an area quadrature instead, whose error falls
as 1 / level^2 (docs/accuracy.md: level 4 was the default, 0.05 mm median error in R'). Near
rest the drag is regularised (accuracy.plate_v_reg, default 1e-4 m/s): while the fastest point
moves slower than v_reg the exact drag is scaled by its speed / v_reg (a viscous creep instead
of Coulomb chatter); the quadrature regularises each point as v / sqrt(|v|^2 + v_reg^2).
While rolling about a fixed vertex P, v(r) = omega z x (r - P), so the drag is the torque
-sign(omega) mu_p g_n <|r - P|> about P (plus a force, which the pivot takes). For the
experiment (beta = 80 deg, mu_p = 0.1) the drag is 0.1 cot(80 deg) = 1.8 % of the in-plane
gravity. A plate with mu_p cot(beta) >= 1 is refused at load: its drag could hold the part
still against the in-plane gravity anywhere, in mid-air too, which the model cannot represent.

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

import numpy as np

from ._common import hold_turn
from ..errors import InputError
from ..jit import njit

NAME = 'backplate_friction'
SCHEMA = {'plate': ('mu',)}
KNOBS = {'plate_quadrature': 0, 'plate_v_reg': 1e-4}
# The rk4 flight step (integrator_step's default): the exact drag has kinks, and 2 ms is 7x
# less accurate than 1 ms (docs/accuracy.md). Under picard, the contact search's least step.
FLIGHT_STEP = 1e-3
# The flight a scene with the plate takes unless it names flight_method or integrator_step
# (it keeps those of these knobs it names; session 39): the series flight with pieces graded
# about the drag's singularities, more accurate than rk4 at 1 ms in under half its time
# (docs/accuracy.md, "graded pieces"). Grade 1.5, not 3 (session 41): a piece's error grows
# about as the grade's tenth power, and at 3 the hard parts (a 1 mm plate thrown from 7-13 m,
# a part balanced on a vertex, a nearly unstable edge) were 16-26x worse than rk4 at 1 ms.
FLIGHT_KNOBS = {'flight_method': 'picard', 'flight_step': 0.08, 'flight_tol': 1e-10,
                'flight_grade': 1.5}

# coef = mu_p g_n (m/s^2); vreg: plate_v_reg; QU, QV: quadrature points in every edge frame
# (n, points), QW: weights (sum 1) (plate_quadrature > 0; else one dummy point); exact: the
# closed form (plate_quadrature 0); OU, OV: the outline in every edge frame; CU, CV: the
# centroid's offset from the CM in every edge frame; size: largest vertex distance from the CM.
# MOM: the outline's complex moments in every edge frame (:func:`plate_moments`), for the
# series of a slow spin.
PlateParams = namedtuple('PlateParams', ['coef', 'vreg', 'QU', 'QV', 'QW', 'exact', 'OU', 'OV',
                                         'CU', 'CV', 'size', 'MOM'])
# The exact drag of a slow spin, eps = |omega| size / |v_cm| < SERIES_EPS, is the series of
# :func:`plate_drag_series` to total degree SERIES_ORDER in eps (truncation error below 1e-15
# of mu_p g_n at eps 0.2, the triangle); above it the closed form of :func:`polar_moments`,
# whose cancellation grows as eps falls (1e-14 at 0.2, 1e-10 at 0.01, 20 at 1e-6). Measured
# against the high-precision reference (test_effect_physics: plate_drag_mp, 40 digits).
SERIES_EPS = 0.2
SERIES_ORDER = 18
SERIES_TAIL = (SERIES_ORDER + 1) * math.log(SERIES_EPS)    # ln of the tail's size at SERIES_EPS


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
    in_plane = plate['g0'] * math.sin(math.radians(plate['inclination_deg']))
    ratio = plate['mu'] * plate['g_normal'] / in_plane
    if ratio >= 1.0:
        # The drag (up to mu_p g_n against any motion) would then hold the part still on the
        # plate anywhere, in mid-air too: flight and catch as modelled cannot happen.
        raise InputError('plate.mu', f"mu_p cot(inclination) = {ratio:.3g} >= 1: the plate's "
                         f'Coulomb drag ({plate["mu"] * plate["g_normal"]:.3g} m/s^2) can hold '
                         f'the part against the in-plane gravity ({in_plane:.3g} m/s^2), so it '
                         'would stop on the plate in mid-air; the model cannot represent that',
                         f'give plate.mu < tan(inclination) = {1.0 / ratio * plate["mu"]:.3g}, '
                         'or a steeper plate')
    return BackplateFriction(plate['mu'], plate['g_normal'])


def slots(params):
    """Fill body_force (the drag in flight and contact) and static_hold."""
    return ('body_force', 'static_hold')


def bundle(params, part, knobs):
    """Return the compiled parameters: the drag coefficient, the outline or a quadrature."""
    level = int(knobs.plate_quadrature)
    if level < 0:
        raise InputError('accuracy.plate_quadrature', f'must be >= 0, got {level}',
                         'give 0 (the exact drag, default) or a quadrature level 1..32')
    if level > 0:
        qu, qv, qw = part.area_quadrature(level)
    else:
        qu, qv, qw = np.zeros((part.n, 1)), np.zeros((part.n, 1)), np.ones(1)
    ou, ov, cu, cv = part.outline_frames()
    size = float(part.vertex_radius.max())
    return PlateParams(float(params.drag), float(knobs.plate_v_reg), qu, qv, qw, level == 0,
                       ou, ov, cu, cv, size, plate_moments(ou, ov, size))


def plate_moments(ou, ov, size, order=SERIES_ORDER):
    """
    Return the area averages <w^k conj(w)^l>, w = (u + i v) / size, over each edge frame's outline.

    ou, ov: the outline from the CM in every edge frame (Part.outline_frames), shape (n, m).
    Returns shape (n, order + 1, order + 2), complex. Exact up to rounding: a Gauss-Legendre
    rule in collapsed coordinates over the signed triangles (CM, a, b) integrates these
    polynomials of degree <= 2 order + 1 exactly. Computed in the first frame; the others are
    rotations of it (w_i = w_0 r_i, so their moments are r_i^(k - l) times the first's).
    """
    ou = np.atleast_2d(np.asarray(ou, dtype=float)) / size
    ov = np.atleast_2d(np.asarray(ov, dtype=float)) / size
    x, w = np.polynomial.legendre.leggauss(order + 3)
    x = 0.5 * (x + 1.0)
    w = 0.5 * w
    su, sv = np.meshgrid(x, x, indexing='ij')          # u: out from the CM; v: along the edge
    wt = (np.outer(w, w) * su).ravel()
    a = ou[0] + 1j * ov[0]
    b = np.roll(a, -1)
    jac = (a.conj() * b).imag                          # twice each signed triangle's area
    z = (su.ravel()[None, :] * ((1.0 - sv.ravel())[None, :] * a[:, None]
                                + sv.ravel()[None, :] * b[:, None])).ravel()
    wz = (wt[None, :] * jac[:, None]).ravel() / (0.5 * jac.sum())
    powers = np.cumprod(np.vstack([np.ones_like(z), np.tile(z, (order + 1, 1))]), axis=0)
    first = (powers[:order + 1] * wz) @ powers[:order + 2].conj().T
    far = np.argmax(np.abs(a))
    turn = (ou[:, far] + 1j * ov[:, far]) / a[far]     # frame i from frame 0: unit rotations
    turn /= np.abs(turn)
    k = np.arange(order + 1)[:, None]
    m = np.arange(order + 2)[None, :]
    return first[None, :, :] * turn[:, None, None] ** (k - m)[None, :, :]


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


@njit(inline=True)
def twice_area(ou, ov):
    """Twice the outline's signed area (the shoelace sum)."""
    m = ou.shape[0]
    area2 = 0.0
    for k in range(m):
        kn = (k + 1) % m
        area2 += ou[k] * ov[kn] - ou[kn] * ov[k]
    return area2


@njit(inline=True)
def drag_about_centre(mx, my, m3, p0x, p0y, scale, om, area2, c, s):
    """
    Return the drag (fx, fy, torque) in the arm's frame from polar moments about the centre p0.

    (mx, my, m3) as :func:`polar_moments` returns them (or a part of them), in the part's
    frame, which is the arm's turned by phi (c, s its cosine and sine); ``scale`` the drag's
    mu_p g_n. The field turns with om, so the moments' unit field takes its sign.
    """
    sgn = scale * math.copysign(2.0, om) / area2
    gx = -sgn * mx
    gy = -sgn * my
    return c * gx - s * gy, s * gx + c * gy, -sgn * (m3 + p0x * my - p0y * mx)


@njit
def polar_moments(p0x, p0y, xs, ys):
    """
    Area integrals over an outline in polar coordinates about p0, by signed triangles.

    Returns (gx, gy, m3): int z x (r - p0) / |r - p0| dA (the unit field of a rotation about
    p0, counterclockwise) and int |r - p0| dA. Each outline edge's triangle (p0, a, b) is
    closed form: with rho_max(t) = p sec(t - t_n) (p the line's distance from p0, t_n its
    normal's direction), int rho_max^2 / 2 (-sin t, cos t) dt and int rho_max^3 / 3 dt take
    sec, ln(sec + tan) and sec tan, which are algebraic in the ends' distances and positions
    along the line (no trigonometry). A triangle turning clockwise counts negatively.
    Positions along the line times the edge's length: an edge takes one logarithm (of the
    ratio of sec + tan at its ends; at t < 0 as 1 / (sec - tan), without cancellation), two
    square roots (the next vertex's distance, the edge's length) and four divisions.
    """
    gx = 0.0
    gy = 0.0
    m3 = 0.0
    m = xs.shape[0]
    bx = xs[0] - p0x
    by = ys[0] - p0y
    rb = math.sqrt(bx * bx + by * by)
    for k in range(m):
        # the edge from a (vertex k) to b (vertex k + 1); distances carried from one to the next
        ax = bx
        ay = by
        ra = rb
        kn = (k + 1) % m
        bx = xs[kn] - p0x
        by = ys[kn] - p0y
        rb = math.sqrt(bx * bx + by * by)
        ex = xs[kn] - xs[k]
        ey = ys[kn] - ys[k]
        l2 = ex * ex + ey * ey
        cross = ax * by - ay * bx
        if l2 == 0.0 or abs(cross) <= 1e-13 * (ra * ra + rb * rb):
            # p0 on the edge's line (a pivot's own edges): no area, and sec would overflow
            continue
        length = math.sqrt(l2)
        ae = ax * ex + ay * ey
        w = ae / l2
        fx = ax - w * ex            # the foot of p0 on the line, from p0: p times the normal
        fy = ay - w * ey
        ta = ae
        tb = ae + l2                # positions along the line times the edge's length
        if cross < 0.0:             # the triangle turns clockwise: positions count negatively
            ta = -ta
            tb = -tb
        pl = abs(cross)             # p times the length
        la = ra * length
        lb = rb * length
        if ta >= 0.0:
            if tb >= 0.0:
                ratio = (lb + tb) / (la + ta)
            else:
                ratio = pl * pl / ((la + ta) * (lb - tb))
        elif tb >= 0.0:
            ratio = (lb + tb) * (la - ta) / (pl * pl)
        else:
            ratio = (la - ta) / (lb - tb)
        s1 = math.log(ratio)
        p = pl / length
        ps1 = p * s1
        dr = rb - ra
        gx -= 0.5 * (fx * dr + fy * ps1)
        gy += 0.5 * (fx * ps1 - fy * dr)
        m3 += p * ((tb * rb - ta * ra) / length + p * ps1) / 6.0
    return gx, gy, m3


# The binomial series' ratios: (1 + zeta)^(1/2) = sum A_k zeta^k with A_(k+1) = A_k RA[k],
# (1 + conj(zeta))^(-1/2) = sum B_m conj(zeta)^m with B_(m+1) = B_m RB[m] (a table: a division
# per term cost more than the rest of the series).
SERIES_RA = np.array([(0.5 - k) / (k + 1.0) for k in range(64)])
SERIES_RB = np.array([(-0.5 - m) / (m + 1.0) for m in range(64)])


@njit
def plate_drag_series(bx, by, om, size, mom):
    """
    Return the area averages (<u>, <r x u>) of the unit slip direction u for a slow spin.

    In the part's frame, with complex w = r / size and V = bx + i by the CM's velocity, every
    element slides at V (1 + zeta), zeta = c w, c = i omega size / V, so u = (V / |V|)
    (1 + zeta)^(1/2) (1 + conj(zeta))^(-1/2): a double binomial series in zeta, conj(zeta),
    convergent for |zeta| <= eps = |omega| size / |V| < 1, summed to total degree
    ``mom.shape[0] - 1`` over the moments <w^k conj(w)^l> (:func:`plate_moments`). No
    cancellation: this is what the closed form loses digits to when the instantaneous centre
    is far away. Returns (gx, gy, torque about the CM) of <u> (not yet times -mu_p g_n).
    """
    speed = math.hypot(bx, by)
    e_hat = complex(bx / speed, by / speed)
    c = complex(0.0, om * size) / complex(bx, by)
    cc = c.conjugate()
    order = mom.shape[0] - 1
    # A slower spin needs fewer terms: the tail falls as eps^(order + 1), so the degree that
    # keeps it below its size at (SERIES_EPS, SERIES_ORDER) is enough.
    eps = abs(om) * size / speed
    if 0.0 < eps < SERIES_EPS:
        order = min(order, max(2, int(math.ceil(SERIES_TAIL / math.log(eps))) - 1))
    elif eps == 0.0:
        order = 0
    force = 0j
    torque = 0j
    a_k = 1.0
    ck = 1.0 + 0j
    for k in range(order + 1):
        term = a_k * ck
        for m in range(order + 1 - k):
            force += term * mom[k, m]
            torque += term * mom[k, m + 1]
            term *= cc * SERIES_RB[m]
        a_k *= SERIES_RA[k]
        ck *= c
    force *= e_hat
    torque = size * (e_hat * torque).imag
    return force.real, force.imag, torque


@njit
def plate_drag_exact(vx, vy, om, phi, ou, ov, cu, cv, size, mom, coef, vreg):
    """
    Return the same drag as :func:`plate_drag`, integrated exactly (no quadrature).

    The velocity field is a rotation about the instantaneous centre p0 = z x v_cm / om (from
    the CM), so v / |v| = sign(om) z x (r - p0) / |r - p0| and the area averages are
    :func:`polar_moments`; pure translation is the uniform field, and a slow spin (the centre
    farther than size / SERIES_EPS, where the closed form cancels) the series of
    :func:`plate_drag_series` over the moments ``mom``. Regularisation: while the
    fastest point of the part moves slower than vreg the drag is scaled by (its speed / vreg),
    a viscous creep instead of Coulomb chatter at rest (the purpose of plate_v_reg).
    """
    if coef == 0.0:
        return 0.0, 0.0, 0.0
    # Work in the part's frame (rotated by phi): distances and areas do not change.
    c = math.cos(phi)
    s = math.sin(phi)
    bx = c * vx + s * vy
    by = -s * vx + c * vy
    m = ou.shape[0]
    speed = math.sqrt(bx * bx + by * by)
    scale = coef
    if speed <= vreg + abs(om) * size:
        # the fastest point may be slower than vreg (elsewhere it is at least speed - |om| size),
        # or the part at rest (<=: with vreg 0 too)
        vmax2 = 0.0
        for k in range(m):
            wx = bx - om * ov[k]
            wy = by + om * ou[k]
            vmax2 = max(vmax2, wx * wx + wy * wy)
        if vmax2 == 0.0:
            return 0.0, 0.0, 0.0
        if vmax2 < vreg * vreg:
            scale = coef * math.sqrt(vmax2) / vreg
    if abs(om) * size < SERIES_EPS * speed:
        ux, uy, tu = plate_drag_series(bx, by, om, size, mom)
        gx = -scale * ux
        gy = -scale * uy
        return c * gx - s * gy, s * gx + c * gy, -scale * tu
    inv = 1.0 / om
    p0x = -by * inv
    p0y = bx * inv
    mx, my, m3 = polar_moments(p0x, p0y, ou, ov)
    return drag_about_centre(mx, my, m3, p0x, p0y, scale, om, twice_area(ou, ov), c, s)


@njit
def crossing_log_coefficient(vx, vy, om, phi, ou, ov, coef, k):
    """
    Return B = (fx, fy, tq): the drag is B ln|delta| plus a part smooth across edge k.

    delta: the instantaneous centre's signed distance from outline edge k's line, where the
    centre crosses the edge between its ends (at a vertex this does not hold). There
    :func:`polar_moments`' logarithm of edge k holds -2 ln|delta| (ln(p^2) on one side, its
    inverse on the other); times its factors (p, the foot, p^3) B is a polynomial in the
    centre, of order delta^2 (the d^2 ln|d| bend). Along a flight that crosses at t_k,
    ln|delta(t)| = ln|t - t_k| + a smooth function, so B is also the coefficient of
    ln|t - t_k|: subtracted, the drag is smooth through the crossing, and B ln|t - t_k|
    integrates in closed form. The Coulomb drag's (neither the creep's scale nor the slow-spin
    series applies where the centre is on the outline).
    """
    c = math.cos(phi)
    s = math.sin(phi)
    inv = 1.0 / om
    p0x = -(-s * vx + c * vy) * inv
    p0y = (c * vx + s * vy) * inv
    kn = (k + 1) % ou.shape[0]
    ax = ou[k] - p0x
    ay = ov[k] - p0y
    ex = ou[kn] - ou[k]
    ey = ov[kn] - ov[k]
    l2 = ex * ex + ey * ey
    d = (ax * ey - ay * ex) / math.sqrt(l2)     # signed distance: the cross product a x b
    w = (ax * ex + ay * ey) / l2
    fx = ax - w * ex                            # the foot of p0 on the line, from p0
    fy = ay - w * ey
    return drag_about_centre(fy * d, -fx * d, -d * d * d / 3.0, p0x, p0y, coef, om,
                             twice_area(ou, ov), c, s)


@njit
def body_force(vx, vy, om, phi, edge, prm):
    """Return the drag on the part moving at (vx, vy, om), at phi from rest on ``edge`` (hook)."""
    if prm.exact:
        return plate_drag_exact(vx, vy, om, phi, prm.OU[edge], prm.OV[edge], prm.CU[edge],
                                prm.CV[edge], prm.size, prm.MOM[edge], prm.coef, prm.vreg)
    return plate_drag(vx, vy, om, phi, prm.QU[edge], prm.QV[edge], prm.QW, prm.coef, prm.vreg)


@njit
def mean_distance(bu_p, bv_p, qu, qv, qw, ou, ov, exact):
    """<|r - P|>: the area average of the distance from P (exact, or by the quadrature)."""
    if exact:
        return polar_moments(bu_p, bv_p, ou, ov)[2] / (0.5 * twice_area(ou, ov))
    dmean = 0.0
    for k in range(qu.shape[0]):
        dx = qu[k] - bu_p
        dy = qv[k] - bv_p
        dmean += qw[k] * math.sqrt(dx * dx + dy * dy)
    return dmean


@njit
def plate_hold(phi, om, bu_p, bv_p, dmean, g, coef):
    """
    Return (held, turn): whether plate friction holds the part at rest on pivot p.

    dmean: <|r - P|>: friction outweighs gravity while the CM is within coef dmean / |g| of
    the pivot's vertical.
    """
    return hold_turn(phi, om, bu_p, bv_p, coef * dmean / abs(g))


@njit
def static_hold(phi, om, turned, size, pu, pv, g, edge, prm):
    """
    Tell whether the plate holds the part on its pivot, and the turn that releases it (hook).

    Looked at a turning point of a roll, or in a creep so slow that the drag is in its
    regularised (viscous) zone on the whole part (|omega| 2 size < v_reg).
    """
    if (turned or abs(om) * 2.0 * size < prm.vreg) and prm.coef > 0.0:
        dmean = mean_distance(pu, pv, prm.QU[edge], prm.QV[edge], prm.QW, prm.OU[edge],
                              prm.OV[edge], prm.exact)
        return plate_hold(phi, om, pu, pv, dmean, g, prm.coef)
    return False, 0.0
