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
feeder_monitor: edge1_ready from the one-bit sensor and the predicted limit set; bag_recorder.

ROS-free modules: ``readiness`` (detection-pattern rules, the monitor's state machine, pairing of
proximity with cycle_status), ``bag`` (rosbag2 MCAP bags as rosbag2 writes them). ROS glue:
``monitor_node`` and ``bag_recorder``.
"""
