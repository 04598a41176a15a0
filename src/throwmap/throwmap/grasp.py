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

"""Dynamic grasp (paper section III.A.1): impulse-cone bounds (1)-(4) and the wrench-cone test."""

from dataclasses import dataclass
import math

import numpy as np


@dataclass(frozen=True)
class EdgeGrasp:
    """
    Impulse-cone result for one stable edge.

    ``bounds`` are the right-hand sides of constraints (1)-(4) (bounds 2 and 4 are -inf/+inf
    free when no friction coefficient is given). ``R_grasp`` is the largest of them;
    ``mu_min`` the friction coefficient needed so that (2) and (4) do not bind at the
    geometric R_grasp (max of bounds 1 and 3): |h + d| / R.
    """

    edge: int
    stable: bool
    bounds: tuple
    R_grasp: float
    R_grasp_geometric: float
    mu_min: float
    binding: int


def impulse_bounds(part, edge, h, mu=None):
    """Right-hand sides of constraints (1)-(4) for a stable edge (R must exceed each)."""
    u_l, u_r, v_l, v_r = part.u_l[edge], part.u_r[edge], part.v_l[edge], part.v_r[edge]
    hd = h + part.d[edge]
    b1 = (part.rho2 - v_l * hd) / u_l
    b3 = (part.rho2 - v_r * hd) / u_r
    if mu is None:
        b2 = b4 = -math.inf
    else:
        b2 = -hd / mu
        b4 = hd / mu
    return float(b1), float(b2), float(b3), float(b4)


def edge_grasp(part, edge, h, mu=None):
    stable = bool(part.stable[edge])
    if not stable:
        nan = math.nan
        return EdgeGrasp(edge, False, (nan,) * 4, math.inf, math.inf, nan, 0)
    bounds = impulse_bounds(part, edge, h, mu)
    geometric = max(bounds[0], bounds[2])
    hd = abs(h + part.d[edge])
    mu_min = hd / geometric if geometric > 0 else math.inf
    binding = int(np.argmax(bounds)) + 1
    return EdgeGrasp(edge, True, bounds, float(max(bounds)), float(geometric), float(mu_min),
                     binding)


def grasp_table(part, h, mu=None):
    """Per-edge grasp results plus the part-wide R_grasp and mu_min (as the paper reports)."""
    rows = [edge_grasp(part, i, h, mu) for i in range(part.n)]
    stable = [g for g in rows if g.stable]
    r_all = max(g.R_grasp_geometric for g in stable)
    mu_all = max(abs(h + part.d[g.edge]) for g in stable) / r_all
    return rows, float(r_all), float(mu_all)


def contact_wrench_cone(part, edge, mu):
    """Return the four edge wrenches w_1..w_4 of the contact cone W^i (frame F^i), rows."""
    u_l, u_r, v_l, v_r = part.u_l[edge], part.u_r[edge], part.v_l[edge], part.v_r[edge]
    return np.array([[-mu, 1.0, u_l + mu * v_l],
                     [mu, 1.0, u_l - mu * v_l],
                     [mu, 1.0, u_r - mu * v_r],
                     [-mu, 1.0, u_r + mu * v_r]])


def required_wrench(part, edge, R, h, g, theta, theta_dot, theta_ddot):
    """Wrench (f_u, f_v, tau) per unit mass the arm must apply to carry the part rigidly."""
    hd = h + part.d[edge]
    return (theta_ddot * np.array([-hd, R, part.rho2])
            + theta_dot ** 2 * np.array([-R, -hd, 0.0])
            + np.array([-g * math.sin(theta), -g * math.cos(theta), 0.0]))


def wrench_cone_margins(part, edge, R, h, g, mu, theta, theta_dot, theta_ddot):
    """
    Values w^T (w_j x w_k) for (j, k) = (1,2), (2,3), (3,4), (4,1); all <= 0 means grasp.

    Each value is scaled by |w| so that it reads as a signed distance-like margin.
    """
    w = required_wrench(part, edge, R, h, g, theta, theta_dot, theta_ddot)
    cone = contact_wrench_cone(part, edge, mu)
    pairs = ((0, 1), (1, 2), (2, 3), (3, 0))
    norm = float(np.linalg.norm(w)) or 1.0
    return np.array([w @ np.cross(cone[j], cone[k]) for j, k in pairs]) / norm


def in_dynamic_grasp(part, edge, R, h, g, mu, theta, theta_dot, theta_ddot):
    if not part.stable[edge]:
        return False
    return bool(np.all(wrench_cone_margins(part, edge, R, h, g, mu, theta, theta_dot,
                                           theta_ddot) <= 0.0))
