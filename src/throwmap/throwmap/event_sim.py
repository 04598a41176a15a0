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
The event-driven simulator of one throw and catch, for effects that break closed form.

:func:`build` makes the simulator from three hooks (docs/effects.md has the interface):

* ``body_force(vx, vy, om, phi, edge, prm) -> (fx, fy, torque)``: force and torque about the
  CM per unit mass on the part moving at (vx, vy, om), rotated by phi from its resting pose on
  the start edge; acts in flight and in every contact phase (backplate_friction, air_drag).
* ``contact_load(phase, n, vslip, om, phi, edge, prm) -> (ft, torque)``: a load that the
  contact itself makes, told the phase (PHASE_ROLL, PHASE_SLIDE, PHASE_FLAT) and the normal
  force n per unit mass: a tangential force at the contact on top of the arm's friction and a
  torque about the CM (rolling_resistance). Affine in n on either side of 0, so that the
  contact equations, linear in n, are solved with it exactly.
* ``static_hold(phi, om, turned, size, pu, pv, g, edge, prm) -> (held, turn)``: whether the
  body force holds the part at rest on its pivot (pu, pv) at a turning point of a roll (or a
  creep), and the turn that releases it (backplate_friction).
* ``impact(rx, ry, vx, vy, om, rho2, prm) -> (vx, vy, om, bounces)``: the impact of the
  vertex at (rx, ry) from the CM (impact_restitution); ``bounces``: the part flies off again.

Defaults (:func:`no_force`, :func:`no_contact_load`, :func:`no_hold`, :func:`sticking_law`) are
the base model's. The
contact's friction coefficient, whether a pivot may slide and lift off, and whether the impact
law is the sticking one (then the exact settling rule holds) come as a :data:`ContactLaw`.
The simulator names no effect.

