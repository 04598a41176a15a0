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
feeder_sim: the feeder's simulator node (the predictor, or the hardware's stand-in).

ROS-free modules: ``analysis`` (scene analysis at a chosen sensor radius), ``predictor`` (the
part's state, throw by throw), ``markers`` (RViz geometry in the library's plane), ``params``
(the parameter table and the checks that need the scene). ROS glue: ``marker_msgs`` (Marker
messages in feeder_base) and ``sim_node``; the shared contract is feeder_common's.
"""
