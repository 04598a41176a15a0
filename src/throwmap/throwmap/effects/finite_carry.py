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
Effect finite_carry: a non-impulsive throw along an arm profile theta(t).

Physics: the arm starts horizontal and at rest and turns counterclockwise with constant angular
acceleration a = w^2 / (2 theta_r) until it reaches the release angle theta_r at speed w (the
release speed), after T_c = 2 theta_r / w. During the carry the part must stay in a dynamic
grasp: at every instant the wrench of section III.A.1,
w = theta'' (-(h+d), R, rho^2) + theta'^2 (-R, -(h+d), 0) + (-g sin theta, -g cos theta, 0),
must lie in the contact wrench cone W^i (all four w^T (w_j x w_k) <= 0, throwmap.grasp); it is
checked at accuracy.carry_samples + 1 evenly spaced instants, end points included. A state that
fails is outside the domain (DomainError 'carry_grasp' naming the instant and the constraint).
The cone needs the friction coefficient: contact.mu is required.

At release the part leaves with the arm's rigid motion: CM at Rot(theta_r) (R, h + d), velocity
w z x CM, rotation theta_r and rate w; flight is ballistic from that state (throwmap.ballistic).

The arm's return: with return_time T_r the arm goes from (theta_r, w) back to (0, 0) along
the cubic Hermite curve; the part must clear the moving arm at every sampled instant of
[0, T_r] and may not reach the horizontal arm before T_r (else the throw fails with 'arm_strike':
the model has no impacts with a moving arm). Only vertices above the arm's extent count (the
scene's arm.length with finite_arm). Without return_time the arm is back at once (the base
model's assumption). The catch is on the horizontal arm, unchanged.

Hooks: ``release`` (the grasp along the carry, the release state) and ``check`` (the returning
arm). The domain per edge is an interval of R (:func:`domain`): the carry keeps the grasp on
one interval, which a fast carry bounds above (its centripetal pull outgrows the cone), and the
returning arm's strikes cut its lower end. Limit: theta_r -> 0 gives the impulsive throw: the
release state tends to eqs 5-6 and the grasp test to the impulse-cone bounds (1)-(4) (both
tested).

Scene: throw: {release_speed_deg: 320, carry: {profile: constant_acceleration,
release_angle_deg: 5, return_time: 0.05}}; contact: {mu: 0.8}; effects: [finite_carry].
"""

from collections import namedtuple
from dataclasses import dataclass
import math

import numpy as np

from ._common import check_keys, number
from ..errors import DomainError, InputError
from ..grasp import cone_margins, cone_normals
from ..jit import njit
from ..status import bound_name, ERR_ARM_STRIKE, ERR_CARRY_GRASP, OK

NAME = 'finite_carry'
SCHEMA = {'throw': ('carry',)}
KNOBS = {'carry_samples': 200}
PROFILES = ('constant_acceleration',)
KEYS = {'profile', 'release_angle', 'release_angle_deg', 'return_time'}

# theta_r (rad), return_time (s, 0: back at once), samples (carry_samples), mu (contact.mu),
# arm_length (m, inf without finite_arm); per sampled instant k of the carry (k / samples of
# T_c), whatever the speed: (k / samples)^2, and sin and cos of the arm's angle there,
# theta_r (k / samples)^2.
CarryParams = namedtuple('CarryParams', ['theta_r', 'return_time', 'samples', 'mu',
                                         'arm_length', 'q', 'sin_th', 'cos_th'])


@dataclass(frozen=True)
class FiniteCarry:
    """Parameters: profile, release angle, return time; contact.mu and the arm's length."""

    profile: str
    release_angle: float    # rad
    return_time: float      # s; 0 means the arm is back at once
    mu: float
    arm_length: float       # m; inf without finite_arm


