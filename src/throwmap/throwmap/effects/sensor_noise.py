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
Effect sensor_noise: false positives and negatives of the one-bit sensor.

Physics: the sensor at arm coordinate x with half-width footprint sees the part when its shadow
[R + u_min, R + u_max] overlaps [x - footprint, x + footprint] (throwmap.sensor.sees); a
reading is then wrong with probability sensor.false_negative (a part in view is missed) and,
when the part is not in view, fires with probability sensor.false_positive. Readings use the
scene's seeded Generator. The sensor guarantee becomes P(goal edge | detection), estimated by
Monte Carlo over noisy orbits (throwmap.stochastic.sensor_probability). Rates 0 give the exact
sensor (tested).

A Python-level hook, ``read_sensor``; no compiled code.

Scene: sensor: {goal_edge: 1, radius_cm: 27, footprint_cm: 0.5, false_positive: 0.01,
false_negative: 0.05}; effects: [sensor_noise].
"""

from dataclasses import dataclass

import numpy as np

from ._common import number
from ..errors import InputError

NAME = 'sensor_noise'
SCHEMA = {'sensor': ('false_positive', 'false_negative')}
KNOBS = {}
STOCHASTIC = True


@dataclass(frozen=True)
class SensorNoise:
    """Parameters: the probabilities of a false positive and of a false negative."""

    false_positive: float
    false_negative: float


def parse(scene):
    """From the scene's sensor section."""
    sensor = scene.section('sensor')
    fp = number(sensor, 'false_positive', 'sensor', 'a probability in [0, 1]', lo=0.0, hi=1.0)
    fn = number(sensor, 'false_negative', 'sensor', 'a probability in [0, 1]', lo=0.0, hi=1.0)
    if fp is None and fn is None:
        raise InputError('sensor', 'effect sensor_noise needs false_positive and/or '
                         'false_negative', 'give e.g. sensor: {false_positive: 0.01}')
    return SensorNoise(fp or 0.0, fn or 0.0)


def slots(params):
    """Fill no compiled hook: the noise acts on the reading."""
    return ()


def bundle(params, part, knobs):
    """Return no compiled parameters."""
    return None


def read_sensor(seen, rng, params):
    """Return the readings of an exact sensor's bits ``seen``, with this sensor's errors."""
    u = rng.random(seen.shape)
    return np.where(seen, u >= params.false_negative, u < params.false_positive)
