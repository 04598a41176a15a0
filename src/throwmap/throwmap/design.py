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
Feeder design: evaluate many (h, release speed) designs of one part at once, compiled.

One compiled kernel evaluates a design from start to end without Python: the grasp radii at
its own h, the top of the invariant set Z (R_max, Prop. IV.4, found as
throwmap.basins.design_radii finds it but with fewer samples), a reference limit set (a long
orbit), a basin over every stable edge x radii (which starts reach the reference, which reach
another attractor), and, per goal edge and sensor position, the sensor design of
throwmap.sensor (guarantee and reach radius, the warm-up, the detection rate), the throws from
each start to its first proven ready, the seconds that takes per part and the feed rate under
the cycle-time model (:class:`CycleTime`). The starts are the basin's grid, or a chute's
arrival (``eval_options(arrival=...)``: one edge, R uniform in a range). The kernel releases
the GIL, so :func:`evaluate_grid` runs chunks of designs on threads, one per core.
docs/design.md has the method and the measured figures.

The throws are the scene's own: the kernel takes the one throw kernel of the scene's effect set
as an argument (throwmap.pipeline; the composed module, throwmap.compose, exports the compiled
``evaluate_chunk``) and gives each design its own Context (w, h, grasp radii). With effect
``finite_arm`` a design that puts the part past the arm's end from Z, a start or its limit set
is ST_OFF_ARM (not eligible); a throw that leaves the part outside f's domain fails the design.
:func:`check_scene` says which effects the search takes.
"""

from collections import namedtuple
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
import math
import os
import time

import numpy as np

from .catch import is_jog
from .errors import InputError
from .grasp import impulse_grasp_radius
from .jit import njit
from .pipeline import with_design
from .status import LOST, OFF_DOMAIN, OK, REC_COLS

_is_jog = njit(is_jog)      # the one jog/flip rule (throwmap.catch), compiled here as well

# Options of the compiled evaluation (one bundle; every field a number).
EvalOptions = namedtuple('EvalOptions', [
    'radii_per_edge',       # basin starts per stable edge
    'throws',               # throws per basin start
    'ref_throws',           # throws of the reference orbit (its second half is the limit set)
    'zmax_samples',         # samples per edge when growing R_max (Z of Prop. IV.4)
    'footprint',            # sensor half-width, m
    'arm_length',           # m (inf: no end)
    'settle_time',          # s, cycle-time model
    'reset_time',           # s, cycle-time model
    'mu',                   # friction coefficient of the grasp bounds (inf: none given)
    'arrival_edge',         # edge a chute drops parts on (-1: the grid of starts instead)
    'arrival_r_lo',         # m, the chute's range of R (uniform in [lo, hi])
    'arrival_r_hi',
    'arrival_starts',       # arrival starts (midpoints of equal bins of [lo, hi])
])

# Per-design results (columns of ``design``).
D_STATUS, D_R_HI, D_SHARE, D_ATTRACTORS, D_FLIP_MASK, D_EDGE_MASK, D_TRANSIENT, \
    D_FLIGHT, D_ERRORS, D_REF_EDGE, D_REF_R = range(11)
D_COLS = ('status', 'r_hi', 'share', 'attractors', 'flip_mask', 'edge_mask', 'transient_max',
          'mean_flight_time', 'errors', 'ref_edge', 'ref_R')
# Per-(design, goal edge, sensor position) results (columns of ``sensor``).
# The part_* columns are what a cell sees: seconds from a fresh part's arrival (a start) to its
# first proven ready, and parts per minute = 60 / the mean.
S_GOAL_IN, S_FEASIBLE, S_GUARANTEE, S_REACH, S_RADIUS, S_RATE, S_WARMUP, S_READY_MEAN, \
    S_READY_P95, S_READY_MAX, S_NEVER, S_FITS, S_PER_SECOND, S_PART_MEAN, S_PART_P95, \
    S_PARTS_PER_MINUTE = range(16)
S_COLS = ('goal_in', 'feasible', 'guarantee_radius', 'reach_radius', 'sensor_radius',
          'readies_per_throw', 'warmup', 'first_ready_mean', 'first_ready_p95',
          'first_ready_max', 'never_ready', 'sensor_fits', 'readies_per_second',
          'part_seconds_mean', 'part_seconds_p95', 'parts_per_minute')
# Design status codes.
ST_OK, ST_NO_GRASP, ST_THROW_ERROR, ST_NO_Z, ST_ARRIVAL_OUTSIDE, ST_OFF_ARM = 0, 1, 2, 3, 4, 5
STATUS_TEXT = {ST_OK: 'ok', ST_NO_GRASP: 'no start in the domain of f',
               ST_THROW_ERROR: 'a throw failed, or left the part outside the domain of f (below '
                               'R_min)',
               ST_NO_Z: 'R_max does not converge (Z of Prop. IV.4 is not bounded)',
               ST_ARRIVAL_OUTSIDE: 'the arrival range starts below R_min of its edge at this '
                                   'h (outside the domain of f)',
               ST_OFF_ARM: 'a throw from Z, from a start or in the limit set puts the part past '
                           "the arm's end (the scene's arm.length)"}


@dataclass(frozen=True)
class CycleTime:
    """
    The cycle-time model: one throw-catch cycle takes flight + settle + reset seconds.

    The flight time is each throw's own (release to first contact, from the throw map). The
    settle time covers the sticking impact, the rolling to rest and the sensor sample; the
    reset time is the actuator coming round to the next release. docs/design.md justifies the
    defaults; a scene sets them in ``cycle: {settle_time, reset_time}``.
    """

    settle_time: float = 0.25
    reset_time: float = 0.5

    @classmethod
    def from_scene(cls, scene):
        """Return the scene's model: its ``cycle`` section (checked on load) over the defaults."""
        return cls(**scene.cycle)


