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
[R + u_min, R + u_max] overlaps [x - footprint, x + footprint] (as without noise); a reading is
then wrong with probability sensor.false_negative (a part in view is missed) and, when the
part is not in view, fires with probability sensor.false_positive. Readings use the
scene's seeded Generator. The sensor guarantee becomes P(goal edge | detection), estimated by
Monte Carlo over noisy orbits (throwmap.stochastic.sensor_probability). Rates 0 give the exact
sensor (tested).

Scene: sensor: {goal_edge: 1, radius_cm: 27, footprint_cm: 0.5, false_positive: 0.01,
false_negative: 0.05}; effects: [sensor_noise].
"""

from dataclasses import dataclass

from ._common import number
from ..errors import InputError

NAME = 'sensor_noise'


@dataclass(frozen=True)
class SensorNoise:
    false_positive: float
    false_negative: float


def parse(sensor):
    sensor = sensor or {}
    fp = number(sensor, 'false_positive', 'sensor', 'a probability in [0, 1]', lo=0.0, hi=1.0)
    fn = number(sensor, 'false_negative', 'sensor', 'a probability in [0, 1]', lo=0.0, hi=1.0)
    if fp is None and fn is None:
        raise InputError('sensor', 'effect sensor_noise needs false_positive and/or '
                         'false_negative', 'give e.g. sensor: {false_positive: 0.01}')
    return SensorNoise(fp or 0.0, fn or 0.0)
