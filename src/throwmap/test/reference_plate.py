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
Independent reference for the back plate's Coulomb drag on a uniform lamina (no quadrature).

A lamina moving at CM velocity v_c with rate omega has the velocity field of a rotation about
its instantaneous centre p0 = c + z x v_c / omega: v(r) = omega z x (r - p0), so v / |v| is the
unit vector z x (r - p0) / |r - p0| times sign(omega). In polar coordinates (rho, theta) about
p0 the area integrals of the drag over the triangle (p0, A, B) of each outline edge become

    int (-sin t, cos t) rho_max(t)^2 / 2 dt            (force)
    int rho_max(t)^3 / 3 dt  +  (p0 - c) x force part    (torque about the CM)

with rho_max(t) = p sec(t - t_n) the distance to the edge's line (p its distance from p0, t_n
the direction of its normal). Both have closed forms (sec, sec^3): :func:`plate_drag_exact`.
With the regularisation v / sqrt(|v|^2 + v_reg^2) the radial integrals are still closed form
and the angle integral is done adaptively (scipy.integrate.quad): :func:`plate_drag_regularised`.
Signed triangles make this hold for any simple outline, p0 inside it or not. Pure translation
(omega = 0) is the uniform field -v / |v|.

Returns, like the library's drag, the force (fx, fy) and the torque about the CM per unit mass:
the pressure is uniform over the outline (coef = mu_p g_n is the largest drag per unit mass).
"""

import math

import numpy as np


def _area_centroid(pts):
    x, y = pts[:, 0], pts[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = cross.sum() / 2.0
    return area, np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (6.0 * area)


def _edges_about(pts, p0):
    """Per edge: distance p of its line from p0, the angle t_n of the normal, its ends' angles."""
    out = []
    n = len(pts)
    for k in range(n):
        a = pts[k] - p0
        b = pts[(k + 1) % n] - p0
        cross = a[0] * b[1] - a[1] * b[0]
        length = math.hypot(*(b - a))
        if length == 0.0 or cross == 0.0:
            continue        # p0 on the edge's line: the triangle has no area
        # The angle runs from a to b the short way: a triangle (p0, a, b) turning clockwise
        # is integrated backwards and so counts negatively, as the signed decomposition needs.
        p = cross / length
        e = (b - a) / length
        foot = a - (a @ e) * e                # nearest point of the edge's line, from p0
        tn = math.atan2(foot[1], foot[0])
        ta = math.atan2(a[1], a[0])
        tb = ta + math.atan2(cross, a[0] * b[0] + a[1] * b[1])   # the short way round
        out.append((abs(p), tn, ta, tb))
    return out


def _sec_int(phi):
    return math.log(abs(1.0 / math.cos(phi) + math.tan(phi)))


def plate_drag_exact(outline, cm, vx, vy, om, coef):
    """
    Exact Coulomb drag of the plate (no regularisation): force and torque per unit mass.

    ``outline``: (n, 2) vertices (counterclockwise, world frame); ``cm``: the centre of mass;
    (vx, vy, om): the CM velocity and rate. Undefined at total rest; there it returns zeros.
    """
    pts = np.asarray(outline, dtype=float)
    c = np.asarray(cm, dtype=float)
    area, centroid = _area_centroid(pts)
    speed = math.hypot(vx, vy)
    size = float(np.ptp(pts, axis=0).max())
    if om == 0.0 or abs(om) * size < 1e-12 * speed:
        if speed == 0.0:
            return 0.0, 0.0, 0.0
        ux, uy = vx / speed, vy / speed
        arm = centroid - c
        return -coef * ux, -coef * uy, -coef * (arm[0] * uy - arm[1] * ux)
    p0 = c + np.array([-vy, vx]) / om
    fx = fy = tq = 0.0
    for p, tn, ta, tb in _edges_about(pts, p0):
        pa, pb = ta - tn, tb - tn
        # int (-sin t, cos t) p^2 sec^2(t - tn) / 2 dt = p^2 / 2 Rot(tn) [-sec, ln|sec + tan|]
        s0 = 1.0 / math.cos(pb) - 1.0 / math.cos(pa)
        s1 = _sec_int(pb) - _sec_int(pa)
        gx, gy = -s0, s1
        ct, st = math.cos(tn), math.sin(tn)
        f_x = 0.5 * p * p * (ct * gx - st * gy)
        f_y = 0.5 * p * p * (st * gx + ct * gy)
        # int rho^3 / 3 dt = p^3 / 3 int sec^3 = p^3 / 6 [sec tan + ln|sec + tan|]
        s3 = (math.tan(pb) / math.cos(pb) + _sec_int(pb)
              - math.tan(pa) / math.cos(pa) - _sec_int(pa))
        t_rho = p ** 3 / 6.0 * s3
        fx += f_x
        fy += f_y
        tq += t_rho
    arm = p0 - c
    tq += arm[0] * fy - arm[1] * fx
    s = math.copysign(1.0, om)
    return -coef * s * fx / area, -coef * s * fy / area, -coef * s * tq / area


