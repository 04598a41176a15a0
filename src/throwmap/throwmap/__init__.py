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

The public API is what this module exports; throwmap.internal lists the compiled pieces the
tests exercise directly. docs/physics.md, docs/effects.md and docs/numerics.md describe the
modules (layers, from the bottom: errors, status, part, grasp, ballistic, catch, event_sim,
pipeline, effects, compose, model, orbits, basins, sensor, stochastic, scene, part_on_arm,
analysis, design, robustness, search, cli). One model class, ThrowModel, serves every scene:
its effects (none: the paper's base model) are composed into the one compiled throw kernel.
"""

from .accuracy import Accuracy, SimulatorAccuracy
from .analysis import analyse, Analysis, scene_analysis, SensorDesignError
from .basins import Basin, basin, default_grid, design_radii
from .errors import DomainError, InputError, NumericalError, PartLost, ThrowmapError
from .grasp import edge_grasp, grasp_table, in_dynamic_grasp, wrench_cone_margins
from .model import Impact, ThrowModel, ThrowResult
from .orbits import limit_set, limit_set_from_orbit, LimitSet, Orbit, orbit
from .part import Part
from .part_on_arm import PartOnArm, resting_pose, Throw, wrap_angle
from .scene import load_scene, Scene
from .sensor import read_sensor, sees, sensor_design, SensorDesign
from .stochastic import (basin_distribution, sensor_probability, SensorProbability,
                         wilson_interval)

__all__ = ['Accuracy', 'analyse', 'Analysis', 'basin', 'Basin',
           'basin_distribution', 'default_grid', 'design_radii', 'DomainError', 'edge_grasp',
           'grasp_table', 'Impact', 'in_dynamic_grasp',
           'InputError', 'limit_set', 'limit_set_from_orbit',
           'LimitSet', 'load_scene', 'NumericalError', 'orbit', 'Orbit',
           'Part', 'PartLost', 'PartOnArm', 'read_sensor', 'resting_pose', 'Scene',
           'scene_analysis', 'sees', 'sensor_design', 'sensor_probability', 'SensorDesign',
           'SensorDesignError', 'SensorProbability', 'SimulatorAccuracy', 'Throw',
           'ThrowmapError', 'ThrowModel', 'ThrowResult', 'wilson_interval', 'wrap_angle',
           'wrench_cone_margins']
