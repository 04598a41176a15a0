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
General event-driven simulator of one throw and catch, for effects that break closed form.

Used when a scene names ``backplate_friction`` or ``impact_restitution`` (docs/effects.md). With
neither (plate friction 0, restitution 0, infinite arm friction) it reproduces the closed-form
kernel; that equivalence is tested and anchors the accuracy benchmark.

Phases (per unit mass, frame F, the arm surface is y = h):
* FLIGHT: gravity plus the back plate's Coulomb drag, integrated with fixed-step RK4
  (``integrator_step``). Contact is looked for at the end of every step: a vertex at or below
  the arm and moving down. The crossing is refined by bisection on re-integrated sub-steps to
  ``contact_root_tol``. A graze shorter than a step is missed; the benchmark shows how often.
* IMPACT at one vertex: Routh's method with Stronge's energetic restitution e and Coulomb
  friction mu (impact()). A rebound slower than ``bounce_threshold`` counts as plastic (its
  normal velocity is removed by a further normal impulse, which only dissipates). With e = 0
  and mu = inf it is the sticking impact (eqs 7-9).
* CONTACT at one vertex P: sticking (rolling about P) or sliding along the arm, integrated with
  RK4 at ``roll_step``. Events: another vertex lands (single-point impact there; if the old
  pivot would then be driven into the arm, the edge lands flat instead), the normal force turns
  negative (liftoff into flight), the friction force leaves the cone (stick -> slip), the slip
  velocity reaches zero (slip -> stick test).
* FLAT on edge j: two-point contact, sliding with Coulomb friction until it stops; a vertex whose
  share of the normal force turns negative starts a rotation about the other one.
* Settling: at rest flat on a stable edge. With e = 0 and mu = inf the base model's exact rule
  applies (a landing on a stable edge with kinetic energy below both tip-over barriers cannot
  leave it, and sticking vertices cannot move). Otherwise, rocking is simulated until the energy
  above the flat pose falls below ``settle_energy``; then the part is laid flat about its pivot.
