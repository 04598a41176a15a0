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


"""Marker messages from feeder_sim.markers specs, in frame feeder_base (REP 103: z up)."""

from feeder_common.frames import plane_point, plane_quaternion, plane_scale
from geometry_msgs.msg import Point
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

_MARKER_TYPES = {'cube': Marker.CUBE, 'sphere': Marker.SPHERE, 'line_strip': Marker.LINE_STRIP,
                 'line_list': Marker.LINE_LIST, 'triangle_list': Marker.TRIANGLE_LIST,
                 'text': Marker.TEXT_VIEW_FACING}
# Shapes whose scale is a size along the plane's axes (lines: scale.x is the width; text:
# scale.z is the height; triangle lists: 1).
_SOLIDS = ('cube', 'sphere')


def marker_array(specs, frame_id, stamp):
    """Build a MarkerArray from specs in the library's plane, converted to ``frame_id``."""
    out = MarkerArray()
    header = Header(stamp=stamp, frame_id=frame_id)
    for s in specs:
        m = Marker()
        m.header = header
        m.ns = s.ns
        m.id = int(s.marker_id)
        m.type = _MARKER_TYPES[s.kind]
        m.action = Marker.DELETE if s.delete else Marker.ADD
        m.pose.position.x, m.pose.position.y, m.pose.position.z = plane_point(*s.position)
        q = m.pose.orientation
        q.x, q.y, q.z, q.w = plane_quaternion(s.yaw)
        if s.kind in _SOLIDS:
            m.scale.x, m.scale.y, m.scale.z = plane_scale(*s.scale)
        else:
            m.scale.x, m.scale.y, m.scale.z = (float(v) for v in s.scale)
        m.color.r, m.color.g, m.color.b, m.color.a = (float(v) for v in s.color)
        m.points = [Point(x=px, y=py, z=pz) for px, py, pz in
                    (plane_point(x, y) for x, y in s.points)]
        m.text = s.text
        m.frame_locked = False
        out.markers.append(m)
    return out
