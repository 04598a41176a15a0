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
tension and the foam's compression vary from throw to throw. h_k is the arm surface for that
whole throw (release and catch). The grasp bounds are evaluated at the throw's own h_k, so a
noisy throw near R_grasp can leave the domain. The throw map becomes a random map: basins
become distributions of outcomes over seeds and the sensor guarantee a probability
(throwmap.stochastic).

Hook: ``perturb``. With both sd = 0 the effect fills no hook and draws nothing: the
deterministic map bit for bit (tested).

Scene: noise: {seed: 1, release_speed_sd_deg: 5, offset_sd_cm: 0.02}; effects: [release_noise].
"""

from collections import namedtuple
from dataclasses import dataclass
import math

from ._common import number
from ..errors import InputError
from ..jit import njit

NAME = 'release_noise'
SCHEMA = {'noise': ('release_speed_sd', 'release_speed_sd_deg', 'offset_sd', 'offset_sd_cm')}
KNOBS = {}
STOCHASTIC = True

NoiseParams = namedtuple('NoiseParams', ['speed_sd', 'offset_sd'])


@dataclass(frozen=True)
class ReleaseNoise:
    """Parameters: standard deviations of the release speed and of the arm offset."""

    speed_sd: float     # rad/s
    offset_sd: float    # m


def parse(scene):
    """From the scene's noise section."""
    noise = scene.section('noise')
    sd_w = number(noise, 'release_speed_sd', 'noise', 'a standard deviation >= 0', lo=0.0,
                  scale_keys=[('release_speed_sd', 1.0),
                              ('release_speed_sd_deg', math.pi / 180.0)])
    sd_h = number(noise, 'offset_sd', 'noise', 'a standard deviation >= 0', lo=0.0,
                  scale_keys=[('offset_sd', 1.0), ('offset_sd_cm', 0.01)])
    if sd_w is None and sd_h is None:
        raise InputError('noise', 'effect release_noise needs release_speed_sd(_deg) and/or '
                         'offset_sd(_cm)', 'give e.g. noise: {release_speed_sd_deg: 5}')
    return ReleaseNoise(sd_w or 0.0, sd_h or 0.0)


def slots(params):
    """Fill perturb, unless both deviations are 0."""
    return ('perturb',) if (params.speed_sd > 0.0 or params.offset_sd > 0.0) else ()


def bundle(params, part, knobs):
    """Return the compiled parameters."""
    return NoiseParams(float(params.speed_sd), float(params.offset_sd))


@njit
def perturb(w, h, z0, z1, prm):
    """Return this throw's release speed and arm offset from two standard normal draws (hook)."""
    return w + prm.speed_sd * z0, h + prm.offset_sd * z1