"""

import math

import numpy as np

from . import _jitcache  # noqa: F401  (drops stale compiled code first)
from .kernel import _record as kernel_record
from .kernel import (ERR_NONFINITE, ERR_SETTLE_CAP, EV_FLAT_LANDING,
                     EV_FLIGHT_IMPACT, EV_LANDING, EV_TIP_FROM_REST, njit, OK, REC_COLS,
                     sticking_impact)

ERR_PAINLEVE = 9        # sliding contact with no consistent normal force (mu too large)
ERR_SIM_CAP = 10        # more integrator steps than accuracy.max_sim_steps
EV_BOUNCE = 4           # an impact that sends the part back into flight
EV_LIFTOFF = 5          # the normal force at the pivot reached zero: back into flight
EV_SETTLE_SNAP = 6      # rocking energy below settle_energy: laid flat about the pivot
EV_HELD = 7             # plate friction held the part on a corner: released from its edge

# Indices of the float parameter vector ``prm``.
(P_G, P_H, P_FRIC, P_MU, P_E, P_VB, P_DT, P_RDT, P_ROOT, P_VREG, P_SETTLE, P_FLAT, P_MAXSTEPS,
 P_MAXIMP, P_FIRST_STABLE, P_UNILATERAL) = range(16)
N_PRM = 16

MODE_FLIGHT = 0
MODE_CONTACT = 1
MODE_FLAT = 2
MODE_DONE = 3


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
def _flight_rhs(vx, vy, om, phi, g, rho2, qu, qv, qw, coef, vreg):
    fx, fy, tq = plate_drag(vx, vy, om, phi, qu, qv, qw, coef, vreg)
    return fx, g + fy, tq / rho2


@njit
def flight_step(x, y, phi, vx, vy, om, dt, g, rho2, qu, qv, qw, coef, vreg):
    """One RK4 step of free flight (exact for the ballistic case: polynomial of degree 2)."""
    a1, b1, c1 = _flight_rhs(vx, vy, om, phi, g, rho2, qu, qv, qw, coef, vreg)
    h2 = 0.5 * dt
    a2, b2, c2 = _flight_rhs(vx + h2 * a1, vy + h2 * b1, om + h2 * c1, phi + h2 * om, g, rho2,
                             qu, qv, qw, coef, vreg)
    a3, b3, c3 = _flight_rhs(vx + h2 * a2, vy + h2 * b2, om + h2 * c2,
                             phi + h2 * (om + h2 * c1), g, rho2, qu, qv, qw, coef, vreg)
    a4, b4, c4 = _flight_rhs(vx + dt * a3, vy + dt * b3, om + dt * c3,
                             phi + dt * (om + h2 * c2), g, rho2, qu, qv, qw, coef, vreg)
    # Positions integrate the velocity stages (RK4 of the first-order system).
    x_new = x + dt * (6.0 * vx + dt * (a1 + a2 + a3)) / 6.0
    y_new = y + dt * (6.0 * vy + dt * (b1 + b2 + b3)) / 6.0
    p_new = phi + dt * (6.0 * om + dt * (c1 + c2 + c3)) / 6.0
    vx_new = vx + dt * (a1 + 2.0 * a2 + 2.0 * a3 + a4) / 6.0
    vy_new = vy + dt * (b1 + 2.0 * b2 + 2.0 * b3 + b4) / 6.0
    om_new = om + dt * (c1 + 2.0 * c2 + 2.0 * c3 + c4) / 6.0
    return x_new, y_new, p_new, vx_new, vy_new, om_new


@njit
def _lowest_approaching(x, y, phi, vx, vy, om, h, bu, bv, skip):
    """(index, height) of a vertex at or below the arm and moving down, else (-1, lowest)."""
    c = math.cos(phi)
    s = math.sin(phi)
    best = -1
    best_f = math.inf
    low = math.inf
    for k in range(bu.shape[0]):
        if k == skip:
            continue
        rx = c * bu[k] - s * bv[k]
        ry = s * bu[k] + c * bv[k]
        f = y + ry - h
        if f < low:
            low = f
        if f <= 0.0 and vy + om * rx < 0.0 and f < best_f:
            best = k
            best_f = f
    return best, low


@njit
def _energy(vx, vy, om, y, h, g, rho2):
    return 0.5 * (vx * vx + vy * vy + rho2 * om * om) - g * (y - h)


@njit
def impact(rx, ry, vx, vy, om, rho2, e, mu):
    """
    Frictional impact at a contact point r = (rx, ry) from the CM on the arm (normal +y).

    Routh's method with Stronge's energetic restitution: the impact is followed in terms of the
    normal impulse p. The contact velocity u = (u_t, u_n) changes by K dP, where the tangential
    impulse follows Coulomb's law: -mu sign(u_t) dp while slipping; while stuck, whatever keeps
    u_t = 0 if that lies within the cone, else slip starts. Compression ends when u_n = 0;
    restitution then goes on until the normal impulse has given back e^2 of the work it took
    in compression. Friction only removes energy and the normal work is (1 - e^2) times the
    (negative) compression work, so kinetic energy never increases. mu = inf stops slip at
    once; with e = 0 the result is then the sticking impact of eqs 7-9. Returns (vx, vy, om).
    """
    ut = vx - om * ry
    un = vy + om * rx
    if un >= 0.0:
        return vx, vy, om    # separating or resting: no impact
    inv = 1.0 / rho2
    ktt = 1.0 + ry * ry * inv
    knn = 1.0 + rx * rx * inv
    ktn = -rx * ry * inv
    pt = 0.0
    pn = 0.0
    eps = 1e-13 * (abs(ut) + abs(un))
    if math.isinf(mu) and ut != 0.0:
        # unbounded friction: a tangential impulse stops the slip at once
        d_pt = -ut / ktt
        pt += d_pt
        ut = 0.0
        un += ktn * d_pt
        if un >= 0.0:
            return vx + pt, vy, om - ry * pt * inv
    work = 0.0
    compressing = True
    target = 0.0
    for _ in range(16):
        if abs(ut) > eps:
            sigma = 1.0 if ut > 0.0 else -1.0
            rate_t = -mu * sigma
            stuck = False
        else:
            ut = 0.0
            lam = -ktn / ktt
            if abs(lam) <= mu:
                rate_t = lam
                stuck = True
            else:
                rate_t = mu if lam > 0.0 else -mu
                stuck = False
        dut = ktt * rate_t + ktn
        dun = ktn * rate_t + knn
        step = math.inf
        ends_slip = False
        if not stuck and ut != 0.0 and dut * ut < 0.0:
            step = -ut / dut
            ends_slip = True
        if compressing:
            if dun <= 0.0:
                # No normal impulse can stop the approach while slipping (Painleve jam): the
                # contact sticks instead (the impulse that stops the point, as in eqs 7-9).
                det = ktt * knn - ktn * ktn
                pt -= (knn * ut - ktn * un) / det
                pn -= (-ktn * ut + ktt * un) / det
                return vx + pt, vy + pn, om + (rx * pn - ry * pt) * inv
            s_c = -un / dun
            if s_c <= step:
                step = s_c
                ends_slip = False
        else:
            # W(p + s) = work + un s + dun s^2 / 2 reaches the target
            rem = target - work
            if dun > 0.0:
                s_r = (-un + math.sqrt(un * un + 2.0 * dun * rem)) / dun
            else:
                s_r = rem / un if un > 0.0 else 0.0
            if s_r <= step:
                step = s_r
                ends_slip = False
        work += un * step + 0.5 * dun * step * step
        pn += step
        pt += rate_t * step
        ut = 0.0 if ends_slip else ut + dut * step
        un = un + dun * step
        if ends_slip:
            continue
        if compressing:
            compressing = False
            un = 0.0
            target = work * (1.0 - e * e)
            if e == 0.0:
                break
        elif not ends_slip:
            break
    return vx + pt, vy + pn, om + (rx * pn - ry * pt) * inv


@njit
def _remove_normal(rx, ry, vx, vy, om, rho2):
    """Pure normal impulse that stops the contact point's normal motion (dissipative)."""
    un = vy + om * rx
    knn = 1.0 + rx * rx / rho2
    lam = -un / knn
    return vx, vy + lam, om + rx * lam / rho2


