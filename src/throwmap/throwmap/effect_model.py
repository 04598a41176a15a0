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
The throw map with effects: the ThrowModel interface over the effects a scene names.

One compiled core, throw_core(), evaluates a throw with every effect as a parameter that is
neutral when the effect is off (sd = 0, theta_r = 0, L = inf, ...), and routes flight and catch
to the closed form (throwmap.closed: ballistic flight, kernel.settle) or, for
backplate_friction and impact_restitution, to the general simulator (throwmap.general).
A scene without effects never gets here: its model is the base ThrowModel.
"""

from dataclasses import dataclass, replace
import math

import numpy as np

from . import closed, general, kernel
from .effects import EffectSet
from .errors import DomainError, InputError, NumericalError, ThrowmapError
from .model import batch_buffers, batch_result, Impact, orbit_buffers, ThrowModel, ThrowResult

LOST = 20                   # the part left the finite arm (an outcome, not an error)
ERR_CARRY_GRASP = 21        # the part is not in a dynamic grasp somewhere along the carry
ERR_ARM_STRIKE = 22         # the returning arm meets the part
ERR_RECORDS = 23            # more catch events than the record buffer holds
ERR_RELEASE = 24            # a sampled release speed <= 0
REC_ROWS = 2048

CONTACT_METHODS = ('advancement', 'scan')

_EVENT_NAMES = {kernel.EV_FLIGHT_IMPACT: 'flight', kernel.EV_LANDING: 'landing',
                kernel.EV_FLAT_LANDING: 'flat_landing', kernel.EV_TIP_FROM_REST: 'tip_from_rest',
                general.EV_BOUNCE: 'bounce', general.EV_LIFTOFF: 'liftoff',
                general.EV_SETTLE_SNAP: 'settle_snap', general.EV_HELD: 'held_by_plate'}


@dataclass(frozen=True)
class EffectAccuracy:
    """
    Accuracy knobs of the effect paths (docs/accuracy.md measures what each one costs).

    contact_method : 'advancement' (conservative advancement: exact, never misses a contact)
        or 'scan' (samples every contact_scan_step, bisects to contact_root_tol; misses any
        graze shorter than a step). Applies to ballistic flight (closed form).
    contact_scan_step : s, sample interval of the 'scan' method.
    contact_root_tol : s, bisection tolerance of every scanned event (scan method, and all
        events of the general simulator).
    integrator_step : s, RK4 step of flight in the general simulator; contacts are looked for
        at every step, so this is also its scan resolution.
    roll_step : s, RK4 step of rolling/sliding phases in the general simulator.
    plate_quadrature : subdivisions per triangle edge of the area quadrature of the plate drag
        (points = triangles x level^2).
    plate_v_reg : m/s, regularisation of v/|v| in the plate drag.
    settle_energy : J/kg, rocking energy above the flat pose below which the general simulator
        lays the part flat (only when e > 0 or mu is finite; otherwise the exact rule holds).
    max_sim_steps : cap on integrator steps per throw in the general simulator.
    carry_samples : instants (+1) at which the finite carry's wrench cone and the returning
        arm's clearance are checked.
    """

    contact_method: str = 'advancement'
    contact_scan_step: float = 1e-3
    contact_root_tol: float = 1e-12
    integrator_step: float = 1e-3
    roll_step: float = 1e-3
    plate_quadrature: int = 4
    plate_v_reg: float = 1e-4
    settle_energy: float = 1e-8
    max_sim_steps: int = 2_000_000
    carry_samples: int = 200

    FLOATS = ('contact_scan_step', 'contact_root_tol', 'integrator_step', 'roll_step',
              'plate_v_reg', 'settle_energy')
    INTS = ('plate_quadrature', 'max_sim_steps', 'carry_samples')

    def __post_init__(self):
        if self.contact_method not in CONTACT_METHODS:
            raise InputError('accuracy.contact_method', f'unknown method {self.contact_method!r}',
                             f'use one of {", ".join(CONTACT_METHODS)}')
        for name in self.FLOATS:
            value = getattr(self, name)
            if (isinstance(value, bool) or not isinstance(value, (int, float))
                    or not math.isfinite(value) or value <= 0):
                raise InputError(f'accuracy.{name}', f'must be a number > 0, got {value!r}',
                                 f'use e.g. the default {getattr(EffectAccuracy, name)}')
        for name in self.INTS:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise InputError(f'accuracy.{name}', f'must be an integer >= 1, got {value!r}',
                                 f'use e.g. the default {getattr(EffectAccuracy, name)}')


EFFECT_ACCURACY_KEYS = tuple(f for f in EffectAccuracy.__dataclass_fields__)


@kernel.njit
def impulse_grasp_radius(edge, h, mu, rho2, d, u_l, u_r):
    """R_grasp of eqs (1)-(4) at offset h (bounds 2 and 4 only with a finite mu)."""
    hd = h + d[edge]
    b = (rho2 + d[edge] * hd) / u_l[edge]
    b3 = (rho2 + d[edge] * hd) / u_r[edge]
    if b3 > b:
        b = b3
    if math.isfinite(mu):
        if -hd / mu > b:
            b = -hd / mu
        if hd / mu > b:
            b = hd / mu
    return b


@kernel.njit
def carry_margin(edge, R, w, h, g, mu, theta_r, samples, rho2, d, u_l, u_r):
    """
    Return the largest wrench-cone margin along the carry (<= 0: in a dynamic grasp).

    Returns (margin, sample index, constraint 1..4) of the worst instant.
    """
    hd = h + d[edge]
    vl = -d[edge]
    a = w * w / (2.0 * theta_r)
    tc = 2.0 * theta_r / w
    cone = np.empty((4, 3))
    ul = u_l[edge]
    ur = u_r[edge]
    cone[0, 0], cone[0, 1], cone[0, 2] = -mu, 1.0, ul + mu * vl
    cone[1, 0], cone[1, 1], cone[1, 2] = mu, 1.0, ul - mu * vl
    cone[2, 0], cone[2, 1], cone[2, 2] = mu, 1.0, ur - mu * vl
    cone[3, 0], cone[3, 1], cone[3, 2] = -mu, 1.0, ur + mu * vl
    worst = -math.inf
    worst_k = 0
    worst_c = 0
    for k in range(samples + 1):
        t = tc * k / samples
        th = 0.5 * a * t * t
        thd = a * t
        w0 = -a * hd - thd * thd * R - g * math.sin(th)
        w1 = a * R - thd * thd * hd - g * math.cos(th)
        w2 = a * rho2
        norm = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
        for c in range(4):
            j = c
            m = (c + 1) % 4
            x0 = cone[j, 1] * cone[m, 2] - cone[j, 2] * cone[m, 1]
            x1 = cone[j, 2] * cone[m, 0] - cone[j, 0] * cone[m, 2]
            x2 = cone[j, 0] * cone[m, 1] - cone[j, 1] * cone[m, 0]
            val = (w0 * x0 + w1 * x1 + w2 * x2) / norm
            if val > worst:
                worst = val
                worst_k = k
                worst_c = c + 1
    return worst, worst_k, worst_c


@kernel.njit
def arm_clearance(edge, x0, y0, phi0, vx, vy, om, g, h, theta_r, w, ret_time, samples, arm_len,
                  n, U, V):
    """
    Return the smallest clearance of the part's vertices over the returning arm.

    The arm follows the Hermite profile from (theta_r, w) to (0, 0) in ret_time; only vertices
    above the arm's extent [0, L] count.
    """
    worst = math.inf
    for k in range(1, samples + 1):
        t = ret_time * k / samples
        s = t / ret_time
        th = ((2 * s ** 3 - 3 * s * s + 1) * theta_r + (s ** 3 - 2 * s * s + s) * ret_time * w)
        c = math.cos(th)
        sn = math.sin(th)
        ph = phi0 + om * t
        cp = math.cos(ph)
        sp = math.sin(ph)
        xc = x0 + vx * t
        yc = y0 + vy * t + 0.5 * g * t * t
        for j in range(n):
            xv = xc + cp * U[edge, j] - sp * V[edge, j]
            yv = yc + sp * U[edge, j] + cp * V[edge, j]
            along = c * xv + sn * yv
            if along < 0.0 or along > arm_len:
                continue
            clear = -sn * xv + c * yv - h
            if clear < worst:
                worst = clear
    return worst


@kernel.njit
def throw_core(edge, R, zw, zh, w0, h0, g, sd_w, sd_h, mu, theta_r, ret_time, carry_n, arm_len,
               use_general, prm, method, scan_step, root_tol, tol_t, flat_tol, max_steps,
               max_impacts, first_stable, n, rho2, d, u_l, u_r, stable, edge_len, vrad, acw,
               accw, kcw, kccw, U, V, rest_angle, QU, QV, QW, nobound, rec):
    """
    Evaluate one throw with effects.

    Returns (status, edge, R, first contact time, net rotation, impacts, first contact vertex,
    records written, w used, h used).
    """
    nan = math.nan
    if edge < 0 or edge >= n:
        return kernel.ERR_EDGE_INDEX, -1, nan, nan, nan, 0, -1, 0, nan, nan
    if not stable[edge]:
        return kernel.ERR_UNSTABLE_EDGE, -1, nan, nan, nan, 0, -1, 0, nan, nan
    w = w0 + sd_w * zw
    h = h0 + sd_h * zh
    if not w > 0.0:
        return ERR_RELEASE, -1, nan, nan, nan, 0, -1, 0, w, h
    if theta_r == 0.0:
        if not R >= impulse_grasp_radius(edge, h, mu, rho2, d, u_l, u_r):
            return kernel.ERR_GRASP, -1, nan, nan, nan, 0, -1, 0, w, h
    elif carry_margin(edge, R, w, h, g, mu, theta_r, carry_n, rho2, d, u_l, u_r)[0] > 0.0:
        return ERR_CARRY_GRASP, -1, nan, nan, nan, 0, -1, 0, w, h
    if not (R + u_l[edge] > 0.0):
        return kernel.ERR_TOE_STUB, -1, nan, nan, nan, 0, -1, 0, w, h
    x0, y0, phi0, vx, vy, om = closed.release_state(edge, R, w, h, theta_r, d)
    if use_general:
        prm[general.P_G] = g
        prm[general.P_H] = h
        status, j, r1, t, rot, imp, k0, nrec, x_lo, x_hi = general.simulate(
            edge, x0, y0, phi0, vx, vy, om, prm, n, rho2, d, u_l, u_r, stable, edge_len,
            rest_angle, U, V, QU, QV, QW, acw, accw, rec)
    elif theta_r == 0.0 and method == closed.METHOD_ADVANCEMENT:
        # The impulsive release of eqs 5-6: the base kernel itself (bit-identical results).
        status, j, r1, t, rot, imp, k0, nrec = kernel.throw_one(
            edge, R, w, g, h, n, rho2, d, u_l, u_r, stable, edge_len, vrad, acw, accw, kcw,
            kccw, U, V, nobound, first_stable, tol_t, flat_tol, max_steps, max_impacts,
            rec)
    else:
        status, j, r1, t, rot, imp, k0, nrec = closed.ballistic_throw(
            edge, x0, y0, phi0, vx, vy, om, g, h, n, rho2, d, u_l, u_r, stable, edge_len, vrad,
            acw, accw, kcw, kccw, U, V, first_stable, tol_t, flat_tol, max_steps, max_impacts,
            method, scan_step, root_tol, rec)
    if not use_general:
        x_lo = math.inf
        x_hi = -math.inf
        if math.isfinite(arm_len):
            if nrec > rec.shape[0]:
                return ERR_RECORDS, -1, nan, t, nan, imp, k0, nrec, w, h
            for k in range(nrec):
                x_lo = min(x_lo, rec[k, kernel.REC_X])
                x_hi = max(x_hi, rec[k, kernel.REC_X])
                if rec[k, kernel.REC_KIND] == kernel.EV_FLAT_LANDING:
                    # both corners of a flat-landing edge touch down
                    jj = int(rec[k, kernel.REC_EDGE])
                    x_l = rec[k, kernel.REC_X] if jj == rec[k, kernel.REC_VERTEX] else (
                        rec[k, kernel.REC_X] - edge_len[jj])
                    x_lo = min(x_lo, x_l)
                    x_hi = max(x_hi, x_l + edge_len[jj])
    if ret_time > 0.0 and status == kernel.OK:
        if t < ret_time or arm_clearance(edge, x0, y0, phi0, vx, vy, om, g, h, theta_r, w,
                                         ret_time, carry_n, arm_len, n, U, V) < 0.0:
            return ERR_ARM_STRIKE, -1, nan, t, nan, imp, k0, nrec, w, h
    if status == kernel.OK and math.isfinite(arm_len):
        if x_lo < 0.0 or x_hi > arm_len or r1 < 0.0 or r1 > arm_len:
            return LOST, -1, nan, t, rot, imp, k0, nrec, w, h
    if status != kernel.OK and math.isfinite(arm_len) and k0 >= 0 and (
            x_lo < 0.0 or x_hi > arm_len):
        # A catch that failed numerically after leaving the arm is lost all the same.
        return LOST, -1, nan, t, nan, imp, k0, nrec, w, h
    return status, j, r1, t, rot, imp, k0, nrec, w, h


@kernel.njit
def throw_batch(edges, radii, z, w0, h0, g, sd_w, sd_h, mu, theta_r, ret_time, carry_n,
                arm_len, use_general, prm, method, scan_step, root_tol, tol_t, flat_tol,
                max_steps, max_impacts, first_stable, n, rho2, d, u_l, u_r, stable, edge_len,
                vrad, acw, accw, kcw, kccw, U, V, rest_angle, QU, QV, QW, nobound, out_edge,
                out_r, out_status, out_t, out_rot):
    rec = np.empty((REC_ROWS, kernel.REC_COLS))
    for i in range(edges.shape[0]):
        st, j, r1, t, rot, _, _, _, _, _ = throw_core(
            edges[i], radii[i], z[i, 0], z[i, 1], w0, h0, g, sd_w, sd_h, mu, theta_r, ret_time,
            carry_n, arm_len, use_general, prm, method, scan_step, root_tol, tol_t, flat_tol,
            max_steps, max_impacts, first_stable, n, rho2, d, u_l, u_r, stable, edge_len, vrad,
            acw, accw, kcw, kccw, U, V, rest_angle, QU, QV, QW, nobound, rec)
        out_edge[i] = j
        out_r[i] = r1
        out_status[i] = st
        out_t[i] = t
        out_rot[i] = rot


@kernel.njit
def orbit_batch(edges, radii, steps, z, w0, h0, g, sd_w, sd_h, mu, theta_r, ret_time, carry_n,
                arm_len, use_general, prm, method, scan_step, root_tol, tol_t, flat_tol,
                max_steps, max_impacts, first_stable, n, rho2, d, u_l, u_r, stable, edge_len,
                vrad, acw, accw, kcw, kccw, U, V, rest_angle, QU, QV, QW, nobound, out_edge,
                out_r, out_rot, out_status, out_done):
    """
    Iterate f from many starts; z has shape (starts, steps, 2).

    A lost throw ends its orbit with edge -1 and status LOST.
    """
    rec = np.empty((REC_ROWS, kernel.REC_COLS))
    for s in range(edges.shape[0]):
        edge = edges[s]
        R = radii[s]
        out_edge[s, 0] = edge
        out_r[s, 0] = R
        out_rot[s, 0] = 0.0
        out_status[s] = kernel.OK
        out_done[s] = steps
        for k in range(steps):
            st, j, r1, t, rot, _, _, _, _, _ = throw_core(
                edge, R, z[s, k, 0], z[s, k, 1], w0, h0, g, sd_w, sd_h, mu, theta_r, ret_time,
                carry_n, arm_len, use_general, prm, method, scan_step, root_tol, tol_t,
                flat_tol, max_steps, max_impacts, first_stable, n, rho2, d, u_l, u_r, stable,
                edge_len, vrad, acw, accw, kcw, kccw, U, V, rest_angle, QU, QV, QW, nobound,
                rec)
            if st != kernel.OK:
                out_status[s] = st
                out_done[s] = k
                if st == LOST:
                    out_edge[s, k + 1] = -1
                break
            out_edge[s, k + 1] = j
            out_r[s, k + 1] = r1
            out_rot[s, k + 1] = rot
            edge = j
            R = r1


class PartLost(ThrowmapError):
    """The part fell off the finite arm (effect finite_arm): an outcome that ends an orbit."""

    def __init__(self, message, after=None):
        self.after = after
        super().__init__(message)


@dataclass(frozen=True)
class EffectThrowResult(ThrowResult):
    """ThrowResult of a scene with effects: ``kind`` may be 'lost' (edge -1, R nan)."""

    release_speed: float = math.nan     # the throw's own w (release_noise)
    offset: float = math.nan            # the throw's own h
    lost_reason: str = ''

    def as_dict(self):
        d = super().as_dict()
        d.update({'release_speed': self.release_speed, 'offset': self.offset,
                  'lost_reason': self.lost_reason})
        return d


class EffectModel(ThrowModel):
    """
    ThrowModel over the effects of an EffectSet.

    Same interface as ThrowModel: f, throw, f_batch, orbit_arrays, orbits, domain_error,
    error_message.

    With release_noise or sensor_noise the model owns a seeded numpy Generator (``rng``):
    every f, f_batch and orbit call draws from it, so results depend on the seed and on the
    order of calls; ``reseed(seed)`` starts the sequence again.
    """

    def __init__(self, part, offset, release_speed, gravity, mu=None, settle_rule='full',
                 accuracy=None, effects=None, knobs=None, seed=0, g_normal=None,
                 field_prefix=''):
        super().__init__(part, offset, release_speed, gravity, mu=mu, settle_rule=settle_rule,
                         accuracy=accuracy, field_prefix=field_prefix)
        self.effects = effects or EffectSet()
        self.knobs = knobs or EffectAccuracy()
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        eff = self.effects
        k = self.knobs
        self.g_normal = g_normal
        self.arm_length = eff.arm.length if eff.arm else math.inf
        self.theta_r = eff.carry.release_angle if eff.carry else 0.0
        self.return_time = eff.carry.return_time if eff.carry else 0.0
        self.sd_w = eff.release_noise.speed_sd if eff.release_noise else 0.0
        self.sd_h = eff.release_noise.offset_sd if eff.release_noise else 0.0
        if eff.general:
            self.quadrature = general.plate_quadrature(part, k.plate_quadrature)
        else:
            self.quadrature = (np.zeros((part.n, 0)), np.zeros((part.n, 0)), np.zeros(0))
        prm = np.zeros(general.N_PRM)
        prm[general.P_G] = self.g
        prm[general.P_H] = self.h
        prm[general.P_FRIC] = eff.backplate.drag if eff.backplate else 0.0
        rest = eff.restitution
        prm[general.P_MU] = rest.mu if rest else math.inf
        prm[general.P_E] = rest.restitution if rest else 0.0
        prm[general.P_VB] = rest.bounce_threshold if rest else 0.0
        prm[general.P_UNILATERAL] = 1.0 if (rest and rest.unilateral) else 0.0
        prm[general.P_DT] = k.integrator_step
        prm[general.P_RDT] = k.roll_step
        prm[general.P_ROOT] = k.contact_root_tol
        prm[general.P_VREG] = k.plate_v_reg
        prm[general.P_SETTLE] = k.settle_energy
        prm[general.P_FLAT] = self.accuracy.flat_landing_tol
        prm[general.P_MAXSTEPS] = k.max_sim_steps
        prm[general.P_MAXIMP] = self.accuracy.max_impacts
        prm[general.P_FIRST_STABLE] = 1.0 if settle_rule == 'first_stable' else 0.0
        self.prm = prm
        # One record buffer per model (f and throw are not re-entrant across threads).
        self._rec = np.empty((REC_ROWS, kernel.REC_COLS))
        acc = self.accuracy
        qu, qv, qw = self.quadrature
        self._cargs = (self.w, self.h, self.g, self.sd_w, self.sd_h,
                       math.inf if mu is None else float(mu), self.theta_r, self.return_time,
                       k.carry_samples, self.arm_length, eff.general, prm,
                       closed.METHOD_SCAN if k.contact_method == 'scan'
                       else closed.METHOD_ADVANCEMENT,
                       k.contact_scan_step, k.contact_root_tol, acc.contact_time_tol,
                       acc.flat_landing_tol, acc.max_flight_steps, acc.max_impacts,
                       settle_rule == 'first_stable', part.n, part.rho2, part.d, part.u_l,
                       part.u_r, part.stable, part.edge_length, part.vertex_radius,
                       part.alpha_cw_end, part.alpha_ccw_end, part.k_cw, part.k_ccw, part.U,
                       part.V, part.rest_angle, qu, qv, qw,
                       # throw_core checks the grasp itself (at the throw's own h), so the
                       # kernel it calls gets no bound
                       np.full(part.n, -np.inf))

        if eff.carry is not None:
            self.r_grasp = self._carry_domain()

    def _carry_domain(self, r_top=1.0, step=1e-3):
        """
        Return the lower end of the domain per stable edge with a finite carry.

        Above it the carry keeps the dynamic grasp and the returning arm clears the part (on a
        1 mm grid up to 1 m, then bisection to 1e-7 m). The impulse-cone R_grasp does not
        apply here.
        """
        part = self.part
        out = np.full(part.n, np.inf)
        bad = (ERR_CARRY_GRASP, ERR_ARM_STRIKE, kernel.ERR_TOE_STUB)
        for i in part.stable_edges:
            rs = np.arange(max(-part.u_l[i], 0.0) + step / 2, r_top, step)
            st = self._nominal_status(np.full(rs.size, i), rs)
            failing = np.flatnonzero(np.isin(st, bad))
            if failing.size == 0:
                out[i] = max(-part.u_l[i], 0.0)
                continue
            k = int(failing[-1])
            if k + 1 >= rs.size:
                continue        # no domain on this edge below r_top
            lo, hi = float(rs[k]), float(rs[k + 1])
            while hi - lo > 1e-7:
                mid = 0.5 * (lo + hi)
                if self._nominal_status(np.array([i]), np.array([mid]))[0] in bad:
                    lo = mid
                else:
                    hi = mid
            out[i] = hi
        return out

    def _nominal_status(self, edges, radii):
        m = edges.size
        out = (np.empty(m, dtype=np.int64), np.empty(m), np.empty(m, dtype=np.int64),
               np.empty(m), np.empty(m))
        throw_batch(np.ascontiguousarray(edges, dtype=np.int64),
                    np.ascontiguousarray(radii, dtype=float), np.zeros((m, 2)), *self._cargs,
                    *out)
        return out[2]

    # ------------------------------------------------------------------------- randomness
    def reseed(self, seed):
        self.seed = seed
        self.rng = np.random.default_rng(seed)

    def nominal(self):
        """Return the same model without release_noise and sensor_noise."""
        eff = replace(self.effects, release_noise=None, sensor_noise=None,
                      names=tuple(n for n in self.effects.names
                                  if n not in ('release_noise', 'sensor_noise')))
        return EffectModel(self.part, self.h, self.w, self.g, mu=self.mu,
                           settle_rule=self.settle_rule, accuracy=self.accuracy, effects=eff,
                           knobs=self.knobs, seed=self.seed, g_normal=self.g_normal)

    def _draw(self, shape):
        if self.effects.release_noise is None:
            return np.zeros(shape + (2,))
        return self.rng.standard_normal(shape + (2,))

    def sensor_reading(self, edge, R, x, footprint=0.0):
        """One reading of the sensor at x: geometry, then sensor_noise's errors if named."""
        from .dynamics import sees
        seen = np.asarray(sees(self.part, np.maximum(edge, 0), R, x, footprint)
                          & (np.asarray(edge) >= 0))
        noise = self.effects.sensor_noise
        if noise is None:
            return seen
        u = self.rng.random(seen.shape)
        return np.where(seen, u >= noise.false_negative, u < noise.false_positive)

    # ------------------------------------------------------------------------- domain
    def domain_error(self, edge, R):
        if self.effects.carry is None:
            return super().domain_error(edge, R)
        part = self.part
        if isinstance(edge, bool) or not isinstance(edge, (int, np.integer)) or not (
                0 <= edge < part.n) or not part.stable[edge] or not (
                isinstance(R, (int, float, np.floating)) and math.isfinite(R)):
            err = super().domain_error(edge, R)
            if err is not None:
                return err
        mu = math.inf if self.mu is None else self.mu
        margin, k, c = carry_margin(int(edge), float(R), self.w, self.h, self.g, mu,
                                    self.theta_r, self.knobs.carry_samples, part.rho2, part.d,
                                    part.u_l, part.u_r)
        if margin > 0.0:
            tc = 2 * self.theta_r / self.w
            names = {1: 'line of force passes left of the left vertex',
                     2: 'force outside the right edge of the friction cone',
                     3: 'line of force passes right of the right vertex',
                     4: 'force outside the left edge of the friction cone'}
            return DomainError('carry_grasp', f'no dynamic grasp on edge {edge} at R = '
                               f'{R:.6g} m during the carry: constraint ({c}) ({names[c]}) '
                               f'fails at t = {tc * k / self.knobs.carry_samples * 1000:.3f} ms '
                               f'of {tc * 1000:.3f} ms (margin {margin:.3g}); throw from '
                               'further out, or carry less abruptly (larger release angle)',
                               margin=margin)
        if not R + part.u_l[edge] > 0:
            return super().domain_error(edge, R) or DomainError(
                'toe_stub', f'the left vertex of edge {edge} is not right of the pivot')
        if R < self.r_grasp[edge]:
            return DomainError('carry_domain', f'on edge {edge} the finite carry needs R >= '
                               f'{self.r_grasp[edge]:.6g} m (below it the carry loses the '
                               'grasp or the returning arm meets the part); got R = '
                               f'{R:.6g} m', margin=self.r_grasp[edge] - R)
        return None

    # ------------------------------------------------------------------------- the map
    def _core(self, edge, R, z, rec):
        return throw_core(edge, R, z[0], z[1], *self._cargs, rec)

    def f(self, edge, R):
        """(edge', R', kind); kind 'lost' (edge -1, R nan) when the part leaves the arm."""
        self._check_types(edge, R)
        out = self._core(int(edge), float(R), self._draw((1,))[0], self._rec)
        status = out[0]
        if status == LOST:
            return -1, math.nan, 'lost'
        if status != kernel.OK:
            self._raise(status, edge, R)
        return out[1], out[2], _classify(edge, out[1], out[4])

    def throw(self, edge, R, trajectory=False, samples=60):
        """
        Return the full result of one throw.

        ``trajectory`` is filled only where the flight and catch are the base model's (effects
        finite_arm, sensor_noise alone), else None: the general simulator keeps no poses.
        """
        self._check_types(edge, R)
        rec = self._rec
        z = self._draw((1,))[0]
        out = self._core(int(edge), float(R), z, rec)
        status, j, r1, t, rot, nimp, k0, nrec, w, h = out
        if status not in (kernel.OK, LOST):
            self._raise(status, edge, R)
        rows = rec[:min(nrec, REC_ROWS)]
        impacts = tuple(Impact(_EVENT_NAMES.get(int(row[0]), 'event'), int(row[1]),
                               int(row[2]), float(row[3]), float(row[4]), float(row[5]),
                               float(row[6]), float(row[7])) for row in rows)
        part = self.part
        x0, y0, phi0, vx, vy, om = closed.release_state(int(edge), float(R), w, h, self.theta_r,
                                                        part.d)
        e0 = 0.5 * (vx * vx + vy * vy + part.rho2 * om * om) - self.g * (y0 - h)
        reason = ''
        kind = 'lost' if status == LOST else _classify(edge, j, rot)
        if status == LOST:
            reason = self._lost_reason(rows, r1)
        traj = None
        if trajectory and status == kernel.OK and self._base_path():
            traj = super().throw(edge, R, trajectory=True, samples=samples).trajectory
        return EffectThrowResult(int(edge), float(R), int(j), float(r1), kind, float(t),
                                 float(rot), int(k0), impacts, float(e0), traj, float(w),
                                 float(h), reason)

    def _base_path(self):
        """Tell whether throws are the base kernel's own (range checks or sensor noise)."""
        return (not self.effects.general and self.theta_r == 0.0 and self.sd_w == 0.0
                and self.sd_h == 0.0 and self.knobs.contact_method == 'advancement')

    def _lost_reason(self, rows, r1):
        xs = rows[:, kernel.REC_X] if len(rows) else np.array([])
        L = self.arm_length
        if len(xs) and not 0 <= xs[0] <= L:
            return (f'first contact at x = {xs[0] * 100:.2f} cm, off the arm [0, '
                    f'{L * 100:g} cm]: the part missed the arm')
        return f'the part rolled or slid off the arm [0, {L * 100:g} cm]'

    def f_batch(self, edges, radii):
        edges, radii, out = batch_buffers(edges, radii)
        z = np.ascontiguousarray(self._draw((edges.size,)))
        throw_batch(edges, radii, z, *self._cargs, *out)
        return batch_result(edges, out, lost_status=LOST)

    def orbits(self, edges, radii, throws):
        edges, radii, out = orbit_buffers(edges, radii, throws)
        z = np.ascontiguousarray(self._draw((edges.size, throws)))
        orbit_batch(edges, radii, throws, z, *self._cargs, *out)
        return out

    def orbit_arrays(self, edge, R, throws):
        """Like ThrowModel.orbit_arrays; a lost throw ends the arrays with edge -1, R nan."""
        self.check(edge, R)
        e, r, rot, status, done = self.orbits([edge], [R], throws)
        status, done = int(status[0]), int(done[0])
        if status == LOST:
            return e[0, :done + 2], r[0, :done + 2], rot[0, :done + 2]
        if status != kernel.OK:
            self._raise(status, int(e[0, done]), float(r[0, done]), after=done)
        return e[0], r[0], rot[0]

    # ------------------------------------------------------------------------- errors
    def _check_types(self, edge, R):
        err = ThrowModel.domain_error(self, edge, R)
        if err is not None and err.condition in ('edge_index', 'stable_edge', 'radius'):
            raise err

    def error_message(self, status, edge, R):
        if status == LOST:
            return (f'lost: from ({edge}, {R:.6g} m) the part left the arm [0, '
                    f'{self.arm_length:g} m]')
        if status in (ERR_ARM_STRIKE, ERR_RECORDS, ERR_RELEASE, general.ERR_PAINLEVE,
                      general.ERR_SIM_CAP):
            return str(self._effect_error(status, edge, R))
        return super().error_message(status, edge, R)

    def _effect_error(self, status, edge, R):
        if status == ERR_ARM_STRIKE:
            return DomainError('arm_strike', f'from ({edge}, {R:.6g} m) the returning arm meets '
                               f'the part within throw.carry.return_time = {self.return_time:g} '
                               's; return the arm faster (smaller return_time) or throw higher')
        if status == ERR_RELEASE:
            return DomainError('release_speed', f'from ({edge}, {R:.6g} m) the sampled release '
                               'speed is <= 0; noise.release_speed_sd is too large for the '
                               'release speed')
        if status == general.ERR_PAINLEVE:
            return NumericalError(f'catch after ({edge}, {R:.6g} m): sliding contact with no '
                                  'consistent normal force (Painleve paradox); lower contact.mu')
        if status == general.ERR_SIM_CAP:
            return NumericalError(f'throw from ({edge}, {R:.6g} m) did not settle within '
                                  f'accuracy.max_sim_steps = {self.knobs.max_sim_steps} '
                                  'integrator steps; raise it, or integrator_step / roll_step')
        return NumericalError(f'catch after ({edge}, {R:.6g} m) has more than {REC_ROWS} events '
                              'to check against the arm length')

    def _raise(self, status, edge, R, after=None):
        if status in (ERR_ARM_STRIKE, ERR_RECORDS, ERR_RELEASE, general.ERR_PAINLEVE,
                      general.ERR_SIM_CAP):
            err = self._effect_error(status, edge, R)
        elif status == ERR_CARRY_GRASP or (status == kernel.ERR_GRASP and self.sd_h > 0):
            err = self.domain_error(edge, R)
            if err is None:
                err = DomainError('grasp_noise', f'no dynamic grasp at ({edge}, {R:.6g} m) '
                                  "with this throw's sampled release speed and offset "
                                  '(release_noise); throw from further out')
        elif status == LOST:
            err = PartLost(self.error_message(status, edge, R), after)
        else:
            return super()._raise(status, edge, R, after)
        if after is not None:
            err.args = (f'after {after} throws the orbit left the domain of f: {err}',)
        raise err


def _classify(edge0, edge, rot):
    return 'jog' if edge == edge0 and abs(rot) < math.pi else 'flip'
