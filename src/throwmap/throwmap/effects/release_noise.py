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
Effect release_noise: seeded random release speed and offset per throw.

Physics: every throw draws w_k = w + sd_w z1 and h_k = h + sd_h z2 with z1, z2 standard
normal from a numpy Generator seeded by noise.seed (or the CLI's --seed): the spring's
tension and the foam's compression vary from throw to throw. ``distribution: uniform`` bounds
the errors instead: w_k = w + dw u1, h_k = h + dh u2 with u = erf(z / sqrt 2) uniform in
[-1, 1] (the same normal draws mapped through their distribution function), every throw within
+-dw, +-dh: the bounded nondeterminism of docs/design.md section 3. ``distribution: corner``
puts every throw on a corner of that box (u = sign z, each corner equally likely), the throws
of the robustness brute force. Both map a zero draw to zero: ``model.nominal()`` (zero draws)
is the noise-free map. h_k is the arm surface for that
whole throw (release and catch). The grasp bounds are evaluated at the throw's own h_k, so a
noisy throw near R_grasp can leave the domain. The throw map becomes a random map: basins
become distributions of outcomes over seeds and the sensor guarantee a probability
(throwmap.stochastic).

Hook: ``perturb``. With both sd (or both bounds) = 0 the effect fills no hook and draws
nothing: the deterministic map bit for bit (tested).

Scene: noise: {seed: 1, release_speed_sd_deg: 5, offset_sd_cm: 0.02}, or noise: {distribution:
uniform, release_speed_bound_deg: 1.2, offset_bound_cm: 0.05}; effects: [release_noise].
``release_speed_sd_rel`` / ``release_speed_bound_rel`` (a fraction of the throw's own w, added
to the absolute part) give the design search's error box w +- s w at every speed, for a
policy that changes the speed per throw (docs/funnel.md).
"""

from collections import namedtuple
from dataclasses import dataclass
import math

from ._common import number
from ..errors import InputError
from ..jit import njit

NAME = 'release_noise'
SCHEMA = {'noise': ('distribution', 'release_speed_sd', 'release_speed_sd_deg',
                    'release_speed_sd_rel', 'offset_sd', 'offset_sd_cm', 'release_speed_bound',
                    'release_speed_bound_deg', 'release_speed_bound_rel', 'offset_bound',
                    'offset_bound_cm')}
KNOBS = {}
STOCHASTIC = True

# distribution -> the code the compiled hook branches on
DISTRIBUTIONS = {'normal': 0, 'uniform': 1, 'corner': 2}
_SD_KEYS = ('release_speed_sd', 'release_speed_sd_deg', 'release_speed_sd_rel', 'offset_sd',
            'offset_sd_cm')
_BOUND_KEYS = ('release_speed_bound', 'release_speed_bound_deg', 'release_speed_bound_rel',
               'offset_bound', 'offset_bound_cm')

NoiseParams = namedtuple('NoiseParams', ['speed_sd', 'offset_sd', 'kind', 'speed_rel'])


@dataclass(frozen=True)
class ReleaseNoise:
    """
    Parameters: the distribution and the scale of the release speed's and offset's errors.

    speed_sd and offset_sd are standard deviations (normal) or the bounds dw, dh (uniform,
    corner); speed_rel adds a part proportional to the throw's speed (dw = speed_sd +
    speed_rel w): the design search's error box (w +- s w) at every speed a policy throws.
    """

    speed_sd: float     # rad/s
    offset_sd: float    # m
    distribution: str = 'normal'
    speed_rel: float = 0.0  # per unit of w


def parse(scene):
    """From the scene's noise section."""
    noise = scene.section('noise')
    dist = noise.get('distribution', 'normal')
    if dist not in DISTRIBUTIONS:
        raise InputError('noise.distribution', f'unknown distribution {dist!r}',
                         f'give one of {", ".join(DISTRIBUTIONS)}')
    bounded = dist != 'normal'
    scale, wrong = ('bound', _SD_KEYS) if bounded else ('sd', _BOUND_KEYS)
    what = 'a bound >= 0' if bounded else 'a standard deviation >= 0'
    for key in wrong:
        if key in noise:
            raise InputError(f'noise.{key}', f'does not apply to distribution {dist}',
                             'give release_speed_bound(_deg) / offset_bound(_cm) with '
                             'distribution uniform or corner, release_speed_sd(_deg) / '
                             'offset_sd(_cm) with distribution normal (the default)')
    d_w = number(noise, f'release_speed_{scale}', 'noise', what, lo=0.0,
                 scale_keys=[(f'release_speed_{scale}', 1.0),
                             (f'release_speed_{scale}_deg', math.pi / 180.0)])
    d_h = number(noise, f'offset_{scale}', 'noise', what, lo=0.0,
                 scale_keys=[(f'offset_{scale}', 1.0), (f'offset_{scale}_cm', 0.01)])
    rel_key = f'release_speed_{scale}_rel'
    d_rel = number(noise, rel_key, 'noise', f'{what} (a fraction of the release speed)',
                   lo=0.0, scale_keys=[(rel_key, 1.0)])
    if d_rel is not None and d_rel >= 1.0:
        raise InputError(f'noise.{rel_key}', f'must be below 1 (a fraction of the release '
                         f'speed), got {d_rel!r}', 'give e.g. 0.005 for +-0.5 %')
    if d_w is None and d_h is None and d_rel is None:
        raise InputError('noise', f'effect release_noise needs release_speed_{scale}(_deg or '
                         f'_rel) and/or offset_{scale}(_cm)',
                         f'give e.g. noise: {{release_speed_{scale}_deg: 5}}')
    return ReleaseNoise(d_w or 0.0, d_h or 0.0, dist, d_rel or 0.0)


def slots(params):
    """Fill perturb, unless every deviation (bound) is 0."""
    return ('perturb',) if (params.speed_sd > 0.0 or params.offset_sd > 0.0
                            or params.speed_rel > 0.0) else ()


def bundle(params, part, knobs):
    """Return the compiled parameters."""
    return NoiseParams(float(params.speed_sd), float(params.offset_sd),
                       DISTRIBUTIONS[params.distribution], float(params.speed_rel))


@njit
def perturb(w, h, z0, z1, prm):
    """Return this throw's release speed and arm offset from two standard normal draws (hook)."""
    if prm.kind == 1:       # uniform in [-1, 1]: 2 Phi(z) - 1
        z0 = math.erf(z0 / math.sqrt(2.0))
        z1 = math.erf(z1 / math.sqrt(2.0))
    elif prm.kind == 2:     # a corner of the box; a zero draw (model.nominal()) stays nominal
        z0 = 1.0 if z0 > 0.0 else (-1.0 if z0 < 0.0 else 0.0)
        z1 = 1.0 if z1 > 0.0 else (-1.0 if z1 < 0.0 else 0.0)
    return w + (prm.speed_sd + prm.speed_rel * w) * z0, h + prm.offset_sd * z1
