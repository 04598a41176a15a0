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
Parameter specs (ROS-free): one table per node, from which descriptors and checks are built.

The idea of generate_parameter_library without the tool: name, default (its Python type is the
parameter's type), range, allowed values, read-only flag and description live in one place.
ROS users write ``1`` for ``1.0``: an integer given for a double is taken as that double
(:meth:`ParamSpec.coerce`); every other type mismatch is an error that names the parameter,
what it got and how to write it.
"""

from dataclasses import dataclass
import math
from typing import Optional

from .frames import FRAME_ID_MAX_LENGTH, SENSOR_FRAME

_KINDS = ((bool, 'bool'), (int, 'integer'), (float, 'double'), (str, 'string'))


def kind_of(value):
    """ROS parameter type name of a Python value: bool, integer, double, string (or other)."""
    for py, name in _KINDS:     # bool first: it is an int to Python
        if isinstance(value, py):
            return name
    return type(value).__name__


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
    choices: tuple = ()         # allowed values (e.g. baud rates); empty: any in range
    max_length: Optional[int] = None    # longest string accepted (characters)

    @property
    def kind(self):
        return kind_of(self.default)

    def coerce(self, value):
        """
        Return ``(value, None)`` with ``value`` of this parameter's type, or ``(None, reason)``.

        An integer for a double becomes that double; nothing else is converted.
        """
        got = kind_of(value)
        want = self.kind
        if got == want:
            return value, None
        if want == 'double' and got == 'integer':
            return float(value), None
        if want == 'integer' and got == 'double' and math.isfinite(value) and \
                value == int(value):
            hint = f'; write {int(value)}'
        elif want == 'string':
            hint = f"; quote it to pass it as text: -p {self.name}:=\"'{value}'\""
        elif want == 'bool':
            hint = '; write true or false'
        elif want in ('integer', 'double'):
            hint = f'; write a number, e.g. {self.default!r}'
        else:
            hint = ''
        return None, f'{self.name} must be a{"n" if want == "integer" else ""} {want}, got ' \
            f'{got} {value!r}{hint}'

    def check(self, value):
        """Reason why ``value`` (already of the right type) is invalid, or None."""
        if self.kind == 'double' and not math.isfinite(value):
            return f'{self.name} must be finite, got {value!r}'
        reason = self.check_range(value)
        if reason:
            return reason
        if self.choices and value not in self.choices:
            return (f'{self.name} = {value!r} is not one of the allowed values: '
                    f'{", ".join(str(c) for c in self.choices)}')
        if self.kind == 'string' and self.constraints == 'not empty' and not value.strip():
            return f'{self.name} must not be empty'
        if self.kind == 'string' and self.max_length is not None and \
                len(value) > self.max_length:
            return (f'{self.name} is {len(value)} characters long; at most {self.max_length} '
                    'are accepted')
        return None

    def check_range(self, value):
        """Reason why a number is out of range, or None (rclpy checks the range too)."""
        if self.kind not in ('integer', 'double'):
            return None
        lo, hi = self.minimum, self.maximum
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            if lo is not None and hi is not None:
                return f'{self.name} = {value!r} is outside [{lo}, {hi}]; pick a value in ' \
                    'that range'
            if lo is not None:
                return f'{self.name} = {value!r} is below the minimum {lo}'
            return f'{self.name} = {value!r} is above the maximum {hi}'
        return None

    def validate(self, value):
        """Coerce and check: ``(value, None)`` or ``(None, reason)``."""
        value, reason = self.coerce(value)
        if reason is None:
            reason = self.check(value)
        return (None, reason) if reason else (value, None)


# Every node on the path of a cycle (driver or its stand-in, monitor, predictor) takes it: run
# at start-up by feeder_common.node.run_node (feeder_common.realtime says why).
REALTIME_PRIORITY = ParamSpec(
    'realtime_priority', 0, 'SCHED_FIFO priority (1-99) of every thread of the node, so that '
    'other work on busy cores cannot delay a cycle; needs an rtprio limit or CAP_SYS_NICE (the '
    'node refuses to start without it); 0: the normal scheduler', minimum=0, maximum=99,
    read_only=True)


# The driver (or its stand-in) signs its cycle reports and the monitor its verdicts with the key
# of this file (feeder_common.auth); they must share it.
KEY_FILE = ParamSpec(
    'key_file', '', 'HMAC key file shared by the driver (or its stand-in) and the monitor: one '
    'key in hex, mode 0600; empty: $ROS_HOME/feeder/hmac.key (~/.ros/feeder/hmac.key), created '
    'when absent; a given file must exist (the launch creates it)', read_only=True,
    max_length=4096)


# The driver and its stand-in publish joint_states at this rate between cycle events: the arm's
# swing (feeder_common.arm), so robot_state_publisher and RViz animate it.
JOINT_STATES_RATE = ParamSpec(
    'joint_states_rate', 30.0, 'Hz of joint_states between cycle events (the arm along '
    "feeder_common.arm's swing, at rest between cycles), besides the release and rest "
    'messages; 0: only those', minimum=0.0, maximum=1000.0)


# ---- one name and one range per parameter the nodes share (issue 23) ----------------------
# The driver and its stand-in take the same cycle parameters (the stand-in accepts the
# driver's config/driver.yaml); every node names its /diagnostics period as diagnostic_updater
# does.

CYCLE_PERIOD = ParamSpec(
    'cycle_period', 1.0, 'seconds between cycles while ~/enable is true (the next cycle never '
    'starts before the previous one ended)', 0.005, 3600.0)

DIAGNOSTIC_PERIOD = ParamSpec(
    'diagnostic_updater.period', 1.0, 'seconds between /diagnostics messages', 0.1, 60.0)

# Old names still taken at start-up (with a warning) for their one name.
RENAMED = {'diagnostics_period': 'diagnostic_updater.period'}

SENSOR_RANGE = ParamSpec(
    'sensor_range_m', 0.02, 'fixed distance of the proximity ranger, m '
    '(Range.min_range = max_range)', 0.001, 10.0)

FRAME_ID = ParamSpec('frame_id', SENSOR_FRAME, 'frame_id of the proximity messages',
                     constraints='not empty', max_length=FRAME_ID_MAX_LENGTH)

# The serial link's timing: the driver's; the stand-in (no serial link) takes them, checked
# the same way, so that one parameter file serves both, and they change nothing there.
LINK_SPECS = (
    ParamSpec('ack_timeout_s', 0.5, 'a cycle fails if no ACK (or REL/SENS) arrives within this '
              'time after FIRE; also the PING repeat interval of the handshake', 0.01, 10.0,
              constraints='below cycle_timeout_s and watchdog_timeout_s'),
    ParamSpec('cycle_timeout_s', 5.0, 'a cycle fails if no SENS arrives within this time after '
              'FIRE; must exceed ack_timeout_s', 0.05, 120.0,
              constraints='must exceed ack_timeout_s'),
    ParamSpec('watchdog_timeout_s', 3.0, 'the link is declared lost (port closed and reopened) '
              'after this long without a valid frame (the controller sends HB at 1 Hz)',
              0.2, 60.0),
    ParamSpec('reconnect_initial_s', 0.5, 'first reopen delay after a failure; doubles per '
              'failed attempt', 0.01, 60.0),
    ParamSpec('reconnect_max_s', 10.0, 'cap of the reopen delay; must be >= '
              'reconnect_initial_s', 0.01, 600.0,
              constraints='must be >= reconnect_initial_s'),
)


# The release speed per cycle (issue 25): the driver and its stand-in take the same three.
RELEASE_SPEED_MODES = ('fixed', 'setpoint')
SETPOINT_SPECS = (
    ParamSpec('release_speed_mode', 'fixed', "'fixed': every cycle at the controller's own "
              "speed; 'setpoint': every cycle at the signed setpoint for it on "
              'release_speed_setpoint (from speed_source), none: no cycle (a controller that '
              'cannot set its speed: fixed, said once)', choices=RELEASE_SPEED_MODES),
    ParamSpec('speed_source', 'feeder_monitor', 'node whose signed setpoints are taken '
              '(resolved like a topic name: relative to the namespace)', read_only=True,
              constraints='not empty', max_length=256),
    ParamSpec('max_setpoint_age', 1.0, 'a setpoint sent longer ago than this (s) is not used '
              '(the sender republishes it four times a second)', 0.05, 60.0),
)


def check_link(new, current):
    """
    Reason why setting ``new`` on top of ``current`` breaks a rule of LINK_SPECS, or None.

    Rules whose parameters are not all declared yet (during start-up) wait for the check of
    the complete set.
    """
    merged = dict(current)
    merged.update(new)

    def have(*names):
        return all(n in merged for n in names)

    if have('reconnect_initial_s', 'reconnect_max_s') and \
            merged['reconnect_initial_s'] > merged['reconnect_max_s']:
        return (f'reconnect_initial_s ({merged["reconnect_initial_s"]}) must not exceed '
                f'reconnect_max_s ({merged["reconnect_max_s"]}); raise reconnect_max_s or '
                'lower reconnect_initial_s')
    if have('ack_timeout_s', 'cycle_timeout_s') and \
            merged['ack_timeout_s'] >= merged['cycle_timeout_s']:
        return (f'ack_timeout_s ({merged["ack_timeout_s"]}) must be smaller than '
                f'cycle_timeout_s ({merged["cycle_timeout_s"]})')
    if have('ack_timeout_s', 'watchdog_timeout_s') and \
            merged['ack_timeout_s'] >= merged['watchdog_timeout_s']:
        return (f'ack_timeout_s ({merged["ack_timeout_s"]}) must be smaller than '
                f'watchdog_timeout_s ({merged["watchdog_timeout_s"]}), or the handshake '
                'cannot repeat its PING')
    return None


def by_name(specs):
    """Map names to specs; a name given twice is an error in the table."""
    out = {}
    for s in specs:
        if s.name in out:
            raise ValueError(f'parameter {s.name} is declared twice')
        out[s.name] = s
    return out


def defaults(specs):
    return {s.name: s.default for s in specs}


def check_scene(path, loader):
    """
    Reason why the scene file at ``path`` is unusable, or None.

    ``loader(path)`` loads it and raises ValueError (throwmap's errors are ValueErrors, their
    text names the field and the fix) or OSError (unreadable file).
    """
    if not path:
        return ('scene: not set; give the path of a scene YAML, e.g. '
                '--ros-args -p scene:=scenes/triangle.yaml')
    try:
        loader(path)
    except OSError as exc:
        return f'scene: cannot read {path}: {exc}'
    except ValueError as exc:
        return f'scene: {exc}'
    return None
