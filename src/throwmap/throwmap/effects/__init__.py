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
Effects beyond the paper's base model, each a module of its own (docs/effects.md).

A scene lists the effects it calls for (``effects: [backplate_friction, finite_arm]``); their
parameters live in the scene's natural sections (plate, contact, throw.carry, arm, noise,
sensor). compose() validates the list, reads each named effect's parameters and rejects
parameters of effects that are not named, so nothing is silently ignored. Only named effects
are computed; with none, the scene's model is the base ThrowModel itself (bit-identical, same
speed).
"""

from dataclasses import dataclass
from typing import Optional

from . import (backplate_friction, finite_arm, finite_carry, impact_restitution, release_noise,
               sensor_noise)
from .backplate_friction import BackplateFriction
from .finite_arm import FiniteArm
from .finite_carry import FiniteCarry
from .impact_restitution import ImpactRestitution
from .release_noise import ReleaseNoise
from .sensor_noise import SensorNoise
from ..errors import InputError

MODULES = {m.NAME: m for m in (backplate_friction, finite_carry, impact_restitution, finite_arm,
                               release_noise, sensor_noise)}
NAMES = tuple(MODULES)


@dataclass(frozen=True)
class EffectSet:
    """The effects a scene calls for, with their parameters (None: not named)."""

    names: tuple = ()
    backplate: Optional[BackplateFriction] = None
    restitution: Optional[ImpactRestitution] = None
    carry: Optional[FiniteCarry] = None
    arm: Optional[FiniteArm] = None
    release_noise: Optional[ReleaseNoise] = None
    sensor_noise: Optional[SensorNoise] = None

    @property
    def general(self):
        """Tell whether flight or the catch is no longer closed form (throwmap.general)."""
        return self.backplate is not None or self.restitution is not None

    @property
    def stochastic(self):
        return self.release_noise is not None or self.sensor_noise is not None

    def __bool__(self):
        return bool(self.names)


def parse_names(value):
    """Validate the scene's ``effects`` list: known names, each once."""
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
    return tuple(seen)


# Parameters that belong to one effect: giving them without naming it is an error.
OWNED = {
    'backplate_friction': [('plate', 'mu')],
    'impact_restitution': [('contact', 'restitution'), ('contact', 'bounce_threshold'),
                           ('contact', 'pivot')],
    'finite_carry': [('throw', 'carry')],
    'finite_arm': [('arm', 'length'), ('arm', 'length_cm')],
    'release_noise': [('noise', 'release_speed_sd'), ('noise', 'release_speed_sd_deg'),
                      ('noise', 'offset_sd'), ('noise', 'offset_sd_cm')],
    'sensor_noise': [('sensor', 'false_positive'), ('sensor', 'false_negative')],
}


def compose(names, data, plate, arm_length, mu):
    """
    Build the EffectSet of the named effects.

    data: the raw scene mapping; plate: the parsed plate section (dict with g_normal, mu) or
    None; arm_length in m or None; mu: contact.mu or None.
    """
    for effect, keys in OWNED.items():
        if effect in names:
            continue
        for section, key in keys:
            if isinstance(data.get(section), dict) and key in data[section]:
                raise InputError(f'{section}.{key}', f'is a parameter of effect {effect}, which '
                                 'the scene does not name',
                                 f'add {effect} to effects, or remove {section}.{key}')
    kw = {'names': tuple(names)}
    if 'backplate_friction' in names:
        kw['backplate'] = backplate_friction.parse(plate)
    if 'impact_restitution' in names:
        kw['restitution'] = impact_restitution.parse(data.get('contact'))
    if 'finite_carry' in names:
        kw['carry'] = finite_carry.parse(data.get('throw', {}).get('carry'), mu)
    if 'finite_arm' in names:
        kw['arm'] = finite_arm.parse(arm_length)
    if 'release_noise' in names:
        kw['release_noise'] = release_noise.parse(data.get('noise'))
    if 'sensor_noise' in names:
        kw['sensor_noise'] = sensor_noise.parse(data.get('sensor'))
    return EffectSet(**kw)


__all__ = ['BackplateFriction', 'compose', 'EffectSet', 'FiniteArm', 'FiniteCarry',
           'ImpactRestitution', 'MODULES', 'NAMES', 'parse_names', 'ReleaseNoise',
           'SensorNoise']
