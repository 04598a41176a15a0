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
The one throw kernel: perturb, release, motion, check, composed over a scene's effects.

Every scene throws through it: :func:`build` compiles the pipeline over the hooks of one effect
set (throwmap.compose writes the module that calls it; docs/effects.md has the interface), and
the base model is the empty set, whose hooks are the defaults below (the paper's map).

1. ``perturb(w, h, z0, z1, prm) -> (w, h)``: this throw's release speed and arm offset from two
   standard normal draws (release_noise). Default: the nominal ones.
2. ``release(edge, R, w, h, ctx, prm) -> (status, x0, y0, phi0, vx, vy, om)``: the grasp check
   and the state in which the part leaves the arm (finite_carry). Default
   :func:`impulsive_release`: the impulse-cone R_grasp at this throw's offset, then eqs 5-6.
3. ``motion(edge, x0, y0, phi0, vx, vy, om, ctx, prm, rec) -> Outcome``: flight and catch.
   :func:`closed_motion` (ballistic flight, the closed-form catch) unless an effect adds a body
   force or an impact law; then the event simulator built over those (throwmap.event_sim).
4. ``check(outcome, release, edge, ctx, prm) -> status``: checks that can fail or lose the
   throw after the fact (finite_carry's returning arm, finite_arm's losses). Checks run in the
   registry's order; the first one that changes the status decides.

Last, a throw that ends at rest outside the domain of f (below R_min: under ``liftoff`` a roll
can slip inwards; a spin fast enough to carry the part behind the pivot) has the outcome
OFF_DOMAIN with its rest state; a batch or an orbit reports it as LOST (edge -1): no later
throw is defined. The domain is the nominal release's: the part must rest on a stable edge,
right of the pivot, where the ``release`` hook grasps it at the context's w and h.

Every throw answers with one named record, :data:`throwmap.status.ThrowRecord`. Callers that
vary the design (throwmap.design, throwmap.robustness) pass a Context of their own w and h.
"""

from collections import namedtuple
import math

import numpy as np

from .ballistic import first_contact, impulsive_release as release_state, state_at
from .catch import catch_at_contact
from .grasp import impulse_grasp_radius
from .jit import njit
from .status import (ERR_EDGE_INDEX, ERR_GRASP, ERR_RELEASE, ERR_TOE_STUB, ERR_UNSTABLE_EDGE,
                     LOST, OFF_DOMAIN, OK, Outcome, ThrowRecord)

# Everything a throw needs besides its state: nominal release speed w, arm offset h, gravity g,
# the arm's friction mu (inf: none given), the part and knobs bundles, the event simulator's
# contact law (throwmap.event_sim.ContactLaw), and r_grasp: the impulse-cone R_grasp of every
# edge at h (inf on unstable edges), which the default release reads instead of computing it
# again at every throw of the nominal offset.
Context = namedtuple('Context', ['w', 'h', 'g', 'mu', 'part', 'knobs', 'law', 'r_grasp'])
# The state in which the part left the arm, and this throw's w and h.
Release = namedtuple('Release', ['x0', 'y0', 'phi0', 'vx', 'vy', 'om', 'w', 'h'])


def grasp_radii(part, h, mu):
    """Return the Context's r_grasp: the impulse-cone R_grasp of each edge at h (inf: unstable)."""
    out = np.full(part.n, math.inf)
    for i in range(part.n):
        if part.stable[i]:
            out[i] = impulse_grasp_radius(i, h, mu, part.rho2, part.d, part.u_l, part.u_r)
    return out


@njit
def with_design(ctx, w, h, r_grasp):
    """Return ``ctx`` with another nominal w, h and its grasp radii (a design's own Context)."""
    return Context(w, h, ctx.g, ctx.mu, ctx.part, ctx.knobs, ctx.law, r_grasp)


# ------------------------------------------------------------------------------- defaults
@njit(cache=False)
def no_perturbation(w, h, z0, z1, prm):
    """Return the nominal release speed and offset: no perturbation."""
    return w, h


@njit(cache=False)
def impulsive_release(edge, R, w, h, ctx, prm):
    """Check the impulse-cone grasp at this throw's h, then release as in eqs 5-6."""
    part = ctx.part
    if h == ctx.h:
        r_grasp = ctx.r_grasp[edge]
    else:
        r_grasp = impulse_grasp_radius(edge, h, ctx.mu, part.rho2, part.d, part.u_l, part.u_r)
    if not R >= r_grasp:
        return ERR_GRASP, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    x0, y0, phi0, vx, vy, om = release_state(edge, R, w, h, part.d)
    return OK, x0, y0, phi0, vx, vy, om


@njit(cache=False)
def no_check(outcome, release, edge, ctx, prm):
    """Return the outcome's status: nothing fails or loses the throw after the fact."""
    return outcome.status


# Inlined into the pipeline: the same reason as throw_one's (:func:`build`).
@njit(cache=False, inline=True)
def closed_motion(edge, x0, y0, phi0, vx, vy, om, ctx, prm, rec):
    """Ballistic flight (throwmap.ballistic) and the closed-form catch (throwmap.catch)."""
    part = ctx.part
    g = ctx.g
    status, T, k = first_contact(edge, y0, phi0, vy, om, g, part, ctx.knobs)
    if status != OK:
        return Outcome(status, -1, math.nan, math.nan, math.nan, 0, -1, 0, math.inf, -math.inf)
    rx, ry, x_cm, xdot, ydot, phi, energy = state_at(T, edge, k, x0, y0, phi0, vx, vy, om, g,
                                                     part)
    status, j, r1, rot, imp, nrec, x_lo, x_hi = catch_at_contact(
        k, phi, rx, ry, x_cm, xdot, ydot, om, energy, -g, part, ctx.knobs, rec)
    return Outcome(status, j, r1, T, rot, imp, k, nrec, x_lo, x_hi)


# ------------------------------------------------------------------------------- the builder
def build(perturb=no_perturbation, release=impulsive_release, motion=closed_motion,
          check=no_check):
    """
    Return (throw_one, throw_many, orbit_many) compiled over these hooks.

    Every function takes its record buffer ``rec`` (usually with no rows for batches).
    throw_one(edge, R, z0, z1, ctx, prm, rec) -> ThrowRecord (throwmap.status); the batches
    take the draws z0, z1 of every throw in ``z`` (no rows: no perturbation, all zeros).
    ``prm`` is the effect set's parameter bundle, passed to every hook. Status OFF_DOMAIN comes
    with the rest state; throw_many and orbit_many report it as LOST.
    """

    @njit(cache=False)
    def rests_in_domain(edge, R, ctx, prm):
        # The nominal throw from (edge, R) would pass the domain checks of throw_one.
        part = ctx.part
        if not (0 <= edge < part.n and part.stable[edge] and R + part.u_l[edge] > 0.0):
            return False
        return release(edge, R, ctx.w, ctx.h, ctx, prm)[0] == OK

    # Inlined into its callers: a call passes every field of the Context (the part's arrays,
    # the knobs) as separate arguments, which cost a batch 20 % of its time (docs/numerics.md).
    @njit(cache=False, inline=True)
    def throw_one(edge, R, z0, z1, ctx, prm, rec):
        nan = math.nan
        part = ctx.part
        if edge < 0 or edge >= part.n:
            return ThrowRecord(ERR_EDGE_INDEX, -1, nan, nan, nan, 0, -1, 0, nan, nan, nan)
        if not part.stable[edge]:
            return ThrowRecord(ERR_UNSTABLE_EDGE, -1, nan, nan, nan, 0, -1, 0, nan, nan, nan)
        if not abs(R) < math.inf:   # outside every grasp (model.domain_error says why)
            return ThrowRecord(ERR_GRASP, -1, nan, nan, nan, 0, -1, 0, nan, nan, nan)
        w, h = perturb(ctx.w, ctx.h, z0, z1, prm)
        if not w > 0.0:
            return ThrowRecord(ERR_RELEASE, -1, nan, nan, nan, 0, -1, 0, w, h, nan)
        status, x0, y0, phi0, vx, vy, om = release(edge, R, w, h, ctx, prm)
        if status != OK:
            return ThrowRecord(status, -1, nan, nan, nan, 0, -1, 0, w, h, nan)
        if not (R + part.u_l[edge] > 0.0):
            return ThrowRecord(ERR_TOE_STUB, -1, nan, nan, nan, 0, -1, 0, w, h, nan)
        e0 = 0.5 * (vx * vx + vy * vy + part.rho2 * om * om) - ctx.g * y0
        out = motion(edge, x0, y0, phi0, vx, vy, om, ctx, prm, rec)
        st = out.status
        status = check(out, Release(x0, y0, phi0, vx, vy, om, w, h), edge, ctx, prm)
        if status == st:
            if st == OK and not rests_in_domain(out.edge, out.R, ctx, prm):
                status = OFF_DOMAIN
            return ThrowRecord(status, out.edge, out.R, out.t, out.rot, out.impacts,
                               out.vertex, out.records, w, h, e0)
        # A check failed or lost the throw. A lost part keeps the rotation of its throw.
        rot = out.rot if status == LOST and st == OK else nan
        return ThrowRecord(status, -1, nan, out.t, rot, out.impacts, out.vertex, out.records,
                           w, h, e0)

    @njit(cache=False)
    def throw_many(edges, radii, z, ctx, prm, rec, out_edge, out_r, out_status, out_t, out_rot,
                   out_events, out_vertex):
        draws = z.shape[0] > 0
        for i in range(edges.shape[0]):
            z0 = z[i, 0] if draws else 0.0
            z1 = z[i, 1] if draws else 0.0
            t = throw_one(edges[i], radii[i], z0, z1, ctx, prm, rec)
            if t.status == OFF_DOMAIN:
                out_edge[i] = -1
                out_r[i] = math.nan
                out_status[i] = LOST
            else:
                out_edge[i] = t.edge
                out_r[i] = t.R
                out_status[i] = t.status
            out_t[i] = t.t
            out_rot[i] = t.rot
            out_events[i] = t.records
            out_vertex[i] = t.vertex

    @njit(cache=False)
    def orbit_many(edges, radii, steps, z, ctx, prm, rec, out_edge, out_r, out_rot, out_status,
                   out_done):
        """
        Iterate f from many starts; z has shape (starts, steps, 2), or no rows: no draws.

        A lost throw ends its orbit with edge -1 and status LOST.
        """
        draws = z.shape[0] > 0
        for s in range(edges.shape[0]):
            edge = edges[s]
            R = radii[s]
            out_edge[s, 0] = edge
            out_r[s, 0] = R
            out_rot[s, 0] = 0.0
            out_status[s] = OK
            out_done[s] = steps
            for k in range(steps):
                z0 = z[s, k, 0] if draws else 0.0
                z1 = z[s, k, 1] if draws else 0.0
                t = throw_one(edge, R, z0, z1, ctx, prm, rec)
                if t.status != OK:
                    st = LOST if t.status == OFF_DOMAIN else t.status
                    out_status[s] = st
                    out_done[s] = k
                    if st == LOST:
                        out_edge[s, k + 1] = -1
                    break
                out_edge[s, k + 1] = t.edge
                out_r[s, k + 1] = t.R
                out_rot[s, k + 1] = t.rot
                edge = t.edge
                R = t.R

    return throw_one, throw_many, orbit_many


def event_motion(simulate):
    """Return the motion hook that runs ``simulate`` (throwmap.event_sim.build)."""

    @njit(cache=False)
    def motion(edge, x0, y0, phi0, vx, vy, om, ctx, prm, rec):
        return simulate(edge, x0, y0, phi0, vx, vy, om, ctx.g, ctx.part, ctx.knobs, ctx.law,
                        prm, rec)

    return motion
