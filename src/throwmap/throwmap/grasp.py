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
Dynamic grasp (paper section III.A.1): impulse-cone bounds (1)-(4) and the wrench-cone test.

The bounds and the cone test are written once, compiled (:func:`impulse_bounds`,
:func:`cone_margins`), and used both here (the Python API, the grasp table) and inside throws
(the composed release checks the grasp at each throw's own offset; finite_carry checks the
wrench cone along the carry).
"""

from dataclasses import dataclass
import math

import numpy as np

from .jit import njit


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


@njit
def impulse_bounds(edge, h, mu, rho2, d, u_l, u_r):
    """
    Right-hand sides of constraints (1)-(4) on a stable edge (R must exceed each).

    The edge's vertices sit at v = -d in F^i. mu = inf: no friction bound (2), (4) is -inf.
    """
    hd = h + d[edge]
    b1 = (rho2 + d[edge] * hd) / u_l[edge]
    b3 = (rho2 + d[edge] * hd) / u_r[edge]
    if math.isinf(mu):
        return b1, -math.inf, b3, -math.inf
    return b1, -hd / mu, b3, hd / mu


@njit
def impulse_grasp_radius(edge, h, mu, rho2, d, u_l, u_r):
    """R_grasp on a stable edge at offset h: the largest of the bounds (1)-(4)."""
    b1, b2, b3, b4 = impulse_bounds(edge, h, mu, rho2, d, u_l, u_r)
    return max(max(b1, b3), max(b2, b4))


def _bounds(part, edge, h, mu):
    b = impulse_bounds(edge, float(h), math.inf if mu is None else float(mu), part.rho2, part.d,
                       part.u_l, part.u_r)
    return tuple(float(x) for x in b)


def edge_grasp(part, edge, h, mu=None):
    stable = bool(part.stable[edge])
    if not stable:
        nan = math.nan
        return EdgeGrasp(edge, False, (nan,) * 4, math.inf, math.inf, nan, 0)
    bounds = _bounds(part, edge, h, mu)
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


@njit
def cone_normals(ul, ur, vl, mu):
    """
    Return the cone's face normals w_j x w_k for (j, k) = (1,2), (2,3), (3,4), (4,1), flat.

    The contact wrench cone W^i of an edge with vertices (ul, vl), (ur, vl) in F^i and friction
    mu is spanned by w_1..w_4 = (-mu, 1, ul + mu vl), (mu, 1, ul - mu vl), (mu, 1, ur - mu vl),
    (-mu, 1, ur + mu vl); a wrench w is in it when every w . (w_j x w_k) <= 0.
    """
    c00, c01, c02 = -mu, 1.0, ul + mu * vl
    c10, c11, c12 = mu, 1.0, ul - mu * vl
    c20, c21, c22 = mu, 1.0, ur - mu * vl
    c30, c31, c32 = -mu, 1.0, ur + mu * vl
    return (c01 * c12 - c02 * c11, c02 * c10 - c00 * c12, c00 * c11 - c01 * c10,
            c11 * c22 - c12 * c21, c12 * c20 - c10 * c22, c10 * c21 - c11 * c20,
            c21 * c32 - c22 * c31, c22 * c30 - c20 * c32, c20 * c31 - c21 * c30,
            c31 * c02 - c32 * c01, c32 * c00 - c30 * c02, c30 * c01 - c31 * c00)


@njit
def cone_margins(ul, ur, vl, mu, w0, w1, w2):
    """
    Return w^T (w_j x w_k) / |w| for (j, k) = (1,2), (2,3), (3,4), (4,1); all <= 0: in the cone.

    The cone of :func:`cone_normals`. Each value reads as a signed distance-like margin.
    """
    n10, n11, n12, n20, n21, n22, n30, n31, n32, n40, n41, n42 = cone_normals(ul, ur, vl, mu)
    norm = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    if norm == 0.0:
        norm = 1.0
    return ((w0 * n10 + w1 * n11 + w2 * n12) / norm, (w0 * n20 + w1 * n21 + w2 * n22) / norm,
            (w0 * n30 + w1 * n31 + w2 * n32) / norm, (w0 * n40 + w1 * n41 + w2 * n42) / norm)


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
    return np.array(cone_margins(float(part.u_l[edge]), float(part.u_r[edge]),
                                 float(part.v_l[edge]), float(mu), float(w[0]), float(w[1]),
                                 float(w[2])))


def in_dynamic_grasp(part, edge, R, h, g, mu, theta, theta_dot, theta_ddot):
    if not part.stable[edge]:
        return False
    return bool(np.all(wrench_cone_margins(part, edge, R, h, g, mu, theta, theta_dot,
                                           theta_ddot) <= 0.0))
