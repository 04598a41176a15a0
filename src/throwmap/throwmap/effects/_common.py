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

"""Helpers shared by the effect modules: the scene's values, number parsing with clear errors."""

from dataclasses import dataclass
import math
from typing import Optional

from ..errors import InputError


@dataclass(frozen=True)
class SceneValues:
    """
    What an effect's ``parse`` reads: the raw scene mapping and the values the scene parsed.

    data: the scene's mapping as loaded; plate: the parsed plate section (g0, inclination_deg,
    g_normal = g0 cos(inclination), mu) or None; mu: contact.mu or None; arm_length: arm.length
    in m or None.
    """

    data: dict
    plate: Optional[dict] = None
    mu: Optional[float] = None
    arm_length: Optional[float] = None

    def section(self, name):
        """Return the scene's section ``name`` (an empty mapping when absent)."""
        value = self.data.get(name)
        return value if isinstance(value, dict) else {}


def number(data, key, where, what, lo=None, hi=None, lo_open=False, default=None,
           scale_keys=None):
    """
    Return a finite number from ``data`` in SI, from ``key`` or one of its unit spellings.

    scale_keys: [(spelled_key, factor), ...]; the first present wins and two present is an
    error. Bounds are checked on the SI value; the error names the key as written.
    """
    spellings = scale_keys or [(key, 1.0)]
    present = [(k, f) for k, f in spellings if k in data]
    if len(present) > 1:
        raise InputError(f'{where}.{present[0][0]}',
                         f'given twice ({" and ".join(k for k, _ in present)})',
                         'give only one of them')
    if not present:
        if default is None:
            return None
        return default
    spelled, factor = present[0]
    value = data[spelled]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f'{where}.{spelled}', f'must be a number, got {value!r}', f'give {what}')
    if not math.isfinite(value):
        raise InputError(f'{where}.{spelled}', f'must be finite, got {value!r}', f'give {what}')
    si = float(value) * factor
    if lo is not None and (si < lo or (lo_open and si == lo)):
        raise InputError(f'{where}.{spelled}', f'must be {">" if lo_open else ">="} '
                         f'{lo / factor:g}, got {value!r}', f'give {what}')
    if hi is not None and si > hi:
        raise InputError(f'{where}.{spelled}', f'must be <= {hi / factor:g}, got {value!r}',
                         f'give {what}')
    return si


def check_keys(data, allowed, where):
    if not isinstance(data, dict):
        raise InputError(where, f'must be a mapping, got {type(data).__name__}',
                         'write it as key: value pairs')
    for key in data:
        if key not in allowed:
            raise InputError(f'{where}.{key}', 'unknown key',
                             f'allowed here: {", ".join(sorted(allowed))}')
