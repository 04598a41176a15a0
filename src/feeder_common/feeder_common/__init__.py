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
feeder_common: the contract between the feeder's nodes, as code (docs/interfaces.md).

ROS-free: :mod:`.params` (parameter specs, types, ranges), :mod:`.frames` (REP 103 frames and
the conversion from the library's plane). ROS glue: :mod:`.qos` (every QoS profile of the
graph), :mod:`.parameters` (descriptors and the one validate-on-set gate), :mod:`.messages`
(builders and parsers of the feeder_interfaces messages, ``proximity``, ``joint_states``;
stamps as integer ns), :mod:`.diagnostics` (periodic ``/diagnostics``), :mod:`.node` (the run
helper of every node's ``main``: clean exit on SIGINT, SIGTERM and lifecycle shutdown).
"""