@njit
def _contact_accel(xp, phi, vxp, om, sliding, sigma, bu_p, bv_p, h, g, rho2, mu, qu, qv, qw,
                   coef, vreg):
    """
    Accelerations (axp, alpha) and contact force (Ft, N) with vertex p on the arm.

    sliding = False: p sticks (axp = 0); True: p slides with friction -mu N sigma. The status
    flag is False when no consistent normal force exists (Painleve).
    """
    c = math.cos(phi)
    s = math.sin(phi)
    cx = -(c * bu_p - s * bv_p)    # CM - P
    cy = -(s * bu_p + c * bv_p)
    vcx = vxp - om * cy
    vcy = om * cx
    fx, fy, tq = plate_drag(vcx, vcy, om, phi, qu, qv, qw, coef, vreg)
    if not sliding:
        alpha = (tq + cx * (g + fy) - cy * fx) / (rho2 + cx * cx + cy * cy)
        ft = -alpha * cy - om * om * cx - fx
        n = alpha * cx - om * om * cy - g - fy
        return 0.0, alpha, ft, n, True
    # Friction -mu |N| sigma: solve with N >= 0 first; a hinge pivot (bilateral) may need N < 0,
    # then the friction term changes sign.
    for sgn_n in (1.0, -1.0):
        ms = mu * sigma * sgn_n
        b = cx + ms * cy
        den = rho2 + b * cx
        if den <= 1e-12 * rho2:
            return 0.0, 0.0, 0.0, 0.0, False
        alpha = (tq + b * (om * om * cy + g + fy)) / den
        n = alpha * cx - om * om * cy - g - fy
        if n * sgn_n >= 0.0:
            ft = -ms * n
            axp = fx + ft + alpha * cy + om * om * cx
            return axp, alpha, ft, n, True
    return 0.0, 0.0, 0.0, 0.0, False


@njit
def _contact_step(xp, phi, vxp, om, dt, sliding, sigma, bu_p, bv_p, h, g, rho2, mu, qu, qv,
                  qw, coef, vreg):
    a1, b1, _, _, _ = _contact_accel(xp, phi, vxp, om, sliding, sigma, bu_p, bv_p, h, g, rho2,
                                     mu, qu, qv, qw, coef, vreg)
    h2 = 0.5 * dt
    a2, b2, _, _, _ = _contact_accel(xp + h2 * vxp, phi + h2 * om, vxp + h2 * a1, om + h2 * b1,
                                     sliding, sigma, bu_p, bv_p, h, g, rho2, mu, qu, qv, qw,
                                     coef, vreg)
    a3, b3, _, _, _ = _contact_accel(xp + h2 * (vxp + h2 * a1), phi + h2 * (om + h2 * b1),
                                     vxp + h2 * a2, om + h2 * b2, sliding, sigma, bu_p, bv_p, h,
                                     g, rho2, mu, qu, qv, qw, coef, vreg)
    a4, b4, _, _, _ = _contact_accel(xp + dt * (vxp + h2 * a2), phi + dt * (om + h2 * b2),
                                     vxp + dt * a3, om + dt * b3, sliding, sigma, bu_p, bv_p, h,
                                     g, rho2, mu, qu, qv, qw, coef, vreg)
    xp_new = xp + dt * (6.0 * vxp + dt * (a1 + a2 + a3)) / 6.0
    p_new = phi + dt * (6.0 * om + dt * (b1 + b2 + b3)) / 6.0
    v_new = vxp + dt * (a1 + 2.0 * a2 + 2.0 * a3 + a4) / 6.0
    o_new = om + dt * (b1 + 2.0 * b2 + 2.0 * b3 + b4) / 6.0
    if not sliding:
        return xp, p_new, 0.0, o_new
    return xp_new, p_new, v_new, o_new


@njit
def _contact_to_cm(xp, phi, vxp, om, bu_p, bv_p, h):
    c = math.cos(phi)
    s = math.sin(phi)
    cx = -(c * bu_p - s * bv_p)
    cy = -(s * bu_p + c * bv_p)
    return xp + cx, h + cy, vxp - om * cy, om * cx


@njit
def _contact_trigger(xp, phi, vxp, om, sliding, sigma, p, bu, bv, h, g, rho2, mu, qu, qv, qw,
                     coef, vreg, unilateral):
    """
    Return the event code at a contact state, and the landing vertex.

    0 none, 1 landing (vertex index in the second value), 2 liftoff, 3 stick -> slip, 4 slip
    reversal (velocity reached zero), 5 Painleve.
    """
    x, y, vx, vy = _contact_to_cm(xp, phi, vxp, om, bu[p], bv[p], h)
    k, _ = _lowest_approaching(x, y, phi, vx, vy, om, h, bu, bv, p)
    if k >= 0:
        return 1, k
    _, _, ft, n, ok = _contact_accel(xp, phi, vxp, om, sliding, sigma, bu[p], bv[p], h, g,
                                     rho2, mu, qu, qv, qw, coef, vreg)
    if not ok:
        return 5, -1
    if n < 0.0 and unilateral:
        return 2, -1
    if sliding:
        if vxp * sigma < 0.0:
            return 4, -1
    elif unilateral and abs(ft) > mu * n:
        return 3, -1
    return 0, -1