def plate_drag_regularised(outline, cm, vx, vy, om, coef, v_reg, epsrel=1e-13):
    """
    Return the drag with v / |v| replaced by v / sqrt(|v|^2 + v_reg^2), as the library writes it.

    Radial integrals in closed form, the angle adaptively (scipy.integrate.quad).
    """
    from scipy.integrate import quad
    pts = np.asarray(outline, dtype=float)
    c = np.asarray(cm, dtype=float)
    area, centroid = _area_centroid(pts)
    speed = math.hypot(vx, vy)
    size = float(np.ptp(pts, axis=0).max())
    if om == 0.0 or abs(om) * size < 1e-12 * speed:
        k = 1.0 / math.sqrt(speed * speed + v_reg * v_reg)
        arm = centroid - c
        return -coef * vx * k, -coef * vy * k, -coef * (arm[0] * vy - arm[1] * vx) * k
    w = abs(om)
    a = v_reg / w
    p0 = c + np.array([-vy, vx]) / om

    def r1(rho):      # int_0^rho r^2 / sqrt(r^2 + a^2) dr
        root = math.sqrt(rho * rho + a * a)
        return 0.5 * (rho * root - a * a * math.asinh(rho / a)) if a > 0 else 0.5 * rho * rho

    def r2(rho):      # int_0^rho r^3 / sqrt(r^2 + a^2) dr
        root = math.sqrt(rho * rho + a * a)
        return ((rho * rho - 2 * a * a) * root + 2 * a ** 3) / 3.0

    fx = fy = tq = 0.0
    for p, tn, ta, tb in _edges_about(pts, p0):
        def rho_max(t, p=p, tn=tn):
            return p / math.cos(t - tn)
        ix = quad(lambda t: -math.sin(t) * r1(rho_max(t)), ta, tb, epsabs=0, epsrel=epsrel,
                  limit=200)[0]
        iy = quad(lambda t: math.cos(t) * r1(rho_max(t)), ta, tb, epsabs=0, epsrel=epsrel,
                  limit=200)[0]
        it = quad(lambda t: r2(rho_max(t)), ta, tb, epsabs=0, epsrel=epsrel, limit=200)[0]
        fx += ix
        fy += iy
        tq += it
    arm = p0 - c
    tq += arm[0] * fy - arm[1] * fx
    # The field's magnitude factor |omega| rho / sqrt(...) is folded into r1, r2 (divided by w)
    s = math.copysign(1.0, om)
    return -coef * s * fx / area, -coef * s * fy / area, -coef * s * tq / area


def plate_drag_mp(outline, vx, vy, om, coef=1.0, dps=40, tol=1e-24):
    """
    Return the exact drag (force, torque about the origin) in high precision (mpmath).

    Written apart from the closed forms: Gauss-Legendre quadrature (nodes in ``dps`` digits)
    over the outline's signed triangles in collapsed (Duffy) coordinates, every area element's
    unit velocity evaluated in ``dps`` digits, so no cancellation survives. The fan is spun from
    the instantaneous centre p0 = z x v / om when it lies within 3 outline radii of the origin
    (v / |v| then depends on the fan's angle only: along a ray the integrand is a polynomial of
    degree 2, six points are exact), else from the origin (the field is analytic over the whole
    part). Along the edges the rule is refined (24, 48, ... points) until two levels agree to
    ``tol`` (relative). The origin is the CM.
    """
    import mpmath
    from mpmath.calculus.quadrature import GaussLegendre
    with mpmath.workdps(dps):
        rule = GaussLegendre(mpmath.mp)

        def nodes(level):
            return [((x + 1) / 2, w / 2) for x, w in rule.calc_nodes(level, mpmath.mp.prec)]

        pts = [(mpmath.mpf(float(x)), mpmath.mpf(float(y))) for x, y in outline]
        vx, vy, om = mpmath.mpf(vx), mpmath.mpf(vy), mpmath.mpf(om)
        radius = max(mpmath.sqrt(x * x + y * y) for x, y in pts)
        cx = cy = mpmath.mpf(0)
        ray = nodes(5)
        if om != 0 and mpmath.sqrt(vx * vx + vy * vy) < 3 * radius * abs(om):
            cx, cy = -vy / om, vx / om
            ray = nodes(2)

        def integrate(along):
            fx = fy = tq = area = mpmath.mpf(0)
            m = len(pts)
            for k in range(m):
                ax, ay = pts[k][0] - cx, pts[k][1] - cy
                bx, by = pts[(k + 1) % m][0] - cx, pts[(k + 1) % m][1] - cy
                jac = ax * by - ay * bx                 # signed: twice the triangle's area
                area += jac / 2
                for u, wu in ray:
                    for v, wv in along:
                        px = cx + u * ((1 - v) * ax + v * bx)
                        py = cy + u * ((1 - v) * ay + v * by)
                        sx = vx - om * py
                        sy = vy + om * px
                        speed = mpmath.sqrt(sx * sx + sy * sy)
                        if speed == 0:
                            continue
                        w = wu * wv * u * jac / speed
                        fx -= w * sx
                        fy -= w * sy
                        tq -= w * (px * sy - py * sx)
            return [coef * fx / area, coef * fy / area, coef * tq / area]

        level = 5
        last = integrate(nodes(level))
        while True:
            level += 1
            now = integrate(nodes(level))
            scale = max(abs(x) for x in now) * radius
            if max(abs(a - b) for a, b in zip(now, last)) <= tol * scale or level >= 9:
                return tuple(float(x) for x in now)
            last = now