Phases (per unit mass, frame F, heights over the arm surface):
* FLIGHT: gravity plus the body force, integrated with fixed-step RK4 (``integrator_step``).
  Contact is looked for at the end of every step: a vertex at or below the arm and moving down.
  The crossing is refined by bisection on re-integrated sub-steps to ``contact_root_tol``. A
  graze shorter than a step is missed; the accuracy benchmark shows how often. With
  ``flight_method`` 'rk8' the flight takes order-8 steps of ``flight_step`` instead; contacts
  are looked for on each step's quintic Hermite interpolant (positions, velocities and
  accelerations at both ends) at points no farther apart than ``integrator_step`` (farther
  where a bound on the vertices' downward speed proves the arm out of reach), bisected there,
  and the state at the crossing is integrated from the step's start in one order-8 sub-step
  (:func:`build`'s ``flight_to_contact``). With ``flight_method`` 'picard' the flight is the
  series about the ballistic flight of throwmap.picard (pieces split at the drag's kinks).
  Without a body force the flight is the base model's closed form (:func:`ballistic_to_contact`)
  whatever ``flight_method`` says.
* IMPACT at one vertex: the impact hook. A vertex that stays on the arm has its normal velocity
  removed (a further normal impulse, which only dissipates); a pinned pivot (not
  ``unilateral``) is then caught by a sticking impulse. A pinned pivot also holds a vertex that
  bounces off with no way back (free normal acceleration >= 0): that bounce is plastic.
* CONTACT at one vertex P: sticking (rolling about P) or sliding along the arm, integrated with
  RK4 at ``roll_step``. Events: another vertex lands (impact there; if the old pivot would then
  be driven into the arm, the edge lands flat instead), the normal force turns negative
  (liftoff into flight), the friction force leaves the cone (stick -> slip), the slip velocity
  reaches zero (slip -> stick test); located by regula falsi on the quantity that crossed zero
  along the step's quintic Hermite interpolant (positions, velocities and accelerations at
  both ends; :func:`build`'s ``first_contact_event``). With ``roll_method`` 'energy' a
  sticking roll is in closed form, its liftoff and slip found in the roll angle
  (``closed_roll``; without a body force by safe steps under the forces' closed forms,
  catch.first_cone_exit).
* FLAT on edge j: two-point contact, sliding with Coulomb friction until it stops; a vertex whose
  share of the normal force turns negative starts a rotation about the other one; at rest on an
  unstable edge the part tips over catch.tip_pivot.
* Settling: at rest flat on a stable edge. With the sticking impact law and mu = inf the base
  model's rule applies (catch.stays_on_edge). Otherwise, rocking is simulated until the energy
  above the flat pose falls below ``settle_energy``; then the part is laid flat about its pivot.
"""

from collections import namedtuple
import math

from .accuracy import FLIGHT_PICARD, FLIGHT_RK8, ROLL_ENERGY
from .ballistic import advancement_step, vertex_first_contact
from .bracket import make_crossing, make_first_event
from .catch import (cone_margin, first_cone_exit, flat_landing_edge, record, roll_force_rates,
                    stays_on_edge, sticking_impact, tip_pivot)
from .jit import njit
from .picard import body_centre_side, body_velocity, KINK_SKIP, make_flight
from .rk8 import make_step
from .status import (ERR_NONFINITE, ERR_PAINLEVE, ERR_SETTLE_CAP, ERR_SIM_CAP, EV_BOUNCE,
                     EV_FLAT_LANDING, EV_FLIGHT_IMPACT, EV_HELD, EV_LANDING, EV_LIFTOFF,
                     EV_SETTLE_SNAP, EV_TIP_FROM_REST, OK, Outcome)

# mu: Coulomb friction of the arm (inf: a vertex never slips); unilateral: a pivot may slide and
# lift off (False: it is pinned, the paper's rolling); sticking: the impact law is eqs 7-9.
ContactLaw = namedtuple('ContactLaw', ['mu', 'unilateral', 'sticking'])
STICKING_CONTACT = ContactLaw(math.inf, False, True)

EPS = 2.220446049250313e-16
GRADE = 4.0     # flight_method rk8: step ratio of the graded steps about a kink of the force
CENTRE_SAMPLES = 8  # flight_method rk8: points per step at which centre crossings are looked for
# A closed-form roll about a unilateral pivot looks for liftoff and slip in steps of the roll
# angle that the margins' bounds prove clear, but of at least this rate times roll_step
# (radians; the rk4 roll's resolution at 10 rad/s): near a tangency the margins would shrink
# the steps without end.
ROLL_EVENT_RATE = 10.0
MODE_FLIGHT = 0
MODE_CONTACT = 1
MODE_FLAT = 2
MODE_DONE = 3

# The contact phase a contact_load hook is told.
PHASE_ROLL = 0      # one vertex on the arm, sticking: the part rolls about it
PHASE_SLIDE = 1     # one vertex on the arm, slipping along it
PHASE_FLAT = 2      # an edge flat on the arm

# Event codes of a contact phase (contact_trigger).
NO_EVENT = 0
LANDING = 1
LIFTOFF = 2
STICK_TO_SLIP = 3
SLIP_REVERSAL = 4
PAINLEVE = 5


# ------------------------------------------------------------------------------- defaults
@njit(cache=False)
def no_force(vx, vy, om, phi, edge, prm):
    """Return no body force: the base model's flight and rolling."""
    return 0.0, 0.0, 0.0


@njit(cache=False)
def no_contact_load(phase, n, vslip, om, phi, edge, prm):
    return 0.0, 0.0


@njit(cache=False)
def no_hold(phi, om, turned, size, pu, pv, g, edge, prm):
    """Hold nothing: the part never rests on a corner."""
    return False, 0.0


@njit(cache=False)
def sticking_law(rx, ry, vx, vy, om, rho2, prm):
    """Apply the base model's impact: sticking (eqs 7-9), never a bounce."""
    vx1, vy1, om1 = sticking_impact(rx, ry, vx, vy, om, rho2)
    return vx1, vy1, om1, False


# ------------------------------------------------------------------------------- helpers
@njit
def lowest_approaching(x, y, phi, vx, vy, om, bu, bv, skip):
    """(index, height) of a vertex at or below the arm and moving down, else (-1, lowest)."""
    return lowest_approaching_cs(y, math.cos(phi), math.sin(phi), vy, om, bu, bv, skip)


@njit
def lowest_approaching_cs(y, c, s, vy, om, bu, bv, skip):
    """lowest_approaching with the cosine and sine of phi given (they are most of its cost)."""
    best = -1
    best_f = math.inf
    low = math.inf
    for k in range(bu.shape[0]):
        if k == skip:
            continue
        rx = c * bu[k] - s * bv[k]
        ry = s * bu[k] + c * bv[k]
        f = y + ry
        if f < low:
            low = f
        if f <= 0.0 and vy + om * rx < 0.0 and f < best_f:
            best = k
            best_f = f
    return best, low


@njit
def vertices_down(y, phi, bu, bv, skip):
    """Return how many vertices (but ``skip``) are at or below the arm."""
    c = math.cos(phi)
    s = math.sin(phi)
    count = 0
    for k in range(bu.shape[0]):
        if k != skip and y + s * bu[k] + c * bv[k] <= 0.0:
            count += 1
    return count


@njit
def vertex_normal(y, phi, vy, om, bu_k, bv_k):
    """Height over the arm and normal velocity of the vertex at (bu_k, bv_k) in the body frame."""
    c = math.cos(phi)
    s = math.sin(phi)
    return y + s * bu_k + c * bv_k, vy + om * (c * bu_k - s * bv_k)


@njit(inline=True)
def arm_contact(x, y, phi, vx, vy, om, bu, bv, sep, sep_rising):
    """
    Return (the vertex at or below the arm and moving down, else -1; sep after the look).

    The vertex that just left the arm (sep) counts again once it is seen above the arm, or,
    after a bounce (sep_rising: it left moving up), once it is seen coming down again.
    """
    if sep >= 0:
        h1, un1 = vertex_normal(y, phi, vy, om, bu[sep], bv[sep])
        if h1 > 0.0 or (sep_rising and un1 < 0.0):
            sep = -1
    k, _ = lowest_approaching(x, y, phi, vx, vy, om, bu, bv, sep)
    return k, sep


@njit
def energy(vx, vy, om, y, g, rho2):
    """Energy per unit mass over the arm surface."""
    return 0.5 * (vx * vx + vy * vy + rho2 * om * om) - g * y


@njit
def remove_normal(rx, ry, vx, vy, om, rho2):
    """Pure normal impulse that stops the contact point's normal motion (dissipative)."""
    un = vy + om * rx
    knn = 1.0 + rx * rx / rho2
    lam = -un / knn
    return vx, vy + lam, om + rx * lam / rho2


@njit
def flat_impact(vx, vy, mu):
    """
    Land flat: a two-point plastic impact.

    Vertical velocity and rotation stop; the tangential impulse stops the slide if the friction
    cone allows, else it is clipped to mu times the normal one. Returns (vx, om, vy).
    """
    pn = -vy
    if pn < 0.0:
        pn = 0.0
    pt = -vx
    if abs(pt) > mu * pn:
        pt = math.copysign(mu * pn, pt)
    return vx + pt, 0.0, 0.0


@njit
def contact_to_cm(xp, phi, vxp, om, bu_p, bv_p):
    """CM position and velocity (x, y, vx, vy) with vertex p at arm coordinate xp."""
    c = math.cos(phi)
    s = math.sin(phi)
    cx = -(c * bu_p - s * bv_p)
    cy = -(s * bu_p + c * bv_p)
    return xp + cx, cy, vxp - om * cy, om * cx


@njit
def centre_side(vx, vy, om, phi, bu, bv, k):
    """
    Return om times the side of edge k's line (k to k + 1) on which the instantaneous centre lies.

    The centre of the velocity field is z x v / om from the CM; in the body frame of the start
    edge (where bu, bv are) this is om-free once multiplied by om, so the value is smooth in the
    state and changes sign where the centre crosses the line (or om changes sign). Distributed
    friction-like forces (the plate's drag) are not smooth there.
    """
    bx, by = body_velocity(vx, vy, phi)
    return body_centre_side(bx, by, om, bu, bv, k)


@njit
def centre_crossing(vx0, vy0, om0, p0, vx1, vy1, om1, p1, bu, bv):
    """Return an edge whose line the instantaneous centre crosses between two states, or -1."""
    for k in range(bu.shape[0]):
        a = centre_side(vx0, vy0, om0, p0, bu, bv, k)
        b = centre_side(vx1, vy1, om1, p1, bu, bv, k)
        if (a > 0.0 and b <= 0.0) or (a < 0.0 and b >= 0.0):
            return k
    return -1


@njit
def roll_u(psi, u0, alpha0, sd, g, lp, inertia, a0, a2):
    """
    Return u = omega^2 / 2 and du/dpsi after a roll by psi >= 0 about a pinned pivot.

    The CM is at angle alpha0 from the arm, seen from the pivot at distance lp; sd the sense
    of the roll (the sign of omega); inertia = rho^2 + lp^2; the body force's torque about the
    pivot is -sd (a0 + a2 omega^2). The work-energy equation in the angle,
    inertia du/dpsi = sd g lp cos(alpha0 + sd psi) - a0 - 2 a2 u, is linear in u: closed form.
    """
    th = alpha0 + sd * psi
    if a2 == 0.0:
        u = u0 + g * lp * (math.sin(th) - math.sin(alpha0)) / inertia - a0 * psi / inertia
    else:
        beta = 2.0 * a2 / inertia
        ex = math.exp(-beta * psi)
        u = (ex * u0 + sd * g * lp / (inertia * (beta * beta + 1.0))
             * ((beta * math.cos(th) + sd * math.sin(th))
                - ex * (beta * math.cos(alpha0) + sd * math.sin(alpha0)))
             + a0 / inertia * math.expm1(-beta * psi) / beta)
    return u, (sd * g * lp * math.cos(th) - a0 - 2.0 * a2 * u) / inertia


@njit
def roll_turn(u0, alpha0, sd, psi_end, g, lp, inertia, a0, a2):
    """
    Return the roll angle in [0, psi_end] at which omega first vanishes, or -1 if it does not.

    Newton's method from psi = 0. While u falls, u is convex in psi (inertia u'' =
    |g| lp sin(theta) - 2 a2 u' > 0, the CM being above the arm), so the iterates approach the
    first zero from below and never pass it: an iterate beyond psi_end, or one where u has
    stopped falling, proves there is no zero before psi_end. From rest (u0 = 0, du > 0) the
    part rolls away from the top: the gravity torque grows, and where u' would reach zero
    inertia u'' > 0, so u' stays >= 0: no zero.
    """
    psi = 0.0
    for _ in range(200):
        u, du = roll_u(psi, u0, alpha0, sd, g, lp, inertia, a0, a2)
        if du >= 0.0:
            return -1.0
        if u <= 0.0:
            return psi
        step = -u / du
        psi += step
        if psi >= psi_end:
            return -1.0
        if step <= 4.0 * EPS * (1.0 + psi):
            return psi
    return psi


@njit
def hermite5(q0, v0, a0, q1, v1, a1, h):
    """Coefficients (q0, h v0, h^2 a0 / 2, c3, c4, c5) of the quintic in s = t / h on [0, h]."""
    d = q1 - q0 - h * v0 - 0.5 * h * h * a0
    e = h * (v1 - v0 - h * a0)
    f = h * h * (a1 - a0)
    return (q0, h * v0, 0.5 * h * h * a0, 10.0 * d - 4.0 * e + 0.5 * f,
            -15.0 * d + 7.0 * e - f, 6.0 * d - 3.0 * e + 0.5 * f)


@njit
def _quintic(c, s):
    """Value and d/ds of the quintic with coefficients c at s."""
    q = c[0] + s * (c[1] + s * (c[2] + s * (c[3] + s * (c[4] + s * c[5]))))
    dq = c[1] + s * (2.0 * c[2] + s * (3.0 * c[3] + s * (4.0 * c[4] + s * 5.0 * c[5])))
    return q, dq


@njit
def hermite_at(cx, cy, cp, tau, h):
    """State (x, y, phi, vx, vy, om) of the interpolants cx, cy, cp at time tau of [0, h]."""
    s = tau / h
    x, dx = _quintic(cx, s)
    y, dy = _quintic(cy, s)
    p, dp = _quintic(cp, s)
    return x, y, p, dx / h, dy / h, dp / h


@njit
def _event(rec, nrec, kind, vertex, edge, x, w0, w1, e0, e1):
    nan = math.nan
    return record(rec, nrec, kind, vertex, edge, x, w0, w1, e0, e1, nan, nan, nan, nan, nan)


# ------------------------------------------------------------------------------- the state
# The simulator's state between steps: one record, which every step function takes and returns
# anew (compiled code does not allocate, so it is a value, not a buffer).
SimState = namedtuple('SimState', [
    'mode',                             # MODE_FLIGHT, MODE_CONTACT, MODE_FLAT, MODE_DONE
    't', 'x', 'y', 'phi', 'vx', 'vy', 'om',     # time; the CM's pose and velocity (frame F)
    'sep', 'sep_rising',                # flight: the vertex that just left the arm; bounced?
    'p', 'xp', 'vxp', 'sliding', 'sigma',       # contact: the pivot, its x and slip, slip sign
    'fit_p', 'fit_ok', 'a0', 'a2',      # roll_method energy: pivot fit_p's torque fit
    'j_flat',                           # flat: the edge on the arm
    'out_edge', 'out_r',                # done: the resting edge and R
    'steps', 'impacts', 'nrec', 't_first', 'k_first', 'x_lo', 'x_hi'])   # what it reports
# A throw's constants: the start edge, g, the part's, knobs', contact law's and effects'
# bundles, the event records, the vertices in the start edge's frame and the part's size.
SimEnv = namedtuple('SimEnv', ['edge', 'g', 'part', 'knobs', 'law', 'prm', 'rec', 'bu', 'bv',
                               'size'])


@njit(inline=True)
def vertex_offset(c, s, bu_k, bv_k, y, vy, om, sep, k):
    """
    Return (f0, vy_k, rx, ry) of vertex k at a flight's start.

    Its height, the CM's vertical speed its search starts from, its offset from the CM. The
    vertex that just left (sep) is found when it comes back down: it left rising (a
    bounce) or with zero normal speed (a liftoff: its free normal acceleration >= 0); a
    rounding-sized approach would be found at t = 0.
    """
    rx = c * bu_k - s * bv_k
    ry = s * bu_k + c * bv_k
    if k == sep:
        return 0.0, vy - min(vy + om * rx, 0.0), rx, ry
    return max(y + ry, 0.0), vy, rx, ry


@njit(inline=True)
def first_step(f0, vy_k, g, om, rx, s):
    """
    Return a lower bound of vertex k's first contact: conservative advancement's first step.

    s = |(rx, ry)|, so that |F''| <= |g| + w^2 s (ballistic.advancement_step).
    """
    return advancement_step(f0, vy_k + om * rx, abs(g) + om * om * s)


@njit
def ballistic_to_contact(x, y, phi, vx, vy, om, t, sep, g, bu, bv, knobs, steps):
    """
    Fly in closed form until a vertex meets the arm moving down (no body force).

    Returns (status, vertex, x, y, phi, vx, vy, om, t, steps) at the contact: each vertex's
    first downward crossing by the base model's contact finder (ballistic.vertex_first_contact),
    the earliest wins (the lowest index at a tie). The vertex with the earliest lower bound
    (:func:`first_step`) is searched first; a vertex whose bound is past the contact found
    is not searched (the rectangle: 20 evaluations of a vertex's height a throw instead of 44,
    the same contacts).
    """
    c = math.cos(phi)
    s = math.sin(phi)
    n = bu.shape[0]
    k_first = 0
    tau_first = math.inf
    for k in range(n):
        f0, vy_k, rx, ry = vertex_offset(c, s, bu[k], bv[k], y, vy, om, sep, k)
        tau = first_step(f0, vy_k, g, om, rx, math.sqrt(rx * rx + ry * ry))
        if tau < tau_first:
            tau_first = tau
            k_first = k
    t_best = math.inf
    k_best = -1
    for j in range(n):
        k = k_first if j == 0 else (j - 1 if j <= k_first else j)
        f0, vy_k, rx, ry = vertex_offset(c, s, bu[k], bv[k], y, vy, om, sep, k)
        size = math.sqrt(rx * rx + ry * ry)
        if j > 0:
            tau = first_step(f0, vy_k, g, om, rx, size)
            if tau > t_best or (tau == t_best and k > k_best):
                continue
        tk = vertex_first_contact(f0, vy_k, g, om, rx, ry, size, t_best, knobs)
        if tk < 0.0:
            return ERR_SIM_CAP, -1, x, y, phi, vx, vy, om, t, steps + knobs.max_flight_steps
        if tk < t_best or (tk == t_best and k < k_best):
            t_best = tk
            k_best = k
    if k_best < 0:
        return ERR_NONFINITE, -1, x, y, phi, vx, vy, om, t, steps
    tb = t_best
    return (OK, k_best, x + vx * tb, y + (vy + 0.5 * g * tb) * tb, phi + om * tb, vx,
            vy + g * tb, om, t + tb, steps + 1)


@njit(inline=True)
def moved(st, t, x, y, phi, vx, vy, om, steps):
    return SimState(st.mode, t, x, y, phi, vx, vy, om, st.sep, st.sep_rising, st.p, st.xp,
                    st.vxp, st.sliding, st.sigma, st.fit_p, st.fit_ok, st.a0, st.a2, st.j_flat,
                    st.out_edge, st.out_r, steps, st.impacts, st.nrec, st.t_first, st.k_first,
                    st.x_lo, st.x_hi)


@njit(inline=True)
def counted(st):
    return moved(st, st.t, st.x, st.y, st.phi, st.vx, st.vy, st.om, st.steps + 1)


@njit(inline=True)
def with_slip(st, vxp, sliding, sigma):
    return SimState(st.mode, st.t, st.x, st.y, st.phi, st.vx, st.vy, st.om, st.sep,
                    st.sep_rising, st.p, st.xp, vxp, sliding, sigma, st.fit_p, st.fit_ok, st.a0,
                    st.a2, st.j_flat, st.out_edge, st.out_r, st.steps, st.impacts, st.nrec,
                    st.t_first, st.k_first, st.x_lo, st.x_hi)


@njit(inline=True)
def with_fit(st, fit_p, fit_ok, a0, a2):
    return SimState(st.mode, st.t, st.x, st.y, st.phi, st.vx, st.vy, st.om, st.sep,
                    st.sep_rising, st.p, st.xp, st.vxp, st.sliding, st.sigma, fit_p, fit_ok, a0,
                    a2, st.j_flat, st.out_edge, st.out_r, st.steps, st.impacts, st.nrec,
                    st.t_first, st.k_first, st.x_lo, st.x_hi)


@njit(inline=True)
def with_end(st, out_edge, out_r):
    return SimState(MODE_DONE, st.t, st.x, st.y, st.phi, st.vx, st.vy, st.om, st.sep,
                    st.sep_rising, st.p, st.xp, st.vxp, st.sliding, st.sigma, st.fit_p,
                    st.fit_ok, st.a0, st.a2, st.j_flat, out_edge, out_r, st.steps, st.impacts,
                    st.nrec, st.t_first, st.k_first, st.x_lo, st.x_hi)


@njit(inline=True)
def ended(st, status):
    """Return the Outcome of a simulation that stops with ``status`` (not OK)."""
    return Outcome(status, -1, math.nan, st.t_first, math.nan, st.impacts, st.k_first, st.nrec,
                   st.x_lo, st.x_hi)


@njit(inline=True)
def hermite_centre_event(tau, args):
    """Tell whether the instantaneous centre has crossed edge kc's line at tau of a step."""
    cx, cy, cp, h, bu, bv, kc, side0 = args
    _, _, ps, us, vs, os_ = hermite_at(cx, cy, cp, tau, h)
    return (0 if centre_side(us, vs, os_, ps, bu, bv, kc) * side0 > 0.0 else 1), 0


@njit(inline=True)
def hermite_contact_event(tau, args):
    """Return the vertex at or below the arm and moving down at tau of a step, if any."""
    cx, cy, cp, h, bu, bv, sep = args
    xs, ys, ps, us, vs, os_ = hermite_at(cx, cy, cp, tau, h)
    k, _ = lowest_approaching(xs, ys, ps, us, vs, os_, bu, bv, sep)
    return (1 if k >= 0 else 0), k


# ------------------------------------------------------------------------------- the builder
def build(body_force=no_force, contact_load=no_contact_load, static_hold=no_hold,
          impact=sticking_law):
    """
    Return the simulator ``simulate`` compiled over these hooks.

    simulate(edge, x0, y0, phi0, vx0, vy0, om0, g, part, knobs, law, prm, rec) throws from the
    release state (y0 over the arm, phi0 from the resting pose on ``edge``) and returns its
    :data:`throwmap.status.Outcome` (status, resting edge and R, first contact time and vertex,
    net rotation, impacts, records written, the arm coordinates touched). ``prm`` is passed to
    every hook; ``law`` is a :data:`ContactLaw`.
    """
    # A contact load depends on the normal force, which the roll's energy closed form does not
    # know: with one, rolls about a pinned pivot take rk4 steps (roll_method 'energy' falls back).
    contact_loaded = contact_load is not no_contact_load
    # Without a body force the flight is the base model's closed form, whatever flight_method
    # says (each method's steps are exact there; only their contact finders differ).
    free_flight = body_force is no_force

    @njit(cache=False)
    def flight_rhs(vx, vy, om, phi, g, rho2, edge, prm):
        fx, fy, tq = body_force(vx, vy, om, phi, edge, prm)
        return fx, g + fy, tq / rho2

    @njit(cache=False)
    def flight_step(x, y, phi, vx, vy, om, dt, g, rho2, edge, prm):
        """One RK4 step of free flight (exact for the ballistic case: polynomial of degree 2)."""
        a1, b1, c1 = flight_rhs(vx, vy, om, phi, g, rho2, edge, prm)
        h2 = 0.5 * dt
        a2, b2, c2 = flight_rhs(vx + h2 * a1, vy + h2 * b1, om + h2 * c1, phi + h2 * om, g,
                                rho2, edge, prm)
        a3, b3, c3 = flight_rhs(vx + h2 * a2, vy + h2 * b2, om + h2 * c2,
                                phi + h2 * (om + h2 * c1), g, rho2, edge, prm)
        a4, b4, c4 = flight_rhs(vx + dt * a3, vy + dt * b3, om + dt * c3,
                                phi + dt * (om + h2 * c2), g, rho2, edge, prm)
        # Positions integrate the velocity stages (RK4 of the first-order system).
        x_new = x + dt * (6.0 * vx + dt * (a1 + a2 + a3)) / 6.0
        y_new = y + dt * (6.0 * vy + dt * (b1 + b2 + b3)) / 6.0
        p_new = phi + dt * (6.0 * om + dt * (c1 + c2 + c3)) / 6.0
        vx_new = vx + dt * (a1 + 2.0 * a2 + 2.0 * a3 + a4) / 6.0
        vy_new = vy + dt * (b1 + 2.0 * b2 + 2.0 * b3 + b4) / 6.0
        om_new = om + dt * (c1 + 2.0 * c2 + 2.0 * c3 + c4) / 6.0
        return x_new, y_new, p_new, vx_new, vy_new, om_new

    rk8_step = make_step(flight_rhs)
    picard_flight = make_flight(flight_rhs, lowest_approaching, arm_contact)
    graded_flight = make_flight(flight_rhs, lowest_approaching, arm_contact, graded=True)
    centre_crossing_in = make_first_event(hermite_centre_event)
    contact_in_step = make_first_event(hermite_contact_event)

    @njit(cache=False)
    def flight_to_contact(x, y, phi, vx, vy, om, t, sep, sep_rising, g, rho2, bu, bv, ou, ov,
                          size, edge, prm, knobs, steps):
        """
        Fly with order-8 steps until a vertex meets the arm moving down (flight_method 'rk8').

        Returns (status, vertex, x, y, phi, vx, vy, om, t, steps) at the crossing. Each step's
        state in between is the quintic Hermite interpolant of its ends (error O(step^6) of the
        body force's smooth part: only used to find the crossing). Samples are at most
        integrator_step apart, farther only where the lowest vertex (but the one that just
        left) is higher than a bound on every vertex's downward speed over the step times the
        gap. The crossing is bisected on the interpolant to contact_root_tol and its state is
        then integrated from the step's start in one order-8 sub-step. Vertices: the hull's (bu,
        bv); the body force's kinks: where the centre crosses an edge of the outline (ou, ov),
        but not within KINK_SKIP h_fine of a step's start (a centre the drag holds on a line).
        """
        nan = math.nan
        H = knobs.flight_step
        dts = knobs.integrator_step
        root = knobs.contact_root_tol
        ax0, ay0, ao0 = flight_rhs(vx, vy, om, phi, g, rho2, edge, prm)
        tol = knobs.flight_tol
        h_fine = H / (GRADE * GRADE * GRADE)
        # a crossing this soon after a step's start is not split at (picard's KINK_SKIP)
        t_skip = max(64.0 * root, KINK_SKIP * h_fine)
        h_next = H
        while True:
            steps += 1
            if steps > knobs.max_sim_steps:
                return ERR_SIM_CAP, -1, x, y, phi, vx, vy, om, t, steps
            h_try = min(H, h_next)
            x1, y1, p1, vx1, vy1, om1, ax1, ay1, ao1, err = rk8_step(
                x, y, phi, vx, vy, om, h_try, ax0, ay0, ao0, g, rho2, edge, prm)
            if not (math.isfinite(y1) and math.isfinite(om1) and math.isfinite(x1)):
                return ERR_NONFINITE, -1, x, y, phi, vx, vy, om, t, steps
            cx = hermite5(x, vx, ax0, x1, vx1, ax1, h_try)
            cy = hermite5(y, vy, ay0, y1, vy1, ay1, h_try)
            cp = hermite5(phi, om, ao0, p1, om1, ao1, h_try)
            h_step = h_try
            # Look for the instantaneous centre crossing an edge's line at CENTRE_SAMPLES points
            # of the step (it can sweep across the whole part within a step near the apex).
            kc = -1
            lo = 0.0
            hi = 0.0
            _, _, pa, ua, va, oa = hermite_at(cx, cy, cp, 0.0, h_try)
            for i in range(1, CENTRE_SAMPLES + 1):
                hi = h_try * i / CENTRE_SAMPLES
                _, _, pb, ub, vb_, ob = hermite_at(cx, cy, cp, hi, h_try)
                kc = centre_crossing(ua, va, oa, pa, ub, vb_, ob, pb, ou, ov)
                if kc >= 0:
                    side0 = centre_side(ua, va, oa, pa, ou, ov, kc)
                    hk, _, _ = centre_crossing_in(lo, hi, root, 1, 0,
                                                  (cx, cy, cp, h_try, ou, ov, kc, side0))
                    if hk >= t_skip:
                        hi = hk
                        break
                    # At the step's start: the centre rides the line (the drag can hold it
                    # there, as on a 1 mm plate's long edge), where d^2 ln|d| is ~0 and the
                    # force smooth. Split there and steps shrink to rounding (no progress).
                    kc = -1
                lo = hi
                pa, ua, va, oa = pb, ub, vb_, ob
            passed = False
            if kc >= 0:
                # The body force may have a kink there (distributed friction): the solution's
                # higher derivatives blow up on either side. Approach it in steps that shrink
                # geometrically (GRADE), end a step just past it, and leave it likewise.
                passed = hi <= h_fine
                h_step = hi if passed else (1.0 - 1.0 / GRADE) * hi
                x1, y1, p1, vx1, vy1, om1, ax1, ay1, ao1, err = rk8_step(
                    x, y, phi, vx, vy, om, h_step, ax0, ay0, ao0, g, rho2, edge, prm)
                cx = hermite5(x, vx, ax0, x1, vx1, ax1, h_step)
                cy = hermite5(y, vy, ay0, y1, vy1, ay1, h_step)
                cp = hermite5(phi, om, ao0, p1, om1, ao1, h_step)
            if err > tol and h_step > 64.0 * root:
                # rejected: DOP853's step-size rule (order 8), at least a tenth
                h_next = h_step * max(0.1, 0.9 * (tol / err) ** 0.125)
                continue
            h_next = h_step * (5.0 if err == 0.0 else min(5.0, 0.9 * (tol / err) ** 0.125))
            if passed:
                # leave the kink from h_fine (a step cut short at it says little of the next;
                # error control rejects a step too long)
                h_next = h_fine
            elif kc >= 0:
                h_next = min(h_next, h_step)
            vb = 1.05 * (max(abs(vy), abs(vy1)) + max(abs(om), abs(om1)) * size) + 1e-12
            tau = 0.0
            hit = -1
            lo = 0.0
            while tau < h_step:
                xs, ys, ps, us, vs, os_ = hermite_at(cx, cy, cp, tau, h_step)
                _, low = lowest_approaching(xs, ys, ps, us, vs, os_, bu, bv, sep)
                gap = low / vb if low > 0.0 else 0.0
                lo = tau
                tau = min(h_step, tau + max(gap, dts))
                xs, ys, ps, us, vs, os_ = hermite_at(cx, cy, cp, tau, h_step)
                k, sep = arm_contact(xs, ys, ps, us, vs, os_, bu, bv, sep, sep_rising)
                if k >= 0:
                    hit = k
                    break
            if hit < 0:
                x, y, phi, vx, vy, om = x1, y1, p1, vx1, vy1, om1
                ax0, ay0, ao0 = ax1, ay1, ao1
                t += h_step
                continue
            hi, _, hit = contact_in_step(lo, tau, root, 1, hit,
                                         (cx, cy, cp, h_step, bu, bv, sep))
            xe, ye, pe, vxe, vye, ome, _, _, _, _ = rk8_step(x, y, phi, vx, vy, om, hi, ax0, ay0,
                                                             ao0, g, rho2, edge, prm)
            k2, _ = lowest_approaching(xe, ye, pe, vxe, vye, ome, bu, bv, sep)
            if k2 >= 0:
                hit = k2
            return OK, hit, xe, ye, pe, vxe, vye, ome, t + hi, steps
        return OK, -1, nan, nan, nan, nan, nan, nan, nan, steps

    @njit(cache=False)
    def pivot_torque(om, phi, bu_p, bv_p, edge, prm):
        """Torque about the pivot (bu_p, bv_p) of the body force while rolling about it at om."""
        c = math.cos(phi)
        s = math.sin(phi)
        cx = -(c * bu_p - s * bv_p)
        cy = -(s * bu_p + c * bv_p)
        fx, fy, tq = body_force(-om * cy, om * cx, om, phi, edge, prm)
        return tq + cx * fy - cy * fx

    @njit(cache=False)
    def roll_torque_fit(phi, bu_p, bv_p, edge, prm):
        """
        Return (ok, a0, a2): the body force's torque about a pivot as -sign(om) (a0 + a2 om^2).

        Fitted at om = 1 and 2 rad/s and checked, to 1e-9 of the torque, at om = 0, -1 and 4
        and half a radian further round: ok is False when the torque has another form (then
        the roll takes rk4 steps).
        """
        t1 = pivot_torque(1.0, phi, bu_p, bv_p, edge, prm)
        t2 = pivot_torque(2.0, phi, bu_p, bv_p, edge, prm)
        a2 = (t1 - t2) / 3.0
        a0 = -t1 - a2
        t4 = pivot_torque(4.0, phi, bu_p, bv_p, edge, prm)
        tol = 1e-9 * abs(t4)
        ok = (abs(pivot_torque(0.0, phi, bu_p, bv_p, edge, prm)) <= tol
              and abs(t4 + a0 + 16.0 * a2) <= tol
              and abs(pivot_torque(-1.0, phi, bu_p, bv_p, edge, prm) - a0 - a2) <= tol
              and abs(pivot_torque(1.0, phi + 0.5, bu_p, bv_p, edge, prm) - t1) <= tol
              and a0 >= -tol and a2 >= -tol)
        return ok, max(a0, 0.0), max(a2, 0.0)

    @njit(cache=False)
    def bounce_resolved(rx, ry, vx, vy, om, phi, g, rho2, root, scale, edge, prm, unilateral):
        """
        Tell whether a bounce of the vertex at (rx, ry) is one the simulation can resolve.

        The vertex leaves at normal speed u_n with the normal acceleration a_n of free flight;
        when it would come back (a_n < 0) sooner than ``root`` or rise by less than a few ulps
        of the coordinates (``scale``), the bounce is below resolution: a plastic contact. So
        restitution e -> 0 tends to the sticking model instead of a train of unresolved
        micro-bounces. A vertex that would not come back (a_n >= 0: a roll about it needs a
        pull) leaves a unilateral contact for good; a hinge (not ``unilateral``) holds it, so
        that bounce is plastic too: the pivot stays bilateral, and e -> 0 tends to the hinge
        model of e = 0 (the base model) state by state.
        """
        un = vy + om * rx
        _, ay, alpha = flight_rhs(vx, vy, om, phi, g, rho2, edge, prm)
        an = ay + alpha * rx - om * om * ry
        if an >= 0.0:
            return unilateral
        return -2.0 * un / an > root and -0.5 * un * un / an > 8.0 * EPS * scale

    @njit(cache=False)
    def contact_load_affine(phase, sgn_n, vslip, om, phi, edge, prm):
        """
        Return the contact load as (ft0, tq0) + n (ft1, tq1) for n of sign sgn_n.

        The hook is affine in n on either side of n = 0 (|n| in a Coulomb-type law).
        """
        ft0, tq0 = contact_load(phase, 0.0, vslip, om, phi, edge, prm)
        ft_n, tq_n = contact_load(phase, sgn_n, vslip, om, phi, edge, prm)
        return ft0, tq0, (ft_n - ft0) * sgn_n, (tq_n - tq0) * sgn_n

    @njit(cache=False)
    def contact_accel(xp, phi, vxp, om, sliding, sigma, bu_p, bv_p, g, rho2, mu, edge, prm):
        """
        Accelerations (axp, alpha) and contact force (Ft, N) with vertex p on the arm.

        As :func:`contact_accel_cs`, which takes the cosine and sine of phi.
        """
        return contact_accel_cs(phi, math.cos(phi), math.sin(phi), vxp, om, sliding, sigma, bu_p,
                                bv_p, g, rho2, mu, edge, prm)

    @njit(cache=False)
    def contact_accel_cs(phi, c, s, vxp, om, sliding, sigma, bu_p, bv_p, g, rho2, mu, edge, prm):
        """
        Accelerations (axp, alpha) and contact force (Ft, N) with vertex p on the arm.

        sliding = False: p sticks (axp = 0); True: p slides with friction -mu N sigma. Ft is
        the arm's friction (the contact load's tangential force comes on top). The contact
        load (ft0 + n ft1 at the contact, tq0 + n tq1 about the CM) enters the equations
        exactly: they stay linear in N. The status flag is False when no consistent normal
        force exists (Painleve).
        """
        cx = -(c * bu_p - s * bv_p)    # CM - P
        cy = -(s * bu_p + c * bv_p)
        vcx = vxp - om * cy
        vcy = om * cx
        fx, fy, tq = body_force(vcx, vcy, om, phi, edge, prm)
        phase = PHASE_SLIDE if sliding else PHASE_ROLL
        if not sliding:
            # The arm takes any tangential load of a sticking contact: only the torque counts.
            # Solved with N >= 0 first; a hinge pivot may need N < 0 (a load's other side).
            for sgn_n in (1.0, -1.0):
                ft0, tq0, ft1, tq1 = contact_load_affine(phase, sgn_n, vxp, om, phi, edge, prm)
                alpha = ((tq + tq0 + tq1 * (-om * om * cy - g - fy) + cx * (g + fy) - cy * fx)
                         / (rho2 + cx * cx + cy * cy - tq1 * cx))
                n = alpha * cx - om * om * cy - g - fy
                if n * sgn_n >= 0.0 or not contact_loaded:
                    ft = -alpha * cy - om * om * cx - fx - (ft0 + ft1 * n)
                    return 0.0, alpha, ft, n, True
            return 0.0, 0.0, 0.0, 0.0, False
        # Friction -mu |N| sigma: solve with N >= 0 first; a hinge pivot (bilateral) may need
        # N < 0, then the friction term changes sign.
        for sgn_n in (1.0, -1.0):
            ft0, tq0, ft1, tq1 = contact_load_affine(phase, sgn_n, vxp, om, phi, edge, prm)
            tq_l = tq + tq0 + cy * ft0
            ms = mu * sigma * sgn_n
            b = cx + ms * cy - tq1 - cy * ft1
            den = rho2 + b * cx
            if den <= 1e-12 * rho2:
                return 0.0, 0.0, 0.0, 0.0, False
            alpha = (tq_l + b * (om * om * cy + g + fy)) / den
            n = alpha * cx - om * om * cy - g - fy
            if n * sgn_n >= 0.0:
                ft = -ms * n
                axp = fx + ft + ft0 + ft1 * n + alpha * cy + om * om * cx
                return axp, alpha, ft, n, True
        return 0.0, 0.0, 0.0, 0.0, False

    @njit(cache=False)
    def contact_step(xp, phi, vxp, om, dt, a1, b1, sliding, sigma, bu_p, bv_p, g, rho2, mu, edge,
                     prm):
        """One RK4 step of the contact phase from the accelerations (a1, b1) at its start."""
        h2 = 0.5 * dt
        a2, b2, _, _, _ = contact_accel(xp + h2 * vxp, phi + h2 * om, vxp + h2 * a1,
                                        om + h2 * b1, sliding, sigma, bu_p, bv_p, g, rho2, mu,
                                        edge, prm)
        a3, b3, _, _, _ = contact_accel(xp + h2 * (vxp + h2 * a1), phi + h2 * (om + h2 * b1),
                                        vxp + h2 * a2, om + h2 * b2, sliding, sigma, bu_p, bv_p,
                                        g, rho2, mu, edge, prm)
        a4, b4, _, _, _ = contact_accel(xp + dt * (vxp + h2 * a2), phi + dt * (om + h2 * b2),
                                        vxp + dt * a3, om + dt * b3, sliding, sigma, bu_p, bv_p,
                                        g, rho2, mu, edge, prm)
        xp_new = xp + dt * (6.0 * vxp + dt * (a1 + a2 + a3)) / 6.0
        p_new = phi + dt * (6.0 * om + dt * (b1 + b2 + b3)) / 6.0
        v_new = vxp + dt * (a1 + 2.0 * a2 + 2.0 * a3 + a4) / 6.0
        o_new = om + dt * (b1 + 2.0 * b2 + 2.0 * b3 + b4) / 6.0
        if not sliding:
            return xp, p_new, 0.0, o_new
        return xp_new, p_new, v_new, o_new

    @njit(cache=False)
    def contact_trigger(xp, phi, vxp, om, sliding, sigma, p, bu, bv, g, rho2, law, edge, prm):
        """
        Return the event at a contact state (NO_EVENT, LANDING, ...), the landing vertex.

        And the accelerations (axp, alpha) there: the next step's first stage.
        """
        c = math.cos(phi)
        s = math.sin(phi)
        cx = -(c * bu[p] - s * bv[p])    # CM - P
        cy = -(s * bu[p] + c * bv[p])
        axp, alpha, ft, n, ok = contact_accel_cs(phi, c, s, vxp, om, sliding, sigma, bu[p],
                                                 bv[p], g, rho2, law.mu, edge, prm)
        k, _ = lowest_approaching_cs(cy, c, s, om * cx, om, bu, bv, p)
        if k >= 0:
            return LANDING, k, axp, alpha
        if not ok:
            return PAINLEVE, -1, axp, alpha
        if n < 0.0 and law.unilateral:
            return LIFTOFF, -1, axp, alpha
        if sliding:
            if vxp * sigma < 0.0:
                return SLIP_REVERSAL, -1, axp, alpha
        elif law.unilateral and abs(ft) > law.mu * n:
            return STICK_TO_SLIP, -1, axp, alpha
        return NO_EVENT, -1, axp, alpha

    @njit(cache=False)
    def contact_mode(vxp, xp, phi, om, p, bu, bv, g, rho2, law, edge, prm):
        """
        Return (sliding, sigma) for a new contact phase at vertex p with slip velocity vxp.

        A pinned pivot (not unilateral) never slides.
        """
        mu = law.mu
        if math.isinf(mu) or not law.unilateral:
            return False, 0.0
        if abs(vxp) > 1e-12:
            return True, math.copysign(1.0, vxp)
        _, _, ft, n, _ = contact_accel(xp, phi, 0.0, om, False, 0.0, bu[p], bv[p], g, rho2, mu,
                                       edge, prm)
        if abs(ft) <= mu * n:
            return False, 0.0
        # Slip starts in the direction in which, with friction opposing it, the point
        # accelerates.
        first = -math.copysign(1.0, ft)
        for sigma in (first, -first):
            axp, _, _, _, ok = contact_accel(xp, phi, 0.0, om, True, sigma, bu[p], bv[p], g,
                                             rho2, mu, edge, prm)
            if ok and axp * sigma > 0.0:
                return True, sigma
        return False, 0.0   # no consistent slip (Painleve): the point sticks

    @njit(cache=False)
    def flat_forces(vx, j, part, g, mu, phi, edge, prm):
        """Flat on edge j: (ax, N_left, N_right) for sliding at vx."""
        fx, fy, tq = body_force(vx, 0.0, 0.0, phi, edge, prm)
        n = -(g + fy)
        ft_l, tq_l = contact_load(PHASE_FLAT, n, vx, 0.0, phi, edge, prm)
        if vx != 0.0:
            ft = -mu * n * math.copysign(1.0, vx)
        else:
            ft = -(fx + ft_l)
            if abs(ft) > mu * n:
                ft = math.copysign(mu * n, ft)
        ft += ft_l
        nb = -(tq + tq_l + part.d[j] * ft + part.u_l[j] * n) / (part.u_r[j] - part.u_l[j])
        na = n - nb
        return fx + ft, na, nb

    # ------------------------------------------------------------ the step functions
    # Each takes the simulator's state (a SimState) and the throw's constants (a SimEnv) and
    # returns the next state; simulate runs them by mode.

    @njit(cache=False, inline=True)
    def rk4_flight_event(tau, args):
        """Return the vertex that meets the arm at the end of an rk4 flight step of tau."""
        x, y, phi, vx, vy, om, g, rho2, edge, prm, bu, bv, sep = args
        xm, ym, pm, vxm, vym, omm = flight_step(x, y, phi, vx, vy, om, tau, g, rho2, edge, prm)
        k, _ = lowest_approaching(xm, ym, pm, vxm, vym, omm, bu, bv, sep)
        return (1 if k >= 0 else 0), k

    contact_in_rk4_step = make_first_event(rk4_flight_event)

    @njit(cache=False, inline=True)
    def rk4_vertex_height(tau, args):
        """Return vertex k's height over the arm after an rk4 flight step of tau."""
        x, y, phi, vx, vy, om, g, rho2, edge, prm, bu, bv, sep, k = args
        _, ym, pm, _, vym, omm = flight_step(x, y, phi, vx, vy, om, tau, g, rho2, edge, prm)
        return vertex_normal(ym, pm, vym, omm, bu[k], bv[k])[0]

    rk4_height_crossing = make_crossing(rk4_vertex_height)

    @njit(cache=False, inline=True)
    def rk4_contact_in_step(dt, tol, k, args):
        """
        Return (tau, vertex) of the first contact within an rk4 flight step of dt.

        Vertex k, found at the step's end, by Illinois regula falsi on its height (a few
        sub-steps where bisection takes log2(dt / tol)), accepted where no other vertex (but
        the one that just left) is at or below the arm: two crossing within one step (a nearly
        flat landing) are bisected on the event, which finds the earlier.
        """
        x, y, phi, vx, vy, om, g, rho2, edge, prm, bu, bv, sep = args
        hargs = (x, y, phi, vx, vy, om, g, rho2, edge, prm, bu, bv, sep, k)
        f0 = rk4_vertex_height(0.0, hargs)
        f1 = rk4_vertex_height(dt, hargs)
        if f0 > 0.0 and f1 <= 0.0:
            tau = rk4_height_crossing(0.0, dt, f0, f1, tol, 200, hargs)
            xm, ym, pm, vxm, vym, omm = flight_step(x, y, phi, vx, vy, om, tau, g, rho2, edge,
                                                    prm)
            kh, _ = lowest_approaching(xm, ym, pm, vxm, vym, omm, bu, bv, sep)
            if kh == k and vertices_down(ym, pm, bu, bv, sep) == 1:
                return tau, k
        hi, _, k = contact_in_rk4_step(0.0, dt, tol, 1, k, args)
        return hi, k

    @njit(cache=False)
    def rk4_flight_to_contact(x, y, phi, vx, vy, om, t, sep, sep_rising, g, rho2, bu, bv, edge,
                              prm, knobs, steps):
        """
        Fly with RK4 steps of integrator_step until a vertex meets the arm moving down.

        Returns (status, vertex, x, y, phi, vx, vy, om, t, steps) at the crossing, bisected on
        re-integrated sub-steps. A graze shorter than a step is missed.
        """
        dt = knobs.integrator_step
        while True:
            x1, y1, p1, vx1, vy1, om1 = flight_step(x, y, phi, vx, vy, om, dt, g, rho2, edge, prm)
            if not (math.isfinite(y1) and math.isfinite(om1)):
                return ERR_NONFINITE, -1, x, y, phi, vx, vy, om, t, steps
            k, sep = arm_contact(x1, y1, p1, vx1, vy1, om1, bu, bv, sep, sep_rising)
            if k >= 0:
                break
            x, y, phi, vx, vy, om = x1, y1, p1, vx1, vy1, om1
            t += dt
            steps += 1
            if steps > knobs.max_sim_steps:
                return ERR_SIM_CAP, -1, x, y, phi, vx, vy, om, t, steps
        hi, k = rk4_contact_in_step(dt, knobs.contact_root_tol, k,
                                    (x, y, phi, vx, vy, om, g, rho2, edge, prm, bu, bv, sep))
        x, y, phi, vx, vy, om = flight_step(x, y, phi, vx, vy, om, hi, g, rho2, edge, prm)
        k2, _ = lowest_approaching(x, y, phi, vx, vy, om, bu, bv, sep)
        if k2 >= 0:
            k = k2
        return OK, k, x, y, phi, vx, vy, om, t + hi, steps

    @njit(cache=False, inline=True)
    def fly(st, env):
        """Fly to the next contact: return (status, vertex, the state there)."""
        knobs = env.knobs
        rho2 = env.part.rho2
        if free_flight:
            code, k, x, y, phi, vx, vy, om, t, steps = ballistic_to_contact(
                st.x, st.y, st.phi, st.vx, st.vy, st.om, st.t, st.sep, env.g, env.bu, env.bv,
                knobs, st.steps)
        elif knobs.flight_method == FLIGHT_RK8:
            code, k, x, y, phi, vx, vy, om, t, steps = flight_to_contact(
                st.x, st.y, st.phi, st.vx, st.vy, st.om, st.t, st.sep, st.sep_rising, env.g,
                rho2, env.bu, env.bv, env.part.OU[env.edge], env.part.OV[env.edge], env.size,
                env.edge, env.prm, knobs, st.steps)
        elif knobs.flight_method == FLIGHT_PICARD and knobs.flight_grade > 0.0:
            code, k, x, y, phi, vx, vy, om, t, steps, _, _ = graded_flight(
                st.x, st.y, st.phi, st.vx, st.vy, st.om, st.t, st.sep, st.sep_rising, env.g,
                rho2, env.bu, env.bv, env.part.OU[env.edge], env.part.OV[env.edge], env.size,
                env.edge, env.prm, knobs, st.steps)
        elif knobs.flight_method == FLIGHT_PICARD:
            code, k, x, y, phi, vx, vy, om, t, steps, _, _ = picard_flight(
                st.x, st.y, st.phi, st.vx, st.vy, st.om, st.t, st.sep, st.sep_rising, env.g,
                rho2, env.bu, env.bv, env.part.OU[env.edge], env.part.OV[env.edge], env.size,
                env.edge, env.prm, knobs, st.steps)
        else:
            code, k, x, y, phi, vx, vy, om, t, steps = rk4_flight_to_contact(
                st.x, st.y, st.phi, st.vx, st.vy, st.om, st.t, st.sep, st.sep_rising, env.g,
                rho2, env.bu, env.bv, env.edge, env.prm, knobs, st.steps)
        return code, k, moved(st, t, x, y, phi, vx, vy, om, steps)

    @njit(cache=False, inline=True)
    def lay_flat(st, env, q, j, xq, om_before, e_before, kind):
        """
        Land edge j flat with its vertex q at xq: the two-point plastic impact.

        Vertical velocity and rotation stop; the tangential impulse is clipped to mu times the
        normal one. With settle_rule first_stable a stable edge ends the catch.
        """
        part = env.part
        x_l = xq if j == q else xq - part.edge_len[j]
        vx, om, vy = flat_impact(st.vx, st.vy, env.law.mu)
        x = x_l - part.u_l[j]
        y = part.d[j]
        nrec = _event(env.rec, st.nrec, kind, q, j, xq, om_before, 0.0, e_before,
                      energy(vx, vy, om, y, env.g, part.rho2))
        mode = MODE_FLAT
        out_edge = -1
        out_r = math.nan
        if env.knobs.first_stable and part.stable[j]:
            mode = MODE_DONE
            out_edge = j
            out_r = x
        return SimState(mode, st.t, x, y, st.phi, vx, vy, om, st.sep, st.sep_rising, st.p,
                        st.xp, st.vxp, st.sliding, st.sigma, st.fit_p, st.fit_ok, st.a0, st.a2,
                        j, out_edge, out_r, st.steps, st.impacts, nrec, st.t_first, st.k_first,
                        min(st.x_lo, x_l), max(st.x_hi, x_l + part.edge_len[j]))

    @njit(cache=False, inline=True)
    def on_pivot(st, env, p, xp, vx, vy, om, ry, nrec):
        """Begin a contact phase at vertex p (rolling, or sliding as contact_mode says)."""
        vxp = vx - om * ry
        sliding, sigma = contact_mode(vxp, xp, st.phi, om, p, env.bu, env.bv, env.g,
                                      env.part.rho2, env.law, env.edge, env.prm)
        return SimState(MODE_CONTACT, st.t, st.x, st.y, st.phi, vx, vy, om, -1, False, p, xp,
                        vxp, sliding, sigma, st.fit_p, st.fit_ok, st.a0, st.a2, st.j_flat,
                        st.out_edge, st.out_r, st.steps, st.impacts, nrec, st.t_first,
                        st.k_first, st.x_lo, st.x_hi)

    @njit(cache=False, inline=True)
    def resolve_impact(st, env, q, j, pivot, xq, rx, ry, e_before, kind):
        """
        Resolve vertex q hitting the arm at xq, (rx, ry) from the CM: the one impact code.

        ``pivot``: the vertex the part rolled or slid on (-1 from flight); ``j``: the edge
        from it to q (-1: none). The impact hook gives the velocities after; if they would
        drive the old pivot into the arm, edge j lands flat instead. A bounce the simulation
        resolves flies on; else the vertex stays on the arm (its normal velocity removed, a
        pinned pivot caught sticking), the catch ends on a stable edge j when the settle rule
        says so, or a contact phase begins at q. ``kind``: the event recorded for a vertex
        that stays (EV_FLIGHT_IMPACT, EV_LANDING).
        """
        part = env.part
        g = env.g
        rho2 = part.rho2
        bu = env.bu
        bv = env.bv
        vx, vy, om, y = st.vx, st.vy, st.om, st.y
        vxa, vya, oma, bounces = impact(rx, ry, vx, vy, om, rho2, env.prm)
        if pivot >= 0 and j >= 0:
            c = math.cos(st.phi)
            s = math.sin(st.phi)
            if vya + oma * (c * bu[pivot] - s * bv[pivot]) < 0.0:
                return lay_flat(st, env, q, j, xq, om, e_before, EV_LANDING)
        if bounces and bounce_resolved(rx, ry, vxa, vya, oma, st.phi, g, rho2,
                                       env.knobs.contact_root_tol,
                                       abs(st.x) + abs(y) + env.size, env.edge, env.prm,
                                       env.law.unilateral):
            nrec = _event(env.rec, st.nrec, EV_BOUNCE, q, j, xq, om, oma, e_before,
                          energy(vxa, vya, oma, y, g, rho2))
            mode = MODE_FLIGHT
            out_edge = -1
            out_r = math.nan
            if env.knobs.first_stable and j >= 0 and part.stable[j]:
                mode = MODE_DONE
                out_edge = j
                out_r = (xq if j == q else xq - part.edge_len[j]) - part.u_l[j]
            return SimState(mode, st.t, st.x, y, st.phi, vxa, vya, oma, q, True, st.p, st.xp,
                            st.vxp, st.sliding, st.sigma, st.fit_p, st.fit_ok, st.a0, st.a2,
                            st.j_flat, out_edge, out_r, st.steps, st.impacts, nrec, st.t_first,
                            st.k_first, st.x_lo, st.x_hi)
        vxa, vya, oma = remove_normal(rx, ry, vxa, vya, oma, rho2)
        if not env.law.unilateral:
            # a pinned pivot: the foam catches a vertex that is still slipping
            vxa, vya, oma = sticking_impact(rx, ry, vxa, vya, oma, rho2)
        e_after = energy(vxa, vya, oma, y, g, rho2)
        nrec = _event(env.rec, st.nrec, kind, q, j, xq, om, oma, e_before, e_after)
        if j >= 0 and part.stable[j]:
            x_l = xq if j == q else xq - part.edge_len[j]
            g_abs = -g
            ke = e_after - g_abs * part.d[j]
            lq = math.sqrt(bu[q] * bu[q] + bv[q] * bv[q])
            lp = math.sqrt(bu[pivot] * bu[pivot] + bv[pivot] * bv[pivot])
            exact_rule = env.law.sticking and math.isinf(env.law.mu)
            settled = env.knobs.first_stable or (
                exact_rule and stays_on_edge(ke, lq, lp, part.d[j], g_abs))
            if not settled and not exact_rule and ke <= env.knobs.settle_energy:
                nrec = _event(env.rec, nrec, EV_SETTLE_SNAP, q, j, xq, oma, 0.0, e_after,
                              g_abs * part.d[j])
                settled = True
            if settled:
                return SimState(MODE_DONE, st.t, st.x, y, st.phi, vxa, vya, oma, st.sep,
                                st.sep_rising, st.p, st.xp, st.vxp, st.sliding, st.sigma,
                                st.fit_p, st.fit_ok, st.a0, st.a2, st.j_flat, j,
                                x_l - part.u_l[j], st.steps, st.impacts, nrec, st.t_first,
                                st.k_first, st.x_lo, st.x_hi)
        return on_pivot(st, env, q, xq, vxa, vya, oma, ry, nrec)

    @njit(cache=False, inline=True)
    def touch_down(st, env, k):
        """Flight ends with vertex k on the arm: an edge at k lying flat lands, else impact."""
        part = env.part
        c = math.cos(st.phi)
        s = math.sin(st.phi)
        rx = c * env.bu[k] - s * env.bv[k]
        ry = s * env.bu[k] + c * env.bv[k]
        y = -ry      # put the vertex exactly on the arm (error below root_tol * |v|)
        t_first, k_first = st.t_first, st.k_first
        if k_first < 0:
            k_first = k
            t_first = st.t
        xk = st.x + rx
        e_before = energy(st.vx, st.vy, st.om, y, env.g, part.rho2)
        alpha = math.atan2(-ry, -rx)
        jf = flat_landing_edge(alpha, k, env.knobs.flat_landing_tol, part)
        phi = st.phi
        if jf >= 0:
            # An edge at V^k lies flat: laid exactly flat at the vertex that hit (a
            # sub-tolerance turn about it), it lands on both corners.
            phi += (part.acw[k] if jf == k else part.accw[k]) - alpha
        st = SimState(st.mode, st.t, st.x, y, phi, st.vx, st.vy, st.om, -1, st.sep_rising, st.p,
                      st.xp, st.vxp, st.sliding, st.sigma, st.fit_p, st.fit_ok, st.a0, st.a2,
                      st.j_flat, st.out_edge, st.out_r, st.steps, st.impacts + 1, st.nrec,
                      t_first, k_first, min(st.x_lo, xk), max(st.x_hi, xk))
        if jf >= 0:
            return lay_flat(st, env, k, jf, xk, st.om, e_before, EV_FLAT_LANDING)
        return resolve_impact(st, env, k, -1, -1, xk, rx, ry, e_before, EV_FLIGHT_IMPACT)

    @njit(cache=False, inline=True)
    def contact_at(tau, args):
        """Return the contact state (xp, phi, vxp, om) at tau of the step (its interpolants)."""
        cx, cp, h = args[0], args[1], args[2]
        s = tau / h
        xm, vm = _quintic(cx, s)
        pm, omm = _quintic(cp, s)
        return xm, pm, vm / h, omm / h

    @njit(cache=False, inline=True)
    def contact_event_at(tau, args):
        """Return the event at tau of a contact step, and the landing vertex."""
        _, _, _, sliding, sigma, p, bu, bv, g, rho2, law, edge, prm = args
        xm, pm, vm, omm = contact_at(tau, args)
        code, kk, _, _ = contact_trigger(xm, pm, vm, omm, sliding, sigma, p, bu, bv, g, rho2,
                                         law, edge, prm)
        return code, kk

    event_in_contact_step = make_first_event(contact_event_at)

    @njit(cache=False)
    def event_quantity(xm, pm, vm, omm, code, kk, sliding, sigma, p, bu, bv, g, rho2, law, edge,
                       prm):
        """
        Return the continuous quantity whose sign change makes event ``code`` (kk: its vertex).

        At a contact state: the slip velocity along sigma (SLIP_REVERSAL), vertex kk's height
        (LANDING), n (LIFTOFF), mu n - |ft| (STICK_TO_SLIP); -1 where no normal force is
        consistent.
        """
        if code == SLIP_REVERSAL:
            return vm * sigma
        if code == LANDING:
            # vertex kk's height over the arm, pivot p on it: (R(pm) (b_kk - b_p))_y
            return math.sin(pm) * (bu[kk] - bu[p]) + math.cos(pm) * (bv[kk] - bv[p])
        _, _, ft, n, ok = contact_accel(xm, pm, vm, omm, sliding, sigma, bu[p], bv[p], g, rho2,
                                        law.mu, edge, prm)
        if not ok:
            return -1.0
        if code == LIFTOFF:
            return n
        return law.mu * n - abs(ft)

    @njit(cache=False, inline=True)
    def contact_event_value(tau, args):
        """
        Return event ``code``'s quantity (:func:`event_quantity`) at tau of a contact step.

        Along the step's interpolants; a landing's height over tau + ``lead`` where lead >= 0
        (a vertex that starts rising).
        """
        (cx, cp, h, sliding, sigma, p, bu, bv, g, rho2, law, edge, prm, code, kk, lead) = args
        xm, pm, vm, omm = contact_at(tau, args)
        q = event_quantity(xm, pm, vm, omm, code, kk, sliding, sigma, p, bu, bv, g, rho2, law,
                           edge, prm)
        return q / (tau + lead) if code == LANDING and lead >= 0.0 else q

    contact_event_crossing = make_crossing(contact_event_value)

    @njit(cache=False, inline=True)
    def contact_events_at(tau, args):
        """
        Return how many event conditions hold at tau of a contact step.

        Each landing vertex, liftoff, slip reversal and stick-to-slip count one each; no
        consistent normal force counts two (it makes any other event doubtful).
        """
        _, _, _, sliding, sigma, p, bu, bv, g, rho2, law, edge, prm = args
        xm, pm, vm, omm = contact_at(tau, args)
        c = math.cos(pm)
        s = math.sin(pm)
        y = -(s * bu[p] + c * bv[p])
        vy = -omm * (c * bu[p] - s * bv[p])
        count = 0
        for k in range(bu.shape[0]):
            if (k != p and y + s * bu[k] + c * bv[k] <= 0.0
                    and vy + omm * (c * bu[k] - s * bv[k]) < 0.0):
                count += 1
        _, _, ft, n, ok = contact_accel_cs(pm, c, s, vm, omm, sliding, sigma, bu[p], bv[p], g,
                                           rho2, law.mu, edge, prm)
        if not ok:
            return count + 2
        if n < 0.0 and law.unilateral:
            count += 1
        if sliding:
            if vm * sigma < 0.0:
                count += 1
        elif law.unilateral and abs(ft) > law.mu * n:
            count += 1
        return count

    @njit(cache=False, inline=True)
    def event_crossing(dt, tol, code, kk, args):
        """
        Return (tau, found): where event ``code``'s quantity crosses zero within a step of dt.

        Illinois regula falsi on the quantity along the step's interpolants. found only where
        that event, and no other, holds at tau: another would have begun earlier.
        """
        cx, cp, h, sliding, sigma, p, bu, bv, g, rho2, law, edge, prm = args
        vargs = (cx, cp, h, sliding, sigma, p, bu, bv, g, rho2, law, edge, prm, code, kk, -1.0)
        f0 = contact_event_value(0.0, vargs)
        if code == LANDING:
            xp, phi, vxp, om = contact_at(0.0, args)
            _, y0, _, vy0 = contact_to_cm(xp, phi, vxp, om, bu[p], bv[p])
            _, un0 = vertex_normal(y0, phi, vy0, om, bu[kk], bv[kk])
            if un0 > 0.0:
                # A vertex that starts rising (on the arm, after the pivot left it: its height
                # starts at 0, which regula falsi approaches in tiny steps): its height over
                # tau + h0 / un0 has the same zero and starts at its normal speed.
                f0 = max(f0, 0.0)
                vargs = (cx, cp, h, sliding, sigma, p, bu, bv, g, rho2, law, edge, prm, code, kk,
                         f0 / un0)
                f0 = un0
        f1 = contact_event_value(dt, vargs)
        if not (f0 > 0.0 and f1 <= 0.0):
            return dt, False
        hi = contact_event_crossing(0.0, dt, f0, f1, tol, 200, vargs)
        code_h, kk_h = contact_event_at(hi, args)
        if code_h == NO_EVENT:
            # the quantity is exactly zero there (the strict side is within tol)
            hi = min(hi + tol, dt)
            code_h, kk_h = contact_event_at(hi, args)
        return hi, code_h == code and kk_h == kk and contact_events_at(hi, args) == 1

    @njit(cache=False, inline=True)
    def first_contact_event(dt, tol, code, kk, args):
        """
        Return (tau, code, vertex) of the first event within a contact step of dt.

        The event found at the step's end names a continuous quantity crossing zero: its
        crossing (:func:`event_crossing`); where another event holds there too, a slip that
        reversed before it (a slide's most common earlier event); else bisection on the events.
        """
        if code != PAINLEVE:
            tau, found = event_crossing(dt, tol, code, kk, args)
            if found:
                return tau, code, kk
            if args[3] and code != SLIP_REVERSAL:      # sliding
                tau, found = event_crossing(dt, tol, SLIP_REVERSAL, -1, args)
                if found:
                    return tau, SLIP_REVERSAL, -1
        return event_in_contact_step(0.0, dt, tol, code, kk, args)

    @njit(cache=False, inline=True)
    def event_state(xp, phi, vxp, om, hi, ax, al, code, kk, tol, dargs):
        """
        Return (tau, state) of the event located at hi on a step's interpolants, re-integrated.

        The interpolants' error (O(dt^5) in the rates) would carry on into the rest of the
        throw: the state is one RK4 sub-step from the step's start to hi, moved to the root of
        the event's quantity along those sub-steps (a Newton step with the interpolants'
        slope, then within tol after it, as regula falsi leaves it) by its Taylor polynomial:
        the move is of the interpolants' error (about 1e-11 s at 1 ms steps), so the
        polynomial's remainder is below rounding; a move of more than 1e-6 of the step (coarse
        steps) is a second sub-step, and one of more than 1e-4 of it is not made.
        """
        _, _, dt, sliding, sigma, p, bu, bv, g, rho2, law, edge, prm = dargs
        xs, ps, vs, os_ = contact_step(xp, phi, vxp, om, hi, ax, al, sliding, sigma, bu[p],
                                       bv[p], g, rho2, law.mu, edge, prm)
        if code == PAINLEVE or code == NO_EVENT:
            return hi, xs, ps, vs, os_
        f = event_quantity(xs, ps, vs, os_, code, kk, sliding, sigma, p, bu, bv, g, rho2, law,
                           edge, prm)
        vargs = dargs + (code, kk, -1.0)
        d = min(1e-3 * dt, hi, dt - hi)
        if not d > 0.0:
            return hi, xs, ps, vs, os_
        slope = (contact_event_value(hi + d, vargs) - contact_event_value(hi - d, vargs)) / (
            2.0 * d)
        tau = min(max(hi - f / slope + 0.5 * tol, 0.0), dt) if slope < 0.0 else hi
        if tau == hi or abs(tau - hi) > 1e-4 * dt:
            return hi, xs, ps, vs, os_      # not the refinement of a clean crossing: keep hi
        if abs(tau - hi) > 1e-6 * dt:       # (coarse steps) too far for the polynomial
            xs, ps, vs, os_ = contact_step(xp, phi, vxp, om, tau, ax, al, sliding, sigma, bu[p],
                                           bv[p], g, rho2, law.mu, edge, prm)
            return tau, xs, ps, vs, os_
        a_x, a_p, _, _, _ = contact_accel(xs, ps, vs, os_, sliding, sigma, bu[p], bv[p], g, rho2,
                                          law.mu, edge, prm)
        e = tau - hi
        if not sliding:
            return tau, xs, ps + e * (os_ + 0.5 * e * a_p), 0.0, os_ + e * a_p
        return (tau, xs + e * (vs + 0.5 * e * a_x), ps + e * (os_ + 0.5 * e * a_p),
                vs + e * a_x, os_ + e * a_p)

    @njit(cache=False, inline=True)
    def roll_hold_margin(psi, args):
        """
        Return how far, in roll angle, a sticking unilateral pivot is from letting go.

        At roll angle psi of the closed-form roll: catch.cone_margin over the bounds on the
        forces' rates in psi (so a margin m > 0 proves the contact holds for a further turn of
        m); -1 where no normal force is consistent (Painleve).
        """
        (xp, phi, u0, alpha, sd, lp, inertia, a0, a2, pu, pv, g, rho2, mu, edge, prm, rate_n,
         rate_ft) = args
        u, _ = roll_u(psi, u0, alpha, sd, g, lp, inertia, a0, a2)
        om = sd * math.sqrt(max(2.0 * u, 0.0))
        _, _, ft, n, ok = contact_accel(xp, phi + sd * psi, 0.0, om, False, 0.0, pu, pv, g, rho2,
                                        mu, edge, prm)
        if not ok:
            return -1.0
        return cone_margin(n, ft, mu, rate_n, rate_ft)

    roll_hold_crossing = make_crossing(roll_hold_margin)

    @njit(cache=False, inline=True)
    def roll_hold_lost(psi_stop, dpsi_min, tol, args):
        """
        Return the first roll angle in [0, psi_stop] where the pivot lifts off or slips, or -1.

        Samples step by the margin itself (it cannot reach zero sooner), at least dpsi_min (an
        excursion narrower than that may go unseen, as a graze within an rk4 roll step does);
        a sign change is refined by Illinois regula falsi to tol.
        """
        fa = roll_hold_margin(0.0, args)
        if fa <= 0.0:
            return 0.0
        a = 0.0
        while a < psi_stop:
            b = min(psi_stop, a + max(fa, dpsi_min, 1e-15 * (1.0 + a)))   # (a few ulps at least)
            fb = roll_hold_margin(b, args)
            if fb <= 0.0:
                return roll_hold_crossing(a, b, fa, fb, tol, 200, args)
            a = b
            fa = fb
        return -1.0

    @njit(cache=False, inline=True)
    def closed_roll(st, env):
        """
        Roll about the sticking pivot in closed form (roll_method energy).

        Returns (event code, landing vertex or -1, state): on to the next landing, or to the
        turning point (then the hold test, and the next roll from rest); NO_EVENT with fit_ok
        cleared when the part rests on the pivot with no hold rule (rk4 steps decide). A
        unilateral pivot stops at the first roll angle where its normal force turns negative
        (LIFTOFF) or its friction leaves the cone (STICK_TO_SLIP): both are functions of the
        angle along the closed form (:func:`roll_hold_lost`).
        """
        part = env.part
        g = env.g
        p = st.p
        bu = env.bu
        bv = env.bv
        phi, om, vxp, nrec, fit_ok = st.phi, st.om, st.vxp, st.nrec, st.fit_ok
        a0, a2 = st.a0, st.a2
        c = math.cos(phi)
        s = math.sin(phi)
        cx = -(c * bu[p] - s * bv[p])
        cy = -(s * bu[p] + c * bv[p])
        alpha = math.atan2(cy, cx)
        lp = math.sqrt(bu[p] * bu[p] + bv[p] * bv[p])
        inertia = part.rho2 + lp * lp
        if om > 0.0:
            sd = 1.0
        elif om < 0.0:
            sd = -1.0
        elif cx > 0.0:
            sd = -1.0
        elif cx < 0.0:
            sd = 1.0
        else:
            sd = 1.0 if alpha <= part.acw[p] else -1.0
        kk = -1
        code = NO_EVENT
        if om == 0.0 and sd * g * lp * math.cos(alpha) - a0 <= 0.0:
            fit_ok = False      # held at rest with no hold rule: rk4 decides
        else:
            target = part.acw[p] if sd < 0.0 else part.accw[p]
            psi_end = max(sd * (target - alpha), 0.0)
            psi_t = roll_turn(0.5 * om * om, alpha, sd, psi_end, g, lp, inertia, a0, a2)
            vxp = 0.0
            law = env.law
            psi_e = -1.0
            if law.unilateral and free_flight:
                # without a body force the forces are trigonometric in the angle: safe steps
                energy_k = om * om - 2.0 * g * lp * math.sin(alpha) / inertia
                psi_e = first_cone_exit(alpha, sd, psi_t if psi_t >= 0.0 else psi_end, energy_k,
                                        lp, inertia, -g, law.mu,
                                        ROLL_EVENT_RATE * env.knobs.roll_step,
                                        env.knobs.contact_root_tol)
            elif law.unilateral:
                rate_n, rate_ft = roll_force_rates(g, om, lp, inertia)
                # the bounds doubled for the weak body forces
                args = (st.xp, phi, 0.5 * om * om, alpha, sd, lp, inertia, a0, a2, bu[p], bv[p],
                        g, part.rho2, law.mu, env.edge, env.prm, 2.0 * rate_n, 2.0 * rate_ft)
                psi_e = roll_hold_lost(psi_t if psi_t >= 0.0 else psi_end,
                                       ROLL_EVENT_RATE * env.knobs.roll_step,
                                       env.knobs.contact_root_tol, args)
            if psi_e >= 0.0:
                u_e, _ = roll_u(psi_e, 0.5 * om * om, alpha, sd, g, lp, inertia, a0, a2)
                phi += sd * psi_e
                om = sd * math.sqrt(max(2.0 * u_e, 0.0))
                _, _, _, n, ok = contact_accel(st.xp, phi, 0.0, om, False, 0.0, bu[p], bv[p], g,
                                               part.rho2, law.mu, env.edge, env.prm)
                code = PAINLEVE if not ok else (LIFTOFF if n <= 0.0 else STICK_TO_SLIP)
            # unless the unilateral pivot let go above: the turning point, else the landing
            if code == NO_EVENT and psi_t >= 0.0:
                phi += sd * psi_t
                om = 0.0
                held, dphi = static_hold(phi, 0.0, True, env.size, bu[p], bv[p], g, env.edge,
                                         env.prm)
                if held:
                    phi += dphi
                    e_now = -g * contact_to_cm(st.xp, phi, 0.0, 0.0, bu[p], bv[p])[1]
                    nrec = _event(env.rec, nrec, EV_HELD, p, -1, st.xp, 0.0, 0.0, e_now, e_now)
            elif code == NO_EVENT:
                u_end, _ = roll_u(psi_end, 0.5 * om * om, alpha, sd, g, lp, inertia, a0, a2)
                phi += target - alpha
                om = sd * math.sqrt(max(2.0 * u_end, 0.0))
                kk = (p + 1) % part.n if sd < 0.0 else (p - 1) % part.n
                code = LANDING
        return code, kk, SimState(
            st.mode, st.t, st.x, st.y, phi, st.vx, st.vy, om, st.sep, st.sep_rising, p, st.xp,
            vxp, st.sliding, st.sigma, st.fit_p, fit_ok, a0, a2, st.j_flat, st.out_edge,
            st.out_r, st.steps, st.impacts, nrec, st.t_first, st.k_first, st.x_lo, st.x_hi)

    @njit(cache=False, inline=True)
    def rk4_contact(st, env):
        """
        Run the contact phase in rk4 steps of roll_step to its next event, bisected.

        Returns (status, event code, landing vertex, state); status ERR_SIM_CAP when the
        steps run out, ERR_NONFINITE when a step is not finite.
        """
        part = env.part
        g = env.g
        law = env.law
        edge = env.edge
        prm = env.prm
        p = st.p
        bu = env.bu
        bv = env.bv
        rho2 = part.rho2
        xp, phi, vxp, om = st.xp, st.phi, st.vxp, st.om
        sliding, sigma = st.sliding, st.sigma
        rdt = env.knobs.roll_step
        nrec = st.nrec
        t = st.t
        steps = st.steps
        x_lo, x_hi = st.x_lo, st.x_hi
        status = OK
        clear = False       # no event at the current state (the last step's end was checked)
        ax, al = 0.0, 0.0   # the accelerations at the current state, once checked
        while True:
            if not clear:
                code, kk, ax, al = contact_trigger(xp, phi, vxp, om, sliding, sigma, p, bu, bv, g,
                                                   rho2, law, edge, prm)
                if code != NO_EVENT:
                    break
            xp1, p1, v1, o1 = contact_step(xp, phi, vxp, om, rdt, ax, al, sliding, sigma, bu[p],
                                           bv[p], g, rho2, law.mu, edge, prm)
            if not (math.isfinite(p1) and math.isfinite(o1)):
                status = ERR_NONFINITE
                break
            code, kk, ax1, al1 = contact_trigger(xp1, p1, v1, o1, sliding, sigma, p, bu, bv, g,
                                                 rho2, law, edge, prm)
            if code != NO_EVENT:
                # the step's dense output: quintic Hermite interpolants of xp and phi (their
                # error, O(dt^6), is below the step's own), on which its events are located
                dargs = (hermite5(xp, vxp, ax, xp1, v1, ax1, rdt),
                         hermite5(phi, om, al, p1, o1, al1, rdt), rdt, sliding, sigma, p, bu, bv,
                         g, rho2, law, edge, prm)
                tol = env.knobs.contact_root_tol
                hi, code, kk = first_contact_event(rdt, tol, code, kk, dargs)
                hi, xp, phi, vxp, om = event_state(xp, phi, vxp, om, hi, ax, al, code, kk, tol,
                                                   dargs)
                t += hi
                x_lo = min(x_lo, xp)
                x_hi = max(x_hi, xp)
                code2, kk2, _, _ = contact_trigger(xp, phi, vxp, om, sliding, sigma, p, bu, bv,
                                                   g, rho2, law, edge, prm)
                if code2 != NO_EVENT:
                    code = code2
                    kk = kk2
                break
            turned = om * o1 <= 0.0
            xp, phi, vxp, om = xp1, p1, v1, o1
            ax, al = ax1, al1
            t += rdt
            x_lo = min(x_lo, xp)
            x_hi = max(x_hi, xp)
            clear = True
            if not sliding:
                held, dphi = static_hold(phi, om, turned, env.size, bu[p], bv[p], g, edge, prm)
                if held:
                    clear = False
                    # A resisting torque holds the part balanced on a corner; the feeder's
                    # vibration breaks the tie: turned to the edge of the holding zone on its
                    # CM's side, it falls from rest.
                    phi += dphi
                    e_now = -g * contact_to_cm(xp, phi, 0.0, 0.0, bu[p], bv[p])[1]
                    om = 0.0
                    nrec = _event(env.rec, nrec, EV_HELD, p, -1, xp, 0.0, 0.0, e_now, e_now)
            steps += 1
            if steps > env.knobs.max_sim_steps:
                status = ERR_SIM_CAP
                break
        return status, code, kk, SimState(st.mode, t, st.x, st.y, phi, st.vx, st.vy, om, st.sep,
                                          st.sep_rising, p, xp, vxp, sliding, sigma, st.fit_p,
                                          st.fit_ok, st.a0, st.a2, st.j_flat, st.out_edge,
                                          st.out_r, steps, st.impacts, nrec, st.t_first,
                                          st.k_first, x_lo, x_hi)

    @njit(cache=False, inline=True)
    def contact_event(st, env, code, kk):
        """Apply a contact phase's event: a slip change, liftoff, or vertex kk landing."""
        part = env.part
        g = env.g
        p = st.p
        bu = env.bu
        bv = env.bv
        rho2 = part.rho2
        if code == SLIP_REVERSAL:
            sliding, sigma = contact_mode(0.0, st.xp, st.phi, st.om, p, bu, bv, g, rho2, env.law,
                                          env.edge, env.prm)
            return with_slip(st, 0.0, sliding, sigma)
        if code == STICK_TO_SLIP:
            _, _, ft, _, _ = contact_accel(st.xp, st.phi, 0.0, st.om, False, 0.0, bu[p], bv[p],
                                           g, rho2, env.law.mu, env.edge, env.prm)
            return with_slip(st, st.vxp, True, -math.copysign(1.0, ft))
        phi, om = st.phi, st.om
        x, y, vx, vy = contact_to_cm(st.xp, phi, st.vxp, om, bu[p], bv[p])
        if code == LIFTOFF:
            e_now = energy(vx, vy, om, y, g, rho2)
            nrec = _event(env.rec, st.nrec, EV_LIFTOFF, p, -1, st.xp, om, om, e_now, e_now)
            return SimState(MODE_FLIGHT, st.t, x, y, phi, vx, vy, om, p, False, p, st.xp,
                            st.vxp, st.sliding, st.sigma, st.fit_p, st.fit_ok, st.a0, st.a2,
                            st.j_flat, st.out_edge, st.out_r, st.steps, st.impacts, nrec,
                            st.t_first, st.k_first, st.x_lo, st.x_hi)
        # Landing of vertex kk while rolling/sliding about p.
        q = kk
        n = part.n
        if q == (p + 1) % n:
            j = p
        elif q == (p - 1) % n:
            j = q
        else:
            j = -1
        e_before = energy(vx, vy, om, y, g, rho2)
        if j >= 0:
            # Turn about p until the edge is exactly flat (a sub-root_tol correction), so that
            # both of its vertices lie on the arm.
            c = math.cos(phi)
            s = math.sin(phi)
            alpha_q = math.atan2(-(s * bu[q] + c * bv[q]), -(c * bu[q] - s * bv[q]))
            phi += (part.acw[q] if j == q else part.accw[q]) - alpha_q
            x, y, vx, vy = contact_to_cm(st.xp, phi, st.vxp, om, bu[p], bv[p])
        c = math.cos(phi)
        s = math.sin(phi)
        rx = c * bu[q] - s * bv[q]
        ry = s * bu[q] + c * bv[q]
        xq = x + rx
        st = SimState(st.mode, st.t, x, y, phi, vx, vy, om, st.sep, st.sep_rising, p, st.xp,
                      st.vxp, st.sliding, st.sigma, st.fit_p, st.fit_ok, st.a0, st.a2, st.j_flat,
                      st.out_edge, st.out_r, st.steps, st.impacts + 1, st.nrec, st.t_first,
                      st.k_first, min(st.x_lo, xq), max(st.x_hi, xq))
        return resolve_impact(st, env, q, j, p, xq, rx, ry, e_before, EV_LANDING)

    @njit(cache=False, inline=True)
    def flat_step(st, env):
        """
        One step flat on edge j_flat.

        At rest on a stable edge the catch ends; a corner whose share of N turns negative (or
        rest on an unstable edge) starts a roll about the other corner; else the part slides
        on (RK2: the friction has a constant sign).
        """
        part = env.part
        g = env.g
        j = st.j_flat
        x, vx = st.x, st.vx
        if vx == 0.0 and part.stable[j]:
            return with_end(st, j, x)
        mu = env.law.mu
        ax, na, nb = flat_forces(vx, j, part, g, mu, st.phi, env.edge, env.prm)
        t = st.t
        if vx == 0.0 or na < 0.0 or nb < 0.0:
            # Tip about the vertex that keeps the load; at rest (on an unstable edge) the one
            # the CM lies beyond.
            x_l = x + part.u_l[j]
            if vx == 0.0:
                p = tip_pivot(j, part)[0]
            elif na < 0.0:
                p = (j + 1) % part.n
            else:
                p = j
            xp = x_l + part.edge_len[j] if p != j else x_l
            om = 0.0
            vy = 0.0
            c = math.cos(st.phi)
            s = math.sin(st.phi)
            bu = env.bu
            bv = env.bv
            if not env.law.unilateral and vx != 0.0:
                vx, vy, om = sticking_impact(c * bu[p] - s * bv[p], s * bu[p] + c * bv[p], vx,
                                             0.0, 0.0, part.rho2)
            e_now = energy(vx, vy, om, st.y, g, part.rho2)
            nrec = _event(env.rec, st.nrec, EV_TIP_FROM_REST, p, j, xp, 0.0, 0.0, e_now, e_now)
            st = SimState(st.mode, t, x, st.y, st.phi, vx, vy, om, st.sep, st.sep_rising, st.p,
                          st.xp, st.vxp, st.sliding, st.sigma, st.fit_p, st.fit_ok, st.a0,
                          st.a2, j, st.out_edge, st.out_r, st.steps, st.impacts, st.nrec,
                          st.t_first, st.k_first, min(st.x_lo, xp), max(st.x_hi, xp))
            st = on_pivot(st, env, p, xp, vx, vy, om, s * bu[p] + c * bv[p], nrec)
            return st if st.sliding else with_slip(st, 0.0, False, st.sigma)
        rdt = env.knobs.roll_step
        v_half = vx + 0.5 * rdt * ax
        v1 = -vx
        if v_half * vx > 0.0:
            ax2, _, _ = flat_forces(v_half, j, part, g, mu, st.phi, env.edge, env.prm)
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
        return SimState(st.mode, t, x, st.y, st.phi, vx, st.vy, st.om, st.sep, st.sep_rising,
                        st.p, st.xp, st.vxp, st.sliding, st.sigma, st.fit_p, st.fit_ok, st.a0,
                        st.a2, j, st.out_edge, st.out_r, st.steps, st.impacts, st.nrec,
                        st.t_first, st.k_first, min(st.x_lo, x + part.u_l[j]),
                        max(st.x_hi, x + part.u_r[j]))

    @njit(cache=False)
    def simulate(edge, x0, y0, phi0, vx0, vy0, om0, g, part, knobs, law, prm, rec):
        bu = part.U[edge]
        bv = part.V[edge]
        size = 0.0
        for k in range(part.n):
            size = max(size, math.sqrt(bu[k] * bu[k] + bv[k] * bv[k]))
        env = SimEnv(edge, g, part, knobs, law, prm, rec, bu, bv, size)
        st = SimState(MODE_FLIGHT, 0.0, x0, y0, phi0, vx0, vy0, om0, -1, False, -1, 0.0, 0.0,
                      False, 0.0, -1, False, 0.0, 0.0, -1, -1, math.nan, 0, 0, 0, math.nan, -1,
                      math.inf, -math.inf)
        roll_energy = knobs.roll_method == ROLL_ENERGY and not contact_loaded
        while True:
            st = counted(st)
            if st.steps > knobs.max_sim_steps:
                return ended(st, ERR_SIM_CAP)
            if st.impacts > knobs.max_impacts:
                return ended(st, ERR_SETTLE_CAP)
            if st.mode == MODE_FLIGHT:
                code, k, st = fly(st, env)
                if code != OK:
                    return ended(st, code)
                st = touch_down(st, env, k)
            elif st.mode == MODE_CONTACT:
                if roll_energy and not st.sliding and st.fit_p != st.p:
                    if free_flight:     # no body force: no torque to fit
                        fit_ok, a0, a2 = True, 0.0, 0.0
                    else:
                        fit_ok, a0, a2 = roll_torque_fit(st.phi, bu[st.p], bv[st.p], edge, prm)
                    st = with_fit(st, st.p, fit_ok, a0, a2)
                if roll_energy and not st.sliding and st.fit_ok:
                    code, kk, st = closed_roll(st, env)
                else:
                    status, code, kk, st = rk4_contact(st, env)
                    if status != OK:
                        return ended(st, status)
                if code == PAINLEVE:
                    return ended(st, ERR_PAINLEVE)
                if code != NO_EVENT:
                    st = contact_event(st, env, code, kk)
            elif st.mode == MODE_FLAT:
                st = flat_step(st, env)
            else:
                # MODE_DONE: snap the net rotation to the resting pose on out_edge.
                target = part.rest_angle[st.out_edge] - part.rest_angle[edge]
                rot = target + 2.0 * math.pi * round((st.phi - target) / (2.0 * math.pi))
                return Outcome(OK, st.out_edge, st.out_r, st.t_first, rot, st.impacts,
                               st.k_first, st.nrec, st.x_lo, st.x_hi)

    return simulate