@njit
def _record(rec, nrec, kind, vertex, edge, x, w0, w1, e0, e1):
    """Record an event; the rolling-segment columns of kernel records do not apply here."""
    nan = math.nan
    return kernel_record(rec, nrec, kind, vertex, edge, x, w0, w1, e0, e1, nan, nan, nan, nan,
                         nan)


@njit
def _flat_forces(vx, j, e0, u_l, u_r, d, g, mu, rho2, qu, qv, qw, coef, vreg, phi):
    """Flat on edge j: (ax, N_left, N_right, static friction needed) for sliding at vx."""
    fx, fy, tq = plate_drag(vx, 0.0, 0.0, phi, qu, qv, qw, coef, vreg)
    n = -(g + fy)
    if vx != 0.0:
        ft = -mu * n * math.copysign(1.0, vx)
    else:
        ft = -fx
        if abs(ft) > mu * n:
            ft = math.copysign(mu * n, ft)
    nb = -(tq + d[j] * ft + u_l[j] * n) / (u_r[j] - u_l[j])
    na = n - nb
    return fx + ft, na, nb, -fx


@njit
def simulate(edge, x0, y0, phi0, vx0, vy0, om0, prm, n, rho2, d, u_l, u_r, stable, edge_len,
             rest_angle, U, V, QU, QV, QW, acw, accw, rec):
    """
    Throw and catch from a free release state.

    The state is given in frame F with phi0 the rotation from the resting pose on ``edge``.
    Returns (status, edge, R, first contact time, net rotation, impacts, first contact vertex,
    records, lowest and highest arm x touched).
    """
    g = prm[P_G]
    h = prm[P_H]
    coef = prm[P_FRIC]
    mu = prm[P_MU]
    e = prm[P_E]
    vbounce = prm[P_VB]
    dt = prm[P_DT]
    rdt = prm[P_RDT]
    root = prm[P_ROOT]
    vreg = prm[P_VREG]
    settle_e = prm[P_SETTLE]
    flat_tol = prm[P_FLAT]
    max_steps = int(prm[P_MAXSTEPS])
    max_imp = int(prm[P_MAXIMP])
    first_stable = prm[P_FIRST_STABLE] != 0.0
    unilateral = prm[P_UNILATERAL] != 0.0
    exact_rule = e == 0.0 and math.isinf(mu)
    bu = U[edge]
    bv = V[edge]
    size = 0.0
    for k in range(n):
        size = max(size, math.sqrt(bu[k] * bu[k] + bv[k] * bv[k]))
    qu = QU[edge]
    qv = QV[edge]
    qw = QW
    g_abs = -g
    nan = math.nan
    x, y, phi, vx, vy, om = x0, y0, phi0, vx0, vy0, om0
    mode = MODE_FLIGHT
    t = 0.0
    t_first = nan
    k_first = -1
    impacts = 0
    nrec = 0
    x_lo = math.inf
    x_hi = -math.inf
    steps = 0
    # contact state
    p = -1
    xp = 0.0
    vxp = 0.0
    sliding = False
    sigma = 0.0
    # the vertex that just left the arm is ignored in flight until it is seen above it
    sep = -1
    # flat state
    j_flat = -1
    out_edge = -1
    out_r = nan
    while True:
        steps += 1
        if steps > max_steps:
            return ERR_SIM_CAP, -1, nan, t_first, nan, impacts, k_first, nrec, x_lo, x_hi
        if impacts > max_imp:
            return ERR_SETTLE_CAP, -1, nan, t_first, nan, impacts, k_first, nrec, x_lo, x_hi
        if mode == MODE_FLIGHT:
            x1, y1, p1, vx1, vy1, om1 = flight_step(x, y, phi, vx, vy, om, dt, g, rho2, qu, qv,
                                                    qw, coef, vreg)
            if not (math.isfinite(y1) and math.isfinite(om1)):
                return ERR_NONFINITE, -1, nan, t_first, nan, impacts, k_first, nrec, x_lo, x_hi
            if sep >= 0 and y1 + math.sin(p1) * bu[sep] + math.cos(p1) * bv[sep] - h > 0.0:
                sep = -1
            k, _ = _lowest_approaching(x1, y1, p1, vx1, vy1, om1, h, bu, bv, sep)
            if k < 0:
                x, y, phi, vx, vy, om = x1, y1, p1, vx1, vy1, om1
                t += dt
                continue
            lo = 0.0
            hi = dt
            while hi - lo > root:
                mid = 0.5 * (lo + hi)
                xm, ym, pm, vxm, vym, omm = flight_step(x, y, phi, vx, vy, om, mid, g, rho2,
                                                        qu, qv, qw, coef, vreg)
                km, _ = _lowest_approaching(xm, ym, pm, vxm, vym, omm, h, bu, bv, sep)
                if km >= 0:
                    hi = mid
                    k = km
                else:
                    lo = mid
            x, y, phi, vx, vy, om = flight_step(x, y, phi, vx, vy, om, hi, g, rho2, qu, qv, qw,
                                                coef, vreg)
            t += hi
            k2, _ = _lowest_approaching(x, y, phi, vx, vy, om, h, bu, bv, sep)
            if k2 >= 0:
                k = k2
            sep = -1
            c = math.cos(phi)
            s = math.sin(phi)
            rx = c * bu[k] - s * bv[k]
            ry = s * bu[k] + c * bv[k]
            y = h - ry      # put the vertex exactly on the arm (error below root_tol * |v|)
            if k_first < 0:
                k_first = k
                t_first = t
            xk = x + rx
            x_lo = min(x_lo, xk)
            x_hi = max(x_hi, xk)
            e_before = _energy(vx, vy, om, y, h, g, rho2)
            impacts += 1
            alpha = math.atan2(-ry, -rx)
            if alpha - acw[k] <= flat_tol or accw[k] - alpha <= flat_tol:
                # An edge at V^k lies flat: two-point landing on it.
                if alpha - acw[k] <= flat_tol:
                    j_flat = k
                    phi += acw[k] - alpha
                else:
                    j_flat = (k - 1) % n
                    phi += accw[k] - alpha
                mode = MODE_FLAT
                # Lay the part flat on the edge at the vertex that hit (sub-tolerance turn).
                c = math.cos(phi)
                s = math.sin(phi)
                x = xk - (c * bu[k] - s * bv[k])
                y = h + d[j_flat]
                vx, om, vy, ok2 = _flat_impact(vx, vy, om, j_flat, u_l, u_r, d, rho2, mu)
                x_l = x + u_l[j_flat]
                x_lo = min(x_lo, x_l)
                x_hi = max(x_hi, x_l + edge_len[j_flat])
                nrec = _record(rec, nrec, EV_FLAT_LANDING, k, j_flat, xk, om0, 0.0, e_before,
                               _energy(vx, vy, om, y, h, g, rho2))
                continue
            vxa, vya, oma = impact(rx, ry, vx, vy, om, rho2, e, mu)
            un = vya + oma * rx
            if e > 0.0 and un > vbounce:
                nrec = _record(rec, nrec, EV_BOUNCE, k, -1, xk, om, oma, e_before,
                               _energy(vxa, vya, oma, y, h, g, rho2))
                vx, vy, om = vxa, vya, oma
                sep = k
                continue
            vxa, vya, oma = _remove_normal(rx, ry, vxa, vya, oma, rho2)
            if not unilateral:
                # a hinge pivot: the foam catches a vertex that is still slipping
                vxa, vya, oma = sticking_impact(rx, ry, vxa, vya, oma, rho2)
            nrec = _record(rec, nrec, EV_FLIGHT_IMPACT, k, -1, xk, om, oma, e_before,
                           _energy(vxa, vya, oma, y, h, g, rho2))
            vx, vy, om = vxa, vya, oma
            p = k
            xp = xk
            vxp = vx - om * ry
            mode = MODE_CONTACT
            sliding, sigma = _contact_mode(vxp, xp, phi, om, p, bu, bv, h, g, rho2, mu, qu, qv,
                                           qw, coef, vreg, unilateral)
            continue
        if mode == MODE_CONTACT:
            code, kk = _contact_trigger(xp, phi, vxp, om, sliding, sigma, p, bu, bv, h, g, rho2,
                                        mu, qu, qv, qw, coef, vreg, unilateral)
            if code == 0:
                xp1, p1, v1, o1 = _contact_step(xp, phi, vxp, om, rdt, sliding, sigma, bu[p],
                                                bv[p], h, g, rho2, mu, qu, qv, qw, coef, vreg)
                if not (math.isfinite(p1) and math.isfinite(o1)):
                    return (ERR_NONFINITE, -1, nan, t_first, nan, impacts, k_first, nrec, x_lo,
                            x_hi)
                code, kk = _contact_trigger(xp1, p1, v1, o1, sliding, sigma, p, bu, bv, h, g,
                                            rho2, mu, qu, qv, qw, coef, vreg, unilateral)
                if code == 0:
                    turned = om * o1 <= 0.0
                    xp, phi, vxp, om = xp1, p1, v1, o1
                    t += rdt
                    x_lo = min(x_lo, xp)
                    x_hi = max(x_hi, xp)
                    # A turning point, or a creep so slow that the drag is in its
                    # regularised (viscous) zone everywhere on the part.
                    if (turned or abs(om) * 2.0 * size < vreg) and coef > 0.0 and not sliding:
                        held, dphi = _plate_hold(phi, om, bu[p], bv[p], qu, qv, qw, g, coef)
                        if held:
                            # Near the top the plate's friction can hold the part on a corner
                            # (gravity's torque below the friction's largest torque at rest);
                            # the regularised drag would only let it creep off over minutes.
                            # The feeder's vibration breaks the tie: the part is turned to the
                            # edge of the holding zone on its CM's side and falls from rest.
                            phi += dphi
                            e_now = -g * (_contact_to_cm(xp, phi, 0.0, 0.0, bu[p], bv[p],
                                                         h)[1] - h)
                            om = 0.0
                            nrec = _record(rec, nrec, EV_HELD, p, -1, xp, 0.0, 0.0, e_now,
                                           e_now)
                    continue
                lo = 0.0
                hi = rdt
                while hi - lo > root:
                    mid = 0.5 * (lo + hi)
                    xm, pm, vm, omm = _contact_step(xp, phi, vxp, om, mid, sliding, sigma, bu[p],
                                                    bv[p], h, g, rho2, mu, qu, qv, qw, coef,
                                                    vreg)
                    cm_, km_ = _contact_trigger(xm, pm, vm, omm, sliding, sigma, p, bu, bv, h, g,
                                                rho2, mu, qu, qv, qw, coef, vreg, unilateral)
                    if cm_ != 0:
                        hi = mid
                        code = cm_
                        kk = km_
                    else:
                        lo = mid
                xp, phi, vxp, om = _contact_step(xp, phi, vxp, om, hi, sliding, sigma, bu[p],
                                                 bv[p], h, g, rho2, mu, qu, qv, qw, coef, vreg)
                t += hi
                x_lo = min(x_lo, xp)
                x_hi = max(x_hi, xp)
                code2, kk2 = _contact_trigger(xp, phi, vxp, om, sliding, sigma, p, bu, bv, h,
                                              g, rho2, mu, qu, qv, qw, coef, vreg, unilateral)
                if code2 != 0:
                    code = code2
                    kk = kk2
            if code == 5:
                return ERR_PAINLEVE, -1, nan, t_first, nan, impacts, k_first, nrec, x_lo, x_hi
            if code == 4:
                vxp = 0.0
                sliding, sigma = _contact_mode(0.0, xp, phi, om, p, bu, bv, h, g, rho2, mu, qu,
                                               qv, qw, coef, vreg, unilateral)
                continue
            if code == 3:
                _, _, ft, _, _ = _contact_accel(xp, phi, 0.0, om, False, 0.0, bu[p], bv[p], h,
                                                g, rho2, mu, qu, qv, qw, coef, vreg)
                sliding = True
                sigma = -math.copysign(1.0, ft)
                continue
            x, y, vx, vy = _contact_to_cm(xp, phi, vxp, om, bu[p], bv[p], h)
            if code == 2:
                nrec = _record(rec, nrec, EV_LIFTOFF, p, -1, xp, om, om,
                               _energy(vx, vy, om, y, h, g, rho2),
                               _energy(vx, vy, om, y, h, g, rho2))
                mode = MODE_FLIGHT
                sep = p
                continue
            # Landing of vertex kk while rolling/sliding about p.
            q = kk
            if q == (p + 1) % n:
                j = p
            elif q == (p - 1) % n:
                j = q
            else:
                j = -1
            e_before = _energy(vx, vy, om, y, h, g, rho2)
            if j >= 0:
                # Turn about p until the edge is exactly flat (a sub-root_tol correction), so
                # that both of its vertices lie on the arm.
                c = math.cos(phi)
                s = math.sin(phi)
                alpha_q = math.atan2(-(s * bu[q] + c * bv[q]), -(c * bu[q] - s * bv[q]))
                phi += (acw[q] if j == q else accw[q]) - alpha_q
                x, y, vx, vy = _contact_to_cm(xp, phi, vxp, om, bu[p], bv[p], h)
            c = math.cos(phi)
            s = math.sin(phi)
            rx = c * bu[q] - s * bv[q]
            ry = s * bu[q] + c * bv[q]
            xq = x + rx
            x_lo = min(x_lo, xq)
            x_hi = max(x_hi, xq)
            impacts += 1
            vxa, vya, oma = impact(rx, ry, vx, vy, om, rho2, e, mu)
            # Does the old pivot move into the arm after the impact at q?
            cp = math.cos(phi)
            sp = math.sin(phi)
            rpx = cp * bu[p] - sp * bv[p]
            vpn = vya + oma * rpx
            if j >= 0 and vpn < 0.0:
                x_l = xq if j == q else xq - edge_len[j]
                om_before = om
                vx, om, vy, ok2 = _flat_impact(vx, vy, om, j, u_l, u_r, d, rho2, mu)
                x = x_l - u_l[j]
                y = h + d[j]
                j_flat = j
                mode = MODE_FLAT
                nrec = _record(rec, nrec, EV_LANDING, q, j, xq, om_before, 0.0, e_before,
                               _energy(vx, vy, om, y, h, g, rho2))
                if first_stable and stable[j]:
                    out_edge = j
                    out_r = x
                    mode = MODE_DONE
                continue
            un = vya + oma * rx
            if e > 0.0 and un > vbounce:
                nrec = _record(rec, nrec, EV_BOUNCE, q, j, xq, om, oma, e_before,
                               _energy(vxa, vya, oma, y, h, g, rho2))
                vx, vy, om = vxa, vya, oma
                mode = MODE_FLIGHT
                sep = q
                if first_stable and j >= 0 and stable[j]:
                    out_edge = j
                    out_r = (xq if j == q else xq - edge_len[j]) - u_l[j]
                    mode = MODE_DONE
                continue
            vxa, vya, oma = _remove_normal(rx, ry, vxa, vya, oma, rho2)
            if not unilateral:
                vxa, vya, oma = sticking_impact(rx, ry, vxa, vya, oma, rho2)
            e_after = _energy(vxa, vya, oma, y, h, g, rho2)
            nrec = _record(rec, nrec, EV_LANDING, q, j, xq, om, oma, e_before, e_after)
            vx, vy, om = vxa, vya, oma
            if j >= 0 and stable[j]:
                x_l = xq if j == q else xq - edge_len[j]
                ke = e_after - g_abs * d[j]
                lq = math.sqrt(bu[q] * bu[q] + bv[q] * bv[q])
                lp = math.sqrt(bu[p] * bu[p] + bv[p] * bv[p])
                if first_stable or (exact_rule and ke <= g_abs * (lq - d[j])
                                    and ke <= g_abs * (lp - d[j])):
                    out_edge = j
                    out_r = x_l - u_l[j]
                    mode = MODE_DONE
                    continue
                if not exact_rule and ke <= settle_e:
                    nrec = _record(rec, nrec, EV_SETTLE_SNAP, q, j, xq, oma, 0.0, e_after,
                                   g_abs * d[j])
                    out_edge = j
                    out_r = x_l - u_l[j]
                    mode = MODE_DONE
                    continue
            p = q
            xp = xq
            vxp = vx - om * ry
            sliding, sigma = _contact_mode(vxp, xp, phi, om, p, bu, bv, h, g, rho2, mu, qu, qv,
                                           qw, coef, vreg, unilateral)
            continue
        if mode == MODE_FLAT:
            j = j_flat
            ax, na, nb, _ = _flat_forces(vx, j, edge, u_l, u_r, d, g, mu, rho2, qu, qv, qw, coef,
                                         vreg, phi)
            if na < 0.0 or nb < 0.0:
                # Tip about the vertex that keeps the load.
                x_l = x + u_l[j]
                if na < 0.0:
                    p = (j + 1) % n
                    xp = x_l + edge_len[j]
                else:
                    p = j
                    xp = x_l
                x_lo = min(x_lo, xp)
                x_hi = max(x_hi, xp)
                om = 0.0
                vy = 0.0
                if not unilateral and vx != 0.0:
                    c = math.cos(phi)
                    s = math.sin(phi)
                    vx, vy, om = sticking_impact(c * bu[p] - s * bv[p], s * bu[p] + c * bv[p],
                                                 vx, 0.0, 0.0, rho2)
                vxp = vx - om * (math.sin(phi) * bu[p] + math.cos(phi) * bv[p])
                e_now = _energy(vx, vy, om, y, h, g, rho2)
                nrec = _record(rec, nrec, EV_TIP_FROM_REST, p, j, xp, 0.0, 0.0, e_now, e_now)
                mode = MODE_CONTACT
                sliding, sigma = _contact_mode(vxp, xp, phi, om, p, bu, bv, h, g, rho2, mu, qu,
                                               qv, qw, coef, vreg, unilateral)
                if not sliding:
                    vxp = 0.0
                continue
            if vx == 0.0:
                if stable[j] or first_stable:
                    out_edge = j
                    out_r = x
                    mode = MODE_DONE
                    continue
                # Unstable edge at rest: the load split above is negative at one vertex.
                return ERR_NONFINITE, -1, nan, t_first, nan, impacts, k_first, nrec, x_lo, x_hi
            # Slide flat: ax is constant-sign friction plus plate drag; RK2 is plenty here.
            v_half = vx + 0.5 * rdt * ax
            v1 = -vx
            if v_half * vx > 0.0:
                ax2, _, _, _ = _flat_forces(v_half, j, edge, u_l, u_r, d, g, mu, rho2, qu, qv,
                                            qw, coef, vreg, phi)
                v1 = vx + rdt * ax2
            if v1 * vx <= 0.0:
                # Stops within the step: constant deceleration to zero.
                tau = -vx / ax if ax != 0.0 else 0.0
                x += 0.5 * vx * tau
                vx = 0.0
                t += tau
            else:
                x += 0.5 * (vx + v1) * rdt
                vx = v1
                t += rdt
            x_lo = min(x_lo, x + u_l[j])
            x_hi = max(x_hi, x + u_r[j])
            continue
        # MODE_DONE: snap the net rotation to the resting pose on out_edge.
        target = rest_angle[out_edge] - rest_angle[edge]
        rot = target + 2.0 * math.pi * round((phi - target) / (2.0 * math.pi))
        return OK, out_edge, out_r, t_first, rot, impacts, k_first, nrec, x_lo, x_hi


