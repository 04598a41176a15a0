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
Effect liftoff: the arm pushes the rolling part, never pulls it; where it would, the part leaves.

Physics: the paper rolls the part about its contact vertex as about a hinge. Per unit mass the
arm's forces on that vertex are, in closed form (throwmap.catch, docs/physics.md),
N(s) = |g| (1 - l^2/I) + 3 |g| l^2 s^2 / I - l K s and Ft = l cos(alpha) (3 |g| l s / I - K),
with s = sin(alpha), alpha the angle of (CM - pivot) from the arm and K the roll's energy
constant. A hinge could pull (N < 0); a real arm cannot. And where N reaches 0 the hinge still
needs a tangential force Ft, which no friction can give at N = 0: there the free part's pivot
vertex would accelerate INTO the arm (its free vertical acceleration is omega^2 l s - |g| < 0
exactly where N = 0), so the part cannot simply fly off: it first slips, and lifts off when the
normal force of the slipping contact turns negative (measured: docs/physics.md).

Model: the closed-form catch (throwmap.catch) is run; the first roll that leaves the friction
cone |Ft| <= mu N (N < 0 leaves it for every mu) is cut where it does (safe steps along its
path under the forces' closed forms, catch.first_cone_exit, the exit refined to 1e-14 rad), and
from that rolling state the event simulator (throwmap.event_sim,
no body force, the plastic impact with friction mu: Routh at e = 0, a unilateral Coulomb
contact with friction mu) slips, lifts off, flies, lands and settles. The catch's impacts must
use the same mu: where the e = 0 impact with friction mu is not the sticking one (the flight
impact, a landing, or the rocking on the final edge that the exact settling rule skips), the
whole throw is simulated from the release. A throw whose rolls and impacts all stay in the
cone is the base model's own, bit for bit (tested). mu: ``liftoff.mu``, else the scene's
``contact.mu``, else 1000 (the sticking limit: slip starts where N falls to |Ft| / 1000).

With another effect that needs the event simulator (air_drag, backplate_friction), the whole
throw runs there under this contact law. impact_restitution sets the contact law itself (its
``contact.pivot: unilateral`` is this physics with restitution): a scene names one of them.

Hooks: ``closed_motion``, ``impact`` (used where a force puts the whole throw in the event
simulator); Python: ``contact_law``. Scene: ``effects: [liftoff]``, optional
``liftoff: {mu: 1000}``.
"""

from collections import namedtuple
from dataclasses import dataclass
import math

import numpy as np

from ._common import check_keys, number, routh_stronge_impact
from .. import event_sim
from ..ballistic import first_contact, state_at
from ..catch import (catch_at_contact, first_cone_exit, flat_landing_edge, record, roll_pieces,
                     sticking_impact)
from ..jit import njit
from ..status import (ERR_SETTLE_CAP, EV_FLAT_LANDING, EV_FLIGHT_IMPACT, EV_LANDING, EV_LIFTOFF,
                      OK, Outcome, REC_COLS)

NAME = 'liftoff'
SCHEMA = {'liftoff': ('mu',)}
KNOBS = {}
# The sticking limit: slip starts where |Ft| = MU_DEFAULT N, a 1e-3 fraction of N from its zero.
MU_DEFAULT = 1000.0
# A roll's path is searched for where it leaves the friction cone in steps of at least
# 1 / CONE_SAMPLES of it (farther where the forces' closed forms prove it inside the cone).
CONE_SAMPLES = 256
# mu: the arm's friction while the part rolls on it; scratch: the closed-form catch writes its
# events here to find the first roll that leaves the cone (f and f_batch pass no record
# buffer), sized so that a catch under the impact cap always fits.
LiftoffParams = namedtuple('LiftoffParams', ['mu', 'scratch'])
SCRATCH_ROWS_MAX = 1 << 16


@dataclass(frozen=True)
class Liftoff:
    """The arm's friction coefficient at the rolling vertex (large: the paper's sticking)."""

    mu: float


def parse(scene):
    """From the scene's liftoff section (mu), else contact.mu, else MU_DEFAULT."""
    sec = scene.section('liftoff')
    check_keys(sec, set(SCHEMA['liftoff']), 'liftoff')
    mu = number(sec, 'mu', 'liftoff', 'the friction coefficient of the rolling vertex (> 0)',
                lo=0.0, lo_open=True)
    if mu is None:
        mu = scene.mu if scene.mu is not None else MU_DEFAULT
    return Liftoff(float(mu))


