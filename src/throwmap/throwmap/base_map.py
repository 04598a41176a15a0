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
The paper's throw map f(i, R) compiled: one throw, a batch of throws, orbits.

Impulsive release (eqs 5-6), ballistic flight to the first contact (throwmap.ballistic), the
closed-form catch (throwmap.catch). This is what a scene without effects runs; the entry points
here are called from Python (throwmap.model.ThrowModel, arm = inf) and cached on disk by numba.
The design kernel (throwmap.design) calls them with the arm's length of a scene whose only
effect is ``finite_arm``: a throw that touches the arm line off [0, arm] or rests off it is
LOST, by :func:`off_arm`, the rule that effect's check applies.
"""

import math

from .ballistic import first_contact, impulsive_release, state_at
from .catch import catch_at_contact
from .jit import njit
from .status import ERR_EDGE_INDEX, ERR_GRASP, ERR_TOE_STUB, ERR_UNSTABLE_EDGE, LOST, OK


@njit
def off_arm(status, vertex, x_lo, x_hi, R, length):
    """
    Tell whether a throw left an arm occupying [0, length] (effect finite_arm's rule).

    x_lo, x_hi: the lowest and highest arm coordinate a vertex touched; R: the rest position
    of an OK throw. A throw that failed after a contact off the arm is lost all the same.
    """
    off = x_lo < 0.0 or x_hi > length
    if status == OK:
        return off or R < 0.0 or R > length
    return vertex >= 0 and off


@njit
def throw_one(edge, R, w, g, h, r_grasp, part, knobs, rec, arm=math.inf):
    """
    One evaluation of f(edge, R); ``rec`` receives the catch's events (may have no rows).

    Returns (status, new edge, new R, flight time, net rotation, impacts, first contact vertex,
    records written). ``arm``: the arm's length (inf: no end); a throw off it is LOST.
    """
    nan = math.nan
    if edge < 0 or edge >= part.n:
        return ERR_EDGE_INDEX, -1, nan, nan, nan, 0, -1, 0
    if not part.stable[edge]:
        return ERR_UNSTABLE_EDGE, -1, nan, nan, nan, 0, -1, 0
    if not (r_grasp[edge] <= R < math.inf):    # (an infinite R: model.domain_error says so)
        return ERR_GRASP, -1, nan, nan, nan, 0, -1, 0
    if not (R + part.u_l[edge] > 0.0):
        return ERR_TOE_STUB, -1, nan, nan, nan, 0, -1, 0
    x0, y0, phi0, vx, vy, om = impulsive_release(edge, R, w, h, part.d)
    status, T, k = first_contact(edge, y0, phi0, vy, om, g, part, knobs)
    if status != OK:
        return status, -1, nan, nan, nan, 0, -1, 0
    rx, ry, x_cm, xdot, ydot, phi, energy = state_at(T, edge, k, x0, y0, phi0, vx, vy, om, g,
                                                     part)
    status, j, r1, rot, imp, nrec, x_lo, x_hi = catch_at_contact(k, phi, rx, ry, x_cm, xdot,
                                                                 ydot, om, energy, -g, part,
                                                                 knobs, rec)
    if arm < math.inf and off_arm(status, k, x_lo, x_hi, r1, arm):
        return LOST, -1, nan, T, rot, imp, k, nrec
    return status, j, r1, T, rot, imp, k, nrec


@njit
def throw_many(edges, radii, w, g, h, r_grasp, part, knobs, rec, out_edge, out_r, out_status,
               out_t, out_rot, out_events, out_vertex):
    """
    Vectorised f over many states (loops compile to machine code; no Python per state).

    ``rec``: a record buffer, usually with no rows; out_events: the number of catch events each
    throw's records would hold.
    """
    for i in range(edges.shape[0]):
        status, j, r1, t, rot, _, k, nrec = throw_one(edges[i], radii[i], w, g, h, r_grasp,
                                                      part, knobs, rec)
        out_edge[i] = j
        out_r[i] = r1
        out_status[i] = status
        out_t[i] = t
        out_rot[i] = rot
        out_events[i] = nrec
        out_vertex[i] = k


@njit
def orbit(edge, R, steps, w, g, h, r_grasp, part, knobs, rec, out_edge, out_r, out_rot):
    """Iterate f from (edge, R); returns (status, number of throws done)."""
    out_edge[0] = edge
    out_r[0] = R
    out_rot[0] = 0.0
    for i in range(steps):
        status, j, r1, _, rot, _, _, _ = throw_one(edge, R, w, g, h, r_grasp, part, knobs, rec)
        if status != OK:
            return status, i
        out_edge[i + 1] = j
        out_r[i + 1] = r1
        out_rot[i + 1] = rot
        edge = j
        R = r1
    return OK, steps


@njit
def orbit_many(edges, radii, steps, w, g, h, r_grasp, part, knobs, rec, out_edge, out_r,
               out_rot, out_status, out_done):
    """Many orbits at once (basins): out_* have shape (starts, steps + 1)."""
    for s in range(edges.shape[0]):
        status, done = orbit(edges[s], radii[s], steps, w, g, h, r_grasp, part, knobs, rec,
                             out_edge[s], out_r[s], out_rot[s])
        out_status[s] = status
        out_done[s] = done