# --------------------------------------------------------------------------------- compiled
@njit
def _r_min(edge, h, mu, part):
    """Lower end of f's domain on a stable edge at offset h (ThrowModel.r_min, compiled)."""
    rg = impulse_grasp_radius(edge, h, mu, part.rho2, part.d, part.u_l, part.u_r)
    return max(rg, -part.u_l[edge]), rg


@njit
def _failure(throw_status):
    """Return the design status of a design one of whose throws failed with ``throw_status``."""
    return ST_OFF_ARM if throw_status == LOST else ST_THROW_ERROR


@njit
def _sees(part, edge, R, x, footprint):
    """throwmap.sensor.sees for one state (compiled; the same inequalities)."""
    u_min = part.U[edge, 0]
    u_max = part.U[edge, 0]
    for k in range(1, part.U.shape[1]):
        u_min = min(u_min, part.U[edge, k])
        u_max = max(u_max, part.U[edge, k])
    return (R + u_min <= x + footprint) and (R + u_max >= x - footprint)


def build_kernel(throw):
    """
    Return ``evaluate_chunk`` compiled over ``throw``, the scene's throw kernel.

    ``throw(edge, R, z0, z1, ctx, prm, rec) -> ThrowRecord`` is pipeline.build's throw_one. The
    kernel is a closure over it, as the pipeline is over its hooks: numba caches a function
    that calls a closure's compiled code (the composed module's entry point does), not one that
    takes compiled code as an argument.
    """

    @njit(cache=False)
    def z_top(ctx, prm, lo, r_max, rec, samples):
        """
        R_max over all stable edges: the top of Z (basins.design_radii's growth, compiled).

        Returns (status, R_max_all). R_flip^i is found on a grid (no bisection): it only seeds
        the growth, which then samples each [R_min^i, R_max^i] until f maps it into Z. Z only
        bounds the grid of starts: a sample that loses the part (past the arm's end, or past
        the pivot after a slip under liftoff) has no landing to grow Z by, and one that comes
        to rest below R_min still bounds it by where it rests; whether the design keeps the
        part is the orbits' question (the grid's starts and the reference).
        """
        part = ctx.part
        n = part.n
        for i in range(n):
            # R_min moved 1e-12 m inside the domain where the toe-stub bound (an open end) binds.
            lo[i] = max(lo[i], -part.u_l[i] + 1e-12)
            r_max[i] = lo[i]
            if not part.stable[i]:
                continue
            hi = max(lo[i] * 2.0, lo[i] + 4.0 * math.sqrt(part.rho2 + part.d[i] ** 2))
            found = False
            for _ in range(20):
                for s in range(samples):
                    R = lo[i] + (hi - lo[i]) * s / (samples - 1)
                    t = throw(i, R, 0.0, 0.0, ctx, prm, rec)
                    if t.status == LOST:
                        continue
                    if t.status != OK and t.status != OFF_DOMAIN:
                        return _failure(t.status), math.nan
                    if not _is_jog(i, t.edge, t.rot):
                        r_max[i] = R
                        found = True
                        break
                if found:
                    break
                hi *= 2.0
        for _ in range(50):
            grew = False
            for i in range(n):
                if not part.stable[i]:
                    continue
                for s in range(samples):
                    R = lo[i] + (r_max[i] - lo[i]) * s / (samples - 1)
                    t = throw(i, R, 0.0, 0.0, ctx, prm, rec)
                    if t.status == LOST:
                        continue
                    if t.status != OK and t.status != OFF_DOMAIN:
                        return _failure(t.status), math.nan
                    if t.R > r_max[t.edge] * (1.0 + 1e-12):
                        r_max[t.edge] = t.R
                        grew = True
            if not grew:
                top = 0.0
                for i in range(n):
                    if part.stable[i]:
                        top = max(top, r_max[i])
                return ST_OK, top
        return ST_NO_Z, math.nan

    @njit(cache=False)
    def orbit(edge, R, steps, ctx, prm, rec, oe, orr, orot, ot):
        """
        Iterate f recording edge, R, net rotation and flight time.

        Returns (throws done, the status of the throw after them: OK when all were done).
        """
        oe[0] = edge
        orr[0] = R
        orot[0] = 0.0
        ot[0] = 0.0
        for k in range(steps):
            t = throw(edge, R, 0.0, 0.0, ctx, prm, rec)
            if t.status != OK:
                return k, t.status
            oe[k + 1] = t.edge
            orr[k + 1] = t.R
            orot[k + 1] = t.rot
            ot[k + 1] = t.t
            edge = t.edge
            R = t.R
        return steps, OK

    @njit(cache=False)
    def evaluate_design(h, w, scene_ctx, prm, opt, goals, fractions, rec, edge_buf, work_e,
                        work_r, work_rot, work_t, ref_e, ref_r, ref_rot, ref_t, labels, scratch,
                        out_design, out_sensor, out_bands, out_starts):
        """
        Evaluate one design (module docstring); every buffer is the caller's (no allocation).

        scene_ctx, prm: the scene's Context and effect parameters (the design replaces w, h and
        the grasp radii).

        edge_buf: (4, n); work_*: (rows, throws + 1); ref_*: (ref_throws + 1,); labels, scratch:
        (rows,);
        out_design: (D_COLS,); out_sensor: (goals, fractions, S_COLS); out_bands: (n, 2) R band per
        edge of the reference limit set (NaN where absent); out_starts: (rows, 2) edge and R.
        rows = the grid's starts, then opt.arrival_starts arrival starts when opt.arrival_edge >= 0
        (the first readies then come from those; the basin and the warm-up cover the grid's too).
        """
        part = scene_ctx.part
        n = part.n
        nan = math.nan
        out_design[:] = nan
        out_sensor[:] = nan
        out_bands[:] = nan
        r_grasp = edge_buf[0]
        lo = edge_buf[1]
        n_stable = 0
        for i in range(n):
            lo[i], r_grasp[i] = _r_min(i, h, opt.mu, part)
            if part.stable[i]:
                n_stable += 1
        if n_stable == 0 or w <= 0.0:
            out_design[D_STATUS] = ST_NO_GRASP
            return
        for i in range(n):
            edge_buf[3, i] = lo[i]
        ctx = with_design(scene_ctx, w, h, r_grasp)
        st, r_hi = z_top(ctx, prm, edge_buf[3], edge_buf[2], rec, opt.zmax_samples)
        if st != ST_OK:
            out_design[D_STATUS] = st
            return
        out_design[D_R_HI] = r_hi
        # The basin grid (basins.default_grid with r_max = R_max_all).
        m = opt.radii_per_edge
        s = 0
        for i in range(n):
            if not part.stable[i]:
                continue
            top = max(r_hi, lo[i] * 1.5)
            a = lo[i] + 0.01 * (top - lo[i])
            step = (top - a) / (m - 1)
            for k in range(m):
                out_starts[s, 0] = i
                out_starts[s, 1] = k * step + a if k < m - 1 else top    # as np.linspace
                s += 1
        starts = s
        rows = starts
        # An arrival below f's domain at this h: the design is evaluated (its limit set, sensor and
        # rates are still figures to show) but gets no first readies and is not eligible.
        outside = opt.arrival_edge >= 0 and opt.arrival_r_lo < lo[opt.arrival_edge]
        if opt.arrival_edge >= 0 and not outside:
            na = opt.arrival_starts
            for k in range(na):
                out_starts[starts + k, 0] = opt.arrival_edge
                out_starts[starts + k, 1] = opt.arrival_r_lo + (k + 0.5) / na * (
                    opt.arrival_r_hi - opt.arrival_r_lo)
            rows = starts + na
        # Reference limit set: from the first stable edge of the goals at 1.5 R_min (the scene's
        # default start), the second half of a long orbit.
        e0 = goals[0]
        nref = opt.ref_throws
        done, st = orbit(e0, 1.5 * lo[e0], nref, ctx, prm, rec, ref_e, ref_r, ref_rot, ref_t)
        out_design[D_REF_EDGE] = e0
        out_design[D_REF_R] = 1.5 * lo[e0]
        if done < nref:
            out_design[D_STATUS] = _failure(st)
            return
        tail0 = nref // 2
        rmin_all = math.inf
        rmax_all = -math.inf
        flip_mask = 0
        edge_mask = 0
        flight = 0.0
        for k in range(tail0, nref + 1):
            e = ref_e[k]
            r = ref_r[k]
            edge_mask |= 1 << e
            if math.isnan(out_bands[e, 0]) or r < out_bands[e, 0]:
                out_bands[e, 0] = r
            if math.isnan(out_bands[e, 1]) or r > out_bands[e, 1]:
                out_bands[e, 1] = r
            rmin_all = min(rmin_all, r)
            rmax_all = max(rmax_all, r)
            if k > tail0:
                flight += ref_t[k]
                if not _is_jog(ref_e[k - 1], e, ref_rot[k]):
                    flip_mask |= 1 << e
        flight /= nref - tail0
        out_design[D_FLIGHT] = flight
        out_design[D_FLIP_MASK] = flip_mask
        out_design[D_EDGE_MASK] = edge_mask
        tol = 0.01 * (rmax_all - rmin_all) + 1e-12
        # Basin: label 0 = reaches the reference limit set: its last half flips to exactly the
        # edges the reference flips to (the bands, a finite orbit's estimate, only time the
        # transient: last throw outside them, within tol); -1 = a throw failed; else the mask of
        # edges its tail flips to (+ bit 62: a tail without flips is not 0).
        T = opt.throws
        in_ref = 0
        errors = 0
        losses = 0
        transient_max = 0
        for s in range(starts):
            done, st = orbit(int(out_starts[s, 0]), out_starts[s, 1], T, ctx, prm, rec,
                             work_e[s], work_r[s], work_rot[s], work_t[s])
            if done < T:
                labels[s] = -1
                errors += 1
                losses += st == LOST
                for k in range(done + 1, T + 1):
                    work_e[s, k] = -1
                continue
            last_out = -1
            for k in range(T + 1):
                e = work_e[s, k]
                r = work_r[s, k]
                if math.isnan(out_bands[e, 0]) or not (out_bands[e, 0] - tol <= r
                                                       <= out_bands[e, 1] + tol):
                    last_out = k
            transient = last_out + 1
            own = 0
            for k in range(T // 2 + 1, T + 1):
                if not _is_jog(work_e[s, k - 1], work_e[s, k], work_rot[s, k]):
                    own |= 1 << work_e[s, k]
            if own == flip_mask:
                labels[s] = 0
                in_ref += 1
                transient_max = max(transient_max, transient)
            else:
                labels[s] = own | (1 << 62)
        # Arrival starts: only their first readies (and the warm-up) use them; an orbit that
        # leaves the domain of f gets no ready (never_ready), as a failing grid start would.
        for s in range(starts, rows):
            done, _ = orbit(int(out_starts[s, 0]), out_starts[s, 1], T, ctx, prm, rec,
                            work_e[s], work_r[s], work_rot[s], work_t[s])
            for k in range(done + 1, T + 1):
                work_e[s, k] = -1
        first_row = starts if rows > starts else 0
        # Distinct attractors: the reference (if reached) plus every other label.
        others = 0
        for s in range(starts):
            if labels[s] > 0:
                seen = False
                for q in range(s):
                    if labels[q] == labels[s]:
                        seen = True
                        break
                if not seen:
                    others += 1
        out_design[D_SHARE] = in_ref / starts
        out_design[D_ATTRACTORS] = others + (1 if in_ref > 0 else 0)
        out_design[D_TRANSIENT] = transient_max
        out_design[D_ERRORS] = errors
        out_design[D_STATUS] = ST_OK if errors == 0 else (ST_OFF_ARM if losses else
                                                          ST_THROW_ERROR)
        if outside:
            out_design[D_STATUS] = ST_ARRIVAL_OUTSIDE
        cycle = flight + opt.settle_time + opt.reset_time
        for gi in range(goals.shape[0]):
            goal = goals[gi]
            goal_in = not math.isnan(out_bands[goal, 0])
            other_top = -math.inf
            goal_top = -math.inf
            for e in range(n):
                if math.isnan(out_bands[e, 0]):
                    continue
                u_max = part.U[e, 0]
                for k in range(1, part.U.shape[1]):
                    u_max = max(u_max, part.U[e, k])
                if e == goal:
                    goal_top = out_bands[e, 1] + u_max
                else:
                    other_top = max(other_top, out_bands[e, 1] + u_max)
            guarantee = other_top + opt.footprint
            reach = goal_top + opt.footprint
            feasible = goal_in and reach > guarantee
            for fi in range(fractions.shape[0]):
                row = out_sensor[gi, fi]
                row[S_GOAL_IN] = goal_in
                row[S_FEASIBLE] = feasible
                row[S_GUARANTEE] = guarantee
                row[S_REACH] = reach
                if feasible and math.isinf(guarantee):
                    u_min = part.U[goal, 0]
                    for k in range(1, part.U.shape[1]):
                        u_min = min(u_min, part.U[goal, k])
                    start = out_bands[goal, 0] + u_min - opt.footprint
                    x = start + fractions[fi] * (reach - start)
                elif feasible:
                    x = guarantee + fractions[fi] * (reach - guarantee)
                else:
                    row[S_RADIUS] = guarantee
                    row[S_FITS] = 0.0
                    row[S_RATE] = 0.0
                    row[S_PER_SECOND] = 0.0
                    continue
                row[S_RADIUS] = x
                row[S_FITS] = x + opt.footprint <= opt.arm_length
                hits = 0
                for k in range(tail0, nref + 1):
                    if _sees(part, ref_e[k], ref_r[k], x, opt.footprint):
                        hits += 1
                rate = hits / (nref + 1 - tail0)
                row[S_RATE] = rate
                row[S_PER_SECOND] = rate / cycle
                warmup = 0
                for s in range(rows):
                    for k in range(T + 1):
                        e = work_e[s, k]
                        if e >= 0 and e != goal and _sees(part, e, work_r[s, k], x, opt.footprint):
                            warmup = max(warmup, k + 1)
                row[S_WARMUP] = warmup
                if outside:
                    continue
                never = 0
                got = 0
                total = 0.0
                for s in range(first_row, rows):
                    first = -1
                    for k in range(warmup, T + 1):
                        if work_e[s, k] == goal and _sees(part, goal, work_r[s, k], x,
                                                          opt.footprint):
                            first = k
                            break
                    if first < 0:
                        never += 1
                    else:
                        # Insertion into the sorted prefix scratch[:got].
                        q = got
                        while q > 0 and scratch[q - 1] > first:
                            scratch[q] = scratch[q - 1]
                            q -= 1
                        scratch[q] = first
                        got += 1
                        total += first
                row[S_NEVER] = never
                if got:
                    row[S_READY_MEAN] = total / got
                    row[S_READY_P95] = scratch[min(got - 1, int(math.ceil(0.95 * got)) - 1)]
                    row[S_READY_MAX] = scratch[got - 1] if never == 0 else math.inf
                    # Seconds per part: throws to the first ready x the limit set's mean cycle
                    # (flight + settle + reset), the same cycle as readies_per_second, so the two
                    # objectives price a throw alike. Fair for settle and reset (every throw's);
                    # it ignores that the throws before the first ready are partly the transient,
                    # whose flights differ from the limit set's: on the triangle it overstates the
                    # orbits' own flight times by 3-14 % (docs/design.md section 2). It leaves out
                    # the chute's drop and the cell's pick.
                    row[S_PART_MEAN] = row[S_READY_MEAN] * cycle
                    row[S_PART_P95] = row[S_READY_P95] * cycle
                    row[S_PARTS_PER_MINUTE] = (60.0 / row[S_PART_MEAN] if row[S_PART_MEAN] > 0
                                               else math.inf)

    @njit(cache=False)
    def evaluate_chunk(hs, ws, scene_ctx, prm, opt, goals, fractions, rec, edge_buf, work_e,
                       work_r, work_rot, work_t, ref_e, ref_r, ref_rot, ref_t, labels, scratch,
                       out_design, out_sensor, out_bands, out_starts):
        """
        evaluate_design over designs (hs[k], ws[k]) into out_*[k] (one thread's share).

        Called through the scene's composed module (``model.composed.evaluate_chunk``), whose
        entry point is cached on disk.
        """
        for k in range(hs.shape[0]):
            evaluate_design(hs[k], ws[k], scene_ctx, prm, opt, goals, fractions, rec,
                            edge_buf, work_e, work_r, work_rot, work_t, ref_e, ref_r, ref_rot,
                            ref_t, labels, scratch,
                            out_design[k], out_sensor[k], out_bands[k], out_starts[k])

    return evaluate_chunk


# --------------------------------------------------------------------------------- Python
@dataclass(frozen=True)
class GridResult:
    """Results of many designs: arrays indexed by design (and goal, sensor position)."""

    h: np.ndarray               # (designs,)
    w: np.ndarray
    goals: np.ndarray           # goal edges evaluated
    fractions: np.ndarray       # sensor positions: fraction of the window past the guarantee
    design: np.ndarray          # (designs, D_COLS)
    sensor: np.ndarray          # (designs, goals, fractions, S_COLS)
    bands: np.ndarray           # (designs, n, 2)
    starts: np.ndarray          # (designs, rows, 2): the grid's starts, then the arrival's
    seconds: float
    throws: int                 # throws done (an upper bound: failing orbits stop early)
    arrival: tuple = None       # (edge, R lo, R hi, starts): first readies from these

    def column(self, name, goal_index=None, fraction_index=None):
        if name in D_COLS:
            return self.design[:, D_COLS.index(name)]
        sel = self.sensor[:, slice(None) if goal_index is None else goal_index,
                          slice(None) if fraction_index is None else fraction_index]
        return sel[..., S_COLS.index(name)]


def check_scene(scene):
    """
    Raise InputError unless the design kernel can run the scene's own throw map.

    The kernel throws through the scene's kernel (any effect set), but it places its starts
    and the bound of Z from the impulse-cone domain at each design's h; an effect that moves
    the domain of f (a ``domain`` function: the grasp along a carry) would put them outside it.
    """
    moved = [n for n, module, _ in scene.effects.modules() if hasattr(module, 'domain')]
    if moved:
        raise InputError('effects', f'design search places its starts in the impulse-cone '
                         f'domain of f; effect {", ".join(moved)} moves the domain',
                         f'remove {", ".join(moved)} for the search, then check the chosen '
                         'design with it by `throwmap design`')


def eval_options(scene, radii_per_edge=20, throws=120, ref_throws=1500, zmax_samples=48,
                 cycle=None, arrival=None, arrival_starts=None):
    """
    Return the kernel's EvalOptions for ``scene`` (its footprint, arm length, mu, cycle).

    ``arrival``: (edge, R lo, R hi), a chute that drops parts on that stable edge with R
    uniform in [lo, hi] m: the first readies come from ``arrival_starts`` starts there
    (default: as many as the grid has) instead of the grid of starts. Whether the range lies
    in the domain of f depends on h: :func:`evaluate_grid` checks it per design.
    """
    n_grid = int(np.count_nonzero(scene.part.stable)) * radii_per_edge \
        if isinstance(radii_per_edge, int) else 0
    arrival_starts = arrival_starts if arrival_starts is not None else max(1, n_grid)
    # The upper limits keep the per-thread orbit buffers (starts x throws) far below memory.
    for name, value, least, most in (('radii_per_edge', radii_per_edge, 2, 1000),
                                     ('throws', throws, 10, 10000),
                                     ('ref_throws', ref_throws, 20, 100000),
                                     ('zmax_samples', zmax_samples, 8, 10000),
                                     ('arrival_starts', arrival_starts, 1, 100000)):
        if isinstance(value, bool) or not isinstance(value, int) or not least <= value <= most:
            raise InputError(name, f'must be an integer in [{least}, {most}], got {value!r}',
                             f'give {least} to {most}')
    cycle = cycle or CycleTime.from_scene(scene)
    mu = scene.model.mu
    arm = scene.arm_length if scene.arm_length is not None else math.inf
    edge, r_lo, r_hi = check_arrival(scene, arrival) if arrival is not None else (-1, 0.0, 0.0)
    return EvalOptions(int(radii_per_edge), int(throws), int(ref_throws), int(zmax_samples),
                       float(scene.sensor_footprint), float(arm), float(cycle.settle_time),
                       float(cycle.reset_time), math.inf if mu is None else float(mu),
                       int(edge), float(r_lo), float(r_hi), int(arrival_starts))


def check_arrival(scene, arrival):
    """Return (edge, R lo, R hi) of an arrival, or raise InputError saying what is wrong."""
    part = scene.part
    try:
        edge, r_lo, r_hi = arrival
    except (TypeError, ValueError):
        raise InputError('arrival', f'expected (edge, R lo, R hi), got {arrival!r}',
                         'give EDGE:RMIN:RMAX, e.g. 1:0.10:0.14') from None
    if isinstance(edge, bool) or not isinstance(edge, (int, np.integer)) \
            or edge not in part.stable_edges:
        raise InputError('arrival', f'edge {edge!r} is not a stable edge',
                         f'drop parts on one of {part.stable_edges}')
    if not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
               for x in (r_lo, r_hi)) or not r_lo <= r_hi:
        raise InputError('arrival', f'R range [{r_lo!r}, {r_hi!r}] m is not finite numbers '
                         'with RMIN <= RMAX', 'give e.g. 1:0.10:0.14 (m)')
    arm = scene.arm_length
    if arm is not None and r_hi > arm:
        raise InputError('arrival', f'R up to {r_hi} m lies beyond the arm ({arm} m)',
                         'drop parts on the arm')
    return int(edge), float(r_lo), float(r_hi)


