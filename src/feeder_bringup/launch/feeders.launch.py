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
Several simulated feeders side by side in one domain, one per namespace.

    ros2 launch feeder_bringup feeders.launch.py [namespaces:=feeder_1,feeder_2,feeder_3]

Each namespace gets sim.launch.py's nodes; topics, services and transforms (<ns>/tf) stay in
it. Other arguments as sim.launch.py's (record:=DIR records each feeder to DIR/<ns>).
"""

from feeder_bringup.launch_actions import from_plan
from feeder_bringup.launch_support import FEEDERS_ARGUMENTS, plan_feeders
from launch import LaunchDescription


def generate_launch_description():
    return LaunchDescription(from_plan(FEEDERS_ARGUMENTS, plan_feeders))
