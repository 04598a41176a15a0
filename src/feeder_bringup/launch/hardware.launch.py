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
The real feeder: driver_node on a serial port, the predictor, the monitor and feed_node.

    ros2 launch feeder_bringup hardware.launch.py port:=/dev/ttyACM0 [scene:=triangle]
    ros2 launch feeder_bringup hardware.launch.py emulator:=true   # controller emulator on a pty

Other arguments as sim.launch.py's (namespace, cycle_period, sensor_radius, record, rviz,
robot_state_publisher, arm_length, realtime_priority).
"""

from feeder_bringup.launch_actions import from_plan
from feeder_bringup.launch_support import HARDWARE_ARGUMENTS, plan_hardware
from launch import LaunchDescription


def generate_launch_description():
    return LaunchDescription(from_plan(HARDWARE_ARGUMENTS, plan_hardware))
