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
Independent reference for the finite carry's grasp domain: a dense scan of the wrench cone.

Written from section III.A.1 of the paper only. The arm turns with constant angular
acceleration a = w^2 / (2 theta_r) from rest at theta = 0 to (theta_r, w), in T_c = 2 theta_r / w.
At every instant the wrench the arm must apply (per unit mass, frame F^i)

    w = thetadd (-(h + d), R, rho^2) + thetad^2 (-R, -(h + d), 0) + (-g sin th, -g cos th, 0)

must lie in the cone spanned by w_1..w_4 (friction mu at the two vertices of the resting edge):
w . (w_j x w_k) <= 0 for (j, k) = (1, 2), (2, 3), (3, 4), (4, 1). A radius is in the carry's
grasp domain when that holds at every one of ``time_samples`` + 1 evenly spaced instants and
the left vertex starts right of the pivot (R + u_l > 0). Nothing here assumes the domain is an
interval: the scan returns a mask over the radii it is given.
"""

import numpy as np


def carry_grasp_mask(u_l, u_r, d, rho2, h, g, mu, w, theta_r, radii, time_samples=2000):
    """Return a boolean mask over ``radii``: the dynamic grasp holds along the whole carry."""
    radii = np.asarray(radii, dtype=float)
    v = -d
    cone = np.array([[-mu, 1.0, u_l + mu * v],
                     [mu, 1.0, u_l - mu * v],
                     [mu, 1.0, u_r - mu * v],
                     [-mu, 1.0, u_r + mu * v]])
    normals = np.array([np.cross(cone[j], cone[(j + 1) % 4]) for j in range(4)])
    acc = w * w / (2.0 * theta_r)
    t = np.linspace(0.0, 2.0 * theta_r / w, time_samples + 1)
    th = 0.5 * acc * t * t
    thd = acc * t
    hd = h + d
    ok = np.ones(radii.size, dtype=bool)
    for k in range(t.size):
        wrench = np.stack([-acc * hd - thd[k] ** 2 * radii - g * np.sin(th[k]),
                           acc * radii - thd[k] ** 2 * hd - g * np.cos(th[k]) + 0.0 * radii,
                           np.full(radii.size, acc * rho2)], axis=1)
        ok &= np.all(wrench @ normals.T <= 0.0, axis=1)
    return ok & (radii + u_l > 0.0)


def mask_intervals(radii, mask):
    """Return the maximal runs of True in ``mask`` as [(R_first, R_last), ...] over ``radii``."""
    radii = np.asarray(radii, dtype=float)
    m = np.concatenate(([False], np.asarray(mask, dtype=bool), [False]))
    starts = np.flatnonzero(~m[:-1] & m[1:])
    stops = np.flatnonzero(m[:-1] & ~m[1:]) - 1
    return [(float(radii[a]), float(radii[b])) for a, b in zip(starts, stops)]
