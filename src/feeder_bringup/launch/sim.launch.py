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
The simulated feeder: the hardware stand-in, the predictor, the monitor and feed_node.

    ros2 launch feeder_bringup sim.launch.py [scene:=triangle] [namespace:=feeder]
        [cycle_period:=1.0] [sensor_radius:=auto] [record:=DIR] [rviz:=true]
        [robot_state_publisher:=auto] [arm_length:=0.4] [realtime_priority:=0]
        [speed_policy:=FILE]

Enable cycling with: ros2 service call /feeder/feeder_driver/enable std_srvs/srv/SetBool
'{data: true}'; watch: ros2 topic echo /feeder/edge1_ready.
"""

from feeder_bringup.launch_actions import from_plan
from feeder_bringup.launch_support import plan_sim, SIM_ARGUMENTS
from launch import LaunchDescription


def generate_launch_description():
    return LaunchDescription(from_plan(SIM_ARGUMENTS, plan_sim))
