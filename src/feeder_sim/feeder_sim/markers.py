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
Geometry of the feeder's RViz markers, ROS-free (the node turns these into Marker messages).

Everything is in the library's plane (frame F: x along the arm from the pivot, y up; the
arm's surface is the line y = h); a box's third size is its depth out of the plane.
feeder_sim.marker_msgs turns the specs into Marker messages in ``feeder_base`` (REP 103: F's y
is its z). Namespaces and ids are stable, so that every new
array replaces the previous markers in RViz:

=========== ======= ===========================================================
ns          id      what
=========== ======= ===========================================================
arm         0, 1    the arm (a thin box under the surface y = h) and its pivot
part        0, 1    outline (closed line strip) and fill (triangles) of the part
sensor      0, 1    the sensor under the arm and its beam (red while it fires)
limit_set   edge    R band of each edge of the limit set, under the arm
labels      edge    text of each band; ``guarantee`` 0: the guarantee radius
=========== ======= ===========================================================
"""

from dataclasses import dataclass, field
import math

ARM_THICKNESS = 0.004       # m, drawn under the surface y = h
LINE_WIDTH = 0.002          # m
BAND_WIDTH = 0.003          # m
BAND_SPACING = 0.006        # m between the band lines, under the arm
TEXT_HEIGHT = 0.008         # m

GREY = (0.6, 0.6, 0.6, 1.0)
GOAL_GREEN = (0.1, 0.75, 0.2, 1.0)
PART_ORANGE = (1.0, 0.55, 0.1, 1.0)
SENSOR_RED = (0.95, 0.1, 0.1, 1.0)
GUARANTEE_YELLOW = (0.95, 0.85, 0.1, 1.0)
EDGE_COLOURS = ((0.2, 0.4, 0.9, 1.0), (0.6, 0.3, 0.8, 1.0), (0.1, 0.7, 0.7, 1.0),
                (0.8, 0.5, 0.2, 1.0), (0.5, 0.5, 0.1, 1.0), (0.8, 0.3, 0.5, 1.0))


@dataclass(frozen=True)
class MarkerSpec:
    """
    One marker. ``kind`` names a visualization_msgs/Marker type (``cube``, ``line_strip``..).

    ``position`` and ``yaw`` place the marker's frame; ``points`` are (x, y) in that frame.
    """

    ns: str
    marker_id: int
    kind: str
    position: tuple = (0.0, 0.0)
    yaw: float = 0.0
    scale: tuple = (1.0, 1.0, 1.0)
    color: tuple = GREY
    points: tuple = field(default_factory=tuple)
    text: str = ''
    delete: bool = False        # remove the marker (ns, id) instead of drawing it


def arm_length(scene, analysis, sensor_radius):
    """Compute the arm's drawn length: a finite arm's own, else past the sensor and the bands."""
    if scene.arm_length is not None and math.isfinite(scene.arm_length):
        return float(scene.arm_length)
    part = scene.part
    far = max(hi for _, hi in analysis.limit_set.bands.values()) if analysis.limit_set.bands \
        else 0.0
    guarantee = analysis.sensor.guarantee_radius
    return 1.15 * max(far + part.r, sensor_radius, guarantee if math.isfinite(guarantee) else 0.0)


def part_markers(part, edge, R, h, on_goal):
    """Outline and fill of the part resting on ``edge`` at radius R; deleted for edge -1."""
    if edge < 0:        # no part on the arm (lost off its end)
        return [MarkerSpec('part', 0, 'line_strip', delete=True),
                MarkerSpec('part', 1, 'triangle_list', delete=True)]
    verts = [tuple(float(c) for c in v) for v in part.pose_vertices(edge, R, h)]
    colour = GOAL_GREEN if on_goal else PART_ORANGE
    outline = MarkerSpec('part', 0, 'line_strip', scale=(LINE_WIDTH, 0.0, 0.0), color=colour,
                         points=tuple(verts + verts[:1]))
    tris = []
    for k in range(1, len(verts) - 1):
        tris.extend([verts[0], verts[k], verts[k + 1]])
    fill = MarkerSpec('part', 1, 'triangle_list', scale=(1.0, 1.0, 1.0),
                      color=colour[:3] + (0.5,), points=tuple(tris))
    return [outline, fill]


def sensor_markers(x, h, reach, detected):
    """Draw the sensor under the arm at arm coordinate x and its beam ``reach`` high."""
    colour = SENSOR_RED if detected else GREY
    body = MarkerSpec('sensor', 0, 'cube', position=(x, h - ARM_THICKNESS - 0.003),
                      scale=(0.006, 0.006, 0.006), color=colour)
    beam = MarkerSpec('sensor', 1, 'line_list', scale=(LINE_WIDTH / 2, 0.0, 0.0),
                      color=colour[:3] + (0.6,), points=((x, h), (x, h + reach)))
    return [body, beam]


def static_markers(scene, analysis, sensor_radius):
    """Arm, pivot, limit-set bands with labels and the guarantee radius."""
    h = scene.h
    length = arm_length(scene, analysis, sensor_radius)
    out = [MarkerSpec('arm', 0, 'cube', position=(length / 2, h - ARM_THICKNESS / 2),
                      scale=(length, ARM_THICKNESS, 0.01), color=GREY),
           MarkerSpec('arm', 1, 'sphere', position=(0.0, 0.0), scale=(0.008, 0.008, 0.008),
                      color=GREY)]
    goal = analysis.sensor.goal_edge
    for k, edge in enumerate(sorted(analysis.limit_set.bands)):
        lo, hi = analysis.limit_set.bands[edge]
        y = h - ARM_THICKNESS - 0.008 - BAND_SPACING * k
        colour = GOAL_GREEN if edge == goal else EDGE_COLOURS[edge % len(EDGE_COLOURS)]
        out.append(MarkerSpec('limit_set', int(edge), 'line_list',
                              scale=(BAND_WIDTH, 0.0, 0.0), color=colour,
                              points=((float(lo), y), (float(hi), y))))
        label = f'E{edge}{" (goal)" if edge == goal else ""}: R {100 * lo:.1f}-{100 * hi:.1f} cm'
        out.append(MarkerSpec('labels', int(edge), 'text', position=(float(hi) + 0.03, y),
                              scale=(0.0, 0.0, TEXT_HEIGHT), color=colour, text=label))
    g = float(analysis.sensor.guarantee_radius)
    if math.isfinite(g):        # -inf: every detection is on the goal edge; nothing to draw
        out.append(MarkerSpec('guarantee', 0, 'line_list', scale=(LINE_WIDTH / 2, 0.0, 0.0),
                              color=GUARANTEE_YELLOW, points=((g, h - 0.03), (g, h + 0.03))))
    return out


def state_markers(scene, analysis, sensor_radius, edge, R, detected):
    """Markers that change with the state: the part and the sensor."""
    reach = 2.0 * scene.part.r
    return (part_markers(scene.part, edge, R, scene.h, edge == analysis.sensor.goal_edge)
            + sensor_markers(sensor_radius, scene.h, reach, detected))


def feeder_markers(scene, analysis, sensor_radius, edge, R, detected):
    """Every marker for the part resting at (edge, R) with sensor bit ``detected``."""
    return (static_markers(scene, analysis, sensor_radius)
            + state_markers(scene, analysis, sensor_radius, edge, R, detected))
