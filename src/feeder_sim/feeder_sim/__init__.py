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
feeder_sim: the feeder's simulator nodes, one per executable.

``standin_node`` (class StandInNode) stands in for the hardware with exactly the driver's
interface; ``predictor_node`` (class PredictorNode) predicts the part's state from the
driver's cycle reports. ROS-free modules: ``markers`` (RViz geometry in the library's plane),
``params`` (both nodes' parameter tables and the checks that need the scene), ``truth`` (the
stand-in's truth log). ROS glue: ``part_node`` (the lifecycle skeleton both nodes share),
``marker_msgs`` (Marker messages in feeder_base) and the two node modules; the shared
contract is feeder_common's.
"""