@njit
def _plate_hold(phi, om, bu_p, bv_p, qu, qv, qw, g, coef):
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
def _contact_mode(vxp, xp, phi, om, p, bu, bv, h, g, rho2, mu, qu, qv, qw, coef, vreg,
                  unilateral):
    """
    Return (sliding, sigma) for a new contact phase at vertex p with slip velocity vxp.

    A hinge pivot (not unilateral) is pinned: it never slides.
    """
    if math.isinf(mu) or not unilateral:
        return False, 0.0
    if abs(vxp) > 1e-12:
        return True, math.copysign(1.0, vxp)
    _, _, ft, n, _ = _contact_accel(xp, phi, 0.0, om, False, 0.0, bu[p], bv[p], h, g, rho2, mu,
                                    qu, qv, qw, coef, vreg)
    if abs(ft) <= mu * n:
        return False, 0.0
    # Slip starts in the direction in which, with friction opposing it, the point accelerates.
    first = -math.copysign(1.0, ft)
    for sigma in (first, -first):
        axp, _, _, _, ok = _contact_accel(xp, phi, 0.0, om, True, sigma, bu[p], bv[p], h, g,
                                          rho2, mu, qu, qv, qw, coef, vreg)
        if ok and axp * sigma > 0.0:
            return True, sigma
    return False, 0.0   # no consistent slip (Painleve): the point sticks