def slots(params):
    """Fill the closed-form motion, and the impact law (for a throw in the event simulator)."""
    return ('closed_motion', 'impact')


def contact_law(params):
    """For the event simulator: Coulomb friction mu, a pivot that may slip and lift off."""
    return event_sim.ContactLaw(float(params.mu), True, math.isinf(params.mu))


def bundle(params, part, knobs):
    """Return mu and the scratch record buffer (two rows per impact under the cap, and more)."""
    rows = min(2 * int(getattr(knobs, 'max_impacts', SCRATCH_ROWS_MAX)) + 8, SCRATCH_ROWS_MAX)
    return LiftoffParams(float(params.mu), np.zeros((rows, REC_COLS)))


@njit
def impact(rx, ry, vx, vy, om, rho2, prm):
    """Apply the plastic impact with the rolls' friction mu (Routh, e = 0): in the cone (hook)."""
    vx1, vy1, om1 = routh_stronge_impact(rx, ry, vx, vy, om, rho2, 0.0, prm.mu)
    return vx1, vy1, om1, False


# After the cone (or from the release, when an impact leaves it): slip, flight, impacts with
# friction mu, settling (no body force).
simulate = event_sim.build(impact=impact)

# An impact is the sticking one (eqs 7-9) when the e = 0 impact with friction mu agrees with it
# to this fraction of the speeds (it does exactly, up to rounding, when it ends stuck).
STICK_RTOL = 1e-12


@njit
def sticks(rx, ry, vx, vy, om, rho2, mu):
    """Tell whether the e = 0 impact with friction mu is the sticking impact of eqs 7-9."""
    rho = math.sqrt(rho2)
    ax, ay, ao = sticking_impact(rx, ry, vx, vy, om, rho2)
    bx, by, bo = routh_stronge_impact(rx, ry, vx, vy, om, rho2, 0.0, mu)
    tol = STICK_RTOL * (abs(vx) + abs(vy) + rho * abs(om))
    return abs(ax - bx) <= tol and abs(ay - by) <= tol and rho * abs(ao - bo) <= tol


@njit
def landing_sticks(i, rec, part, mu):
    """Tell whether the closed-form catch's landing in row i is the impact with friction mu."""
    q = int(rec[i, 1])
    j = int(rec[i, 2])
    p = int(rec[i, 8])
    om = rec[i, 4]
    # just before it: rolling about p at rate om with edge j flat (its resting frame)
    vx = om * part.V[j][p]
    vy = -om * part.U[j][p]
    return sticks(part.U[j][q], part.V[j][q], vx, vy, om, part.rho2, mu)


@njit
def _path(u, alpha, a_turn, target):
    # The angle at arc length u along a roll from alpha (through a_turn) to target.
    first = abs(a_turn - alpha)
    if u <= first:
        return alpha + math.copysign(u, a_turn - alpha), True
    return a_turn + math.copysign(u - first, target - a_turn), False


@njit
def roll_cone_exit(alpha, omega, target, lp, rho2, g_abs, mu):
    """
    Return (alpha, omega) where a roll first leaves the friction cone |Ft| <= mu N, else nan.

    N < 0 is outside it for every mu. Along the path (roll_pieces: through the turning point
    of a roll that turns back) piece by piece with catch.first_cone_exit: safe steps under the
    forces' closed forms, at least 1 / CONE_SAMPLES of the path long, the exit refined to
    1e-14 rad.
    """
    inertia = rho2 + lp * lp
    energy_k, peak, two, sg1, sg2 = roll_pieces(alpha, omega, target, lp, inertia, g_abs)
    a_turn = alpha
    if two and omega * (target - alpha) < 0.0:     # turns back where omega = 0
        a_turn = math.asin(peak)
        if alpha > 0.5 * math.pi:
            a_turn = math.pi - a_turn
    first = abs(a_turn - alpha)
    floor = (first + abs(target - a_turn)) / CONE_SAMPLES
    hit = -1.0
    if first > 0.0:
        hit = first_cone_exit(alpha, math.copysign(1.0, a_turn - alpha), first, energy_k, lp,
                              inertia, g_abs, mu, floor, 1e-14)
    if hit < 0.0:
        hit = first_cone_exit(a_turn, math.copysign(1.0, target - a_turn),
                              abs(target - a_turn), energy_k, lp, inertia, g_abs, mu, floor,
                              1e-14)
        if hit < 0.0:
            return math.nan, math.nan
        hit += first
    a, on_first = _path(hit, alpha, a_turn, target)
    w2 = max(energy_k - 2.0 * g_abs * lp * math.sin(a) / inertia, 0.0)
    return a, (sg1 if on_first else sg2) * math.sqrt(w2)


