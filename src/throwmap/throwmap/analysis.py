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
The analysis of a scene that the CLI and the ROS nodes need, computed once, in one place.

:func:`analyse`: the limit set from the scene's start, the design radii (R_flip, R_max), a
basin over the default grid, the sensor design and, for noisy scenes, the outcome distribution
and P(goal edge | detection). :func:`scene_analysis` redoes the sensor design at a sensor
position a node parameter may set (the guarantee radius does not move; the warm-up and the
detection rate do), so that everything published and checked refers to the sensor actually
used. A scene that cannot be run raises a ThrowmapError with the library's message: the part is
lost from the scene's start (PartLost), the orbit leaves the domain of f (DomainError), or the
sensor design gives no finite radius and none was given (:class:`SensorDesignError`).
"""

import dataclasses
from dataclasses import dataclass
import math


from . import analysis_cache
from .basins import Basin, basin, default_grid, design_radii
from .errors import ThrowmapError
from .orbits import limit_set, LimitSet, pull_share
from .sensor import sensor_design, SensorDesign
from .stochastic import stochastic_summary


class SensorDesignError(ThrowmapError):
    """The sensor design of a scene gives no usable sensor radius; the message says the fix."""


@dataclass(frozen=True)
class Analysis:
    """
    Everything the nodes and the CLI derive from a scene.

    That is: the limit set, the design radii, a basin and the sensor placement.
    """

    start: tuple
    limit_set: LimitSet
    radii: dict
    basin: Basin
    sensor: SensorDesign
    stochastic: dict = None     # noisy scenes: outcome distribution, P(goal | detection)
    pull: dict = None           # limit-set throws whose rolls need a pull (orbits.pull_share)

    def as_dict(self):
        d = {'start': {'edge': self.start[0], 'R': self.start[1]},
             'limit_set': self.limit_set.as_dict(), 'design': self.radii,
             'basin': self.basin.summary(), 'sensor': self.sensor.as_dict()}
        if self.stochastic is not None:
            d['stochastic'] = self.stochastic
        d['pull'] = self.pull
        return d


def analyse(scene, throws=10_000, grid_radii=50, grid_throws=200, progress=None):
    """
    Limit set from the scene's start, R_flip/R_max, a basin grid and the sensor design.

    The goal edge is the scene's ``sensor.goal_edge``, else the edge that reaches furthest
    out in the limit set (the only one a far sensor can prove). The result is cached on disk
    by scene content and code version (throwmap.analysis_cache; docs/physics.md): a hit is
    the computation's result bit for bit, and leaves a noisy model's generator as it does.
    """
    digest = analysis_cache.key(scene, throws=throws, grid_radii=grid_radii,
                                grid_throws=grid_throws)
    fields = analysis_cache.cached(
        digest, scene, lambda: _analyse(scene, throws, grid_radii, grid_throws, progress),
        lambda ls, bas: _sensor(scene, ls, bas))
    if scene.model.stochastic:
        scene.model.reseed(scene.seed)      # where the computation leaves it
    return Analysis(**fields)


def _sensor(scene, ls, bas):
    """Return the sensor design of ``analyse`` for the limit set ``ls`` and the basin."""
    goal = scene.goal_edge
    if goal is None:
        u_max = scene.model.part.U.max(axis=1)
        goal = max(ls.bands, key=lambda k: ls.bands[k][1] + u_max[k])
    return sensor_design(scene.model, ls, goal, scene.sensor_footprint, scene.sensor_radius,
                         bas)


def _analyse(scene, throws, grid_radii, grid_throws, progress):
    """Compute the fields of :func:`analyse`'s Analysis."""
    model = scene.model
    start = scene.default_start()
    noisy = model.stochastic
    if noisy:
        model.reseed(scene.seed)
    ls = limit_set(model, start[0], start[1], throws)
    # Design radii are properties of the deterministic map: noise is taken out for them.
    radii = design_radii(model.nominal())
    e, r = default_grid(model, grid_radii, radii['R_max_all'])
    bas = basin(model, e, r, grid_throws, reference=ls, progress=progress)
    sensor = _sensor(scene, ls, bas)
    stoch = None
    if noisy:
        stoch = stochastic_summary(model, sensor, start, (e, r), throws=min(throws, 2000),
                                   grid_throws=grid_throws, seeds=8, reference=ls)
    return {'start': start, 'limit_set': ls, 'radii': radii, 'basin': bas, 'sensor': sensor,
            'stochastic': stoch, 'pull': pull_share(model, ls)}


def scene_analysis(scene, sensor_radius=0.0, analysis=None):
    """
    Analysis of ``scene`` with the sensor at ``sensor_radius`` (0: the analysis's choice).

    ``analysis`` reuses an earlier :func:`analyse` result (it takes 0.5-2 s).
    """
    an = analysis if analysis is not None else analyse(scene)
    if sensor_radius and sensor_radius > 0.0 and sensor_radius != an.sensor.radius:
        sensor = sensor_design(scene.model, an.limit_set, an.sensor.goal_edge,
                               an.sensor.footprint, float(sensor_radius), an.basin)
        an = dataclasses.replace(an, sensor=sensor)
    if not math.isfinite(an.sensor.radius):
        s = an.sensor
        raise SensorDesignError(
            f"sensor: throwmap's sensor design gives no finite radius for this scene "
            f'(guarantee radius {s.guarantee_radius:.6g} m, reach {s.reach_radius:.6g} m); '
            'give the sensor position (parameter sensor_radius, or sensor.radius in the scene)')
    return an