@njit
def _flat_impact(vx, vy, om, j, u_l, u_r, d, rho2, mu):
    """
    Land flat on edge j: a two-point plastic impact.

    Vertical velocity and rotation stop; the tangential impulse stops the slide if the friction
    cone allows, else it is clipped. Returns (vx, om, vy, ok).
    """
    # Normal impulse total removes vy; the tangential one removes vx if it can.
    pn = -vy
    if pn < 0.0:
        pn = 0.0
    pt = -vx
    if abs(pt) > mu * pn:
        pt = math.copysign(mu * pn, pt)
    return vx + pt, 0.0, 0.0, True


@njit
def simulate_state(edge, R, w, h_throw, prm, n, rho2, d, u_l, u_r, stable, edge_len,
                   rest_angle, U, V, QU, QV, QW, acw, accw, rec):
    """simulate() from the impulsive release of eqs 5-6 at (edge, R) with speed w."""
    hd = h_throw + d[edge]
    return simulate(edge, R, hd, 0.0, -hd * w, R * w, w, prm, n, rho2, d, u_l, u_r, stable,
                    edge_len, rest_angle, U, V, QU, QV, QW, acw, accw, rec)


def triangulate(outline):
    """Ear-clipping triangulation of a simple counterclockwise polygon: list of index triples."""
    pts = [tuple(p) for p in np.asarray(outline, dtype=float)]
    idx = list(range(len(pts)))
    tris = []

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    def inside(p, a, b, c):
        return cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0

    guard = 0
    while len(idx) > 3 and guard < 10_000:
        guard += 1
        for m in range(len(idx)):
            i0, i1, i2 = idx[m - 1], idx[m], idx[(m + 1) % len(idx)]
            a, b, c = pts[i0], pts[i1], pts[i2]
            if cross(a, b, c) <= 0:
                continue
            if any(inside(pts[k], a, b, c) for k in idx if k not in (i0, i1, i2)):
                continue
            tris.append((i0, i1, i2))
            idx.pop(m)
            break
        else:   # pragma: no cover - degenerate outline; fall back to a fan
            break
    if len(idx) >= 3:
        for m in range(1, len(idx) - 1):
            tris.append((idx[0], idx[m], idx[m + 1]))
    return tris


