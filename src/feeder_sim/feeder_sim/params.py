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
Parameter tables (ROS-free): one spec per parameter, from which the node builds descriptors.

The idea of generate_parameter_library without the tool: name, default (its type is the
parameter's type), range, read-only flag and description live in one table; docs/nodes.md
shows the same table. Checks that a range cannot express (a scene that must load, a start state
inside the domain of f) are plain functions returning the reason of a rejection, or None.
"""

from dataclasses import dataclass
import math
from typing import Optional

from throwmap import ThrowmapError


@dataclass(frozen=True)
class ParamSpec:
    """A parameter: ``default`` fixes the type (bool, int, float or str)."""

    name: str
    default: object
    description: str
    minimum: Optional[float] = None
    maximum: Optional[float] = None
    read_only: bool = False
    constraints: str = ''

    def check_range(self, value):
        """Reason why ``value`` is out of range, or None (rclpy checks this too)."""
        if self.minimum is not None and value < self.minimum:
            return f'{self.name} = {value} is below {self.minimum}'
        if self.maximum is not None and value > self.maximum:
            return f'{self.name} = {value} is above {self.maximum}'
        return None


SIM_PARAMS = (
    ParamSpec('autostart', True, 'configure and activate at start-up (the pip install of ROS 2 '
              'has no ros2 lifecycle CLI); false: wait for ~/change_state', read_only=True),
    ParamSpec('scene', '', 'scene YAML (throwmap format, e.g. scenes/triangle.yaml); must load',
              read_only=True, constraints='a file throwmap.load_scene accepts'),
    ParamSpec('hardware_mode', False, 'true: stand in for the driver (services ~/trigger_cycle, '
              '~/enable; topics proximity, cycle_status, joint_states) with sensor bits from '
              "the prediction; false: follow the driver's cycle_status", read_only=True),
    ParamSpec('start_edge', 0, 'edge the part rests on before the first throw (default: the '
              "scene's start); setting it (or start_radius) restarts the prediction there",
              minimum=0, maximum=1023,
              constraints='a stable edge; (start_edge, start_radius) in the domain of f'),
    ParamSpec('start_radius', 0.0, "R before the first throw, m (default: the scene's start)",
              minimum=0.0, maximum=10.0,
              constraints='(start_edge, start_radius) in the domain of f'),
    ParamSpec('sensor_radius', 0.0, 'arm coordinate x of the proximity sensor, m; 0: the '
              "analysis's choice (throwmap sensor design)", minimum=0.0, maximum=10.0),
    ParamSpec('seed', -1, "seed of the scene's random effects (release_noise, sensor_noise) for "
              "the throws and readings of hardware mode; -1: the scene's noise.seed",
              minimum=-1, maximum=2 ** 31 - 1, read_only=True),
    ParamSpec('sensor_range_m', 0.02, 'hardware mode: fixed distance of the proximity ranger, '
              "m (Range.min_range = max_range), as the driver's parameter", minimum=0.001,
              maximum=10.0),
    ParamSpec('cycle_period', 1.0, 'hardware mode: seconds between cycles while enabled',
              minimum=0.005, maximum=60.0),
    ParamSpec('markers_period', 0.1, 'at most one markers message per this many seconds (the '
              'last state always follows within it); 0: one after every throw', minimum=0.0,
              maximum=10.0),
    ParamSpec('diagnostics_period', 1.0, 'seconds between /diagnostics messages', minimum=0.1,
              maximum=60.0, read_only=True),
)


def check_scene(path, loader):
    """Reason why the scene at ``path`` is unusable (``loader`` raises ThrowmapError), or None."""
    if not path:
        return ('scene: not set; give the path of a scene YAML, e.g. '
                '--ros-args -p scene:=scenes/triangle.yaml')
    try:
        loader(path)
    except ThrowmapError as exc:
        return f'scene: {exc}'
    except OSError as exc:      # unreadable file: permissions, a directory, ...
        return f'scene: cannot read {path}: {exc}'
    return None


def check_changes(specs, changes, loader):
    """
    Reason to reject a parameter set, or None: ranges of the table and a scene that must load.

    ``specs`` maps names to ParamSpecs (names not in it are not checked); ``changes`` maps
    names to new values; ``loader`` loads a scene (see :func:`check_scene`).
    """
    for name, value in changes.items():
        spec = specs.get(name)
        if spec is None:
            continue
        if not isinstance(value, (bool, str)):
            reason = spec.check_range(value)
            if reason:
                return reason
        if name == 'scene':
            reason = check_scene(value, loader)
            if reason:
                return reason
    return None


def check_start(model, edge, R):
    """Reason why (edge, R) cannot be the start state, or None."""
    if not (isinstance(R, (int, float)) and math.isfinite(R)):
        return f'start_radius must be a finite number, got {R!r}'
    arm = getattr(model, 'arm_length', math.inf)
    if R > arm:
        return (f"start state (edge {edge}, R {R} m) rejected: R is beyond the arm's end "
                f'({arm:g} m; scene arm.length)')
    err = model.domain_error(int(edge), float(R))
    if err is not None:
        return (f'start state (edge {edge}, R {R} m) rejected: {err} (to change edge and '
                'radius together, set both in one atomic call)')
    return None
