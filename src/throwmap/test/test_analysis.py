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

"""The analysis the nodes share (throwmap.analysis): a moved sensor redoes the sensor design."""

import math

import pytest
from throwmap import analyse, scene_analysis, SensorDesignError


@pytest.fixture(scope='module')
def triangle_analysis(triangle_scene):
    return analyse(triangle_scene)


def test_moving_the_sensor_redoes_the_sensor_design(triangle_scene, triangle_analysis):
    base = triangle_analysis
    same = scene_analysis(triangle_scene, 0.0, base)
    assert same is base
    near = scene_analysis(triangle_scene, 0.20, base)
    assert near.sensor.radius == 0.20
    assert near.sensor.guarantee_radius == pytest.approx(base.sensor.guarantee_radius)
    assert near.limit_set is base.limit_set
    # Inside the guarantee radius other edges are seen: the warm-up cannot end within the grid.
    assert near.sensor.warmup_throws > base.sensor.warmup_throws
    assert near.sensor.detection_rate > base.sensor.detection_rate
    # A sensor design without a finite radius is refused with the fix.
    inf = scene_analysis(triangle_scene, 0.0, base).sensor.__class__(
        **dict(vars(base.sensor), radius=math.inf))
    with pytest.raises(SensorDesignError, match='give the sensor position'):
        scene_analysis(triangle_scene, 0.0, base.__class__(**dict(vars(base), sensor=inf)))