def parse(scene):
    """From throw.carry, contact.mu and arm.length."""
    carry = scene.section('throw').get('carry')
    if carry is None:
        raise InputError('throw.carry', 'missing (effect finite_carry needs it)',
                         'give throw: {carry: {profile: constant_acceleration, '
                         'release_angle_deg: 5}}')
    check_keys(carry, KEYS, 'throw.carry')
    profile = carry.get('profile', 'constant_acceleration')
    if profile not in PROFILES:
        raise InputError('throw.carry.profile', f'unknown profile {profile!r}',
                         f'use one of {", ".join(PROFILES)}')
    theta = number(carry, 'release_angle', 'throw.carry', 'the release angle theta_r > 0',
                   lo=0.0, lo_open=True, hi=math.radians(60),
                   scale_keys=[('release_angle', 1.0),
                               ('release_angle_deg', math.pi / 180.0)])
    if theta is None:
        raise InputError('throw.carry.release_angle_deg', 'missing',
                         'give the release angle theta_r > 0, e.g. release_angle_deg: 5')
    ret = number(carry, 'return_time', 'throw.carry', 'the return time in s (> 0)', lo=0.0,
                 lo_open=True, default=0.0)
    if scene.mu is None:
        raise InputError('contact.mu', 'missing (effect finite_carry checks the wrench cone of '
                         'section III.A.1, which needs the friction coefficient)',
                         'give contact: {mu: ...}, the part/arm Coulomb coefficient')
    arm = math.inf if scene.arm_length is None else float(scene.arm_length)
    return FiniteCarry(profile, theta, ret, float(scene.mu), arm)


def slots(params):
    """Fill release; and check (the returning arm) when the arm takes time to return."""
    return ('release', 'check') if params.return_time > 0.0 else ('release',)


def bundle(params, part, knobs):
    """Return the compiled parameters."""
    samples = int(knobs.carry_samples)
    q = (np.arange(samples + 1) / samples) ** 2
    theta = float(params.release_angle) * q
    return CarryParams(float(params.release_angle), float(params.return_time), samples,
                       float(params.mu), float(params.arm_length), q, np.sin(theta),
                       np.cos(theta))


@njit
def release_state(edge, R, w, h, theta_r, d):
    """
    Return the release state (x0, y0, phi0, vx, vy, omega) in frame F (y0 from the pivot).

    The part rests on ``edge`` at radius R of an arm at angle theta_r turning at w about the
    pivot (theta_r = 0 is eq 5 at t = 0).
    """
    c = math.cos(theta_r)
    s = math.sin(theta_r)
    px = c * R - s * (h + d[edge])
    py = s * R + c * (h + d[edge])
    return px, py, theta_r, -w * py, w * px, w


@njit
def carry_margin(edge, R, w, h, g, mu, theta_r, samples, rho2, d, u_l, u_r):
    """
    Return the largest wrench-cone margin along the carry (<= 0: in a dynamic grasp).

    Returns (margin, sample index, constraint 1..4) of the worst instant.
    """
    hd = h + d[edge]
    a = w * w / (2.0 * theta_r)
    tc = 2.0 * theta_r / w
    worst = -math.inf
    worst_k = 0
    worst_c = 0
    for k in range(samples + 1):
        t = tc * k / samples
        th = 0.5 * a * t * t
        thd = a * t
        m = cone_margins(u_l[edge], u_r[edge], -d[edge], mu,
                         -a * hd - thd * thd * R - g * math.sin(th),
                         a * R - thd * thd * hd - g * math.cos(th), a * rho2)
        for c in range(4):
            if m[c] > worst:
                worst = m[c]
                worst_k = k
                worst_c = c + 1
    return worst, worst_k, worst_c


@njit
def carry_holds(edge, R, w, h, g, mu, q, sin_th, cos_th, theta_r, rho2, d, u_l, u_r):
    """
    Tell whether the part stays in a dynamic grasp at every sampled instant of the carry.

    The instants and the test of :func:`carry_margin` (its margins' signs: each margin is
    w^T (w_j x w_k) / |w|), without its trigonometry: the arm's angle at instant k is
    theta_r (k / samples)^2 and its rate squared w^2 (k / samples)^2 whatever the speed, so
    their sines and cosines come from tables (``q``, ``sin_th``, ``cos_th``) made once.
    """
    hd = h + d[edge]
    a = w * w / (2.0 * theta_r)
    n10, n11, n12, n20, n21, n22, n30, n31, n32, n40, n41, n42 = cone_normals(
        u_l[edge], u_r[edge], -d[edge], mu)
    w2 = a * rho2
    for k in range(q.size):
        thd2 = w * w * q[k]
        w0 = -a * hd - thd2 * R - g * sin_th[k]
        w1 = a * R - thd2 * hd - g * cos_th[k]
        if (w0 * n10 + w1 * n11 + w2 * n12 > 0.0 or w0 * n20 + w1 * n21 + w2 * n22 > 0.0
                or w0 * n30 + w1 * n31 + w2 * n32 > 0.0
                or w0 * n40 + w1 * n41 + w2 * n42 > 0.0):
            return False
    return True


