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
Parameter tables of feeder_sim's two nodes (ROS-free) and the checks a range cannot express.

The spec type, the type coercion and the range checks are feeder_common's; here are the
parameters of ``standin_node`` (the hardware's stand-in) and ``predictor_node`` (the
predictor), each declaring only its own, and the checks that need the scene: a scene that
must load, a start state inside the domain of f. Each check returns the reason of a
rejection, or None.
"""

import math

from feeder_common.params import (check_link, check_scene, CYCLE_PERIOD, DIAGNOSTIC_PERIOD,
                                  FRAME_ID, JOINT_STATES_RATE, KEY_FILE, LINK_SPECS,
                                  ParamSpec, REALTIME_PRIORITY, SENSOR_RANGE, SETPOINT_SPECS)


# What both nodes take: the lifecycle, the scene, the part's start state and the sensor.
SHARED_PARAMS = (
    ParamSpec('autostart', True, 'configure and activate at start-up; false: wait for '
              '~/change_state (ros2 lifecycle set)', read_only=True),
    REALTIME_PRIORITY,
    ParamSpec('scene', '', 'scene YAML (throwmap format, e.g. scenes/triangle.yaml); must load',
              read_only=True, constraints='a file throwmap.load_scene accepts'),
    ParamSpec('start_edge', 0, 'edge the part rests on before the first throw (default: the '
              "scene's start); setting it (or start_radius) restarts the part (stand-in) or "
              'the prediction (predictor) there',
              minimum=0, maximum=1023,
              constraints='a stable edge; (start_edge, start_radius) in the domain of f'),
    ParamSpec('start_radius', 0.0, "R before the first throw, m (default: the scene's start)",
              minimum=0.0, maximum=10.0,
              constraints='(start_edge, start_radius) in the domain of f'),
    ParamSpec('sensor_radius', 0.0, 'arm coordinate x of the proximity sensor, m; 0: the '
              "analysis's choice (throwmap sensor design)", minimum=0.0, maximum=10.0),
    DIAGNOSTIC_PERIOD,
)

# standin_node: exactly the driver's interface, so it takes the driver's cycle parameters (one
# file, the driver's config/driver.yaml, serves both): sensor_range_m and frame_id of
# proximity, cycle_period, key_file, joint_states_rate; the serial link's timing is checked as
# the driver checks it and changes nothing (there is no link).
STANDIN_PARAMS = SHARED_PARAMS + (
    ParamSpec('seed', -1, "seed of the scene's random effects (release_noise, sensor_noise) for "
              "the stand-in's throws and readings; -1: the scene's noise.seed",
              minimum=-1, maximum=2 ** 31 - 1, read_only=True),
    ParamSpec('truth_log', '', "file for one JSON line per cycle with the part's true state "
              "(feeder_sim/truth.py), to count false readies against; '': none",
              read_only=True, constraints='a writable path'),
    SENSOR_RANGE,
    FRAME_ID,
    CYCLE_PERIOD,
    *LINK_SPECS,
    KEY_FILE,               # signs the cycle reports as the driver does
    JOINT_STATES_RATE,      # the arm's swing after each (instantaneous) cycle
    *SETPOINT_SPECS,        # the release speed per cycle, as the driver takes it
)

# predictor_node: follows the driver's cycle_status; publishes predicted/* and markers.
PREDICTOR_PARAMS = SHARED_PARAMS + (
    ParamSpec('markers_period', 0.1, 'at most one markers message per this many seconds (the '
              'last state always follows within it); 0: one after every throw',
              minimum=0.0, maximum=10.0),
)


def check_changes(changes, loader, current=None):
    """
    Reason to reject a parameter set beyond types and ranges, or None.

    A scene that must load; the driver's link rules (feeder_common.params.check_link) over
    ``current`` (name -> value) with ``changes``. ``changes`` maps names to new values;
    ``loader`` loads a scene (see :func:`check_scene`).
    """
    if 'scene' in changes:
        reason = check_scene(changes['scene'], loader)
        if reason:
            return reason
    return check_link(changes, current or {})


def check_start(model, edge, R):
    """Reason why (edge, R) cannot be the start state, or None."""
    if not (isinstance(R, (int, float)) and math.isfinite(R)):
        return f'start_radius must be a finite number, got {R!r}'
    arm = getattr(model, 'arm_length', math.inf)
    if R > arm:
        return (f"start_radius = {R} m (start_edge {edge}) rejected: R is beyond the arm's end "
                f'({arm:g} m; scene arm.length)')
    err = model.domain_error(int(edge), float(R))
    if err is None:
        return None
    if err.condition in ('edge_index', 'stable_edge'):
        # The edge alone is wrong: name start_edge (the radius is checked against it next).
        return f'start_edge = {edge} rejected: {err}'
    return (f'start_radius = {R} m on start_edge {edge} rejected: {err} (to change edge and '
            'radius together, set both in one atomic call)')
