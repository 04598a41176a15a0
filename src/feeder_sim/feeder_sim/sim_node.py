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
sim_node: predicted part states; with ``hardware_mode:=true`` it stands in for the driver.

ROS glue only: the throw map, the part's state (throwmap.PartOnArm) and the analysis are
throwmap's, the marker geometry feeder_sim.markers'. Interfaces: docs/interfaces.md;
parameters: docs/nodes.md.
"""

import functools
import math
import sys

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseStamped
from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn
from sensor_msgs.msg import JointState, Range
from std_msgs.msg import Float64, Float64MultiArray, Int32, MultiArrayDimension, String
from std_srvs.srv import SetBool, Trigger
from throwmap import (analyse, analysis_json, LIMIT_SET_FIELDS, limit_set_rows, load_scene,
                      PartOnArm, scene_analysis, ThrowmapError)
from throwmap.part_on_arm import LOST
from visualization_msgs.msg import MarkerArray

from .markers import state_markers, static_markers
from .params import check_changes, check_start, SIM_PARAMS
from .ros_glue import (CYCLE_STATUS_QOS, declare, DEFAULT_DEPTH, diagnostic_array,
                       diagnostic_status, DIAGNOSTICS_QOS, LATCHED_QOS, marker_array,
                       ParameterGate, run_node, stamp_from_text, stamp_text, StartupError,
                       yaw_quaternion)

FRAME = 'feeder_base'
SENSOR_FRAME = 'feeder_sensor'
JOINT = 'feeder_arm_joint'
HARDWARE_ID = 'sim'


class SimNode(LifecycleNode):
    """Lifecycle node: predicts the part's state; optionally offers the driver's interface."""

    def __init__(self, **kwargs):
        super().__init__('feeder_sim', **kwargs)
        self._specs = {s.name: s for s in SIM_PARAMS}
        # Scenes by path, loaded once (the parameter checks load them too).
        self._load_scene = functools.lru_cache(maxsize=None)(load_scene)
        self._scene = None
        self._active = False
        self._lifecycle = 'unconfigured'
        self._base_analysis = None
        self._analysis = None
        self._predictor = None
        self._pubs = {}
        self._sub = None
        self._cycle_timer = None
        self._last_throw = None
        self._lost_seq = None           # cycle that lost the part off the arm's end
        self._configure_error = None
        self._seq = 0
        self._counts = {'completed': 0, 'failed': 0, 'missed': 0, 'agree': 0, 'disagree': 0,
                        'bad_status': 0}
        self._rate_mark = (0, self.get_clock().now())
        self._last_followed_seq = None
        self._static_markers = None     # Marker messages that only change with the analysis
        self._markers_timer = None      # one-shot: sends markers that were due
        self._markers_sent = None       # time of the last markers message
        ParameterGate(self, self._validate, self._apply)
        autostart = declare(self, self._specs['autostart'])
        self._hardware = declare(self, self._specs['hardware_mode'])
        self._scene = self._load_scene(declare(self, self._specs['scene']))
        edge0, r0 = self._scene.default_start()
        declare(self, self._specs['start_edge'], edge0)
        declare(self, self._specs['start_radius'], r0)
        declare(self, self._specs['sensor_radius'])
        declare(self, self._specs['seed'])
        declare(self, self._specs['sensor_range_m'])
        declare(self, self._specs['cycle_period'])
        declare(self, self._specs['markers_period'])
        period = declare(self, self._specs['diagnostics_period'])

        self._diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', DIAGNOSTICS_QOS)
        self._diag_timer = self.create_timer(period, self._publish_diagnostics)
        if self._hardware:
            self.create_service(Trigger, '~/trigger_cycle', self._on_trigger)
            self.create_service(SetBool, '~/enable', self._on_enable)
        self.create_service(Trigger, '~/place_part', self._on_place_part)
        if autostart:
            if self.trigger_configure() != TransitionCallbackReturn.SUCCESS:
                raise StartupError(self._configure_error or 'configure failed')
            self.trigger_activate()

    # ------------------------------------------------------------------ parameters
    def _value(self, changes, name):
        if name in changes:
            return changes[name]
        return self.get_parameter(name).value if self.has_parameter(name) else None

    def _validate(self, changes):
        """On-set: reasons for rejecting ``changes``; never changes the node's state."""
        reason = check_changes(self._specs, changes, self._load_scene)
        if reason:
            return reason
        if ('start_edge' in changes or 'start_radius' in changes) and self._scene is not None:
            edge = self._value(changes, 'start_edge')
            R = self._value(changes, 'start_radius')
            if edge is not None and R is not None:
                return check_start(self._scene.model, edge, R)
        return None

    def _apply(self, changes):
        """Post-set: apply accepted changes to a configured node."""
        if self._predictor is None:
            return
        if 'start_edge' in changes or 'start_radius' in changes:
            self._place_part()
        if 'sensor_radius' in changes:
            self._analysis = scene_analysis(
                self._scene, changes['sensor_radius'], self._base_analysis)
            self._predictor.sensor_radius = self._analysis.sensor.radius
            self._static_markers = None
            self.get_logger().info(f'sensor at {self._analysis.sensor.radius:.4f} m')
            self._publish_latched()
        if 'cycle_period' in changes and self._cycle_timer is not None:
            self._stop_cycling()
            self._start_cycling()

    def _param(self, name):
        return self.get_parameter(name).value

    def _place_part(self):
        """Restart the prediction with a part at (start_edge, start_radius)."""
        edge, R = self._param('start_edge'), self._param('start_radius')
        self._predictor.place(edge, R)
        self._last_throw = None
        self._lost_seq = None
        self.get_logger().info(f'prediction restarted at edge {edge}, R {R:.4f} m')
        self._publish_markers()
        return edge, R

    def _on_place_part(self, request, response):
        if self._predictor is None:
            response.success = False
            response.message = f'refused: node is {self._lifecycle}, not configured'
            return response
        edge, R = self._place_part()
        response.success = True
        response.message = f'part placed on edge {edge} at R {R:.4f} m'
        return response

    # ------------------------------------------------------------------ lifecycle
    def on_configure(self, state):
        scene = self._scene
        try:
            self._base_analysis = analyse(scene)
            self._analysis = scene_analysis(
                scene, self._param('sensor_radius'), self._base_analysis)
            seed = self._param('seed')
            sensor = self._analysis.sensor
            # Hardware mode samples the scene's random effects (seeded); predictor mode
            # predicts with the noise-free map and the geometric sensor bit.
            self._predictor = PartOnArm(
                scene, self._param('start_edge'), self._param('start_radius'), sensor.radius,
                sensor.footprint,
                model=None if self._hardware else scene.model.nominal(),
                noisy_sensor=self._hardware and scene.noisy_sensor,
                seed=(seed if seed >= 0 else scene.seed) if self._hardware else None)
        except ThrowmapError as exc:
            self._configure_error = f'scene {scene.source}: {exc}'
            self.get_logger().error(f'configure failed: {self._configure_error}')
            return TransitionCallbackReturn.FAILURE
        pub = self.create_lifecycle_publisher
        self._pubs = {
            'pose': pub(PoseStamped, 'predicted/part_pose', DEFAULT_DEPTH),
            'edge': pub(Int32, 'predicted/edge', DEFAULT_DEPTH),
            'kind': pub(String, 'predicted/throw_kind', DEFAULT_DEPTH),
            'radius': pub(Float64, 'predicted/radius', DEFAULT_DEPTH),
            'limit_set': pub(Float64MultiArray, 'predicted/limit_set', LATCHED_QOS),
            'analysis': pub(String, 'predicted/analysis', LATCHED_QOS),
            'markers': pub(MarkerArray, 'markers', LATCHED_QOS),
        }
        if self._hardware:
            self._pubs['proximity'] = pub(Range, 'proximity', DEFAULT_DEPTH)
            self._pubs['cycle_status'] = pub(DiagnosticStatus, 'cycle_status', CYCLE_STATUS_QOS)
            self._pubs['joint_states'] = pub(JointState, 'joint_states', DEFAULT_DEPTH)
        else:
            self._sub = self.create_subscription(DiagnosticStatus, 'cycle_status',
                                                 self._on_cycle_status, CYCLE_STATUS_QOS)
        sensor = self._analysis.sensor
        self.get_logger().info(
            f'{self._scene.name}: limit set {self._analysis.limit_set.signature}, goal edge '
            f'{sensor.goal_edge}, sensor at {sensor.radius:.4f} m (guarantee '
            f'{sensor.guarantee_radius:.4f} m), start {self._predictor.state}')
        self._lifecycle = 'inactive'
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state):
        result = super().on_activate(state)
        self._active = True
        self._lifecycle = 'active'
        self._publish_latched()
        return result

    def on_deactivate(self, state):
        self._stop_cycling()
        self._active = False
        self._lifecycle = 'inactive'
        return super().on_deactivate(state)

    def on_cleanup(self, state):
        self._release()
        self._lifecycle = 'unconfigured'
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state):
        self._stop_cycling()
        self._active = False
        self._release()
        self._lifecycle = 'finalized'
        return TransitionCallbackReturn.SUCCESS

    def _release(self):
        for p in self._pubs.values():
            self.destroy_lifecycle_publisher(p)
        self._pubs = {}
        if self._sub is not None:
            self.destroy_subscription(self._sub)
            self._sub = None
        self._predictor = None
        self._analysis = None
        self._static_markers = None

    # ------------------------------------------------------------------ hardware mode
    def _on_trigger(self, request, response):
        if not self._active:
            response.success = False
            response.message = f'refused: node is {self._lifecycle}, not active'
        elif self._cycle_timer is not None:
            response.success = False
            response.message = 'refused: enabled (cycling continuously); call ~/enable false first'
        else:
            seq, error = self._fire()
            response.success = True
            response.message = f'fired cycle seq {seq}' + (f' (failed: {error})' if error else '')
        return response

    def _on_enable(self, request, response):
        if request.data:
            if not self._active:
                response.success = False
                response.message = f'refused: node is {self._lifecycle}, not active'
                return response
            if self._cycle_timer is None:
                self._start_cycling()
            response.success = True
            response.message = f'enabled: one cycle every {self._param("cycle_period")} s'
        else:
            self._stop_cycling()
            response.success = True
            response.message = f'disabled after seq {self._seq}'
        return response

    def _start_cycling(self):
        self._cycle_timer = self.create_timer(self._param('cycle_period'), self._fire)

    def _stop_cycling(self):
        if self._cycle_timer is not None:
            self.destroy_timer(self._cycle_timer)
            self._cycle_timer = None

    def _fire(self):
        """One cycle: release, throw (prediction), catch, sensor sample. Returns (seq, error)."""
        self._seq += 1
        stamp = self.get_clock().now().to_msg()
        self._publish_joint(stamp, self._scene.release_speed)
        try:
            throw = self._predictor.throw()
        except ThrowmapError as exc:
            self._counts['failed'] += 1
            self._publish_joint(stamp, 0.0)
            self._pubs['cycle_status'].publish(self._cycle_status(stamp, False, str(exc), 'none'))
            self.get_logger().error(f'cycle {self._seq} failed: {exc}',
                                    throttle_duration_sec=5.0)
            return self._seq, str(exc)
        if throw.kind == LOST and throw.count == self._predictor.lost_at:
            self._report_lost(self._seq, throw)
        self._counts['completed'] += 1
        self._publish_joint(stamp, 0.0)
        rng = Range()
        rng.header.stamp = stamp
        rng.header.frame_id = SENSOR_FRAME
        rng.radiation_type = Range.INFRARED
        rng.field_of_view = 0.0
        rng.min_range = rng.max_range = float(self._param('sensor_range_m'))
        rng.range = float('-inf') if throw.detected else float('inf')
        status = self._cycle_status(stamp, True, 'completed', '1' if throw.detected else '0')
        self._pubs['proximity'].publish(rng)        # back to back: the monitor needs both
        self._pubs['cycle_status'].publish(status)
        self._publish_prediction(stamp, throw)
        return self._seq, None

    def _cycle_status(self, stamp, ok, message, sensor):
        return DiagnosticStatus(
            level=DiagnosticStatus.OK if ok else DiagnosticStatus.ERROR, name='cycle',
            message=message, hardware_id=HARDWARE_ID,
            values=[KeyValue(key='seq', value=str(self._seq)),
                    KeyValue(key='sensor', value=sensor),
                    KeyValue(key='stamp', value=stamp_text(stamp))])

    def _publish_joint(self, stamp, velocity):
        js = JointState()
        js.header.stamp = stamp
        js.name = [JOINT]
        js.position = [0.0]
        js.velocity = [float(velocity)]
        js.effort = []
        self._pubs['joint_states'].publish(js)

    # ------------------------------------------------------------------ predictor mode
    def _on_cycle_status(self, msg):
        if not self._active:
            return
        values = {kv.key: kv.value for kv in msg.values}
        try:
            seq = int(values['seq'])
        except (KeyError, ValueError):
            self._counts['bad_status'] += 1
            self.get_logger().warning(f'cycle_status without a valid seq: {values}',
                                      throttle_duration_sec=5.0)
            return
        last = self._last_followed_seq
        self._last_followed_seq = seq
        self._seq = seq
        if msg.level != DiagnosticStatus.OK:
            self._counts['failed'] += 1
            self.get_logger().warning(f'cycle {seq} failed ({msg.message}): prediction kept; '
                                      'the part may have moved', throttle_duration_sec=5.0)
            return
        missed = seq - last - 1 if last is not None and seq > last + 1 else 0
        self._counts['missed'] += missed
        try:
            for k in range(missed + 1):
                throw = self._predictor.throw()
                if throw.kind == LOST and throw.count == self._predictor.lost_at:
                    self._report_lost(seq - missed + k, throw)
        except ThrowmapError as exc:
            self.get_logger().error(f'prediction stopped at cycle {seq}: {exc}',
                                    throttle_duration_sec=5.0)
            return
        self._counts['completed'] += 1
        sensor = values.get('sensor')
        if sensor in ('0', '1'):
            self._counts['agree' if (sensor == '1') == throw.detected else 'disagree'] += 1
        try:
            stamp = stamp_from_text(values['stamp'])
        except (KeyError, ValueError):
            stamp = self.get_clock().now().to_msg()
        self._publish_prediction(stamp, throw)

    def _report_lost(self, seq, throw):
        self._lost_seq = seq
        self.get_logger().error(
            f"part lost off the arm's end at cycle {seq} (thrown from edge {throw.edge0} at R "
            f'{throw.R0:.4f} m; arm length {self._scene.arm_length:g} m); set start_edge / '
            'start_radius or call ~/place_part when a part is back on the arm')

    # ------------------------------------------------------------------ outputs
    def _publish_prediction(self, stamp, throw):
        """Publish the state after ``throw``; without a part on the arm only edge -1 and kind."""
        self._last_throw = throw
        if throw.on_arm:
            x, y, yaw = self._predictor.pose()
            pose = PoseStamped()
            pose.header.stamp = stamp
            pose.header.frame_id = FRAME
            pose.pose.position.x, pose.pose.position.y = x, y
            q = pose.pose.orientation
            q.x, q.y, q.z, q.w = yaw_quaternion(yaw)
            self._pubs['pose'].publish(pose)
        self._pubs['edge'].publish(Int32(data=throw.edge))
        self._pubs['kind'].publish(String(data=throw.kind))
        if throw.on_arm:
            self._pubs['radius'].publish(Float64(data=throw.R))
        self._publish_markers(stamp)

    def _publish_markers(self, stamp=None, force=False):
        """Publish the markers now, or once markers_period has passed since the last ones."""
        if not self._active:
            return
        now = self.get_clock().now()
        period = self._param('markers_period')
        wait = 0.0 if force or self._markers_sent is None else \
            period - (now - self._markers_sent).nanoseconds * 1e-9
        if wait > 0.0:
            if self._markers_timer is None:
                self._markers_timer = self.create_timer(wait, self._flush_markers)
            return
        self._markers_sent = now
        stamp = stamp or now.to_msg()
        radius = self._analysis.sensor.radius
        if self._static_markers is None:
            self._static_markers = marker_array(
                static_markers(self._scene, self._analysis, radius), FRAME, stamp).markers
        edge, R = self._predictor.state
        detected = self._last_throw.detected if self._last_throw is not None else \
            self._predictor.sees(edge, R)
        state = marker_array(state_markers(self._scene, self._analysis, radius, edge, R,
                                           detected), FRAME, stamp)
        self._pubs['markers'].publish(MarkerArray(markers=self._static_markers + state.markers))

    def _flush_markers(self):
        self.destroy_timer(self._markers_timer)
        self._markers_timer = None
        if self._predictor is not None:
            self._publish_markers(force=True)

    def _publish_latched(self):
        if not self._active:
            return
        rows = limit_set_rows(self._analysis.limit_set)
        fields = len(LIMIT_SET_FIELDS)
        msg = Float64MultiArray()
        msg.layout.dim = [
            MultiArrayDimension(label='edges', size=len(rows), stride=len(rows) * fields),
            MultiArrayDimension(label='fields', size=fields, stride=fields)]
        msg.data = [v for row in rows for v in row]
        self._pubs['limit_set'].publish(msg)
        self._pubs['analysis'].publish(
            String(data=analysis_json(self._analysis)))
        self._publish_markers(force=True)

    def _publish_diagnostics(self):
        name = self.get_name()
        now = self.get_clock().now()
        statuses = [diagnostic_status(
            f'{name}: lifecycle', 'ok' if self._active else 'warn', self._lifecycle,
            HARDWARE_ID, {'hardware_mode': self._hardware, 'scene': self._scene.source})]
        if self._predictor is not None:
            statuses.append(self._prediction_status(name))
        c = self._counts
        done, mark_time = self._rate_mark
        total = c['completed'] + c['failed']
        dt = (now - mark_time).nanoseconds * 1e-9
        rate = (total - done) / dt if dt > 0 else 0.0
        self._rate_mark = (total, now)
        if self._hardware:
            level = 'warn' if c['failed'] else 'ok'
            msg = 'enabled' if self._cycle_timer is not None else 'idle'
            statuses.append(diagnostic_status(
                f'{name}: actuator', level, msg, HARDWARE_ID,
                {'seq': self._seq, 'completed': c['completed'], 'failed': c['failed'],
                 'cycle_period': self._param('cycle_period'), 'cycles_per_s': f'{rate:.2f}'}))
        else:
            bad = c['disagree'] or c['missed'] or c['failed'] or c['bad_status']
            msg = (f'{c["agree"]} of {c["agree"] + c["disagree"]} sensor bits as predicted'
                   if c['agree'] + c['disagree'] else 'no cycle followed yet')
            statuses.append(diagnostic_status(
                f'{name}: sensor agreement', 'warn' if bad else 'ok', msg, HARDWARE_ID,
                {'last_seq': self._seq, 'followed': c['completed'], 'missed': c['missed'],
                 'failed': c['failed'], 'agree': c['agree'], 'disagree': c['disagree'],
                 'bad_status': c['bad_status'], 'cycles_per_s': f'{rate:.2f}'}))
        self._diag_pub.publish(diagnostic_array(now.to_msg(), statuses))

    def _prediction_status(self, name):
        pred = self._predictor
        edge, R = pred.state
        an = self._analysis
        values = {'edge': edge, 'R': 'none' if pred.lost else f'{R:.6f}',
                  'throws': pred.count,
                  'last_kind': self._last_throw.kind if self._last_throw else 'none',
                  'in_limit_set': not pred.lost and an.limit_set.contains(edge, R),
                  'goal_edge': an.sensor.goal_edge, 'sensor_radius': f'{an.sensor.radius:.6f}',
                  'guarantee_radius': f'{an.sensor.guarantee_radius:.6f}',
                  'warmup_throws': an.sensor.warmup_throws,
                  'noisy_sensor': pred.noisy_sensor,
                  'arm_length': f'{self._scene.arm_length:.6f}'
                  if self._scene.arm_length is not None and math.isfinite(self._scene.arm_length)
                  else 'unbounded'}
        if pred.lost:
            values['lost_at_seq'] = self._lost_seq
            return diagnostic_status(f'{name}: prediction', 'error',
                                     f"part lost off the arm's end at cycle {self._lost_seq}",
                                     HARDWARE_ID, values)
        return diagnostic_status(f'{name}: prediction', 'ok',
                                 f'edge {edge}, R {100 * R:.2f} cm after {pred.count} throws',
                                 HARDWARE_ID, values)


def main(args=None):
    return run_node(SimNode, 'sim_node', args)


if __name__ == '__main__':
    sys.exit(main())
