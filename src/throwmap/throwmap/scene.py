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

"""Scene files: YAML describing a part, an arm, a throw and gravity (docs/scenes.md).

Lengths are metres; a key ending in ``_cm`` gives the same quantity in centimetres and
``release_speed_deg`` gives degrees per second. Unknown keys are errors that list the allowed
names, so a typo never silently falls back to a default.
"""

import math
import os
import warnings

import yaml

from .errors import InputError
from .model import Accuracy, SETTLE_RULES, ThrowModel
from .part import Part

SCHEMA = {
    '': {'name', 'description', 'part', 'arm', 'throw', 'gravity', 'contact', 'catch',
         'accuracy', 'sensor', 'start'},
    'part': {'vertices', 'vertices_cm', 'cm', 'cm_cm', 'radius_of_gyration',
             'radius_of_gyration_cm'},
    'arm': {'offset', 'offset_cm'},
    'throw': {'release_speed', 'release_speed_deg'},
    'contact': {'mu'},
    'catch': {'settle_rule'},
    'accuracy': {'contact_time_tol', 'flat_landing_tol', 'max_flight_steps', 'max_impacts'},
    'sensor': {'goal_edge', 'radius', 'radius_cm', 'footprint', 'footprint_cm'},
    'start': {'edge', 'R', 'R_cm'},
}
REQUIRED = {'': ('name', 'part', 'arm', 'throw', 'gravity'), 'part': (), 'arm': (),
            'throw': ()}
ALTERNATIVES = {'part': [('vertices', 'vertices_cm')], 'arm': [('offset', 'offset_cm')],
                'throw': [('release_speed', 'release_speed_deg')]}


def _check_keys(section, data, where):
    if not isinstance(data, dict):
        raise InputError(where or 'scene', f'must be a mapping, got {type(data).__name__}',
                         'write it as key: value pairs')
    allowed = SCHEMA[section]
    for key in data:
        if key not in allowed:
            raise InputError(f'{where}.{key}' if where else str(key), 'unknown key',
                             f'allowed here: {", ".join(sorted(allowed))}')
    for key in REQUIRED.get(section, ()):
        if key not in data:
            raise InputError(f'{where}.{key}' if where else key, 'missing',
                             'add it (see scenes/triangle.yaml for a complete scene)')
    for group in ALTERNATIVES.get(section, ()):
        present = [k for k in group if k in data]
        if len(present) != 1:
            raise InputError(f'{where}.{group[0]}',
                             'missing' if not present else f'given twice ({" and ".join(present)})',
                             f'give exactly one of {" / ".join(group)}')


def _unit(data, key, where, scale_keys):
    """Value of ``key`` in SI from whichever spelling is present (None if absent)."""
    for spelled, factor in scale_keys:
        if spelled in data:
            value = data[spelled]
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InputError(f'{where}.{spelled}', f'must be a number, got {value!r}',
                                 'give a number')
            if not math.isfinite(value):
                raise InputError(f'{where}.{spelled}', f'must be finite, got {value!r}',
                                 'give a finite number')
            return float(value) * factor
    return None


def _points(data, where, key):
    if key + '_cm' in data and key in data:
        raise InputError(f'{where}.{key}', f'given twice ({key} and {key}_cm)',
                         'give only one of them')
    if key in data:
        return data[key], 1.0, f'{where}.{key}'
    if key + '_cm' in data:
        return data[key + '_cm'], 0.01, f'{where}.{key}_cm'
    return None, 1.0, None


def _scaled(points, factor, field):
    try:
        return [[float(c) * factor for c in p] for p in points]
    except (TypeError, ValueError):
        raise InputError(field, f'not a list of [x, y] pairs: {points!r}',
                         'give [[x0, y0], [x1, y1], ...]') from None