@njit
def carry_interval(edge, w, h, g, mu, theta_r, samples, rho2, d, u_l, u_r):
    """
    Return (lo, hi): the radii at which the carry keeps the grasp at every sampled instant.

    The wrench is affine in R, w = W0 + R W1, and each cone test w . n_c <= 0 is linear in w,
    so every instant and constraint bounds R from one side: the grasp set is one interval
    (possibly empty: lo > hi; possibly unbounded above: hi = inf). The toe-stub bound is not
    applied here.
    """
    hd = h + d[edge]
    a = w * w / (2.0 * theta_r)
    tc = 2.0 * theta_r / w
    lo = -math.inf
    hi = math.inf
    for k in range(samples + 1):
        t = tc * k / samples
        th = 0.5 * a * t * t
        thd = a * t
        w0 = (-a * hd - g * math.sin(th), -thd * thd * hd - g * math.cos(th), a * rho2)
        w1 = (-thd * thd, a, 0.0)
        m0 = cone_margins(u_l[edge], u_r[edge], -d[edge], mu, w0[0], w0[1], w0[2])
        m1 = cone_margins(u_l[edge], u_r[edge], -d[edge], mu, w1[0], w1[1], w1[2])
        n0 = math.sqrt(w0[0] * w0[0] + w0[1] * w0[1] + w0[2] * w0[2])
        n1 = math.sqrt(w1[0] * w1[0] + w1[1] * w1[1])
        if n0 == 0.0:
            n0 = 1.0
        if n1 == 0.0:
            n1 = 1.0
        for c in range(4):
            A = m0[c] * n0      # margin (unnormalised) = A + B R
            B = m1[c] * n1
            if B > 0.0:
                hi = min(hi, -A / B)
            elif B < 0.0:
                lo = max(lo, -A / B)
            elif A > 0.0:
                return math.inf, -math.inf
    return lo, hi


@njit
def release(edge, R, w, h, ctx, prm):
    """Check the grasp along the carry, then return the state at release, y0 over the arm."""
    part = ctx.part
    if not carry_holds(edge, R, w, h, ctx.g, prm.mu, prm.q, prm.sin_th, prm.cos_th,
                       prm.theta_r, part.rho2, part.d, part.u_l, part.u_r):
        return ERR_CARRY_GRASP, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    x0, y0, phi0, vx, vy, om = release_state(edge, R, w, h, prm.theta_r, part.d)
    return OK, x0, y0 - h, phi0, vx, vy, om


