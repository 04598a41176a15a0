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
Lifecycle driver node of the feeder controller (docs/driver.md, docs/interfaces.md).

Thin ROS glue around :mod:`feeder_driver.core` (link and cycle state machine),
:mod:`feeder_driver.serial_link` (pyserial port and reader thread) and
:mod:`feeder_driver.protocol`; the contract (QoS, message builders, parameters, diagnostics,
the run helper) is feeder_common's. The reader thread queues decoded events and hands the
executor a task to drain them (thread-safe in every executor); everything else (writes,
timeouts, publishing) runs on the executor thread, and no callback blocks longer than one
serial write.
"""

import queue
import sys
import time

from diagnostic_msgs.msg import DiagnosticStatus
from feeder_common import auth, qos
from feeder_common.arm import ArmMotion
from feeder_common.diagnostics import Updater
from feeder_common.messages import CycleSigner, joint_state, proximity
from feeder_common.node import (clock_note, FeederLifecycleNode, flush, publish, RateTimer,
                                run_node, StartupError)
from feeder_common.parameters import ParameterGate
from feeder_common.setpoints import SetpointInbox
from feeder_interfaces.msg import CycleStatus, SpeedSetpoint
from rclpy.lifecycle import TransitionCallbackReturn
from sensor_msgs.msg import JointState, Range
from std_srvs.srv import SetBool, Trigger

from . import core as c
from . import params
from . import protocol
from .serial_link import LinkError, SerialLink

# Timeouts and continuous cycling are checked on a timer: 50 Hz, faster for short periods.
TICK_PERIOD_S = 0.02
MIN_TICK_PERIOD_S = 0.005


class DriverNode(FeederLifecycleNode):
    """Owns the serial link to the feeder controller and runs throw-catch cycles."""

    def __init__(self, node_name='feeder_driver', **kwargs):
        # Set before Node.__init__: a context shutdown may destroy a half-built node.
        self.core = self.link = self.diagnostics = None
        self._tick_timer = None
        self._pub_prox = self._pub_status = self._pub_joint = self._pub_fired = None
        # The arm between cycle events, for joint_states at joint_states_rate.
        self._motion = ArmMotion()
        super().__init__(node_name, **kwargs)
        self._joint_timer = RateTimer(self, self._joint_tick)
        self._params = ParameterGate(self, params.SPECS, params.validate,
                                     self._apply_parameters)
        self._params.declare_all()
        self._params.check_startup()
        self._p = self._params.values
        try:
            key = auth.node_key(self._p['key_file'])
        except auth.KeyFileError as exc:
            raise StartupError(f'key_file: {exc}') from None
        # One session per process: a restarted driver is a new run to the monitor.
        self._signer = CycleSigner(key, self.get_fully_qualified_name())
        # Release-speed setpoints (release_speed_mode setpoint): which one, if any, a cycle is
        # fired at is feeder_common.setpoints'; the core holds it and puts it in the FIRE.
        self._inbox = SetpointInbox(key, self.resolve_topic_name(self._p['speed_source']),
                                    self._p['max_setpoint_age'])
        self._setpoint_sub = None
        for name in self._params.unknown_given():
            self.get_logger().warning(f'parameter {name} is not a parameter of driver_node; '
                                      'ignored (docs/driver.md lists them)')

        self.core = c.DriverCore(self._core_config(), log=self._core_log)
        self._events = queue.SimpleQueue()

        self.diagnostics = Updater(self, self._p['diagnostic_updater.period'],
                                   hardware_id=self._p['port'])
        self.diagnostics.add('serial link', self._diag_link)
        self.diagnostics.add('cycles', self._diag_cycles)
        # Services exist in every lifecycle state so that a refusal can say why.
        self.create_service(Trigger, '~/trigger_cycle', self._srv_trigger)
        self.create_service(SetBool, '~/enable', self._srv_enable)

    # ---- parameters ----------------------------------------------------------------------

    def _core_config(self):
        p = self._p
        return c.CoreConfig(ack_timeout_s=p['ack_timeout_s'],
                            cycle_timeout_s=p['cycle_timeout_s'],
                            watchdog_timeout_s=p['watchdog_timeout_s'],
                            reconnect_initial_s=p['reconnect_initial_s'],
                            reconnect_max_s=p['reconnect_max_s'],
                            cycle_period=p['cycle_period'],
                            release_speed_mode=p['release_speed_mode'])

    def _apply_parameters(self, changed):
        self.core.reconfigure(self._core_config())
        if 'diagnostic_updater.period' in changed:
            self.diagnostics.set_period(self._p['diagnostic_updater.period'])
        if 'cycle_period' in changed and self._tick_timer is not None:
            self.destroy_timer(self._tick_timer)
            self._tick_timer = self.create_timer(self._tick_period(), self._tick)
        if 'joint_states_rate' in changed and self._pub_joint is not None:
            self._joint_timer.start(self._p['joint_states_rate'])
        if 'max_setpoint_age' in changed:
            self._inbox.max_age_s = self._p['max_setpoint_age']

    def _tick_period(self):
        return max(MIN_TICK_PERIOD_S, min(TICK_PERIOD_S, self._p['cycle_period'] / 2))

    # ---- lifecycle -----------------------------------------------------------------------

    def on_configure(self, state):
        try:
            self._pub_prox = self.create_lifecycle_publisher(Range, 'proximity', qos.PROXIMITY)
            self._pub_status = self.create_lifecycle_publisher(CycleStatus, 'cycle_status',
                                                               qos.CYCLE_STATUS)
            self._pub_joint = self.create_lifecycle_publisher(JointState, 'joint_states',
                                                              qos.JOINT_STATES)
            self._pub_fired = self.create_lifecycle_publisher(CycleStatus, 'cycle_fired',
                                                              qos.CYCLE_FIRED)
            self.link = SerialLink(self._p['port'], self._p['baud_rate'], self._on_rx,
                                   self._on_lost)
            self._tick_timer = self.create_timer(self._tick_period(), self._tick)
            self._joint_timer.start(self._p['joint_states_rate'])
            self._setpoint_sub = self.create_subscription(
                SpeedSetpoint, 'release_speed_setpoint', self._on_setpoint,
                qos.RELEASE_SPEED_SETPOINT)
            self._apply(self.core.start(time.monotonic()))
        except Exception as exc:    # noqa: B902 - report, then let lifecycle fail cleanly
            self.get_logger().error(f'configure failed: {exc!r}')
            self.configure_error = f'configure failed: {exc!r}'
            self._teardown()
            return TransitionCallbackReturn.FAILURE
        self.get_logger().info(f'configured: port {self._p["port"]} at '
                               f'{self._p["baud_rate"]} baud')
        return super().on_configure(state)

    def on_activate(self, state):
        self._apply(self.core.set_active(True, time.monotonic(), self._stamp()))
        return super().on_activate(state)

    def on_deactivate(self, state):
        # Abort and report before the lifecycle publishers switch off.
        self._apply(self.core.set_active(False, time.monotonic(), self._stamp(),
                                         'node deactivated'))
        return super().on_deactivate(state)

    def on_cleanup(self, state):
        self._teardown('node cleaned up')
        return super().on_cleanup(state)

    def on_shutdown(self, state):
        # exit_reason: the run helper's (e.g. 'interrupted (SIGINT)'), else ros2 lifecycle's.
        self._teardown(self.exit_reason or 'node shutting down')
        return super().on_shutdown(state)

    def on_error(self, state):
        self._teardown('lifecycle error')
        return TransitionCallbackReturn.SUCCESS

    def _teardown(self, reason='stopped'):
        if self.core is None:
            return
        if self.core.running or self.core.pending is not None:
            self._apply(self.core.stop(time.monotonic(), self._stamp(), reason))
            # The aborted cycle's status must reach its readers before the writer goes (DDS
            # drops what a destroyed writer has not delivered).
            for pub in self._own_publishers():
                flush(pub)
        if self.link is not None:
            self.link.close()
            self.link = None
        if self._tick_timer is not None:
            self.destroy_timer(self._tick_timer)
            self._tick_timer = None
        if self._setpoint_sub is not None:
            self.destroy_subscription(self._setpoint_sub)
            self._setpoint_sub = None
        self._joint_timer.stop()
        for pub in self._own_publishers():
            self.destroy_lifecycle_publisher(pub)
        self._pub_prox = self._pub_status = self._pub_joint = self._pub_fired = None

    def _own_publishers(self):
        return [pub for pub in (self._pub_prox, self._pub_status, self._pub_joint,
                                self._pub_fired) if pub is not None]

    def destroy_node(self):
        self._teardown('node destroyed')
        if self.diagnostics is not None:
            self.diagnostics.destroy()
            self.diagnostics = None
        return super().destroy_node()

    # ---- services ------------------------------------------------------------------------

    def _not_active(self):
        return (f'refused: driver is {self.lifecycle_state}, not active (ros2 lifecycle set '
                f'{self.get_fully_qualified_name()} activate, or start it with '
                'autostart:=true)')

    def _srv_trigger(self, request, response):
        if self.lifecycle_state != 'active':
            response.success, response.message = False, self._not_active()
            return response
        ok, message, effects = self.core.trigger(time.monotonic())
        fired = self.core.pending.seq if ok else None
        self._apply(effects)
        last = self.core.last_result
        if ok and last is not None and last.seq == fired and not last.ok:
            message += f' (failed at once: {last.reason})'
        response.success, response.message = ok, message
        return response

    def _srv_enable(self, request, response):
        if request.data and self.lifecycle_state != 'active':
            response.success, response.message = False, self._not_active()
            return response
        ok, message, effects = self.core.enable(bool(request.data), time.monotonic())
        self._apply(effects)
        response.success, response.message = ok, message
        if ok and request.data:
            response.message += clock_note(self)
        return response

    # ---- serial events -------------------------------------------------------------------

    def _stamp(self):
        return self.get_clock().now().nanoseconds

    def _on_rx(self, generation, t, events):
        # Reader thread: stamp now (the sample time of a SENS), hand over, wake the executor.
        self._events.put(('rx', generation, t, self._stamp(), events))
        self._wake()

    def _on_lost(self, generation, error):
        self._events.put(('lost', generation, time.monotonic(), self._stamp(), error))
        self._wake()

    def _wake(self):
        executor = self.executor
        if executor is None:
            return      # not spun (yet, or any more): the events wait in the queue
        try:
            executor.create_task(self._drain)
        except Exception:   # noqa: B902 - executor already shut down; nothing left to wake
            pass

    def _drain(self):
        while True:
            try:
                kind, generation, t, stamp, payload = self._events.get_nowait()
            except queue.Empty:
                return
            if self.link is None or generation != self.link.generation:
                continue    # from a connection that is already closed
            if kind == 'rx':
                self._apply(self.core.received(t, stamp, payload))
            else:
                self._apply(self.core.link_lost(t, stamp, payload))

    def _on_setpoint(self, msg):
        why = self._inbox.offer(msg, self._stamp())
        if why:
            self.get_logger().warning(f'release_speed_setpoint not taken: {why}',
                                      throttle_duration_sec=5.0)
            return
        self._take_setpoint()

    def _take_setpoint(self):
        """Hand the core the setpoint of its next cycle, if the inbox holds one for it."""
        core = self.core
        if core.config.release_speed_mode != c.SETPOINT or \
                (core.setpoint is not None and core.setpoint[0] == core.next_seq):
            return
        speed, _ = self._inbox.for_cycle(core.next_seq, self._signer.session, self._stamp())
        if speed is None:
            return
        accepted, reason, effects = core.set_setpoint(time.monotonic(), core.next_seq, speed)
        if not accepted:
            self.get_logger().warning(f'release-speed setpoint {speed:.4f} rad/s for cycle '
                                      f'{core.next_seq} refused: {reason}',
                                      throttle_duration_sec=5.0)
        self._apply(effects)

    def _tick(self):
        # What the reader has read so far is handled before any deadline is judged: after a
        # stall (SIGSTOP, starved CPU) a reply may be waiting in the queue or the port.
        read_until = self.link.read_until if self.link is not None else None
        self._drain()
        self._apply(self.core.tick(time.monotonic(), self._stamp(), read_until))

    def _apply(self, effects):
        work = list(effects)
        while work:
            effect = work.pop(0)
            if isinstance(effect, c.Send):
                try:
                    if self.link is None:
                        raise LinkError('port is not open')
                    self.link.write(protocol.encode(effect.message))
                except LinkError as exc:
                    work += self.core.link_lost(time.monotonic(), self._stamp(), exc)
            elif isinstance(effect, c.OpenLink):
                if self.link is None:
                    continue
                try:
                    self.link.open_port()
                except LinkError as exc:
                    work += self.core.link_open_failed(time.monotonic(), exc)
                else:
                    work += self.core.link_opened(time.monotonic())
            elif isinstance(effect, c.CloseLink):
                if self.link is not None:
                    self.link.close()
            elif isinstance(effect, c.Firing):
                if effect.speed_setpoint is not None:
                    self._inbox.used()
                stamp = self._stamp()
                self._motion.fired(stamp)
                if self._pub_fired is not None:
                    self._publish(self._pub_fired, self._signer.cycle_fired(
                        effect.seq, stamp, self._p['port']))
            elif isinstance(effect, c.CycleFinished):
                self._motion.rested(effect.result.stamp)
                self._publish_result(effect.result)
            elif isinstance(effect, c.Released):
                self._motion.released(effect.stamp, effect.speed_rad_s)
                self._publish_joint(effect.stamp, effect.speed_rad_s)

    # ---- publishing ----------------------------------------------------------------------

    def _publish_result(self, result):
        if self._pub_status is None:
            self.get_logger().error(f'cycle seq {result.seq} ended while unconfigured: '
                                    f'{result.reason} (not published)')
            return
        ok = result.ok
        if ok:
            self._publish(self._pub_prox, proximity(result.stamp, bool(result.sensor),
                                                    self._p['sensor_range_m'],
                                                    self._p['frame_id']))
        self._publish(self._pub_status, self._signer.cycle_status(
            result.seq, ok, '' if ok else result.reason,
            None if result.sensor is None else bool(result.sensor), result.stamp,
            self._p['port'], result.speed_setpoint))
        if ok:
            self._publish_joint(result.stamp, 0.0)

    def _publish(self, pub, msg):
        publish(pub, msg, self.get_logger())

    def _publish_joint(self, stamp, velocity):
        if self._pub_joint is not None:
            self._publish(self._pub_joint, joint_state(stamp, 0.0, velocity))

    def _joint_tick(self):
        """Publish the arm's angle now (feeder_common.arm), while active."""
        pub = self._pub_joint
        if pub is not None and pub.is_activated:
            stamp = self._stamp()
            self._publish(pub, joint_state(stamp, *self._motion.at(stamp)))

    # ---- diagnostics ---------------------------------------------------------------------

    def _core_log(self, level, text):
        # One call site per severity: rclpy refuses to change the severity of a call site.
        logger = self.get_logger()
        if level == 'debug':
            logger.debug(text)
        elif level == 'info':
            logger.info(text)
        elif level == 'warning':
            logger.warning(text)
        else:
            logger.error(text)

    def _diag_link(self, stat):
        core = self.core
        state = self.lifecycle_state
        if state in ('unconfigured', 'finalized'):
            stat.summary(DiagnosticStatus.WARN, f'{state}: port closed')
        elif core.link == c.CONNECTED:
            stat.summary(DiagnosticStatus.OK, 'connected')
        elif core.link == c.HANDSHAKE:
            stat.summary(DiagnosticStatus.WARN, 'port open, waiting for the controller')
        else:
            stat.summary(DiagnosticStatus.ERROR, f'disconnected: {core.last_link_error}')
        stat.add('lifecycle', state)
        stat.add('port', self._p['port'])
        stat.add('baud_rate', self._p['baud_rate'])
        stat.add('link', core.link)
        stat.add('last link error', core.last_link_error)
        stat.add('firmware', core.firmware or 'unknown')
        stat.add('boot_id', core.boot_id or 'unknown')
        stat.add('controller state', core.hb_state or 'unknown')
        stat.add('controller uptime ms', core.hb_uptime_ms if core.hb_uptime_ms is not None
                 else 'unknown')
        for key in ('link_losses', 'open_failures', 'handshake_timeouts', 'watchdog_timeouts',
                    'controller_resets', 'controller_errors', 'stale_replies'):
            stat.add(key, core.counters[key])
        if self.link is not None:
            stats = self.link.parser.stats
            stat.add('bytes received', stats['bytes'])
            stat.add('bytes sent', self.link.bytes_written)
            stat.add('frames ok', stats['lines'])
            stat.add('garbage bytes', stats['garbage_bytes'])
            stat.add('frames dropped', self.link.parser.dropped_frames)
            for kind in self.link.parser.REJECT_KINDS:
                stat.add(f'dropped {kind}', stats[kind])

    def _diag_cycles(self, stat):
        core = self.core
        last = core.last_result
        if last is not None and not last.ok:
            stat.summary(DiagnosticStatus.WARN, f'last cycle failed: seq {last.seq}: '
                         f'{last.reason}')
        elif core.enabled:
            stat.summary(DiagnosticStatus.OK, 'cycling' if core.link == c.CONNECTED
                         else f'cycling paused: link {core.link}')
        else:
            stat.summary(DiagnosticStatus.OK, 'idle' if core.pending is None
                         else f'cycle seq {core.pending.seq} in flight')
        for key in ('fired', 'completed', 'failed', 'acks_missing'):
            stat.add(key, core.counters[key])
        stat.add('in flight', core.pending.seq if core.pending is not None else 'none')
        stat.add('enabled', str(core.enabled).lower())
        stat.add('cycle_period', self._p['cycle_period'])
        stat.add('last failure', core.last_failure or 'none')
        stat.add('last sensor', 'none' if last is None or last.sensor is None
                 else last.sensor)


def main(args=None):
    """Entry point of ``driver_node`` (see docs/driver.md for parameters)."""
    return run_node(DriverNode, 'driver_node', args)


if __name__ == '__main__':
    sys.exit(main())