def plate_quadrature(part, level):
    """
    Return the quadrature of the part's area for the plate drag.

    Every triangle of the outline is split into level^2 similar ones, each weighted by its area
    at its centroid. Returns QU, QV (per edge frame, shape (n, points)) and weights QW (sum 1).
    """
    pts = part.outline
    tris = triangulate(pts)
    qx, qy, qw = [], [], []
    for i0, i1, i2 in tris:
        a, b, c = pts[i0], pts[i1], pts[i2]
        ab = (b - a) / level
        ac = (c - a) / level
        area = 0.5 * abs(ab[0] * ac[1] - ab[1] * ac[0])
        for r in range(level):
            for s in range(level - r):
                p0 = a + r * ab + s * ac
                subs = [(p0, p0 + ab, p0 + ac)]
                if r + s < level - 1:
                    subs.append((p0 + ab, p0 + ab + ac, p0 + ac))
                for t0, t1, t2 in subs:
                    cen = (t0 + t1 + t2) / 3.0
                    qx.append(cen[0])
                    qy.append(cen[1])
                    qw.append(area)
    qw = np.array(qw)
    qw /= qw.sum()
    rel = np.stack([np.array(qx) - part.cm[0], np.array(qy) - part.cm[1]], axis=1)
    verts = part.vertices
    e = np.roll(verts, -1, axis=0) - verts
    e /= np.hypot(e[:, 0], e[:, 1])[:, None]
    normal = np.stack([-e[:, 1], e[:, 0]], axis=1)
    return (np.ascontiguousarray(e @ rel.T), np.ascontiguousarray(normal @ rel.T),
            np.ascontiguousarray(qw))


def empty_records(rows=256):
    return np.empty((rows, REC_COLS))