@njit
def rocking_sticks(i, rec, part, g_abs, mu):
    """
    Tell whether the rocking after the last landing (row i) stays stuck with friction mu.

    The closed-form catch ends a throw whose last landing keeps turning on a stable edge by
    the exact settling rule (it rocks down to rest where it landed). Each rock rolls about the
    landed vertex q up to a turning point and back, then lands on the other vertex p of the
    edge: the friction the roll needs is checked along its path (catch.first_cone_exit), the
    landing's impact like the catch's (its impulse ratio does not depend on the rate, so one
    check covers them all).
    """
    q = int(rec[i, 1])
    j = int(rec[i, 2])
    p = int(rec[i, 8])
    om = rec[i, 5]
    lq = part.vrad[q]
    inertia = part.rho2 + lq * lq
    a0 = part.acw[q] if q == j else part.accw[q]
    energy_k = om * om + 2.0 * g_abs * lq * math.sin(a0) / inertia
    peak = min(energy_k * inertia / (2.0 * g_abs * lq), 1.0)
    a_turn = math.asin(peak)
    if a0 > 0.5 * math.pi:
        a_turn = math.pi - a_turn
    length = abs(a_turn - a0)
    if first_cone_exit(a0, math.copysign(1.0, a_turn - a0), length, energy_k, lq, inertia,
                       g_abs, mu, length / CONE_SAMPLES, 1e-14) >= 0.0:
        return False
    # back down, rolling about q at -om, onto p (edge j flat)
    return sticks(part.U[j][p], part.V[j][p], -om * part.V[j][q], om * part.U[j][q], -om,
                  part.rho2, mu)


@njit
def _touch(lo, hi, x):
    if math.isfinite(x):
        return min(lo, x), max(hi, x)
    return lo, hi


@njit
def _copy_row(dst, i, src, k):
    for c in range(src.shape[1]):
        dst[i, c] = src[k, c]


