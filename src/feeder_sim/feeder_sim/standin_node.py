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
standin_node: the hardware, simulated, with exactly the driver's interface.

Run as ``/<ns>/feeder_driver`` (``-r __node:=feeder_driver``) it replaces driver_node and the
controller: topics ``proximity``, ``cycle_status``, ``cycle_fired`` (signed as the driver
signs them), ``joint_states`` at a steady rate, ``/diagnostics``; services
``~/trigger_cycle``, ``~/enable``. The part it throws is simulated (the scene's random effects
seeded), each sensor bit is that part's, and its true state can go to a truth log; a
predictor (predictor_node) runs beside it in the same namespace.

ROS glue only: the skeleton (scene, parameters, analysis, lifecycle) is feeder_sim.part_node's,
the throw map and the part's state throwmap's, the contract feeder_common's. Interfaces:
docs/interfaces.md; parameters: docs/nodes.md.
"""

import math
import sys

from feeder_common import auth, qos
from feeder_common.arm import ArmMotion, stand_in_follow
from feeder_common.messages import CycleSigner, joint_state, proximity
from feeder_common.node import clock_note, RateTimer, run_node, StartupError
from feeder_common.setpoints import SetpointInbox
from feeder_interfaces.msg import CycleStatus, SpeedSetpoint
from sensor_msgs.msg import JointState, Range
from std_srvs.srv import SetBool, Trigger
from throwmap import ThrowmapError

from .params import STANDIN_PARAMS
from .part_node import HARDWARE_ID, PartNode
from .truth import TruthLog, TruthLogError


class StandInNode(PartNode):
    """Lifecycle node: stands in for the driver, throwing a simulated part."""

    PROG = 'standin_node'
    PARAMS = STANDIN_PARAMS
    PART = 'part'

    def __init__(self, **kwargs):
        self._cycle_timer = None
        self._truth = None              # the part's true state, per cycle
        super().__init__('feeder_driver', **kwargs)
        self._joint_timer = RateTimer(self, self._joint_tick)
        self._motion = ArmMotion(wind=0.0)
        try:
            key = auth.node_key(self._param('key_file'))
        except auth.KeyFileError as exc:
            raise StartupError(f'key_file: {exc}') from None
        self._signer = CycleSigner(key, self.get_fully_qualified_name())
        self._inbox = SetpointInbox(key, self.resolve_topic_name(self._param('speed_source')),
                                    self._param('max_setpoint_age'))
        self._setpoint_sub = None
        self._waiting = ''      # why the last cycle could not fire ('' : it could)
        self._diagnostics.add('actuator', self._diag_actuator)
        # Services exist in every lifecycle state so that a refusal can say why.
        self.create_service(Trigger, '~/trigger_cycle', self._on_trigger)
        self.create_service(SetBool, '~/enable', self._on_enable)

    # ------------------------------------------------------------------ part node hooks
    def _part_options(self, scene):
        # The scene's random effects are sampled, seeded: a run is reproducible.
        seed = self._param('seed')
        return {'model': None, 'noisy_sensor': scene.noisy_sensor,
                'seed': seed if seed >= 0 else scene.seed}

    def _configure_own(self):
        truth_log = self._param('truth_log')
        if truth_log:
            try:
                self._truth = TruthLog(truth_log, self._truth_header())
            except TruthLogError as exc:
                return str(exc)
        return None

    def _create_interface(self):
        pub = self.create_lifecycle_publisher
        self._pubs = {
            'proximity': pub(Range, 'proximity', qos.PROXIMITY),
            'cycle_status': pub(CycleStatus, 'cycle_status', qos.CYCLE_STATUS),
            'cycle_fired': pub(CycleStatus, 'cycle_fired', qos.CYCLE_FIRED),
            'joint_states': pub(JointState, 'joint_states', qos.JOINT_STATES),
        }
        self._joint_timer.start(self._param('joint_states_rate'))
        self._setpoint_sub = self.create_subscription(
            SpeedSetpoint, 'release_speed_setpoint', self._on_setpoint,
            qos.RELEASE_SPEED_SETPOINT)

    def _on_setpoint(self, msg):
        why = self._inbox.offer(msg, self.get_clock().now().nanoseconds)
        if why:
            self.get_logger().warning(f'release_speed_setpoint not taken: {why}',
                                      throttle_duration_sec=5.0)

    def _apply_own(self, changes):
        if 'max_setpoint_age' in changes:
            self._inbox.max_age_s = changes['max_setpoint_age']
        if 'joint_states_rate' in changes and 'joint_states' in self._pubs:
            self._joint_timer.start(self._param('joint_states_rate'))
        if 'cycle_period' in changes and self._cycle_timer is not None:
            self._stop_cycling()
            self._start_cycling()

    def _release_own(self):
        if self._setpoint_sub is not None:
            self.destroy_subscription(self._setpoint_sub)
            self._setpoint_sub = None
        self._stop_cycling()
        self._joint_timer.stop()
        if self._truth is not None:
            self._truth.close()
            self._truth = None

    def _truth_header(self):
        sensor, scene = self._analysis.sensor, self._scene
        return {'scene': scene.source, 'goal_edge': sensor.goal_edge,
                'sensor_radius': sensor.radius, 'footprint': sensor.footprint,
                'warmup_throws': sensor.warmup_throws, 'detection_rate': sensor.detection_rate,
                'seed': self._param('seed') if self._param('seed') >= 0 else scene.seed,
                'start': list(self._predictor.state)}

    # ------------------------------------------------------------------ lifecycle
    def on_deactivate(self, state):
        self._stop_cycling()
        return super().on_deactivate(state)

    # ------------------------------------------------------------------ services
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
            response.success = seq is not None
            response.message = (f'refused: {error}' if seq is None else f'fired cycle seq {seq}'
                                + (f' (failed: {error})' if error else ''))
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
        timer = self.create_timer(self._param('cycle_period'), lambda: self._tick(timer))
        self._cycle_timer = timer

    def _tick(self, timer):
        """
        Fire a cycle for ``timer`` if it is still the cycling timer.

        The events executor may run a tick queued just before ``~/enable false`` (or a new
        period) destroyed its timer: that cycle would fire after the answer said which cycle
        was the last, and throw a part the caller has since replaced.
        """
        if timer is self._cycle_timer:
            self._fire()

    def _stop_cycling(self):
        if self._cycle_timer is not None:
            self.destroy_timer(self._cycle_timer)
            self._cycle_timer = None

    # ------------------------------------------------------------------ cycles
    def _setpoint(self):
        """Return (speed rad/s or None, why no cycle): None, '' is the scene's own speed."""
        if self._param('release_speed_mode') != 'setpoint':
            return None, ''
        speed, why = self._inbox.for_cycle(self._seq + 1, self._signer.session,
                                           self.get_clock().now().nanoseconds)
        if speed is None:
            if why != self._waiting:
                self._inbox.counts['waited'] += 1
                self.get_logger().info(f'cycle {self._seq + 1} waits: {why}',
                                       throttle_duration_sec=5.0)
            self._waiting = why
            return None, why
        self._waiting = ''
        return speed, ''

    def _fire(self):
        """
        One cycle: release, throw, catch, sensor sample. Returns (seq, error).

        (None, why) when no cycle was fired: release_speed_mode setpoint and no setpoint for it.
        """
        speed, why = self._setpoint()
        if why:
            return None, why
        if speed is not None:
            self._inbox.used()
        self._seq += 1
        stamp = self.get_clock().now().nanoseconds
        self._send('cycle_fired', self._signer.cycle_fired(self._seq, stamp, HARDWARE_ID))
        commanded = self._scene.release_speed if speed is None else speed
        try:
            throw = self._predictor.throw(release_speed=speed)
        except ThrowmapError as exc:
            self._counts['failed'] += 1
            self._released(stamp, commanded)
            self._send('joint_states', joint_state(stamp, 0.0, 0.0))
            self._send('cycle_status', self._signer.cycle_status(
                self._seq, False, str(exc), None, stamp, HARDWARE_ID, speed))
            if self._truth is not None:
                self._truth.cycle(self._seq, stamp, error=exc, setpoint=speed)
            self.get_logger().error(f'cycle {self._seq} failed: {exc}',
                                    throttle_duration_sec=5.0)
            return self._seq, str(exc)
        # The throw's speed (its release noise included); with no part to throw, the setpoint.
        self._released(stamp, commanded if math.isnan(throw.release_speed)
                       else throw.release_speed)
        self._throw_lost(self._seq, throw)
        self._counts['completed'] += 1
        self._last_throw = throw
        if self._truth is not None:
            self._truth.cycle(self._seq, stamp, throw, self._predictor.sees(), setpoint=speed)
        # proximity and cycle_status back to back: the monitor decides on both.
        self._send('proximity', proximity(stamp, throw.detected, self._param('sensor_range_m'),
                                          self._param('frame_id')))
        self._send('cycle_status', self._signer.cycle_status(
            self._seq, True, '', throw.detected, stamp, HARDWARE_ID, speed))
        self._send('joint_states', joint_state(stamp, 0.0, 0.0))
        return self._seq, None

    def _released(self, stamp, speed):
        """Say the arm released at ``speed`` (joint_states), and swing it from there."""
        self._send('joint_states', joint_state(stamp, 0.0, speed))
        self._motion.released(stamp, speed, follow=stand_in_follow(self._param('cycle_period')))

    def _joint_tick(self):
        """Publish the arm's angle now (the follow-through after a cycle), while active."""
        if self._active and 'joint_states' in self._pubs:
            stamp = self.get_clock().now().nanoseconds
            self._send('joint_states', joint_state(stamp, *self._motion.at(stamp)))

    # ------------------------------------------------------------------ diagnostics
    def _diag_actuator(self, stat):
        c = self._counts
        stat.summary('warn' if c['failed'] else 'ok',
                     'enabled' if self._cycle_timer is not None else 'idle')
        stat.update({'seq': self._seq, 'completed': c['completed'], 'failed': c['failed'],
                     'cycle_period': self._param('cycle_period'),
                     'cycles_per_s': f'{self._rate():.2f}',
                     'release_speed_mode': self._param('release_speed_mode'),
                     'waiting_for_setpoint': self._waiting or 'no',
                     **{f'setpoints_{k}': v for k, v in self._inbox.counts.items()},
                     'last_setpoint_refusal': self._inbox.last_refusal or 'none'})


def main(args=None):
    return run_node(StandInNode, 'standin_node', args)


if __name__ == '__main__':
    sys.exit(main())
