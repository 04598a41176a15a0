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
Parameters of the driver node: one table of specs (feeder_common's ParamSpec), rules across them.

The node declares :data:`SPECS` through feeder_common's ParameterGate (types, ranges, the
integer-for-double coercion) and adds :func:`validate` for what one parameter alone cannot
say. config/driver.yaml and the table in docs/driver.md list the same names, defaults and
ranges (a test checks both).
"""

from feeder_common.frames import FRAME_ID_MAX_LENGTH
from feeder_common.params import (by_name, JOINT_STATES_RATE, KEY_FILE, ParamSpec,
                                  REALTIME_PRIORITY)

BAUD_RATES = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000,
              921600, 1000000, 2000000)

SPECS = (
    ParamSpec('port', '/dev/ttyACM0',
              'serial port of the controller: a device path or any pyserial URL (e.g. the '
              'path given to controller_emulator --link, socket://127.0.0.1:PORT)',
              read_only=True, constraints='not empty'),
    ParamSpec('baud_rate', 115200, 'baud rate (8N1, no flow control)', 1200, 2000000,
              read_only=True, choices=BAUD_RATES),
    ParamSpec('autostart', True, 'configure and activate at start-up; false: wait for '
              '~/change_state (ros2 lifecycle set)', read_only=True),
    REALTIME_PRIORITY,
    ParamSpec('cycle_period', 1.0, 'seconds between FIREs while ~/enable is true (the next '
              'cycle never starts before the previous one ended)', 0.01, 3600.0),
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
    ParamSpec('sensor_range_m', 0.02, 'fixed distance of the proximity ranger, m '
              '(Range.min_range = max_range)', 0.001, 10.0),
    ParamSpec('frame_id', 'feeder_sensor', 'frame_id of the proximity messages',
              constraints='not empty', max_length=FRAME_ID_MAX_LENGTH),
    ParamSpec('diagnostic_updater.period', 1.0, 'seconds between /diagnostics messages',
              0.1, 60.0),
    JOINT_STATES_RATE,
    KEY_FILE,
)
BY_NAME = by_name(SPECS)


def validate(new, current):
    """
    Reason why setting ``new`` on top of ``current`` breaks a rule across parameters, or None.

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


def defaults():
    return {s.name: s.default for s in SPECS}
