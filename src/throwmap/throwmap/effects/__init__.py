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
Effects beyond the paper's base model: the registry, and the interface an effect implements.

A scene lists the effects it calls for (``effects: [backplate_friction, finite_arm]``). Each
effect is one module of this package that owns its scene keys, its parsing and its physics
(docs/effects.md, "How to add an effect"). Module attributes:

``NAME``
    the name scenes use.
``SCHEMA``
    ``{section: (keys, ...)}``: the scene keys it owns. They are errors in a scene that does
    not name the effect; a section that only an effect has (``air``) is added to the schema.
``KNOBS``
    ``{name: default}``: accuracy knobs it adds (an int default: an integer >= 1, else a number
    > 0).
``parse(scene)``
    its parameters from a ``SceneValues``; errors name the field and the fix.
``slots(params)``
    the compiled hooks it fills with these parameters (none: the effect is the identity at
    these parameters, and no code of it is compiled). A slot is filled by a compiled function
    of the module with the slot's name: ``perturb``, ``release``, ``check``,
    ``closed_motion`` (throwmap.pipeline; the last is the flight and catch when no effect
    needs the event simulator), ``body_force``, ``contact_load``, ``static_hold``, ``impact``
    (throwmap.event_sim). ``SLOT_TABLE`` declares each one's arguments and results.
``bundle(params, part, knobs)``
    the named tuple of compiled parameters its hooks receive as ``prm``.

Optional, at the Python level: ``FLIGHT_STEP`` (s: the rk4 flight step its body force needs;
a scene whose body forces all declare one takes the smallest as ``integrator_step`` unless it
sets that knob), ``FLIGHT_KNOBS`` (a dict of the flight knobs its body force is best
integrated with, flight_method among them: a scene that names neither flight_method nor
integrator_step takes those of them it does not name; the first such effect in REGISTRY's
order wins), ``contact_law(params)`` (friction, pivot model and
whether the impact law is sticking, for the event simulator), ``STOCHASTIC = True`` (noise:
nominal models leave it out), ``read_sensor(seen, rng, params)``, ``domain(model, params)`` /
``domain_error(model, params, edge, R)`` / ``domain_note(model, params)`` (an effect that moves
the lower end of the domain of f), ``lost_reason(rows, R, params)``.