def arrival_domain(part, opt, hs):
    """
    Return (R_min, R_grasp) of the arrival edge at each h: the lower end of f's domain there.

    Raise InputError naming that domain when the arrival range starts below it at every h
    (no design could take the chute's parts); a design below it alone is marked
    ST_ARRIVAL_OUTSIDE by the kernel (not eligible).
    """
    edge = opt.arrival_edge
    lows = np.array([_r_min(edge, float(h), opt.mu, part.arrays) for h in hs]).reshape(-1, 2)
    if lows.size and not (lows[:, 0] <= opt.arrival_r_lo).any():
        k = int(np.argmin(lows[:, 0]))
        where = (f'at h = {hs[k]:.5g} m' if len(hs) == 1 else
                 f'at every design h ({np.min(hs):.5g}..{np.max(hs):.5g} m; lowest at h = '
                 f'{hs[k]:.5g} m)')
        raise InputError('arrival', f'R from {opt.arrival_r_lo} m on edge {edge} lies outside '
                         f'the domain of f: R_min of edge {edge} is {lows[k, 0]:.5g} m '
                         f'(R_grasp {lows[k, 1]:.5g} m) {where}',
                         f'give an RMIN of at least {lows[k, 0]:.5g} m')
    return lows


def _rows(part, opt):
    starts = int(np.count_nonzero(part.stable)) * opt.radii_per_edge
    return starts + (opt.arrival_starts if opt.arrival_edge >= 0 else 0)


