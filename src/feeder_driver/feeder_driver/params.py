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
Parameters of the driver node: one table of specs, validation without ROS.

The node builds its ParameterDescriptors from :data:`SPECS` and validates every set with
:func:`validate` (the on-set callback only calls this). config/driver.yaml and the table in
docs/driver.md list the same names, defaults and ranges (a test checks the YAML).
"""

from dataclasses import dataclass
import math
from typing import Any, Optional, Tuple

BAUD_RATES = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000,
              921600, 1000000, 2000000)


@dataclass(frozen=True)
class Spec:
    name: str
    default: Any
    description: str
    bounds: Optional[Tuple[float, float]] = None
    read_only: bool = False


SPECS = (
    Spec('port', '/dev/ttyACM0',
         'serial port of the controller: a device path or any pyserial URL (e.g. the '
         'path given to controller_emulator --link, socket://127.0.0.1:PORT)', read_only=True),
    Spec('baud_rate', 115200, 'baud rate (8N1, no flow control); one of ' +
         ', '.join(str(b) for b in BAUD_RATES), (1200, 2000000), read_only=True),
    Spec('autostart', True, 'configure and activate at start-up (there is no ros2 lifecycle '
         'CLI in the pip install); false: wait for ~/change_state', read_only=True),
    Spec('cycle_period', 1.0, 'seconds between FIREs while ~/enable is true (the next '
         'cycle never starts before the previous one ended)', (0.01, 3600.0)),
    Spec('ack_timeout_s', 0.5, 'a cycle fails if no ACK (or REL/SENS) arrives within this '
         'time after FIRE; also the PING repeat interval of the handshake', (0.01, 10.0)),
    Spec('cycle_timeout_s', 5.0, 'a cycle fails if no SENS arrives within this time after '
         'FIRE; must exceed ack_timeout_s', (0.05, 120.0)),
    Spec('watchdog_timeout_s', 3.0, 'the link is declared lost (port closed and reopened) '
         'after this long without a valid frame (the controller sends HB at 1 Hz)',
         (0.2, 60.0)),
    Spec('reconnect_initial_s', 0.5, 'first reopen delay after a failure; doubles per '
         'failed attempt', (0.01, 60.0)),
    Spec('reconnect_max_s', 10.0, 'cap of the reopen delay; must be >= reconnect_initial_s',
         (0.01, 600.0)),
    Spec('sensor_range_m', 0.02, 'fixed distance of the proximity ranger, m '
         '(Range.min_range = max_range)', (0.001, 10.0)),
    Spec('frame_id', 'feeder_sensor', 'frame_id of the proximity messages'),
    Spec('diagnostic_updater.period', 1.0, 'seconds between /diagnostics messages',
         (0.1, 60.0)),
)
BY_NAME = {s.name: s for s in SPECS}


def _kind(value):
    if isinstance(value, bool):
        return 'bool'
    if isinstance(value, int):
        return 'integer'
    if isinstance(value, float):
        return 'double'
    if isinstance(value, str):
        return 'string'
    return type(value).__name__


def check(name, value):
    """Reason why one value is invalid (None if it is fine)."""
    spec = BY_NAME.get(name)
    if spec is None:
        return None
    want = _kind(spec.default)
    got = _kind(value)
    if got != want:
        hint = f'; write {float(value)!r}' if want == 'double' and got == 'integer' else ''
        return f'{name} must be a {want}, got {got} {value!r}{hint}'
    if want == 'double' and not math.isfinite(value):
        return f'{name} must be finite, got {value!r}'
    if spec.bounds is not None:
        lo, hi = spec.bounds
        if not lo <= value <= hi:
            return f'{name} = {value!r} is outside [{lo}, {hi}]; pick a value in that range'
    if name == 'baud_rate' and value not in BAUD_RATES:
        return (f'baud_rate = {value} is not a standard rate; use one of '
                f'{", ".join(str(b) for b in BAUD_RATES)}')
    if name in ('port', 'frame_id') and not value.strip():
        return f'{name} must not be empty'
    return None


def validate(new, current):
    """Reason why setting ``new`` (name -> value) on top of ``current`` is invalid, or None."""
    for name, value in new.items():
        reason = check(name, value)
        if reason:
            return reason
    merged = dict(current)
    merged.update(new)
    if merged['reconnect_initial_s'] > merged['reconnect_max_s']:
        return (f'reconnect_initial_s ({merged["reconnect_initial_s"]}) must not exceed '
                f'reconnect_max_s ({merged["reconnect_max_s"]}); raise reconnect_max_s or '
                'lower reconnect_initial_s')
    if merged['ack_timeout_s'] >= merged['cycle_timeout_s']:
        return (f'ack_timeout_s ({merged["ack_timeout_s"]}) must be smaller than '
                f'cycle_timeout_s ({merged["cycle_timeout_s"]})')
    if merged['ack_timeout_s'] >= merged['watchdog_timeout_s']:
        return (f'ack_timeout_s ({merged["ack_timeout_s"]}) must be smaller than '
                f'watchdog_timeout_s ({merged["watchdog_timeout_s"]}), or the handshake '
                'cannot repeat its PING')
    return None


def defaults():
    return {s.name: s.default for s in SPECS}


def descriptors():
    """Build the ParameterDescriptors from SPECS (imports rcl_interfaces only when called)."""
    from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                    ParameterType)
    types = {'bool': ParameterType.PARAMETER_BOOL, 'integer': ParameterType.PARAMETER_INTEGER,
             'double': ParameterType.PARAMETER_DOUBLE, 'string': ParameterType.PARAMETER_STRING}
    out = {}
    for s in SPECS:
        d = ParameterDescriptor(name=s.name, type=types[_kind(s.default)],
                                description=s.description, read_only=s.read_only)
        if s.bounds is not None and isinstance(s.default, float):
            d.floating_point_range = [FloatingPointRange(from_value=float(s.bounds[0]),
                                                         to_value=float(s.bounds[1]), step=0.0)]
        elif s.bounds is not None:
            d.integer_range = [IntegerRange(from_value=int(s.bounds[0]),
                                            to_value=int(s.bounds[1]), step=0)]
        if s.name == 'cycle_timeout_s':
            d.additional_constraints = 'must exceed ack_timeout_s'
        elif s.name == 'reconnect_max_s':
            d.additional_constraints = 'must be >= reconnect_initial_s'
        elif s.name == 'baud_rate':
            d.additional_constraints = 'one of ' + ', '.join(str(b) for b in BAUD_RATES)
        out[s.name] = d
    return out