@njit
def closed_motion(edge, x0, y0, phi0, vx, vy, om, ctx, prm, rec):
    """
    Fly and catch in closed form until a roll leaves the friction cone, then simulate events.

    From there the event simulator slips, lifts off, flies, lands (sticking) and settles.

    Returns the motion's Outcome (throwmap.status), as throwmap.pipeline.closed_motion.
    """
    part = ctx.part
    knobs = ctx.knobs
    g = ctx.g
    g_abs = -g
    scratch = prm.scratch
    nan = math.nan
    status, t, k = first_contact(edge, y0, phi0, vy, om, g, part, knobs)
    if status != OK:
        return Outcome(status, -1, nan, nan, nan, 0, -1, 0, math.inf, -math.inf)
    rx, ry, x_cm, xdot, ydot, phi, energy = state_at(t, edge, k, x0, y0, phi0, vx, vy, om, g,
                                                     part)
    # The closed-form catch's impacts stick; where the e = 0 impact with friction mu does not
    # (outside the cone, or a slip that outlasts compression), the whole throw is simulated
    # with it from the release: the impacts and the rolls then use the same friction.
    if flat_landing_edge(math.atan2(-ry, -rx), k, knobs.flat_landing_tol, part) >= 0:
        inside = abs(xdot) <= prm.mu * max(-ydot, 0.0)
    else:
        inside = sticks(rx, ry, xdot, ydot, om, part.rho2, prm.mu)
    if not inside:
        return simulate(edge, x0, y0, phi0, vx, vy, om, g, part, knobs, ctx.law, prm, rec)
    st, j, r1, rot, imp, ns, lo, hi = catch_at_contact(k, phi, rx, ry, x_cm, xdot, ydot, om,
                                                       energy, g_abs, part, knobs, scratch)
    lift = -1
    a_lift = nan
    w_lift = nan
    if st == OK:
        for i in range(min(ns, scratch.shape[0])):
            if scratch[i, 0] == EV_LANDING:
                # the roll that ends in this landing, then the landing's impact
                a_lift, w_lift = roll_cone_exit(scratch[i, 9], scratch[i, 10], scratch[i, 11],
                                                part.vrad[int(scratch[i, 8])], part.rho2, g_abs,
                                                prm.mu)
                if not math.isnan(a_lift):
                    lift = i
                    break
                if not landing_sticks(i, scratch, part, prm.mu):
                    return simulate(edge, x0, y0, phi0, vx, vy, om, g, part, knobs, ctx.law,
                                    prm, rec)
    if lift < 0:
        last = min(ns, scratch.shape[0]) - 1
        if (st == OK and not knobs.first_stable and last >= 0 and scratch[last, 0] == EV_LANDING
                and scratch[last, 5] != 0.0
                and not rocking_sticks(last, scratch, part, g_abs, prm.mu)):
            return simulate(edge, x0, y0, phi0, vx, vy, om, g, part, knobs, ctx.law, prm, rec)
        for i in range(min(ns, scratch.shape[0])):
            if i < rec.shape[0]:
                _copy_row(rec, i, scratch, i)
        return Outcome(st, j, r1, t, rot, imp, k, ns, lo, hi)
    # Keep the events before the roll that leaves the cone; it ends there.
    nrec = 0
    impacts = 0
    x_lo = math.inf
    x_hi = -math.inf
    rot_lift = rot
    for i in range(ns):
        kind = scratch[i, 0]
        if i < lift:
            if kind == EV_FLIGHT_IMPACT or kind == EV_FLAT_LANDING or kind == EV_LANDING:
                impacts += 1
            x_lo, x_hi = _touch(x_lo, x_hi, scratch[i, 3])
            x_lo, x_hi = _touch(x_lo, x_hi, scratch[i, 12])
            if kind == EV_FLAT_LANDING:   # the edge that landed flat: both its ends
                jf = int(scratch[i, 2])
                x_other = scratch[i, 3] + (part.edge_len[jf] if jf == int(scratch[i, 1])
                                           else -part.edge_len[jf])
                x_lo, x_hi = _touch(x_lo, x_hi, x_other)
            if nrec < rec.shape[0]:
                _copy_row(rec, nrec, scratch, i)
            nrec += 1
        elif kind == EV_LANDING:
            rot_lift -= scratch[i, 11] - scratch[i, 9]
    p = int(scratch[lift, 8])
    xp = scratch[lift, 12]
    a0 = scratch[lift, 9]
    lp = part.vrad[p]
    ca = math.cos(a_lift)
    sa = math.sin(a_lift)
    e_lift = 0.5 * (part.rho2 + lp * lp) * w_lift * w_lift + g_abs * lp * sa
    nrec = record(rec, nrec, EV_LIFTOFF, p, -1, xp, w_lift, w_lift, e_lift, e_lift, p, a0,
                  scratch[lift, 10], a_lift, xp)
    # The rolling state where the cone is left, in the start edge's frame, handed to the
    # event simulator (its records go to the scratch buffer, then after ours).
    st, j, r1, _, rot, imp2, _, ns, lo, hi = simulate(
        edge, xp + lp * ca, lp * sa, rot_lift + (a_lift - a0), -w_lift * lp * sa,
        w_lift * lp * ca, w_lift, g, part, knobs, ctx.law, prm, scratch)
    for i in range(min(ns, scratch.shape[0])):
        if nrec < rec.shape[0]:
            _copy_row(rec, nrec, scratch, i)
        nrec += 1
    impacts += imp2
    if impacts > knobs.max_impacts and st == OK:
        st = ERR_SETTLE_CAP
    if st != OK:
        return Outcome(st, -1, nan, t, nan, impacts, k, nrec, x_lo, x_hi)
    return Outcome(OK, j, r1, t, rot, impacts, k, nrec, min(x_lo, lo), max(x_hi, hi))
