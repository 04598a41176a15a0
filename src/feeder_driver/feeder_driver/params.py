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

from feeder_common.params import (by_name, check_link, CYCLE_PERIOD, DIAGNOSTIC_PERIOD,
                                  FRAME_ID, JOINT_STATES_RATE, KEY_FILE, LINK_SPECS,
                                  ParamSpec, REALTIME_PRIORITY, SENSOR_RANGE, SETPOINT_SPECS)

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
    CYCLE_PERIOD,
    *LINK_SPECS,
    SENSOR_RANGE,
    FRAME_ID,
    DIAGNOSTIC_PERIOD,
    JOINT_STATES_RATE,
    KEY_FILE,
    *SETPOINT_SPECS,
)
BY_NAME = by_name(SPECS)


def validate(new, current):
    """
    Reason why setting ``new`` on top of ``current`` breaks a rule across parameters, or None.

    The serial link's rules (feeder_common.params.check_link; the stand-in checks the same).
    """
    return check_link(new, current)


def defaults():
    return {s.name: s.default for s in SPECS}
