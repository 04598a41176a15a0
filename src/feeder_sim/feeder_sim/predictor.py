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

With the scene effect ``finite_arm`` a throw may lose the part off the arm's end: f returns
``(-1, nan, 'lost')``. The predictor then holds edge -1 (no part on the arm); every later throw
is an empty one, of kind ``lost`` too (``Predictor.lost_at`` names the throw that lost it),
until :meth:`Predictor.reset` places a part again. The sensor
reading comes from ``scene.sense`` when the predictor samples a noisy sensor
(``noisy_sensor``: effect ``sensor_noise``, seeded), else from the geometric ``throwmap.sees``.
"""

from dataclasses import dataclass
import math

from throwmap import sees

LOST = 'lost'       # kind of a throw that lost the part off the arm's end, or found none


@dataclass(frozen=True)
class Throw:
    """One predicted throw from (edge0, R0) to (edge, R); ``detected``: the bit after it."""

    count: int              # throws predicted since the last reset, this one included
    edge0: int              # -1: no part on the arm before the throw
    R0: float
    edge: int               # -1: no part on the arm after the throw (R is nan)
    R: float
    kind: str               # 'jog', 'flip' or 'lost' (no part on the arm after it)
    detected: bool

    @property
    def on_arm(self):
        """Whether a part rests on the arm after this throw."""
        return self.edge >= 0


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


def prediction_model(scene):
    """
    Return the throw map to predict with when following real hardware: the noise-free one.

    A scene with ``release_noise`` has a random f; its draws cannot match the real feeder's, so
    the expected (nominal) map is the better prediction. Other scenes: ``scene.model`` itself.
    """
    if scene.stochastic and hasattr(scene.model, 'nominal'):
        return scene.model.nominal()
    return scene.model


def has_noisy_sensor(scene):
    """Whether the scene names the ``sensor_noise`` effect."""
    return getattr(scene.effects, 'sensor_noise', None) is not None


class Predictor:
    """
    Predicted state of the part on the arm, advanced one throw at a time.

    ``model`` defaults to ``scene.model`` (the scene's seeded randomness included);
    ``noisy_sensor`` takes each reading from ``scene.sense`` (false positives and negatives of
    ``sensor_noise``); ``seed`` (not None) restarts the scene model's random sequences.
    """

    def __init__(self, scene, edge, R, sensor_radius, footprint=0.0, model=None,
                 noisy_sensor=False, seed=None):
        self.scene = scene
        self.model = scene.model if model is None else model
        self.part = scene.part
        self.sensor_radius = float(sensor_radius)
        self.footprint = float(footprint)
        self.noisy_sensor = bool(noisy_sensor)
        if seed is not None and hasattr(scene.model, 'reseed'):
            scene.model.reseed(int(seed))
        self.reset(edge, R)

    def reset(self, edge, R):
        """Put the part at (edge, R); raises throwmap.DomainError outside the domain of f."""
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
        """Whether the part has left the arm (no part to throw until the next reset)."""
        return self.edge < 0

    def sees(self, edge, R):
        """Geometric sensor bit for the part resting at (edge, R); False for no part."""
        if edge < 0:
            return False
        return bool(sees(self.part, int(edge), float(R), self.sensor_radius, self.footprint))

    def read(self, edge, R):
        """Return the sensor's reading: with a noisy sensor a seeded sample, else :meth:`sees`."""
        if not self.noisy_sensor:
            return self.sees(edge, R)
        return bool(self.scene.sense(int(edge), float(R), self.sensor_radius, self.footprint))

    def step(self):
        """Advance one throw; raises throwmap.DomainError / NumericalError (state unchanged)."""
        edge0, r0 = self.edge, self.R
        if self.lost:
            edge, R, kind = -1, math.nan, LOST
        else:
            edge, R, kind = self.model.f(edge0, r0)
        self.edge, self.R = int(edge), float(R)
        self.count += 1
        if kind == LOST and self.lost_at is None:
            self.lost_at = self.count
        return Throw(self.count, edge0, r0, self.edge, self.R, kind,
                     self.read(self.edge, self.R))

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