class Scene:
    """A validated scene: the part, the throw-map model and the sensor/start settings."""

    def __init__(self, data, source='<scene>'):
        self.source = source
        _check_keys('', data, '')
        for section in ('part', 'arm', 'throw', 'contact', 'catch', 'accuracy', 'sensor',
                        'start'):
            if section in data:
                _check_keys(section, data[section], section)
        self.data = data
        self.name = str(data['name'])
        self.description = str(data.get('description', ''))
        pd = data['part']
        verts, factor, vfield = _points(pd, 'part', 'vertices')
        vertices = _scaled(verts, factor, vfield) if isinstance(verts, list) else verts
        cm_raw, cm_factor, cm_field = _points(pd, 'part', 'cm')
        cm = _scaled([cm_raw], cm_factor, cm_field)[0] if cm_raw is not None else None
        rho = _unit(pd, 'radius_of_gyration', 'part', [('radius_of_gyration', 1.0),
                                                        ('radius_of_gyration_cm', 0.01)])
        if rho is not None and rho <= 0:
            key = 'radius_of_gyration' if 'radius_of_gyration' in pd else 'radius_of_gyration_cm'
            raise InputError(f'part.{key}', f'must be > 0, got {pd[key]!r}',
                             'give rho = sqrt(I_cm / m), or omit it for a uniform lamina')
        self.part = Part(vertices, cm=cm, radius_of_gyration=rho, field='part')
        h = _unit(data['arm'], 'offset', 'arm', [('offset', 1.0), ('offset_cm', 0.01)])
        w = _unit(data['throw'], 'release_speed', 'throw',
                  [('release_speed', 1.0), ('release_speed_deg', math.pi / 180.0)])
        g = data['gravity']
        mu = data.get('contact', {}).get('mu')
        rule = data.get('catch', {}).get('settle_rule', 'full')
        if rule not in SETTLE_RULES:
            raise InputError('catch.settle_rule', f'unknown rule {rule!r}',
                             f'use one of {", ".join(SETTLE_RULES)}')
        accuracy = Accuracy(**data.get('accuracy', {}))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter('always')
            self.model = ThrowModel(self.part, h, w, g, mu=mu, settle_rule=rule,
                                    accuracy=accuracy)
        self.warnings = [str(c.message) for c in caught]
        for msg in self.warnings:
            warnings.warn(f'{source}: {msg}', stacklevel=2)
        sensor = data.get('sensor', {})
        self.goal_edge = sensor.get('goal_edge', None)
        if self.goal_edge is not None and (isinstance(self.goal_edge, bool)
                                           or not isinstance(self.goal_edge, int)
                                           or self.goal_edge not in self.part.stable_edges):
            raise InputError('sensor.goal_edge', f'{self.goal_edge!r} is not a stable edge',
                             f'use one of {self.part.stable_edges}')
        self.sensor_radius = _unit(sensor, 'radius', 'sensor',
                                   [('radius', 1.0), ('radius_cm', 0.01)])
        footprint = _unit(sensor, 'footprint', 'sensor',
                          [('footprint', 1.0), ('footprint_cm', 0.01)])
        if footprint is not None and footprint < 0:
            raise InputError('sensor.footprint', f'must be >= 0, got {footprint!r}',
                             'give the half-width of the sensed spot in metres')
        self.sensor_footprint = footprint or 0.0
        start = data.get('start', {})
        self.start_edge = start.get('edge')
        self.start_R = _unit(start, 'R', 'start', [('R', 1.0), ('R_cm', 0.01)])
        if self.start_edge is not None:
            err = self.model.domain_error(self.start_edge, self.start_R if self.start_R
                                          is not None else math.inf)
            if err is not None:
                raise InputError('start', str(err), 'pick a start inside the domain of f')

    @property
    def h(self):
        return self.model.h

    @property
    def release_speed(self):
        return self.model.w

    @property
    def gravity(self):
        return self.model.g

    def default_start(self):
        """(edge, R) to start orbits from: the scene's ``start``, else the goal edge (or the
        first stable edge) at 1.5 x its R_grasp."""
        edge = self.start_edge
        if edge is None:
            edge = self.goal_edge if self.goal_edge is not None else self.part.stable_edges[0]
        R = self.start_R
        if R is None:
            R = 1.5 * max(self.model.r_grasp[edge], -self.part.u_l[edge])
        return int(edge), float(R)


def load_scene(path):
    """Read and validate a scene file; every error names the file and the field."""
    if not os.path.exists(path):
        raise InputError('scene', f'no such file: {path}',
                         'give the path of a scene YAML (e.g. scenes/triangle.yaml)')
    try:
        with open(path, encoding='utf-8') as fh:
            data = yaml.safe_load(fh)
    except yaml.YAMLError as exc:
        raise InputError(f'{path}', f'is not valid YAML ({exc})', 'fix the syntax') from None
    if data is None:
        raise InputError(f'{path}', 'is empty', 'see scenes/triangle.yaml for a scene')
    try:
        return Scene(data, source=path)
    except InputError as exc:
        raise InputError(f'{path}: {exc.field}', exc.problem, exc.fix) from None
