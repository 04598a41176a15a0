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
The feeder's frames (REP 103) and the conversion from the library's plane (ROS-free).

throwmap works in the paper's frame F: origin at the arm pivot, x along the arm, y up, in the
plane of the plate (z_F out of it). ROS frames have z up, so ``feeder_base`` is F turned a
quarter turn about x: x along the arm, z up (F's y), y into the plate (F's -z). A point (x, y)
of the plane is (x, 0, y) in ``feeder_base``; a rotation by ``angle`` in the plane
(counterclockwise seen from the front, about z_F) is a rotation about -y of ``feeder_base``.

Frames of the URDF (feeder_bringup/urdf/feeder.urdf): ``feeder_base`` at the pivot;
``feeder_arm`` on the revolute joint ``feeder_arm_joint`` (axis -y: a positive angle lifts the
arm's tip, as the paper's theta); ``feeder_sensor`` fixed on the arm at the sensor radius, on the
arm's surface, its x axis (the Range's beam, REP 117) pointing up through the arm.
"""

import math

BASE_FRAME = 'feeder_base'
ARM_LINK = 'feeder_arm'
SENSOR_FRAME = 'feeder_sensor'
ARM_JOINT = 'feeder_arm_joint'
# The arm turns about F's z, which is -y of feeder_base.
ARM_AXIS = (0.0, -1.0, 0.0)


def plane_point(x, y):
    """Return (x, y, z) in feeder_base of the point (x, y) of the library's plane."""
    return float(x), 0.0, float(y)


def plane_quaternion(angle):
    """
    Return (x, y, z, w) in feeder_base of a rotation by ``angle`` in the library's plane.

    ``angle`` is about F's z (counterclockwise seen from the front of the plate), i.e. about
    -y of feeder_base. (This replaces a quaternion about z, which was right only while
    feeder_base was y-up.)
    """
    half = 0.5 * float(angle)
    return 0.0, -math.sin(half), 0.0, math.cos(half)


def plane_scale(along_x, along_y, depth):
    """Return the (x, y, z) size in feeder_base of a box ``along_x`` x ``along_y`` in the plane."""
    return float(along_x), float(depth), float(along_y)
