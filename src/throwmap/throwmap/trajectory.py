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
Sampled poses of one throw (for plots and RViz markers): flight, then each rolling segment.

The throw map itself never needs rolling *times* (energy decides where rolling ends); only this
module integrates the pendulum, so that a trajectory has a time axis.
"""

from dataclasses import dataclass
import math

import numpy as np

from .status import (EV_FLAT_LANDING, EV_LANDING, REC_ALPHA0, REC_ALPHA1, REC_EDGE, REC_KIND,
                     REC_OMEGA0, REC_PIVOT, REC_PIVOT_X, REC_VERTEX)


@dataclass(frozen=True)
class Trajectory:
    """
    Samples of the part's pose in frame F.

    Time (s), CM x, y (m), and rotation phi (rad) relative to the resting pose on the start
    edge (vertices: ``vertices_at(k)``).
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    phi: np.ndarray
    phase: tuple            # 'flight' or 'roll' per sample
    body_u: np.ndarray      # vertex coordinates in F^{edge0}
    body_v: np.ndarray

    def vertices_at(self, k):
        c, s = math.cos(self.phi[k]), math.sin(self.phi[k])
        return np.stack([self.x[k] + c * self.body_u - s * self.body_v,
                         self.y[k] + s * self.body_u + c * self.body_v], axis=1)


def _roll_segment(alpha0, omega0, alpha1, g_abs, lp, inertia, dt_max):
    """
    Integrate alpha'' = -|g| l cos(alpha) / I from (alpha0, omega0) to alpha1.

    Stops when alpha reaches alpha1 moving in its final direction; returns arrays (t, alpha).
    """
    def acc(a):
        return -g_abs * lp * math.cos(a) / inertia

    # Final direction: towards alpha1 from the turning side, which is the sign of alpha1 - alpha0
    # unless alpha1 == alpha0 (a full rock back to the same end).
    direction = math.copysign(1.0, alpha1 - alpha0) if alpha1 != alpha0 else -math.copysign(
        1.0, omega0 or 1.0)
    ts, als = [0.0], [alpha0]
    a, w, t = alpha0, omega0, 0.0
    for _ in range(200_000):
        dt = dt_max
        k1a, k1w = w, acc(a)
        k2a, k2w = w + 0.5 * dt * k1w, acc(a + 0.5 * dt * k1a)
        k3a, k3w = w + 0.5 * dt * k2w, acc(a + 0.5 * dt * k2a)
        k4a, k4w = w + dt * k3w, acc(a + dt * k3a)
        a_new = a + dt * (k1a + 2 * k2a + 2 * k3a + k4a) / 6
        w_new = w + dt * (k1w + 2 * k2w + 2 * k3w + k4w) / 6
        t += dt
        if (a_new - alpha1) * direction >= 0 and w_new * direction > 0:
            frac = (alpha1 - a) / (a_new - a) if a_new != a else 1.0
            ts.append(t - dt + frac * dt)
            als.append(alpha1)
            break
        a, w = a_new, w_new
        ts.append(t)
        als.append(a)
    else:
        ts.append(t)
        als.append(alpha1)
    return np.array(ts), np.array(als)


def throw_trajectory(model, edge, R, flight_time, records, samples=60):
    """Sample the poses of the base model's throw from (edge, R) and its event records."""
    part = model.part
    g_abs = -model.g
    w = model.w
    h = model.h
    d = part.d[edge]
    T = flight_time
    ts = np.linspace(0.0, T, samples)
    xs = R - (h + d) * w * ts
    ys = h + d + R * w * ts + 0.5 * model.g * ts * ts
    phis = w * ts
    phase = ['flight'] * samples
    t_all, x_all, y_all, p_all = [ts], [xs], [ys], [phis]
    phi = w * T
    t0 = T
    dt = max(T, 1e-3) / samples
    for row in records:
        kind = int(row[REC_KIND])
        if kind == EV_FLAT_LANDING:
            pivot = int(row[REC_VERTEX])
            j = int(row[REC_EDGE])
            a_end = (part.alpha_cw_end[pivot] if j == pivot else part.alpha_ccw_end[pivot])
            # Snap the (tiny) residual tilt at the flat landing.
            c, s = math.cos(phi), math.sin(phi)
            rx = c * part.U[edge, pivot] - s * part.V[edge, pivot]
            ry = s * part.U[edge, pivot] + c * part.V[edge, pivot]
            phi += a_end - math.atan2(-ry, -rx)
            continue
        if kind != EV_LANDING:
            continue
        p = int(row[REC_PIVOT])
        a0, om0, a1 = row[REC_ALPHA0], row[REC_OMEGA0], row[REC_ALPHA1]
        xp = row[REC_PIVOT_X]
        lp = part.vertex_radius[p]
        seg_t, seg_a = _roll_segment(a0, om0, a1, g_abs, lp, part.rho2 + lp * lp, dt)
        t_all.append(t0 + seg_t)
        x_all.append(xp + lp * np.cos(seg_a))
        y_all.append(h + lp * np.sin(seg_a))
        p_all.append(phi + (seg_a - a0))
        phase.extend(['roll'] * len(seg_t))
        phi += a1 - a0
        t0 += seg_t[-1]
    return Trajectory(np.concatenate(t_all), np.concatenate(x_all), np.concatenate(y_all),
                      np.concatenate(p_all), tuple(phase), part.U[edge].copy(),
                      part.V[edge].copy())