def _buffers(part, opt):
    starts = _rows(part, opt)
    T = opt.throws
    work = (np.full((starts, T + 1), -1, dtype=np.int64), np.full((starts, T + 1), np.nan),
            np.zeros((starts, T + 1)), np.zeros((starts, T + 1)))
    ref = (np.full(opt.ref_throws + 1, -1, dtype=np.int64), np.full(opt.ref_throws + 1, np.nan),
           np.zeros(opt.ref_throws + 1), np.zeros(opt.ref_throws + 1))
    # No catch records are kept (a buffer without rows), as f_batch does.
    return ((np.empty((0, REC_COLS)), np.zeros((4, part.n))) + work + ref
            + (np.zeros(starts, dtype=np.int64), np.zeros(starts)))


def evaluate_grid(scene, hs, ws, goals=None, fractions=(0.25,), options=None, workers=None,
                  chunk=64, progress=None, refuse_arrival_outside=True):
    """
    Evaluate designs (hs[k], ws[k]) of ``scene``'s part (base model) on ``workers`` threads.

    ``goals``: goal edges to design the sensor for (default: the scene's goal edge, else every
    stable edge); the reference orbit starts on the first. ``progress(done, total)`` after
    each chunk. With an arrival (``options``) below f's domain at every design's h: InputError
    (:func:`arrival_domain`), unless ``refuse_arrival_outside`` is false (then those designs
    are marked ST_ARRIVAL_OUTSIDE like any other outside it).
    """
    check_scene(scene)
    part = scene.part
    opt = options or eval_options(scene)
    hs = np.ascontiguousarray(np.asarray(hs, dtype=float).ravel())
    ws = np.ascontiguousarray(np.asarray(ws, dtype=float).ravel())
    if hs.shape != ws.shape:
        raise InputError('designs', f'{hs.size} offsets but {ws.size} speeds',
                         'give one speed per offset')
    if goals is None:
        goals = [scene.goal_edge] if scene.goal_edge is not None else part.stable_edges
    goals = np.asarray([int(x) for x in goals], dtype=np.int64)
    for gl in goals:
        if gl not in part.stable_edges:
            raise InputError('goal_edge', f'{gl} is not a stable edge',
                             f'use one of {part.stable_edges}')
    fractions = np.asarray(fractions, dtype=float)
    if not np.all((fractions > 0) & (fractions < 1)):
        raise InputError('sensor_fraction', f'must lie in (0, 1), got {fractions.tolist()}',
                         'give fractions of the window between guarantee and reach, e.g. 0.25')
    model = scene.model
    kernel, ctx, prm = model.composed.evaluate_chunk, model.ctx, model.prm
    nd = hs.size
    if opt.arrival_edge >= 0 and refuse_arrival_outside:
        arrival_domain(part, opt, np.unique(hs))
    starts = _rows(part, opt)
    out_design = np.full((nd, len(D_COLS)), np.nan)
    out_sensor = np.full((nd, goals.size, fractions.size, len(S_COLS)), np.nan)
    out_bands = np.full((nd, part.n, 2), np.nan)
    out_starts = np.zeros((nd, starts, 2))
    workers = workers or min(os.cpu_count() or 1, 2)
    chunks = [(a, min(a + chunk, nd)) for a in range(0, nd, chunk)]

    def run(bounds):
        a, b = bounds
        kernel(hs[a:b], ws[a:b], ctx, prm, opt, goals, fractions, *_buffers(part, opt),
               out_design[a:b], out_sensor[a:b], out_bands[a:b], out_starts[a:b])
        return b - a

    # Compile (or load from numba's cache) before the clock starts: no design, same types.
    kernel(hs[:0], ws[:0], ctx, prm, opt, goals, fractions, *_buffers(part, opt),
           out_design[:0], out_sensor[:0], out_bands[:0], out_starts[:0])
    t0 = time.perf_counter()
    done = 0
    if workers <= 1 or len(chunks) <= 1:
        for c in chunks:
            done += run(c)
            if progress:
                progress(done, nd)
    else:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            for k in pool.map(run, chunks):
                done += k
                if progress:
                    progress(done, nd)
    seconds = time.perf_counter() - t0
    throws = nd * (starts * opt.throws + opt.ref_throws)
    arrival = ((opt.arrival_edge, opt.arrival_r_lo, opt.arrival_r_hi, opt.arrival_starts)
               if opt.arrival_edge >= 0 else None)
    return GridResult(hs, ws, goals, fractions, out_design, out_sensor, out_bands, out_starts,
                      seconds, int(throws), arrival)
