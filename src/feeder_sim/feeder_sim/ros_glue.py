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

"""Thin ROS glue shared by the feeder nodes: descriptors, QoS, diagnostics and marker messages."""

import gc
import math
import sys

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
import rclpy
from rclpy.exceptions import InvalidParameterValueException
from rclpy.executors import ExternalShutdownException
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

# Latched state: the last message reaches late subscribers (transient local on both ends).
LATCHED_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
# cycle_status: reliable, volatile, depth 100 (docs/interfaces.md).
CYCLE_STATUS_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                              reliability=ReliabilityPolicy.RELIABLE,
                              durability=DurabilityPolicy.VOLATILE)
# /diagnostics: reliable, depth 1, like diagnostic_updater.
DIAGNOSTICS_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                             reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.VOLATILE)
# System default for sensor data and predictions (REP 2003): reliable, volatile, depth 10.
DEFAULT_DEPTH = 10

LEVELS = {'ok': DiagnosticStatus.OK, 'warn': DiagnosticStatus.WARN,
          'error': DiagnosticStatus.ERROR, 'stale': DiagnosticStatus.STALE}

_MARKER_TYPES = {'cube': Marker.CUBE, 'sphere': Marker.SPHERE, 'line_strip': Marker.LINE_STRIP,
                 'line_list': Marker.LINE_LIST, 'triangle_list': Marker.TRIANGLE_LIST,
                 'text': Marker.TEXT_VIEW_FACING}


def yaw_quaternion(yaw):
    """(x, y, z, w) of a rotation by ``yaw`` about z."""
    return 0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw)


def descriptor(spec):
    """Build the ParameterDescriptor of a ParamSpec (rclpy enforces its range)."""
    desc = ParameterDescriptor(description=spec.description, read_only=spec.read_only,
                               additional_constraints=spec.constraints)
    if isinstance(spec.default, bool) or isinstance(spec.default, str):
        return desc
    if isinstance(spec.default, int):
        lo = int(spec.minimum) if spec.minimum is not None else -(2 ** 63)
        hi = int(spec.maximum) if spec.maximum is not None else 2 ** 63 - 1
        desc.integer_range = [IntegerRange(from_value=lo, to_value=hi, step=1)]
    else:
        lo = float(spec.minimum) if spec.minimum is not None else -math.inf
        hi = float(spec.maximum) if spec.maximum is not None else math.inf
        desc.floating_point_range = [FloatingPointRange(from_value=lo, to_value=hi, step=0.0)]
    return desc


def declare(node, spec, default=None):
    """Declare ``spec`` on ``node`` (``default`` overrides the table's); returns the value."""
    value = spec.default if default is None else type(spec.default)(default)
    return node.declare_parameter(spec.name, value, descriptor(spec)).value


class ParameterGate:
    """
    Validate in on-set (``validate(changes) -> reason or None``), apply in post-set.

    ``changes`` maps each parameter name of the request to its new value. Register the gate
    before declaring: rclpy runs on-set callbacks on declaration too, so a bad command-line
    value stops the node with the reason.
    """

    def __init__(self, node, validate, apply=None):
        self._validate = validate
        self._apply = apply
        node.add_on_set_parameters_callback(self._on_set)
        if apply is not None:
            node.add_post_set_parameters_callback(self._post_set)

    def _on_set(self, params):
        reason = self._validate({p.name: p.value for p in params})
        return SetParametersResult(successful=reason is None, reason=reason or '')

    def _post_set(self, params):
        self._apply({p.name: p.value for p in params})


def diagnostic_status(name, level, message, hardware_id, values):
    """Build a DiagnosticStatus; ``values`` (a dict) become string KeyValues."""
    return DiagnosticStatus(level=LEVELS[level], name=name, message=message,
                            hardware_id=hardware_id,
                            values=[KeyValue(key=str(k), value=str(v)) for k, v in
                                    values.items()])


def diagnostic_array(stamp, statuses):
    return DiagnosticArray(header=_header(stamp, ''), status=list(statuses))


def _header(stamp, frame_id):
    return Header(stamp=stamp, frame_id=frame_id)


def marker_array(specs, frame_id, stamp):
    """Build a MarkerArray from feeder_sim.markers specs (action ADD, planar z = 0)."""
    out = MarkerArray()
    for s in specs:
        m = Marker()
        m.header = _header(stamp, frame_id)
        m.ns = s.ns
        m.id = int(s.marker_id)
        m.type = _MARKER_TYPES[s.kind]
        m.action = Marker.DELETE if s.delete else Marker.ADD
        m.pose.position.x = float(s.position[0])
        m.pose.position.y = float(s.position[1])
        qx, qy, qz, qw = yaw_quaternion(s.yaw)
        m.pose.orientation.x, m.pose.orientation.y = qx, qy
        m.pose.orientation.z, m.pose.orientation.w = qz, qw
        m.scale.x, m.scale.y, m.scale.z = (float(v) for v in s.scale)
        m.color.r, m.color.g, m.color.b, m.color.a = (float(v) for v in s.color)
        m.points = [Point(x=float(x), y=float(y), z=0.0) for x, y in s.points]
        m.text = s.text
        m.frame_locked = False
        out.markers.append(m)
    return out


def stamp_text(stamp):
    """Write a builtin_interfaces/Time as exact seconds, ``'<sec>.<9 digits>'``."""
    return f'{stamp.sec}.{stamp.nanosec:09d}'


def stamp_from_text(text):
    """
    Parse seconds written as ``'<sec>.<fraction>'`` into a builtin_interfaces/Time, exactly.

    A float would lose the last nanoseconds of a stamp near 1.8e9 s. Raises ValueError.
    """
    whole, _, frac = text.strip().partition('.')
    if not whole.isdigit() or (frac and not frac.isdigit()):
        raise ValueError(f'not a time in seconds: {text!r}')
    return Time(sec=int(whole), nanosec=int((frac + '000000000')[:9]))


def stamp_seconds(stamp):
    """Convert a builtin_interfaces/Time to float seconds."""
    return stamp.sec + 1e-9 * stamp.nanosec


class StartupError(Exception):
    """The node cannot run (e.g. the scene's analysis fails); the text says why and the fix."""


def run_node(make_node, prog, args=None):
    """
    Run ``make_node()`` until SIGINT or shutdown; the exit status of the node's executable.

    A bad start-up parameter or a :class:`StartupError` prints ``<prog>: error: <reason>`` to
    stderr and returns 2; otherwise 0.
    """
    try:
        with rclpy.init(args=args):
            try:
                node = make_node()
            except (InvalidParameterValueException, StartupError) as exc:
                print(f'{prog}: error: {exc}', file=sys.stderr)
                return 2
            # Start-up objects (numba, throwmap's analysis) never die: keep them out of the
            # garbage collector's way, so that a collection cannot stall a cycle.
            gc.freeze()
            rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    return 0
