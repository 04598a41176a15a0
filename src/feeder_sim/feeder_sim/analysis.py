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
The scene analysis the sim and the monitor share, so that both derive the same numbers.

``throwmap.analyse`` places the sensor itself (or takes the scene's ``sensor.radius``); a node
parameter may move it. :func:`scene_analysis` then redoes the sensor design at that radius (the
guarantee radius does not move, the warm-up and the detection rate do), so that everything
published and checked refers to the sensor actually used.

A scene the nodes cannot run raises a ``throwmap.ThrowmapError`` here, with throwmap's message:
``analyse`` fails (the part is lost from the scene's start: ``PartLost``; the orbit leaves the
domain of f: ``DomainError``), or the sensor design gives no finite radius and none was given
(:class:`SensorDesignError`). The nodes stop at start-up with that message (exit status 2).
"""

import dataclasses
import json
import math

import numpy as np
from throwmap import analyse, load_scene, sensor_design, ThrowmapError

# Fields of one predicted/limit_set row, in order.
LIMIT_SET_FIELDS = ('edge', 'R_min', 'R_max', 'jogs_min', 'jogs_max')


class SensorDesignError(ThrowmapError):
    """The sensor design of a scene gives no usable sensor radius; the message says the fix."""


def load(path):
    """Load a scene file; raises throwmap.InputError naming the field and the fix."""
    return load_scene(str(path))


def scene_analysis(scene, sensor_radius=0.0, analysis=None):
    """
    Analysis of ``scene`` with the sensor at ``sensor_radius`` (0: the analysis's choice).

    ``analysis`` reuses an earlier ``throwmap.analyse(scene)`` result (it takes 0.5-2 s).
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


def limit_set_rows(limit_set):
    """Rows ``[edge, R_min, R_max, jogs_min, jogs_max]`` sorted by edge (NaN: no jog count)."""
    rows = []
    for edge in sorted(limit_set.bands):
        lo, hi = limit_set.bands[edge]
        jogs = limit_set.jogs.get(edge, (math.nan, math.nan))
        rows.append([float(edge), float(lo), float(hi), float(jogs[0]), float(jogs[1])])
    return rows


def _plain(value):
    """JSON-safe copy: numpy scalars to Python, tuples to lists, non-finite floats to None."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_plain(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    return value


def analysis_json(analysis):
    """Strict JSON of ``analysis.as_dict()`` (infinities and NaN become null)."""
    return json.dumps(_plain(analysis.as_dict()), sort_keys=True)
