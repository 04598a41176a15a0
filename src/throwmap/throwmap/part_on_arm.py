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
A part on the arm of a scene, throw by throw (the object the sim, the emulator, the monitor use).

:class:`PartOnArm` holds (edge, R) and advances it with the scene's throw map. With effect
``finite_arm`` a throw may lose the part off the arm's end, and under ``liftoff`` a roll may
slip the part inwards to rest below R_min, where no later throw is defined: f returns
``(-1, nan, 'lost')`` and the throw says why (``Throw.lost_reason``); the part is then gone
(edge -1) and every later throw is an empty one, of kind ``lost`` too
(``lost_at`` names the throw that lost it), until :meth:`PartOnArm.place` puts a part back. The
sensor's reading goes through the scene's sensor model (``sensor_noise``: seeded false positives
and negatives) unless the object is told to read the geometric bit. :meth:`PartOnArm.orbit` and
:meth:`PartOnArm.readings` do the same for long orbits at once (the monitor's rules).
"""

from dataclasses import dataclass
import math
from typing import NamedTuple

import numpy as np

from .sensor import read_sensor

LOST = 'lost'       # kind of a throw that lost the part off the arm, or found none to throw
# Models at other release speeds kept per part (a speed policy uses a few dozen).
MAX_SPEEDS_KEPT = 64


@dataclass(frozen=True)
class Throw:
    """One throw from (edge0, R0) to (edge, R); ``detected``: the sensor's bit after it."""

    count: int              # throws since the part was placed, this one included
    edge0: int              # -1: no part on the arm before the throw
    R0: float
    edge: int               # -1: no part on the arm after the throw (R is nan)
    R: float
    kind: str               # 'jog', 'flip' or 'lost' (no part on the arm after it)
    detected: bool
    lost_reason: str = ''   # why this throw lost the part ('' if it did not, or had none)
    release_speed: float = math.nan     # rad/s the arm released at (noise included); nan: none

    @property
    def on_arm(self):
        """Whether a part rests on the arm after this throw."""
        return self.edge >= 0


class OrbitSegments(NamedTuple):
    """States of a long orbit; ``segments``: (start, stop) index ranges of unbroken runs."""

    edges: np.ndarray
    radii: np.ndarray
    segments: tuple


def wrap_angle(angle):
    """Angle in (-pi, pi]."""
    a = math.remainder(angle, 2.0 * math.pi)
    return math.pi if a == -math.pi else a


def resting_pose(part, edge, R, h):
    """
    (x, y, yaw) of the part's CM resting on ``edge`` at radius R (frame F = feeder_base).

    The body frame is the scene's outline frame shifted to the CM: a body vertex v sits at
    ``(x, y) + Rot(yaw) (v - part.cm)``.
    """
    return float(R), float(h + part.d[edge]), wrap_angle(float(part.rest_angle[edge]))


class PartOnArm:
    """
    A part on the arm of ``scene``, advanced one throw at a time.

    ``model`` defaults to ``scene.model`` (its seeded randomness included; the noise-free
    ``scene.model.nominal()`` predicts a real feeder better). ``edge``, ``R`` default to the
    scene's start; ``sensor_radius`` and ``footprint`` to the scene's sensor. ``noisy_sensor``
    (default: whether the scene's sensor is noisy) reads through the scene's sensor model, else
    the geometric bit. ``seed`` (not None) restarts the scene model's random sequences.
    """

    def __init__(self, scene, edge=None, R=None, sensor_radius=None, footprint=None,
                 model=None, noisy_sensor=None, seed=None):
        self.scene = scene
        self.model = scene.model if model is None else model
        self.part = scene.part
        radius = scene.sensor_radius if sensor_radius is None else sensor_radius
        self.sensor_radius = math.nan if radius is None else float(radius)
        self.footprint = float(scene.sensor_footprint if footprint is None else footprint)
        self.noisy_sensor = scene.noisy_sensor if noisy_sensor is None else bool(noisy_sensor)
        if seed is not None:
            scene.model.reseed(int(seed))
            if self.model is not scene.model:
                self.model.reseed(int(seed))
        if edge is None or R is None:
            edge, R = scene.default_start()
        self._at_speed = {}     # release speed -> the model at it (one random stream)
        self.place(edge, R)

    def model_at(self, release_speed=None):
        """
        Return this part's model at another release speed (rad/s; None: the scene's own).

        The same part, offset, effects and knobs (``ThrowModel.at``), and the same random
        stream: a throw at any speed draws the next of this part's seeded draws, so a run that
        changes speed per throw is as reproducible as one that does not. Kept per speed.
        """
        base = self.model
        if release_speed is None or float(release_speed) == base.w:
            return base
        w = float(release_speed)
        model = self._at_speed.get(w)
        if model is None:
            model = base.at(base.h, w)
            if not base.stochastic:
                model = model.nominal()
            if len(self._at_speed) >= MAX_SPEEDS_KEPT:
                self._at_speed.pop(next(iter(self._at_speed)))
            self._at_speed[w] = model
        if model.stochastic:
            model.rng = base.rng
        return model

    def place(self, edge, R):
        """Put a part at (edge, R); raises throwmap.DomainError outside the domain of f."""
        self.model.check(int(edge), float(R))
        self.edge = int(edge)
        self.R = float(R)
        self.count = 0
        self.lost_at = None     # count of the throw that lost the part

    @property
    def state(self):
        return self.edge, self.R

    @property
    def lost(self):
        """Whether the part has left the arm (no part to throw until the next place)."""
        return self.edge < 0

    def sees(self, edge=None, R=None):
        """Geometric sensor bit for a part resting at (edge, R) (default: this one)."""
        edge, R = (self.edge, self.R) if edge is None else (edge, R)
        if edge < 0:
            return False
        return bool(read_sensor(self.part, int(edge), float(R), self.sensor_radius,
                                self.footprint))

    def read(self, edge=None, R=None):
        """Return the sensor's reading: a seeded sample of a noisy sensor, else :meth:`sees`."""
        edge, R = (self.edge, self.R) if edge is None else (edge, R)
        if not self.noisy_sensor:
            return self.sees(edge, R)
        return bool(self.scene.model.read_sensor(int(edge), math.nan if R is None else float(R),
                                                 self.sensor_radius, self.footprint))

    def throw(self, release_speed=None):
        """
        Advance one throw; raises throwmap.DomainError / NumericalError (state unchanged).

        ``release_speed`` (rad/s): the arm's setpoint for this throw (None: the scene's own
        speed); release_noise, when the scene has it, perturbs it as it does the scene's. A
        speed at which the part cannot be held raises throwmap.DomainError.
        """
        edge0, r0 = self.edge, self.R
        reason = ''
        speed = math.nan
        if self.lost:
            edge, R, kind = -1, math.nan, LOST
        else:
            # The full result, not f: the same throw (and random draws), with the reason of a loss.
            res = self.model_at(release_speed).throw(edge0, r0)
            edge, R, kind = res.edge, res.R, res.kind
            reason = res.lost_reason
            speed = res.release_speed
            if not res.in_domain:   # off the arm, or at rest outside f's domain: no next throw
                edge, R, kind = -1, math.nan, LOST
        self.edge, self.R = int(edge), float(R)
        self.count += 1
        if kind == LOST and self.lost_at is None:
            self.lost_at = self.count
        return Throw(self.count, edge0, r0, self.edge, self.R, kind, self.read(), reason,
                     float(speed))

    def pose(self):
        """(x, y, yaw) of the resting part's CM in frame feeder_base; None without a part."""
        if self.lost:
            return None
        return resting_pose(self.part, self.edge, self.R, self.scene.h)

    def polygon(self):
        """(n, 2) hull vertices of the resting part in frame feeder_base; None without a part."""
        if self.lost:
            return None
        return self.part.pose_vertices(self.edge, self.R, self.scene.h)

    # ----------------------------------------------------------------------------- orbits
    def orbit(self, throws, start=None, attempts=20):
        """
        Return the ``throws`` states after ``start`` (default: this part's state, not moved).

        An orbit may end early: the part is lost off a finite arm, or a noisy throw leaves the
        domain of f. The states before that are kept as one segment and, when the map is random
        (release_noise), the orbit starts again from ``start``, up to ``attempts`` times.
        """
        start = self.state if start is None else (int(start[0]), float(start[1]))
        edges, radii, segments, total = [], [], [], 0
        for _ in range(attempts):
            e, r, _, _, done = self.model.orbits([start[0]], [start[1]], int(throws) - total)
            n = int(done[0])
            if n > 0:
                edges.append(e[0, 1:n + 1])
                radii.append(r[0, 1:n + 1])
                segments.append((total, total + n))
                total += n
            if total >= throws or not self.model.stochastic:
                break
        if not edges:
            return OrbitSegments(np.zeros(0, dtype=np.int64), np.zeros(0), ())
        return OrbitSegments(np.concatenate(edges), np.concatenate(radii), tuple(segments))

    def readings(self, edges, radii):
        """Return the sensor's bits for parts resting at each (edge, R), noise if noisy."""
        if not self.noisy_sensor:
            return np.asarray(read_sensor(self.part, edges, radii, self.sensor_radius,
                                          self.footprint), dtype=bool)
        return np.asarray(self.scene.model.read_sensor(edges, radii, self.sensor_radius,
                                                       self.footprint), dtype=bool)
