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
sim_node: the predictor of the part's state, or (``hardware_mode:=true``) the hardware itself.

* Predictor mode follows the driver's ``cycle_status`` and publishes ``predicted/*`` and
  ``markers``.
* Hardware mode stands in for the driver with exactly the driver's interface (topics
  ``proximity``, ``cycle_status``, ``joint_states``, ``/diagnostics``; services
  ``~/trigger_cycle``, ``~/enable``): the part it throws is simulated, so a predictor can run
  beside it in the same namespace.

ROS glue only: the throw map, the part's state (throwmap.PartOnArm) and the analysis are
throwmap's, the marker geometry feeder_sim.markers', the contract (QoS, messages, frames,
parameters, run helper) feeder_common's. Interfaces: docs/interfaces.md; parameters: docs/nodes.md.
"""

import functools
import math
import sys

from diagnostic_msgs.msg import DiagnosticStatus
from feeder_common import auth, qos
from feeder_common.arm import ArmMotion, stand_in_follow
from feeder_common.diagnostics import Updater
from feeder_common.frames import BASE_FRAME, plane_point, plane_quaternion
from feeder_common.messages import (CycleSigner, joint_state, MAX_SEQ_JUMP, parse_cycle_status,
                                    predicted_state, proximity, time_msg)
from feeder_common.node import (clock_note, FeederLifecycleNode, RateTimer, run_node,
                                StartupError)
from feeder_common.parameters import ParameterGate
from geometry_msgs.msg import PoseStamped
from rclpy.lifecycle import TransitionCallbackReturn
from sensor_msgs.msg import JointState, Range
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, String
from std_srvs.srv import SetBool, Trigger
from throwmap import (analyse, analysis_json, LIMIT_SET_FIELDS, limit_set_rows, load_scene,
                      PartOnArm, scene_analysis, ThrowmapError)
from throwmap.part_on_arm import LOST
from visualization_msgs.msg import MarkerArray

from .marker_msgs import marker_array
from .markers import state_markers, static_markers
from .params import check_changes, check_start, SIM_PARAMS
from .truth import TruthLog, TruthLogError

HARDWARE_ID = 'sim'


class SimNode(FeederLifecycleNode):
    """Lifecycle node: predicts the part's state, or stands in for the driver."""

    def __init__(self, **kwargs):
        super().__init__('feeder_sim', **kwargs)
        # Scenes by path, loaded once (the parameter checks load them too).
        self._load_scene = functools.lru_cache(maxsize=None)(load_scene)
        self._scene = None
        self._active = False
        self._base_analysis = None
        self._analysis = None
        self._predictor = None
        self._truth = None              # hardware mode: the part's true state, per cycle
        self._pubs = {}
        self._sub = None
        self._cycle_timer = None
        self._joint_timer = RateTimer(self, self._joint_tick)  # hardware mode
        self._motion = ArmMotion(wind=0.0)
        self._last_throw = None
        self._lost_seq = None           # cycle that lost the part off the arm's end
        self._seq = 0
        self._counts = {'completed': 0, 'failed': 0, 'missed': 0, 'agree': 0, 'disagree': 0,
                        'bad_status': 0, 'implausible_jumps': 0}
        self._implausible = None        # the last implausible seq jump (text), for diagnostics
        self._rate_mark = (0, self.get_clock().now())
        self._last_followed_seq = None
        self._static_markers = None     # Marker messages that only change with the analysis
        self._markers_timer = None      # re-armed one-shot: sends markers that were due
        self._markers_sent = None       # time of the last markers message
        self._params = ParameterGate(self, SIM_PARAMS, self._validate, self._apply)
        p = self._params
        p.declare_all(names=('autostart', 'hardware_mode', 'scene'))
        self._hardware = p.values['hardware_mode']
        self._scene = self._load_scene(p.values['scene'])
        edge0, r0 = self._scene.default_start()
        p.declare_all(defaults={'start_edge': edge0, 'start_radius': r0})
        for name in p.unknown_given():
            self.get_logger().warning(f'parameter {name} is not a parameter of sim_node; '
                                      'ignored (docs/nodes.md lists them)')
        self._signer = None
        if self._hardware:
            try:
                self._signer = CycleSigner(auth.node_key(p.values['key_file']),
                                           self.get_fully_qualified_name())
            except auth.KeyFileError as exc:
                raise StartupError(f'key_file: {exc}') from None

        self._diagnostics = Updater(self, p.values['diagnostic_updater.period'], HARDWARE_ID)
        self._diagnostics.add('lifecycle', self._diag_lifecycle)
        self._diagnostics.add('prediction', self._diag_prediction)
        if self._hardware:
            self._diagnostics.add('actuator', self._diag_actuator)
            # Services exist in every lifecycle state so that a refusal can say why.
            self.create_service(Trigger, '~/trigger_cycle', self._on_trigger)
            self.create_service(SetBool, '~/enable', self._on_enable)
        else:
            self._diagnostics.add('sensor agreement', self._diag_agreement)
            self.create_service(Trigger, '~/place_part', self._on_place_part)

    # ------------------------------------------------------------------ parameters
    def _validate(self, changes, current):
        """On-set: the reason to reject ``changes``; never changes the node's state."""
        reason = check_changes(changes, self._load_scene, current)
        if reason:
            return reason
        if ('start_edge' in changes or 'start_radius' in changes) and self._scene is not None:
            edge = changes.get('start_edge', current.get('start_edge'))
            R = changes.get('start_radius', current.get('start_radius'))
            if edge is not None and R is not None:
                return check_start(self._scene.model, edge, R)
        return None

    def _apply(self, changes):
        """Post-set: apply accepted changes."""
        if 'diagnostic_updater.period' in changes:
            self._diagnostics.set_period(changes['diagnostic_updater.period'])
        if 'joint_states_rate' in changes and 'joint_states' in self._pubs:
            self._joint_timer.start(self._param('joint_states_rate'))
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
        return self._params.values[name]

    def _place_part(self):
        """Restart the part (hardware mode) or the prediction at (start_edge, start_radius)."""
        edge, R = self._param('start_edge'), self._param('start_radius')
        self._predictor.place(edge, R)
        self._last_throw = None
        self._lost_seq = None
        what = 'part' if self._hardware else 'prediction'
        self.get_logger().info(f'{what} restarted at edge {edge}, R {R:.4f} m')
        self._publish_markers()
        return edge, R

    def _on_place_part(self, request, response):
        if self._predictor is None:
            response.success = False
            response.message = f'refused: node is {self.lifecycle_state}, not configured'
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
            self.configure_error = f'scene {scene.source}: {exc}'
            self.get_logger().error(f'configure failed: {self.configure_error}')
            return TransitionCallbackReturn.FAILURE
        truth_log = self._param('truth_log')
        if truth_log:
            try:
                if not self._hardware:
                    raise TruthLogError(f'truth_log {truth_log!r}: only hardware mode has a '
                                        "true part; set hardware_mode:=true or truth_log:=''")
                self._truth = TruthLog(truth_log, self._truth_header())
            except TruthLogError as exc:
                self.configure_error = str(exc)
                self.get_logger().error(f'configure failed: {exc}')
                return TransitionCallbackReturn.FAILURE
        pub = self.create_lifecycle_publisher
        if self._hardware:
            self._pubs = {
                'proximity': pub(Range, 'proximity', qos.PROXIMITY),
                'cycle_status': pub(DiagnosticStatus, 'cycle_status', qos.CYCLE_STATUS),
                'cycle_fired': pub(DiagnosticStatus, 'cycle_fired', qos.CYCLE_FIRED),
                'joint_states': pub(JointState, 'joint_states', qos.JOINT_STATES),
            }
            self._joint_timer.start(self._param('joint_states_rate'))
        else:
            self._pubs = {
                'pose': pub(PoseStamped, 'predicted/part_pose', qos.PREDICTION),
                'state': pub(DiagnosticStatus, 'predicted/state', qos.PREDICTED_STATE),
                'limit_set': pub(Float64MultiArray, 'predicted/limit_set',
                                 qos.PREDICTION_LATCHED),
                'analysis': pub(String, 'predicted/analysis', qos.PREDICTION_LATCHED),
                'markers': pub(MarkerArray, 'markers', qos.MARKERS),
            }
            self._sub = self.create_subscription(DiagnosticStatus, 'cycle_status',
                                                 self._on_cycle_status, qos.CYCLE_STATUS)
        sensor = self._analysis.sensor
        self.get_logger().info(
            f'{self._scene.name}: limit set {self._analysis.limit_set.signature}, goal edge '
            f'{sensor.goal_edge}, sensor at {sensor.radius:.4f} m (guarantee '
            f'{sensor.guarantee_radius:.4f} m), start {self._predictor.state}')
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state):
        result = super().on_activate(state)
        self._active = True
        self._publish_latched()
        return result

    def on_deactivate(self, state):
        self._stop_cycling()
        self._active = False
        return super().on_deactivate(state)

    def on_cleanup(self, state):
        self._release()
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state):
        self._stop_cycling()
        self._active = False
        self._release()
        return TransitionCallbackReturn.SUCCESS

    def _release(self):
        self._joint_timer.stop()
        for p in self._pubs.values():
            self.destroy_lifecycle_publisher(p)
        self._pubs = {}
        if self._sub is not None:
            self.destroy_subscription(self._sub)
            self._sub = None
        if self._markers_timer is not None:
            self.destroy_timer(self._markers_timer)
            self._markers_timer = None
        self._predictor = None
        self._analysis = None
        self._static_markers = None
        if self._truth is not None:
            self._truth.close()
            self._truth = None

    # ------------------------------------------------------------------ hardware mode
    def _truth_header(self):
        sensor, scene = self._analysis.sensor, self._scene
        return {'scene': scene.source, 'goal_edge': sensor.goal_edge,
                'sensor_radius': sensor.radius, 'footprint': sensor.footprint,
                'warmup_throws': sensor.warmup_throws, 'detection_rate': sensor.detection_rate,
                'seed': self._param('seed') if self._param('seed') >= 0 else scene.seed,
                'start': list(self._predictor.state)}

    def _refusal(self):
        return (f'refused: node is {self.lifecycle_state}, not active (ros2 lifecycle set '
                f'{self.get_fully_qualified_name()} activate, or start it with '
                'autostart:=true)')

    def _on_trigger(self, request, response):
        if not self._active:
            response.success = False
            response.message = self._refusal()
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
                response.message = self._refusal()
                return response
            if self._cycle_timer is None:
                self._start_cycling()
            response.success = True
            response.message = (f'enabled: one cycle every {self._param("cycle_period")} s'
                                + clock_note(self))
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
        """One cycle: release, throw, catch, sensor sample. Returns (seq, error)."""
        self._seq += 1
        stamp = self.get_clock().now().nanoseconds
        pubs = self._pubs
        pubs['cycle_fired'].publish(self._signer.cycle_fired(self._seq, stamp, HARDWARE_ID))
        pubs['joint_states'].publish(joint_state(stamp, 0.0, self._scene.release_speed))
        self._motion.released(stamp, self._scene.release_speed,
                              follow=stand_in_follow(self._param('cycle_period')))
        try:
            throw = self._predictor.throw()
        except ThrowmapError as exc:
            self._counts['failed'] += 1
            pubs['joint_states'].publish(joint_state(stamp, 0.0, 0.0))
            pubs['cycle_status'].publish(self._signer.cycle_status(
                self._seq, False, str(exc), None, stamp, HARDWARE_ID))
            if self._truth is not None:
                self._truth.cycle(self._seq, stamp, error=exc)
            self.get_logger().error(f'cycle {self._seq} failed: {exc}',
                                    throttle_duration_sec=5.0)
            return self._seq, str(exc)
        if throw.kind == LOST and throw.count == self._predictor.lost_at:
            self._report_lost(self._seq, throw)
        self._counts['completed'] += 1
        self._last_throw = throw
        if self._truth is not None:
            self._truth.cycle(self._seq, stamp, throw, self._predictor.sees())
        # proximity and cycle_status back to back: the monitor decides on both.
        pubs['proximity'].publish(proximity(stamp, throw.detected,
                                            self._param('sensor_range_m'),
                                            self._param('frame_id')))
        pubs['cycle_status'].publish(self._signer.cycle_status(
            self._seq, True, 'completed', throw.detected, stamp, HARDWARE_ID))
        pubs['joint_states'].publish(joint_state(stamp, 0.0, 0.0))
        return self._seq, None

    def _joint_tick(self):
        """Publish the arm's angle now (the follow-through after a cycle), while active."""
        if self._active and 'joint_states' in self._pubs:
            stamp = self.get_clock().now().nanoseconds
            self._pubs['joint_states'].publish(joint_state(stamp, *self._motion.at(stamp)))

    # ------------------------------------------------------------------ predictor mode
    def _on_cycle_status(self, msg):
        if not self._active:
            return
        try:
            status = parse_cycle_status(msg)
        except ValueError as exc:
            self._counts['bad_status'] += 1
            self.get_logger().warning(f'{exc}; ignored', throttle_duration_sec=5.0)
            return
        seq = status.seq
        last = self._last_followed_seq
        self._last_followed_seq = seq
        self._seq = seq
        if not status.ok:
            self._counts['failed'] += 1
            self.get_logger().warning(f'cycle {seq} failed ({status.message}): prediction '
                                      'kept; the part may have moved', throttle_duration_sec=5.0)
            return
        missed = seq - last - 1 if last is not None and seq > last + 1 else 0
        if missed > MAX_SEQ_JUMP:
            # Replaying them would take (for seq 2**70) forever: an anomaly, not a catch-up.
            # The prediction stays where it was; the next cycles are followed from this seq.
            self._counts['implausible_jumps'] += 1
            self._implausible = (f'seq jumped from {last} to {seq} ({missed} cycles unseen, '
                                 f'more than the {MAX_SEQ_JUMP} a prediction replays): '
                                 'prediction not advanced; place_part or a restart resyncs it')
            self.get_logger().error(self._implausible, throttle_duration_sec=5.0)
            return
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
        if status.sensor is not None:
            self._counts['agree' if status.sensor == throw.detected else 'disagree'] += 1
        stamp = status.stamp_ns if status.stamp_ns is not None else \
            self.get_clock().now().nanoseconds
        self._publish_prediction(seq, stamp, throw)

    def _report_lost(self, seq, throw):
        self._lost_seq = seq
        self.get_logger().error(
            f"part lost off the arm's end at cycle {seq} (thrown from edge {throw.edge0} at R "
            f'{throw.R0:.4f} m; arm length {self._scene.arm_length:g} m); set start_edge / '
            'start_radius' + ('' if self._hardware else ' or call ~/place_part') +
            ' when a part is back on the arm')

    # ------------------------------------------------------------------ outputs (predictor)
    def _publish_prediction(self, seq, stamp_ns, throw):
        """Publish the state after cycle ``seq``; without a part on the arm, no pose."""
        self._last_throw = throw
        stamp = time_msg(stamp_ns)
        if throw.on_arm:
            x, y, angle = self._predictor.pose()
            pose = PoseStamped()
            pose.header.stamp = stamp
            pose.header.frame_id = BASE_FRAME
            p = pose.pose.position
            p.x, p.y, p.z = plane_point(x, y)
            q = pose.pose.orientation
            q.x, q.y, q.z, q.w = plane_quaternion(angle)
            self._pubs['pose'].publish(pose)
        self._pubs['state'].publish(predicted_state(
            seq, stamp_ns, throw.edge, throw.R if throw.on_arm else None, throw.kind))
        self._publish_markers(stamp)

    def _publish_markers(self, stamp=None, force=False):
        """Publish the markers now, or once markers_period has passed since the last ones."""
        if not self._active or self._hardware:
            return
        now = self.get_clock().now()
        period = self._param('markers_period')
        wait = 0.0 if force or self._markers_sent is None else \
            period - (now - self._markers_sent).nanoseconds * 1e-9
        if wait > 0.0:
            # One timer per activation, re-armed for each wait: rclpy's callback group keeps a
            # dead reference to every timer ever created, so a timer per wait (10 per second
            # while cycling fast) grew the predictor by 5 KB per 1000 cycles (bench/mem_trace.py).
            # Re-armed, it fires one markers_period after the first state that had to wait:
            # still within a period of that state, and never sooner than a period after the
            # last markers.
            timer = self._markers_timer
            if timer is None:
                self._markers_timer = self.create_timer(period, self._flush_markers)
            elif timer.is_canceled():
                if timer.timer_period_ns != int(period * 1e9):
                    timer.timer_period_ns = int(period * 1e9)
                timer.reset()
            return
        self._markers_sent = now
        stamp = stamp or now.to_msg()
        radius = self._analysis.sensor.radius
        if self._static_markers is None:
            self._static_markers = marker_array(
                static_markers(self._scene, self._analysis, radius), BASE_FRAME, stamp).markers
        edge, R = self._predictor.state
        detected = self._last_throw.detected if self._last_throw is not None else \
            self._predictor.sees(edge, R)
        state = marker_array(state_markers(self._scene, self._analysis, radius, edge, R,
                                           detected), BASE_FRAME, stamp)
        self._pubs['markers'].publish(MarkerArray(markers=self._static_markers + state.markers))

    def _flush_markers(self):
        self._markers_timer.cancel()
        if self._predictor is not None:
            # Not forced: the events executor can run a timer's callback once more just after
            # it was re-armed; a flush that is not due re-arms the timer instead of sending.
            self._publish_markers()

    def _publish_latched(self):
        if not self._active or self._hardware:
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

    # ------------------------------------------------------------------ diagnostics
    def _rate(self):
        now = self.get_clock().now()
        done, mark_time = self._rate_mark
        total = self._counts['completed'] + self._counts['failed']
        dt = (now - mark_time).nanoseconds * 1e-9
        self._rate_mark = (total, now)
        return (total - done) / dt if dt > 0 else 0.0

    def _diag_lifecycle(self, stat):
        stat.summary('ok' if self._active else 'warn', self.lifecycle_state)
        stat.update({'hardware_mode': self._hardware, 'scene': self._scene.source,
                     'namespace': self.get_namespace()})

    def _diag_actuator(self, stat):
        c = self._counts
        stat.summary('warn' if c['failed'] else 'ok',
                     'enabled' if self._cycle_timer is not None else 'idle')
        stat.update({'seq': self._seq, 'completed': c['completed'], 'failed': c['failed'],
                     'cycle_period': self._param('cycle_period'),
                     'cycles_per_s': f'{self._rate():.2f}'})

    def _diag_agreement(self, stat):
        c = self._counts
        bad = c['disagree'] or c['missed'] or c['failed'] or c['bad_status']
        msg = (f'{c["agree"]} of {c["agree"] + c["disagree"]} sensor bits as predicted'
               if c['agree'] + c['disagree'] else 'no cycle followed yet')
        if self._implausible:
            stat.summary('error', self._implausible)
            self._implausible = None
        else:
            stat.summary('warn' if bad else 'ok', msg)
        stat.update({'last_seq': self._seq, 'followed': c['completed'], 'missed': c['missed'],
                     'failed': c['failed'], 'agree': c['agree'], 'disagree': c['disagree'],
                     'bad_status': c['bad_status'],
                     'implausible_jumps': c['implausible_jumps'],
                     'cycles_per_s': f'{self._rate():.2f}'})

    def _diag_prediction(self, stat):
        pred = self._predictor
        if pred is None:
            stat.summary('warn', f'{self.lifecycle_state}: no prediction')
            return
        edge, R = pred.state
        an = self._analysis
        arm = self._scene.arm_length
        stat.update({
            'edge': edge, 'R': 'none' if pred.lost else f'{R:.6f}', 'throws': pred.count,
            'last_kind': self._last_throw.kind if self._last_throw else 'none',
            'in_limit_set': not pred.lost and an.limit_set.contains(edge, R),
            'goal_edge': an.sensor.goal_edge, 'sensor_radius': f'{an.sensor.radius:.6f}',
            'guarantee_radius': f'{an.sensor.guarantee_radius:.6f}',
            'warmup_throws': an.sensor.warmup_throws, 'noisy_sensor': pred.noisy_sensor,
            'arm_length': f'{arm:.6f}' if arm is not None and math.isfinite(arm)
            else 'unbounded'})
        if pred.lost:
            stat.add('lost_at_seq', self._lost_seq)
            stat.summary('error', f"part lost off the arm's end at cycle {self._lost_seq}")
        else:
            stat.summary('ok', f'edge {edge}, R {100 * R:.2f} cm after {pred.count} throws')


def main(args=None):
    return run_node(SimNode, 'sim_node', args)


if __name__ == '__main__':
    sys.exit(main())
