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
Scene files: YAML describing a part, an arm, a throw, gravity and effects (docs/scenes.md).

Lengths are metres; a key ending in ``_cm`` gives the same quantity in centimetres and
``release_speed_deg`` gives degrees per second. Unknown keys are errors that list the allowed
names, so a typo never silently falls back to a default. ``effects: [...]`` names the effects
beyond the paper's base model (throwmap.effects, docs/effects.md); a scene without effects gets
the base ThrowModel itself.
"""

import dataclasses
import math
import os
import re
import stat
import warnings

import yaml

from . import effects as fx
from .accuracy import (Accuracy, BASE_KEYS, check_knob, SETTLE_RULES, SIMULATOR_KEYS,
                       SimulatorAccuracy)
from .errors import InputError
from .model import ThrowModel
from .part import MAX_VERTICES, Part

# The base model's keys; every effect adds the keys it owns (throwmap.effects, SCHEMA).
SCHEMA = {
    '': {'name', 'description', 'part', 'arm', 'throw', 'gravity', 'plate', 'contact', 'catch',
         'effects', 'noise', 'accuracy', 'sensor', 'start', 'cycle'},
    'part': {'vertices', 'vertices_cm', 'cm', 'cm_cm', 'radius_of_gyration',
             'radius_of_gyration_cm'},
    'arm': {'offset', 'offset_cm'},
    'throw': {'release_speed', 'release_speed_deg'},
    'plate': {'inclination_deg', 'g0'},
    'contact': {'mu'},
    'catch': {'settle_rule'},
    'noise': {'seed'},
    'accuracy': set(BASE_KEYS) | set(SIMULATOR_KEYS) | set(fx.knob_defaults()),
    'sensor': {'goal_edge', 'radius', 'radius_cm', 'footprint', 'footprint_cm'},
    'start': {'edge', 'R', 'R_cm'},
    'cycle': {'settle_time', 'reset_time'},     # s: the feed rate's cycle time (throwmap.design)
}
for _section, _keys in fx.owned_keys().items():
    SCHEMA[''].add(_section)
    SCHEMA.setdefault(_section, set()).update(_keys)
SECTIONS = tuple(sorted(s for s in SCHEMA if s))
REQUIRED = {'': ('name', 'part', 'arm', 'throw'), 'part': (), 'arm': (), 'throw': ()}
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
            problem = 'missing' if not present else f'given twice ({" and ".join(present)})'
            raise InputError(f'{where}.{group[0]}', problem,
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


def _plate(data):
    """
    Read gravity from ``gravity`` (in-plane, < 0) or from ``plate`` (exactly one of them).

    g = -g0 sin(inclination); the plate's pressure per unit mass is g0 cos(inclination).
    """
    if 'gravity' in data and 'plate' in data:
        raise InputError('gravity', 'given together with plate',
                         'give either gravity (in-plane, < 0) or plate: {inclination_deg, g0}, '
                         'not both')
    if 'plate' not in data:
        if 'gravity' not in data:
            raise InputError('gravity', 'missing',
                             'give gravity (in-plane, m/s^2, < 0, e.g. -9.66) or plate: '
                             '{inclination_deg: 80, g0: 9.81}')
        return data['gravity'], None
    plate = data['plate']
    incl = _unit(plate, 'inclination_deg', 'plate', [('inclination_deg', 1.0)])
    if incl is None or not 0 < incl <= 90:
        raise InputError('plate.inclination_deg', f'must be in (0, 90], got '
                         f'{plate.get("inclination_deg")!r}',
                         "give the back plate's inclination from horizontal, e.g. 80")
    g0 = _unit(plate, 'g0', 'plate', [('g0', 1.0)])
    if g0 is None:
        g0 = 9.81
    if not g0 > 0:
        raise InputError('plate.g0', f'must be > 0, got {g0!r}', 'give e.g. 9.81 (m/s^2)')
    mu = _unit(plate, 'mu', 'plate', [('mu', 1.0)])
    if mu is not None and mu < 0:
        raise InputError('plate.mu', f'must be >= 0, got {mu!r}',
                         'give the part/plate Coulomb coefficient, e.g. 0.1')
    rad = math.radians(incl)
    g_normal = 0.0 if incl == 90 else g0 * math.cos(rad)
    return -g0 * math.sin(rad), {'g_normal': g_normal, 'mu': mu, 'inclination_deg': incl,
                                 'g0': g0}


def _seed(data, seed):
    if seed is not None:
        value, field = seed, 'seed'
    else:
        value, field = data.get('noise', {}).get('seed', 0), 'noise.seed'
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise InputError(field, f'must be an integer >= 0, got {value!r}',
                         'give a seed for the random numbers, e.g. 1')
    return value


def _as_written(exc, section, spelled):
    """
    Return the Part's InputError under the key the file used (``vertices_cm``, ...).

    Part sees metres and names ``part.vertices`` / ``part.cm``; a file that gave centimetres
    gets its own key, a note that the numbers shown are converted, and a fix in its units.
    """
    field = spelled.get(exc.field)
    if not field or field == exc.field:
        return exc
    key = field.split('.', 1)[1]
    fix = exc.fix.replace(' in metres', ' in centimetres')
    if 'clockwise' in exc.problem and isinstance(section.get(key), list):
        fix = ('list the vertices counterclockwise (paper numbering), e.g. reversed: '
               f'{list(reversed(section[key]))}')
    note = ' (numbers converted to metres)' if re.search(r'\d\.\d', exc.problem) else ''
    return InputError(field, exc.problem + note, fix)


class _DuplicateKey(yaml.YAMLError):
    """A key given twice in one YAML mapping."""

    def __init__(self, key, first, second):
        self.key, self.first, self.second = key, first, second
        super().__init__(f'{key!r} given twice (lines {first} and {second})')


# Limits no scene reaches (triangle.yaml: 600 bytes, 4 levels, no aliases, 40 values), checked
# while the file is read, before any work on its contents: a file past them is not a scene.
MAX_SCENE_BYTES = 1 << 18
MAX_DEPTH = 20                  # nested mappings/lists
MAX_ALIASES = 100               # *name references
MAX_VALUES = 20_000             # scalars, lists and mappings, every alias expanded


class _LimitExceeded(yaml.YAMLError):
    """The YAML document passes one of the limits above."""

    def __init__(self, problem, fix, mark):
        self.problem, self.fix = problem, fix
        self.line = mark.line + 1 if mark is not None else None
        super().__init__(problem)


class _StrictLoader(yaml.SafeLoader):
    """
    yaml.SafeLoader that refuses a key given twice in one mapping (PyYAML keeps the last).

    It also enforces the limits above as it composes the document (so a "billion laughs" file
    stops after MAX_VALUES values, not after gigabytes, and deep nesting never reaches Python's
    recursion limit), and reads floats as YAML 1.2 does (1e308, 1E-3: YAML 1.1 wants a dot and a
    signed exponent and would give the strings '1e308', '1E-3').
    """

    def __init__(self, stream):
        super().__init__(stream)
        self._depth = 0
        self._aliases = 0
        self._values = 0
        self._anchor_values = {}        # anchor -> values in its node, aliases expanded

    def _count(self, values, mark):
        self._values += values
        if self._values > MAX_VALUES:
            raise _LimitExceeded(
                f'holds more than {MAX_VALUES} values (aliases expanded)',
                f'a scene has a few hundred and a part outline at most {MAX_VERTICES} points; '
                'shorten the outline, and do not alias big lists again and again', mark)

    def compose_node(self, parent, index):
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                raise _LimitExceeded(f'uses more than {MAX_ALIASES} aliases (*name)',
                                     'write the values out', event.start_mark)
            if event.anchor in self.anchors and event.anchor not in self._anchor_values:
                raise _LimitExceeded(f'alias *{event.anchor} refers to the node that contains '
                                     'it (a value that holds itself)',
                                     'write the value out', event.start_mark)
            self._count(self._anchor_values.get(event.anchor, 0), event.start_mark)
            return super().compose_node(parent, index)
        self._depth += 1
        if self._depth > MAX_DEPTH:
            raise _LimitExceeded(f'nests lists/mappings more than {MAX_DEPTH} levels deep',
                                 'a scene needs 4 or 5 levels; check the brackets',
                                 event.start_mark)
        before = self._values
        self._count(1, event.start_mark)
        node = super().compose_node(parent, index)
        self._depth -= 1
        if event.anchor is not None:
            self._anchor_values[event.anchor] = self._values - before
        return node


def _mapping_without_repeats(loader, node, deep=False):
    seen = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        try:
            hash(key)
        except TypeError:
            continue                    # construct_mapping reports unhashable keys itself
        line = key_node.start_mark.line + 1
        if key in seen:
            raise _DuplicateKey(key, seen[key], line)
        seen[key] = line
    return loader.construct_mapping(node, deep=deep)


_StrictLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG,
                              _mapping_without_repeats)
# YAML 1.2 core-schema floats that YAML 1.1's pattern misses (no dot, or an unsigned exponent);
# the 1.1 pattern is tried first, a real string ('1e3x', 'e5') still matches neither.
_StrictLoader.add_implicit_resolver(
    'tag:yaml.org,2002:float',
    re.compile(r'^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$'),
    list('-+0123456789.'))


_FILE_KINDS = ((stat.S_ISDIR, 'a directory'), (stat.S_ISFIFO, 'a FIFO (named pipe)'),
               (stat.S_ISCHR, 'a character device'), (stat.S_ISBLK, 'a block device'),
               (stat.S_ISSOCK, 'a socket'))


def _check_regular(path, mode, what):
    """Raise InputError naming what ``path`` is when it is not a regular file."""
    if stat.S_ISREG(mode):
        return
    kind = next((name for test, name in _FILE_KINDS if test(mode)), 'not a regular file')
    raise InputError(what, f'{path} is {kind}, not a regular file',
                     'give the path of a scene YAML file (e.g. scenes/triangle.yaml)')


def read_yaml(path, what='scene'):
    """
    Read a YAML file as the scene loader does: strict (no repeated keys), within the limits.

    Every entry point (CLI, nodes, API, benches) reads scene YAML through here, so every user
    meets the same limits; errors are InputErrors naming the file, the limit and the fix.
    """
    if not os.path.exists(path):
        raise InputError(what, f'no such file: {path}',
                         'give the path of a scene YAML (e.g. scenes/triangle.yaml)')
    try:
        # Refused before opening: opening a FIFO blocks until a writer comes, and opening a
        # device can act on it (a serial port resets its board).
        _check_regular(path, os.stat(path).st_mode, what)
        # O_NONBLOCK: should the path become a FIFO after that check, the open cannot block;
        # fstat then refuses it.
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, 'O_CLOEXEC', 0))
        with os.fdopen(fd, 'rb') as fh:
            _check_regular(path, os.fstat(fh.fileno()).st_mode, what)
            raw = fh.read(MAX_SCENE_BYTES + 1)     # a huge file is not read whole
    except OSError as exc:
        raise InputError(f'{path}', f'cannot be read ({exc.strerror})',
                         'check the path and its permissions') from None
    if len(raw) > MAX_SCENE_BYTES:
        raise InputError(f'{path}', f'is larger than {MAX_SCENE_BYTES} bytes, the limit (a '
                         'scene is a few KB)', 'give a scene file; a part outline has at most '
                         f'{MAX_VERTICES} points')
    try:
        return yaml.load(raw.decode('utf-8'), Loader=_StrictLoader)
    except _LimitExceeded as exc:
        at = f' (line {exc.line})' if exc.line else ''
        raise InputError(f'{path}', f'{exc.problem}{at}; the limit is there because no scene '
                         'comes near it', exc.fix) from None
    except _DuplicateKey as exc:
        raise InputError(f'{path}', f'gives {exc.key!r} twice in one mapping (lines '
                         f'{exc.first} and {exc.second}); YAML would keep the last silently',
                         'keep one of them') from None
    except yaml.YAMLError as exc:
        raise InputError(f'{path}', f'is not valid YAML ({exc})', 'fix the syntax') from None
    except UnicodeDecodeError as exc:
        raise InputError(f'{path}', f'is not UTF-8 text (byte {exc.start}: {exc.reason})',
                         'save the scene as UTF-8 YAML') from None
    except ValueError as exc:   # a scalar Python refuses to convert, e.g. a 5000-digit integer
        raise InputError(f'{path}', f'holds a value that cannot be converted ({exc})',
                         'give ordinary numbers') from None


class Scene:
    """
    A validated scene: the part, the throw-map model and the sensor/start settings.

    ``seed`` overrides ``noise.seed`` (the CLI's --seed). ``model`` is the scene's ThrowModel:
    its effects composed into the one throw kernel (none: the paper's base model).
    """

    def __init__(self, data, source='<scene>', seed=None):
        self.source = source
        _check_keys('', data, '')
        for section in SECTIONS:
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
        rho = _unit(pd, 'radius_of_gyration', 'part',
                    [('radius_of_gyration', 1.0), ('radius_of_gyration_cm', 0.01)])
        if rho is not None and rho <= 0:
            key = 'radius_of_gyration' if 'radius_of_gyration' in pd else 'radius_of_gyration_cm'
            raise InputError(f'part.{key}', f'must be > 0, got {pd[key]!r}',
                             'give rho = sqrt(I_cm / m), or omit it for a uniform lamina')
        try:
            self.part = Part(vertices, cm=cm, radius_of_gyration=rho, field='part')
        except InputError as exc:
            raise _as_written(exc, pd, {'part.vertices': vfield, 'part.cm': cm_field}) from None
        h = _unit(data['arm'], 'offset', 'arm', [('offset', 1.0), ('offset_cm', 0.01)])
        w = _unit(data['throw'], 'release_speed', 'throw',
                  [('release_speed', 1.0), ('release_speed_deg', math.pi / 180.0)])
        if 'release_speed_deg' in data['throw'] and w <= 0:
            raise InputError('throw.release_speed_deg',
                             f'must be > 0 deg/s, got {data["throw"]["release_speed_deg"]!r}',
                             'give the arm speed at release, e.g. 320')
        g, self.plate = _plate(data)
        mu = data.get('contact', {}).get('mu')
        rule = data.get('catch', {}).get('settle_rule', 'full')
        if rule not in SETTLE_RULES:
            raise InputError('catch.settle_rule', f'unknown rule {rule!r}',
                             f'use one of {", ".join(SETTLE_RULES)}')
        acc = data.get('accuracy', {})
        accuracy = Accuracy(**{k: v for k, v in acc.items() if k in BASE_KEYS})
        simulator = SimulatorAccuracy(**{k: v for k, v in acc.items() if k in SIMULATOR_KEYS})
        defaults = fx.knob_defaults()
        knobs = {k: check_knob(k, v, defaults[k]) for k, v in acc.items() if k in defaults}
        if 'length' in data['arm'] and 'length_cm' in data['arm']:
            raise InputError('arm.length', 'given twice (length and length_cm)',
                             'give only one of them')
        self.arm_length = _unit(data['arm'], 'length', 'arm',
                                [('length', 1.0), ('length_cm', 0.01)])
        if mu is not None:
            mu = ThrowModel._number(mu, 'contact.mu', 'the friction coefficient')
        self.effects = fx.compose(fx.parse_names(data.get('effects')),
                                  fx.SceneValues(data, self.plate, mu, self.arm_length))
        step = self.effects.flight_step()
        if step is not None and 'integrator_step' not in acc:
            simulator = dataclasses.replace(simulator, integrator_step=step)
        flight = self.effects.flight_knobs()
        if flight and not {'flight_method', 'integrator_step'} & set(acc):
            simulator = dataclasses.replace(
                simulator, **{k: v for k, v in flight.items() if k not in acc})
        self.seed = _seed(data, seed)
        self.cycle = _cycle(data)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter('always')
            self.model = ThrowModel(self.part, h, w, g, mu=mu, settle_rule=rule,
                                    accuracy=accuracy, effects=self.effects,
                                    simulator=simulator, knobs=knobs, seed=self.seed,
                                    arm_length=self.arm_length)
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
            err = self.model.domain_error(self.start_edge, 0.0)
            if err is not None and err.condition in ('edge_index', 'stable_edge'):
                raise InputError('start.edge', str(err), 'pick a stable edge')
        if self.start_edge is not None or self.start_R is not None:
            # The state default_start gives: R defaults to 1.5 R_min, the edge to the goal edge.
            err = self.model.domain_error(*self.default_start())
            if err is not None:
                raise InputError('start', str(err), 'pick a start inside the domain of f')

    @property
    def h(self):
        return self.model.h

    @property
    def stochastic(self):
        """Tell whether the scene names a random effect (seeded results)."""
        return self.effects.stochastic

    @property
    def noisy_sensor(self):
        """Tell whether the scene's sensor has a model of its own errors (sensor_noise)."""
        return any(hasattr(m, 'read_sensor') for _, m, _ in self.effects.modules())

    def sense(self, edge, R, x=None, footprint=None):
        """
        Return the sensor's reading for a part resting at (edge, R).

        The shadow test of throwmap.sensor.sees, through the scene's sensor model (sensor_noise:
        seeded false positives/negatives). x and footprint default to the scene's sensor;
        edge -1 (lost) is never seen by the geometry.
        """
        x = self.sensor_radius if x is None else x
        if x is None:
            raise InputError('sensor.radius', 'missing', 'give the sensor position, or pass x')
        footprint = self.sensor_footprint if footprint is None else footprint
        return self.model.read_sensor(edge, R, x, footprint)

    @property
    def release_speed(self):
        return self.model.w

    @property
    def gravity(self):
        return self.model.g

    def default_start(self):
        """
        Return the (edge, R) to start orbits from.

        The scene's ``start``, else the goal edge (or the first stable edge) at 1.5 x its
        R_min (mid-domain when the domain is bounded above closer than that).
        """
        edge = self.start_edge
        if edge is None:
            edge = self.goal_edge if self.goal_edge is not None else self.part.stable_edges[0]
        R = self.start_R
        if R is None:
            R = self.model.start_radius(edge)
        return int(edge), float(R)


def _cycle(data):
    """Return the ``cycle`` section (s) as given, each value checked (>= 0, finite)."""
    values = {}
    for key, value in (data.get('cycle') or {}).items():
        if (isinstance(value, bool) or not isinstance(value, (int, float))
                or not math.isfinite(value) or value < 0):
            raise InputError(f'cycle.{key}', f'must be a number of seconds >= 0, got {value!r}',
                             'give e.g. settle_time: 0.25, reset_time: 0.5 (docs/design.md)')
        values[key] = float(value)
    return values


def load_scene(path, seed=None):
    """
    Read and validate a scene file; every error names the file and the field.

    ``seed`` overrides the scene's noise.seed.
    """
    data = read_yaml(path)
    if data is None:
        raise InputError(f'{path}', 'is empty', 'see scenes/triangle.yaml for a scene')
    try:
        return Scene(data, source=path, seed=seed)
    except InputError as exc:
        raise InputError(f'{path}: {exc.field}', exc.problem, exc.fix) from None
