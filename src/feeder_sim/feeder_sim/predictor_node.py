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
predictor_node: the part's state predicted throw by throw, following the driver.

Each completed ``cycle_status`` of the driver (or its stand-in, standin_node) advances the
prediction by one throw of the noise-free map; the node publishes ``predicted/*`` and
``markers``, compares the driver's sensor bits with the predicted ones (``/diagnostics``,
``sensor agreement``) and offers ``~/place_part``.

ROS glue only: the skeleton (scene, parameters, analysis, lifecycle) is feeder_sim.part_node's,
the throw map, the part's state and the analysis throwmap's, the marker geometry
feeder_sim.markers', the contract feeder_common's. Interfaces: docs/interfaces.md;
parameters: docs/nodes.md.
"""

import hashlib
import sys

from feeder_common import qos
from feeder_common.frames import BASE_FRAME, plane_point, plane_quaternion
from feeder_common.messages import (analysis_msg, MAX_SEQ_JUMP, parse_cycle_status,
                                    predicted_state, time_msg)
from feeder_common.node import run_node
from feeder_interfaces.msg import Analysis, CycleStatus, LimitSet, PredictedState
from geometry_msgs.msg import PoseStamped
from std_srvs.srv import Trigger
from throwmap import ThrowmapError
from visualization_msgs.msg import MarkerArray

from .marker_msgs import marker_array
from .markers import state_markers, static_markers
from .params import PREDICTOR_PARAMS
from .part_node import PartNode


class PredictorNode(PartNode):
    """Lifecycle node: predicts the part's state from the driver's cycle reports."""

    PROG = 'predictor_node'
    PARAMS = PREDICTOR_PARAMS
    PART = 'prediction'

    def __init__(self, **kwargs):
        self._sub = None
        self._static_markers = None     # Marker messages that only change with the analysis
        self._markers_timer = None      # re-armed one-shot: sends markers that were due
        self._markers_sent = None       # time of the last markers message
        super().__init__('feeder_sim', **kwargs)
        self._counts.update({'missed': 0, 'agree': 0, 'disagree': 0, 'bad_status': 0,
                             'implausible_jumps': 0})
        self._implausible = None        # the last implausible seq jump (text), for diagnostics
        self._last_followed_seq = None
        self._diagnostics.add('sensor agreement', self._diag_agreement)
        self.create_service(Trigger, '~/place_part', self._on_place_part)

    # ------------------------------------------------------------------ part node hooks
    def _part_options(self, scene):
        # The expected behaviour: the noise-free map (a scene's release_noise draws could
        # never match the real feeder's) and the geometric sensor bit.
        return {'model': scene.model.nominal(), 'noisy_sensor': False, 'seed': None}

    def _create_interface(self):
        pub = self.create_lifecycle_publisher
        self._pubs = {
            'pose': pub(PoseStamped, 'predicted/part_pose', qos.PREDICTION),
            'state': pub(PredictedState, 'predicted/state', qos.PREDICTED_STATE),
            'limit_set': pub(LimitSet, 'predicted/limit_set', qos.PREDICTION_LATCHED),
            'analysis': pub(Analysis, 'predicted/analysis', qos.PREDICTION_LATCHED),
            'markers': pub(MarkerArray, 'markers', qos.MARKERS),
        }
        self._sub = self.create_subscription(CycleStatus, 'cycle_status',
                                             self._on_cycle_status, qos.CYCLE_STATUS)

    def _analysis_changed(self):
        self._static_markers = None
        self._publish_latched()

    def _part_placed(self):
        self._publish_markers()

    def _place_hint(self):
        return ' or call ~/place_part'

    def _release_own(self):
        if self._sub is not None:
            self.destroy_subscription(self._sub)
            self._sub = None
        if self._markers_timer is not None:
            self.destroy_timer(self._markers_timer)
            self._markers_timer = None
        self._static_markers = None

    # ------------------------------------------------------------------ lifecycle
    def on_activate(self, state):
        result = super().on_activate(state)
        self._publish_latched()
        return result

    # ------------------------------------------------------------------ services
    def _on_place_part(self, request, response):
        if self._predictor is None:
            response.success = False
            response.message = f'refused: node is {self.lifecycle_state}, not configured'
            return response
        edge, R = self._place_part()
        response.success = True
        response.message = f'part placed on edge {edge} at R {R:.4f} m'
        return response

    # ------------------------------------------------------------------ following the driver
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
            self.get_logger().warning(f'cycle {seq} failed ({status.reason}): prediction '
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
                self._throw_lost(seq - missed + k, throw)
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

    # ------------------------------------------------------------------ outputs
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
            self._send('pose', pose)
        self._send('state', predicted_state(
            seq, stamp_ns, throw.edge, throw.R if throw.on_arm else None, throw.kind))
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
        self._send('markers', MarkerArray(markers=self._static_markers + state.markers))

    def _flush_markers(self):
        self._markers_timer.cancel()
        if self._predictor is not None:
            # Not forced: the events executor can run a timer's callback once more just after
            # it was re-armed; a flush that is not due re-arms the timer instead of sending.
            self._publish_markers()

    def _publish_latched(self):
        if not self._active:
            return
        analysis = analysis_msg(self._analysis.as_dict(), self._scene.name, self._scene_hash())
        self._send('limit_set', analysis.limit_set)
        self._send('analysis', analysis)
        self._publish_markers(force=True)

    def _scene_hash(self):
        """First 8 bytes of the SHA-256 of the scene's file, as an integer (0: no file)."""
        try:
            with open(self._scene.source, 'rb') as scene_file:
                digest = hashlib.sha256(scene_file.read()).digest()
        except OSError:
            return 0
        return int.from_bytes(digest[:8], 'big')

    # ------------------------------------------------------------------ diagnostics
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


def main(args=None):
    return run_node(PredictorNode, 'predictor_node', args)


if __name__ == '__main__':
    sys.exit(main())
