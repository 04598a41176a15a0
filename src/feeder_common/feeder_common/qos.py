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

from rclpy.duration import Duration
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, LivelinessPolicy,
                       qos_profile_sensor_data, QoSProfile, ReliabilityPolicy)

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
# The driver's process asserts liveliness on its cycle writers at least this often (s): a
# reader that asks for the same lease learns within it that the driver died or hangs (a
# SIGKILL included), instead of after DDS's participant lease (20 s).
DRIVER_LEASE_S = 1.0
# One message per fired cycle; a reader must not lose one: reliable, volatile, depth 100.
CYCLE_STATUS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                          reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.VOLATILE,
                          liveliness=LivelinessPolicy.AUTOMATIC,
                          liveliness_lease_duration=Duration(seconds=DRIVER_LEASE_S))
# The notice "cycle N is being fired", sent before the actuator moves: as deep and as live.
CYCLE_FIRED = CYCLE_STATUS
PREDICTION = DEFAULT
# The predicted state of every followed cycle (seq, stamp, edge, R, throw kind): counted and
# matched to cycles by seq, like cycle_status, so as deep.
PREDICTED_STATE = CYCLE_STATUS
PREDICTION_LATCHED = LATCHED
MARKERS = LATCHED
# The release speed of the next cycle (the speed policy's): the newest one reaches a driver
# that starts or restarts later; the sender republishes it with a fresh ``sent``.
RELEASE_SPEED_SETPOINT = LATCHED


def edge1_ready(period):
    """
    ``edge1_ready``: the latched state, with the promise that it is live (docs/interfaces.md).

    The monitor publishes it at least every ``period`` s (every judged cycle, and again when
    idle): deadline ``period``. Its process asserts liveliness automatically, lease ``period``:
    a reader that asks for deadline and lease >= ``period`` learns within that time that a
    verdict is stale (the monitor hangs or died, even by SIGKILL) and must then take it as
    false. Depth 1: a late joiner gets the current state, never a history.
    """
    d = Duration(seconds=float(period))
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL, deadline=d,
                      liveliness=LivelinessPolicy.AUTOMATIC, liveliness_lease_duration=d)


# The verdict of every judged cycle (seq, stamp, ready, state): a reader that counts or logs
# verdicts must not lose one (a depth-1 latched writer may replace a sample before a reader
# acknowledged it): reliable, volatile, deep.
EDGE1_VERDICT = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                           reliability=ReliabilityPolicy.RELIABLE,
                           durability=DurabilityPolicy.VOLATILE)
# /diagnostics: reliable, like diagnostic_updater, but depth 10 on our writers: at depth 1 a
# message (an ERROR that lasted one period) could be replaced before a slow reader got it.
DIAGNOSTICS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.VOLATILE)

# feed_node's action feedback (one per cycle; a client should read it with the same profile).
FEED_FEEDBACK = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                           reliability=ReliabilityPolicy.RELIABLE,
                           durability=DurabilityPolicy.VOLATILE)
