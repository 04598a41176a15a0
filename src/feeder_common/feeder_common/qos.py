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
Every QoS profile of the feeder graph, one name per topic (docs/interfaces.md).

Publishers of sensor data and predictions use the system default (reliable, volatile, depth
10; REP 2003); subscribers of sensor data use ``qos_profile_sensor_data`` (best effort matches a
reliable publisher). Latched state is reliable + transient local on both ends. A topic whose
delivery needs watching (deadline, liveliness, lifespan of a latched value) gets it here, in its
own profile, so that publisher and subscriber keep matching.
"""

from rclpy.qos import (DurabilityPolicy, HistoryPolicy, qos_profile_sensor_data, QoSProfile,
                       ReliabilityPolicy)

# The system default, written out: reliable, volatile, keep last 10.
DEFAULT = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                     reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.VOLATILE)
# Latched state: the last message reaches late subscribers.
LATCHED = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                     reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)

PROXIMITY = DEFAULT
PROXIMITY_SUBSCRIPTION = qos_profile_sensor_data
JOINT_STATES = DEFAULT
# One message per fired cycle; a reader must not lose one: reliable, volatile, depth 100.
CYCLE_STATUS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                          reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.VOLATILE)
PREDICTION = DEFAULT
PREDICTION_LATCHED = LATCHED
MARKERS = LATCHED
EDGE1_READY = LATCHED
# /diagnostics: reliable, depth 1, like diagnostic_updater.
DIAGNOSTICS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.VOLATILE)
