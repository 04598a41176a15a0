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
The part's predicted state, throw by throw (ROS-free).

A :class:`Predictor` holds (edge, R) and advances it with the throw map f. It also answers what
the one-bit sensor at ``sensor_radius`` reads for a state and where the resting part is in frame
``feeder_base`` (x along the arm from the pivot, y up).
"""

from dataclasses import dataclass
import math

from throwmap import sees


@dataclass(frozen=True)
class Throw:
    """One predicted throw from (edge0, R0) to (edge, R); ``detected``: the bit after it."""

    count: int              # throws predicted since the last reset, this one included
    edge0: int
    R0: float
    edge: int
    R: float
    kind: str               # 'jog' or 'flip'
    detected: bool


def wrap_angle(angle):
    """Angle in (-pi, pi]."""
    a = math.remainder(angle, 2.0 * math.pi)
    return math.pi if a == -math.pi else a


def yaw_quaternion(yaw):
    """(x, y, z, w) of a rotation by ``yaw`` about z."""
    return 0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw)


def resting_pose(part, edge, R, h):
    """
    (x, y, yaw) of the part's CM resting on ``edge`` at radius R, frame feeder_base.

    The body frame is the scene's outline frame shifted to the CM: a body vertex v sits at
    ``(x, y) + Rot(yaw) (v - part.cm)``.
    """
    return float(R), float(h + part.d[edge]), wrap_angle(float(part.rest_angle[edge]))


class Predictor:
    """Predicted state of the part on the arm, advanced one throw at a time."""

    def __init__(self, scene, edge, R, sensor_radius, footprint=0.0):
        self.scene = scene
        self.model = scene.model
        self.part = scene.part
        self.sensor_radius = float(sensor_radius)
        self.footprint = float(footprint)
        self.reset(edge, R)

    def reset(self, edge, R):
        """Put the part at (edge, R); raises throwmap.DomainError outside the domain of f."""
        self.model.check(int(edge), float(R))
        self.edge = int(edge)
        self.R = float(R)
        self.count = 0

    @property
    def state(self):
        return self.edge, self.R

    def sees(self, edge, R):
        """Sensor bit for the part resting at (edge, R)."""
        return bool(sees(self.part, int(edge), float(R), self.sensor_radius, self.footprint))

    def step(self):
        """Advance one throw; raises throwmap.DomainError / NumericalError (state unchanged)."""
        edge0, r0 = self.edge, self.R
        edge, R, kind = self.model.f(edge0, r0)
        self.edge, self.R = int(edge), float(R)
        self.count += 1
        return Throw(self.count, edge0, r0, self.edge, self.R, kind, self.sees(edge, R))

    def pose(self):
        """(x, y, yaw) of the resting part's CM in frame feeder_base."""
        return resting_pose(self.part, self.edge, self.R, self.scene.h)

    def polygon(self):
        """(n, 2) hull vertices of the resting part in frame feeder_base."""
        return self.part.pose_vertices(self.edge, self.R, self.scene.h)
