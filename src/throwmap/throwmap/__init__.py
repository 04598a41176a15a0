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
throwmap: the throw map of a dynamic parts feeder (Lynch, Northrop, Pan), ROS-free.

Quick use::

    from throwmap import load_scene
    scene = load_scene('scenes/triangle.yaml')
    scene.model.f(1, 0.12)          # -> (edge', R', 'jog' | 'flip')
"""

from .dynamics import (analyse, Analysis, Basin, basin, default_grid, design_radii, limit_set,
                       limit_set_from_orbit, LimitSet, Orbit, orbit, sees, sensor_design,
                       SensorDesign)
from .effect_model import EffectModel, PartLost
from .errors import DomainError, InputError, NumericalError, ThrowmapError
from .grasp import edge_grasp, grasp_table, in_dynamic_grasp, wrench_cone_margins
from .model import Accuracy, Impact, ThrowModel, ThrowResult
from .part import Part
from .scene import load_scene, Scene

__all__ = ['Accuracy', 'analyse', 'Analysis', 'basin', 'Basin', 'default_grid', 'design_radii',
           'DomainError', 'edge_grasp', 'EffectModel', 'grasp_table', 'Impact',
           'in_dynamic_grasp', 'InputError', 'limit_set', 'limit_set_from_orbit', 'LimitSet',
           'load_scene', 'NumericalError', 'orbit', 'Orbit', 'Part', 'PartLost', 'Scene', 'sees',
           'sensor_design', 'SensorDesign', 'ThrowmapError', 'ThrowModel', 'ThrowResult',
           'wrench_cone_margins']