@njit
def arm_clearance(edge, x0, y0, phi0, vx, vy, om, g, h, theta_r, w, ret_time, samples, arm_len,
                  part):
    """
    Return the smallest clearance of the part's vertices over the returning arm.

    The arm follows the Hermite profile from (theta_r, w) to (0, 0) in ret_time; only vertices
    above the arm's extent [0, arm_len] count. (x0, y0) is the CM at release from the pivot.
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
        for j in range(part.n):
            xv = xc + cp * part.U[edge, j] - sp * part.V[edge, j]
            yv = yc + sp * part.U[edge, j] + cp * part.V[edge, j]
            along = c * xv + sn * yv
            if along < 0.0 or along > arm_len:
                continue
            clear = -sn * xv + c * yv - h
            if clear < worst:
                worst = clear
    return worst


@njit
def check(outcome, release, edge, ctx, prm):
    """Fail the throw if the returning arm meets the part or is not back before it lands (hook)."""
    if outcome.status == OK and (outcome.t < prm.return_time or arm_clearance(
            edge, release.x0, release.y0 + release.h, release.phi0, release.vx, release.vy,
            release.om, ctx.g, release.h, prm.theta_r, release.w, prm.return_time, prm.samples,
            prm.arm_length, ctx.part) < 0.0):
        return ERR_ARM_STRIKE
    return outcome.status


# ------------------------------------------------------------------------------- Python level
# Throws per edge, at most, to find where the returning arm clears the part: a 1 mm grid with
# closed-form throws (microseconds each); a coarser one through the event simulator.
STRIKE_STEP = 1e-3
STRIKE_SCAN = 1000
STRIKE_SCAN_GENERAL = 100


def domain(model, params):
    """
    Return the domain per edge as a list of intervals [(lo, hi), ...] (empty: none).

    The carry's grasp holds on one interval of R per edge (:func:`carry_interval`, exact at the
    sampled instants; it can be bounded above: a fast carry's centripetal pull outgrows the
    friction cone). With a returning arm, the radii it strikes are cut from the interval's
    lower end: a scan on a 1 mm grid over [lo, min(hi, 1 m)] (at most STRIKE_SCAN throws, or
    STRIKE_SCAN_GENERAL when the throws need the event simulator), then bisection to 1e-7 m
    (the throws are checked again one by one: f raises 'arm_strike').
    """
    part = model.part
    out = {}
    for i in part.stable_edges:
        lo, hi = carry_interval(int(i), model.w, model.h, model.g, params.mu,
                                params.release_angle, model.knobs.carry_samples, part.rho2,
                                part.d, part.u_l, part.u_r)
        lo = max(lo, float(-part.u_l[i]), 0.0)
        if not lo < hi:
            out[int(i)] = []
            continue
        if params.return_time > 0.0:
            lo = _strike_clear(model, int(i), lo, hi)
        out[int(i)] = [(float(lo), float(hi))] if lo < hi else []
    return out


def _strike_clear(model, edge, lo, hi):
    """Return the smallest R in [lo, hi] above which the returning arm clears the part."""
    top = min(hi, max(1.0, 2.0 * lo))
    cap = STRIKE_SCAN_GENERAL if model.effects.general else STRIKE_SCAN
    count = max(2, min(cap, int(math.ceil((top - lo) / STRIKE_STEP))))
    rs = np.linspace(lo, top, count + 1)[1:]
    rs[-1] = min(rs[-1], np.nextafter(top, -np.inf))
    st = model.nominal_status(np.full(rs.size, edge), rs)
    failing = np.flatnonzero(st == ERR_ARM_STRIKE)
    if failing.size == 0:
        return lo
    k = int(failing[-1])
    if k + 1 >= rs.size:
        return hi if top >= hi else top
    a, b = float(rs[k]), float(rs[k + 1])
    while b - a > 1e-7:
        mid = 0.5 * (a + b)
        if model.nominal_status(np.array([edge]), np.array([mid]))[0] == ERR_ARM_STRIKE:
            a = mid
        else:
            b = mid
    return b


def domain_error(model, params, edge, R):
    """Return the DomainError of (edge, R) with the carry, or None inside the domain."""
    part = model.part
    margin, k, c = carry_margin(int(edge), float(R), model.w, model.h, model.g, params.mu,
                                params.release_angle, model.knobs.carry_samples, part.rho2,
                                part.d, part.u_l, part.u_r)
    if margin > 0.0:
        tc = 2 * params.release_angle / model.w
        return DomainError('carry_grasp', f'no dynamic grasp on edge {edge} at R = {R:.6g} m '
                           f'during the carry: constraint ({c}) ({bound_name(c, False)}) fails '
                           f'at t = {tc * k / model.knobs.carry_samples * 1000:.3f} ms of '
                           f'{tc * 1000:.3f} ms (margin {margin:.3g}); the carry holds the part '
                           f'on edge {edge} for R in {_spans(model.domain_intervals(edge))}',
                           margin=margin)
    if not R + part.u_l[edge] > 0:
        return DomainError('toe_stub', f'the left vertex of edge {edge} is not right of the '
                           'pivot')
    spans = model.domain_intervals(edge)
    if spans and R < spans[0][0]:
        return DomainError('carry_domain', f'on edge {edge} the returning arm meets the part '
                           f'below R = {spans[0][0]:.6g} m; got R = {R:.6g} m (domain: '
                           f'{_spans(spans)})', margin=spans[0][0] - R)
    return None


def _spans(spans):
    if not spans:
        return ('no radius at all (the carry is too abrupt for contact.mu: carry over a larger '
                'release angle, or give a larger mu)')
    return ' and '.join(f'[{lo:.6g}, {hi:.6g}] m' for lo, hi in spans)


def domain_note(model, params):
    """One line for ``throwmap grasp``: the carry's own domain next to the impulse cone's."""
    spans = []
    for i in model.part.stable_edges:
        ranges = ' and '.join(f'[{lo * 100:.3f}, {hi * 100:.3f}] cm'
                              for lo, hi in model.domain_intervals(i))
        spans.append(f'E{i}: {ranges or "none"}')
    return (f'with the finite carry (release at {math.degrees(params.release_angle):g} deg, '
            f'mu = {params.mu:g}): ' + ', '.join(spans))
