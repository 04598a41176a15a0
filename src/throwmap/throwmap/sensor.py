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
The one-bit sensor (paper section V.B): what it sees, what it reads, where to put it.

The sensor at arm coordinate x (half-width ``footprint``) sees the part when the part's shadow
on the arm, [R + u_min, R + u_max] of its resting edge, overlaps [x - footprint,
x + footprint] (:func:`sees`). A reading is that bit, passed through the sensor models of the
scene's effects (sensor_noise: false positives and negatives) (:func:`read_sensor`). A lost part
(edge -1) is never seen. :func:`sensor_design` places the sensor from a limit set so that a
detection proves the part is on the goal edge.
"""

from dataclasses import dataclass
import math

import numpy as np


def sees(part, edge, R, x, footprint=0.0):
    """Tell whether a sensor at arm coordinate x (half-width footprint) detects the part."""
    u_min = part.U.min(axis=1)[edge]
    u_max = part.U.max(axis=1)[edge]
    return (R + u_min <= x + footprint) & (R + u_max >= x - footprint)


def seen_radii(part, x, footprint=0.0):
    """
    Return (lo, hi) per edge: the radii R at which :func:`sees` detects a part on that edge.

    The part's extent [R + u_min, R + u_max] meets the sensor's [x - fp, x + fp].
    """
    return x - footprint - part.U.max(axis=1), x + footprint - part.U.min(axis=1)


def read_sensor(part, edge, R, x, footprint=0.0, models=(), rng=None):
    """
    Return the sensor's readings for parts resting at (edge, R); edge -1 (lost) reads 0.

    ``models``: (read, params) pairs, each ``read(seen, rng, params)`` (an effect's
    ``read_sensor``), applied in order with the Generator ``rng``.
    """
    edge = np.asarray(edge)
    # Index -1 would read the last edge's shadow: a lost part must read as nothing.
    seen = np.asarray(sees(part, np.maximum(edge, 0), R, x, footprint) & (edge >= 0))
    for read, params in models:
        seen = read(seen, rng, params)
    return seen


@dataclass(frozen=True)
class SensorDesign:
    """
    Where a one-bit sensor proves the part is on the goal edge (paper section V.B).

    ``guarantee_radius``: beyond it no limit-set state on another edge is seen.
    ``reach_radius``: beyond it no limit-set state is seen at all; the sensor must sit between.
    ``radius``: the chosen position; ``warmup_throws``: throws after which, from every start
    of the grid, no other edge is ever seen there; ``detection_rate``: fraction of limit-set
    throws the sensor fires at ``radius``.
    """

    goal_edge: int
    footprint: float
    guarantee_radius: float
    reach_radius: float
    radius: float
    warmup_throws: int
    detection_rate: float
    feasible: bool

    def as_dict(self):
        return dict(vars(self))


def sensor_design(model, ls, goal_edge, footprint=0.0, radius=None, basin_result=None):
    """
    Design the sensor for the limit set ``ls`` (throwmap.orbits.LimitSet) and the goal edge.

    ``radius`` fixes the position (else: beyond the guarantee radius by a quarter of the usable
    window); ``basin_result`` (throwmap.basins.Basin) gives the warm-up throws.
    """
    part = model.part
    u_max = part.U.max(axis=1)
    other_top = -math.inf
    goal_top = -math.inf
    for e, (_, hi) in ls.bands.items():
        top = hi + u_max[e]
        if e == goal_edge:
            goal_top = max(goal_top, top)
        else:
            other_top = max(other_top, top)
    guarantee = other_top + footprint
    reach = goal_top + footprint
    feasible = goal_edge in ls.bands and reach > guarantee
    if radius is None:
        if feasible and math.isinf(guarantee):
            # Only the goal edge recurs: any spot its shadow covers proves it; take the middle
            # of the window the goal states' shadows span.
            goal_low = ls.bands[goal_edge][0] + part.U.min(axis=1)[goal_edge] - footprint
            radius = 0.5 * (goal_low + reach)
        elif feasible:
            # Beyond the guarantee, with a margin of a quarter of the usable window.
            radius = guarantee + 0.25 * (reach - guarantee)
        else:
            radius = guarantee
    tail_seen = sees(part, ls.tail_edges, ls.tail_radii, radius, footprint)
    detection_rate = float(tail_seen.mean()) if tail_seen.size else 0.0
    warmup = 0
    if basin_result is not None:
        seen = read_sensor(part, basin_result.edges, basin_result.radii, radius, footprint)
        wrong = seen & (basin_result.edges != goal_edge)
        idx = np.argwhere(wrong)
        warmup = int(idx[:, 1].max() + 1) if idx.size else 0
    return SensorDesign(int(goal_edge), float(footprint), float(guarantee), float(reach),
                        float(radius), warmup, detection_rate, bool(feasible))