Registering an effect is one line in ``REGISTRY``. Its order is the order of the effects'
checks (the first check that changes a throw's status decides) and of summed forces.
"""

from collections import namedtuple
from dataclasses import dataclass, field
import importlib

from ._common import SceneValues
from ..errors import InputError

REGISTRY = (
    'backplate_friction',
    'air_drag',
    'finite_carry',
    'impact_restitution',
    'liftoff',
    'rolling_resistance',
    'finite_arm',
    'release_noise',
    'sensor_noise',
)
MODULES = {name: importlib.import_module(f'{__name__}.{name}') for name in REGISTRY}
NAMES = tuple(MODULES)
# The one table of hooks: slot -> how its compiled function is called (its arguments), what it
# returns, how the hooks of several effects combine, the default when no effect fills it (a
# compiled function of throwmap.pipeline or throwmap.event_sim), and whether it needs the event
# simulator (its event slots are event_sim.build's parameters, in this order). throwmap.compose
# writes the generated module from it; test_structure.py checks every effect's hooks against it.
Slot = namedtuple('Slot', ['signature', 'returns', 'combine', 'default', 'event'])
SLOT_TABLE = {
    'perturb': Slot('w, h, z0, z1, prm', 'w, h', 'chain_wh', 'pipeline.no_perturbation', False),
    'release': Slot('edge, R, w, h, ctx, prm', 'status, x0, y0, phi0, vx, vy, om', 'one',
                    'pipeline.impulsive_release', False),
    'body_force': Slot('vx, vy, om, phi, edge, prm', 'fx, fy, tq', 'sum', 'event_sim.no_force',
                       True),
    'contact_load': Slot('phase, n, vslip, om, phi, edge, prm', 'ft, tq', 'sum',
                         'event_sim.no_contact_load', True),
    'static_hold': Slot('phi, om, turned, size, pu, pv, g, edge, prm', 'held, turn',
                        'first_held', 'event_sim.no_hold', True),
    'impact': Slot('rx, ry, vx, vy, om, rho2, prm', 'vx, vy, om, bounces', 'one',
                   'event_sim.sticking_law', True),
    'check': Slot('outcome, release, edge, ctx, prm', 'status', 'first_change',
                  'pipeline.no_check', False),
    'closed_motion': Slot('edge, x0, y0, phi0, vx, vy, om, ctx, prm, rec', 'outcome', 'one',
                          'pipeline.closed_motion', False),
}
SLOTS = tuple(SLOT_TABLE)
EVENT_SLOTS = tuple(name for name, slot in SLOT_TABLE.items() if slot.event)


def event_simulated(filled):
    """
    Tell whether a throw with these filled slots runs in the event simulator.

    Every event slot needs it (a force, a contact load, a static hold), except an impact law
    whose effect set brings its own closed-form motion (liftoff: its impact law is for the
    event simulator it runs itself, and for the whole throw when a force needs the simulator).
    """
    filled = set(filled)
    return bool(filled & (set(EVENT_SLOTS) - {'impact'})) or (
        'impact' in filled and 'closed_motion' not in filled)


def owned_keys():
    """Return {section: {key: effect}} for every scene key an effect owns."""
    owned = {}
    for name, module in MODULES.items():
        for section, keys in module.SCHEMA.items():
            for key in keys:
                owned.setdefault(section, {})[key] = name
    return owned


def knob_defaults():
    """Return {knob: default} of every effect's accuracy knobs."""
    knobs = {}
    for module in MODULES.values():
        knobs.update(module.KNOBS)
    return knobs


@dataclass(frozen=True)
class EffectSet:
    """The effects a scene calls for (in registry order) with their parameters."""

    names: tuple = ()
    params: dict = field(default_factory=dict, compare=False)

    def __bool__(self):
        return bool(self.names)

    def __contains__(self, name):
        return name in self.names

    def get(self, name):
        """Return the parameters of effect ``name``, None when the scene does not name it."""
        return self.params.get(name)

    def modules(self):
        """Return (name, module, params) of each named effect, in registry order."""
        return [(n, MODULES[n], self.params[n]) for n in self.names]

    def slots(self):
        """Return {effect name: slots it fills}, effects that fill none left out."""
        out = {}
        for name, module, params in self.modules():
            filled = tuple(module.slots(params))
            unknown = set(filled) - set(SLOTS)
            if unknown:   # pragma: no cover - a programming error in an effect module
                raise ValueError(f'effect {name} fills unknown slots {sorted(unknown)}')
            if filled:
                out[name] = filled
        return out

    @property
    def general(self):
        """Tell whether flight or the catch needs the event simulator (a force or impact law)."""
        return any(set(s) & set(EVENT_SLOTS) for s in self.slots().values()) or any(
            hasattr(m, 'contact_law') for _, m, _ in self.modules())

    def flight_step(self):
        """
        Return the rk4 flight step the body forces need (the smallest they declare), or None.

        None where no effect fills body_force or one of them declares no FLIGHT_STEP: then
        the knob's own default holds.
        """
        steps = [getattr(MODULES[name], 'FLIGHT_STEP', None)
                 for name, filled in self.slots().items() if 'body_force' in filled]
        if not steps or None in steps:
            return None
        return min(steps)

    def flight_knobs(self):
        """Return the flight knobs the first body force that declares FLIGHT_KNOBS needs, or {}."""
        for name, filled in self.slots().items():
            if 'body_force' in filled and hasattr(MODULES[name], 'FLIGHT_KNOBS'):
                return dict(MODULES[name].FLIGHT_KNOBS)
        return {}

    @property
    def stochastic(self):
        """Tell whether an effect is random (release_noise, sensor_noise)."""
        return any(getattr(m, 'STOCHASTIC', False) for _, m, _ in self.modules())

    def without_noise(self):
        """Return the same set without its random effects."""
        names = tuple(n for n in self.names if not getattr(MODULES[n], 'STOCHASTIC', False))
        return EffectSet(names, {n: self.params[n] for n in names})


def parse_names(value):
    """Validate the scene's ``effects`` list (known names, each once); registry order."""
    if value is None:
        return ()
    if not isinstance(value, list):
        raise InputError('effects', f'must be a list of effect names, got {value!r}',
                         f'write effects: [name, ...] with names from {", ".join(NAMES)}')
    seen = []
    for k, name in enumerate(value):
        if not isinstance(name, str) or name not in MODULES:
            raise InputError(f'effects[{k}]', f'unknown effect {name!r}',
                             f'allowed effects: {", ".join(NAMES)}')
        if name in seen:
            raise InputError(f'effects[{k}]', f'{name} is listed twice', 'list it once')
        seen.append(name)
    return tuple(n for n in NAMES if n in seen)


def compose(names, scene):
    """
    Build the EffectSet of the named effects from the scene's values (a SceneValues).

    A key owned by an effect the scene does not name is an error: nothing is silently ignored.
    """
    for section, keys in owned_keys().items():
        given = scene.data.get(section)
        if not isinstance(given, dict):
            continue
        for key, effect in keys.items():
            if effect not in names and key in given:
                raise InputError(f'{section}.{key}', f'is a parameter of effect {effect}, which '
                                 'the scene does not name',
                                 f'add {effect} to effects, or remove {section}.{key}')
    return EffectSet(tuple(names), {n: MODULES[n].parse(scene) for n in names})


__all__ = ['compose', 'EffectSet', 'event_simulated', 'EVENT_SLOTS', 'knob_defaults', 'MODULES',
           'NAMES', 'owned_keys', 'parse_names', 'REGISTRY', 'SceneValues', 'SLOT_TABLE', 'SLOTS']
