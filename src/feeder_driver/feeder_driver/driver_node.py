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
:mod:`feeder_driver.protocol`. The reader thread queues decoded events and wakes the
executor through a guard condition; everything else (writes, timeouts, publishing) runs on
the executor thread, and no callback blocks longer than one serial write.
"""

import math
import queue
import sys
import time

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from rcl_interfaces.msg import SetParametersResult
import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time import Time
from sensor_msgs.msg import JointState, Range
from std_srvs.srv import SetBool, Trigger

from . import core as c
from . import params
from . import protocol
from .diagnostics import Updater
from .serial_link import LinkError, SerialLink

JOINT_NAME = 'feeder_arm_joint'
# Timeouts and continuous cycling are checked on a timer: 50 Hz, faster for short periods.
TICK_PERIOD_S = 0.02
MIN_TICK_PERIOD_S = 0.005


class ParameterError(Exception):
    """A start-up parameter is invalid; the text names it and the fix."""


class DriverNode(LifecycleNode):
    """Owns the serial link to the feeder controller and runs throw-catch cycles."""

    def __init__(self, node_name='feeder_driver', **kwargs):
        # Set before Node.__init__: a context shutdown may destroy a half-built node.
        self.core = self.link = self.diagnostics = None
        self._tick_timer = None
        self._pub_prox = self._pub_status = self._pub_joint = None
        super().__init__(node_name, **kwargs)
        self._lifecycle = 'unconfigured'
        descs = params.descriptors()
        for spec in params.SPECS:
            try:
                self.declare_parameter(spec.name, spec.default, descs[spec.name])
            except Exception as exc:    # noqa: B902 - rclpy raises several types here
                given = getattr(self, '_parameter_overrides', {}).get(spec.name)
                reason = params.check(spec.name, given.value) if given is not None else None
                raise ParameterError(f'parameter {reason or f"{spec.name}: {exc}"}') from None
        values = {s.name: self.get_parameter(s.name).value for s in params.SPECS}
        reason = params.validate(values, values)
        if reason:
            raise ParameterError(f'parameter {reason}')
        self._p = values
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

        self.core = c.DriverCore(self._core_config(), log=self._core_log)
        self._events = queue.SimpleQueue()
        self._guard = self.create_guard_condition(self._drain)

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
                            cycle_period=p['cycle_period'])

    def _validate_parameters(self, parameters):
        new = {prm.name: prm.value for prm in parameters if prm.name in params.BY_NAME}
        reason = params.validate(new, self._p)
        return SetParametersResult(successful=reason is None, reason=reason or '')

    def _apply_parameters(self, parameters):
        changed = {prm.name: prm.value for prm in parameters if prm.name in params.BY_NAME}
        self._p.update(changed)
        self.core.reconfigure(self._core_config())
        if 'diagnostic_updater.period' in changed:
            self.diagnostics.set_period(self._p['diagnostic_updater.period'])
        if 'cycle_period' in changed and self._tick_timer is not None:
            self.destroy_timer(self._tick_timer)
            self._tick_timer = self.create_timer(self._tick_period(), self._tick)

    def _tick_period(self):
        return max(MIN_TICK_PERIOD_S, min(TICK_PERIOD_S, self._p['cycle_period'] / 2))

    # ---- lifecycle -----------------------------------------------------------------------

    def on_configure(self, state):
        try:
            self._pub_prox = self.create_lifecycle_publisher(Range, 'proximity',
                                                             QoSProfile(depth=10))
            self._pub_status = self.create_lifecycle_publisher(
                DiagnosticStatus, 'cycle_status',
                QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
            self._pub_joint = self.create_lifecycle_publisher(JointState, 'joint_states',
                                                              QoSProfile(depth=10))
            self.link = SerialLink(self._p['port'], self._p['baud_rate'], self._on_rx,
                                   self._on_lost)
            self._tick_timer = self.create_timer(self._tick_period(), self._tick)
            self._apply(self.core.start(time.monotonic()))
        except Exception as exc:    # noqa: B902 - report, then let lifecycle fail cleanly
            self.get_logger().error(f'configure failed: {exc!r}')
            self._teardown()
            return TransitionCallbackReturn.FAILURE
        self._lifecycle = 'inactive'
        self.get_logger().info(f'configured: port {self._p["port"]} at '
                               f'{self._p["baud_rate"]} baud')
        return super().on_configure(state)

    def on_activate(self, state):
        self._apply(self.core.set_active(True, time.monotonic(), self._stamp()))
        self._lifecycle = 'active'
        return super().on_activate(state)

    def on_deactivate(self, state):
        # Abort and report before the lifecycle publishers switch off.
        self._apply(self.core.set_active(False, time.monotonic(), self._stamp(),
                                         'node deactivated'))
        self._lifecycle = 'inactive'
        return super().on_deactivate(state)

    def on_cleanup(self, state):
        self._teardown('node cleaned up')
        self._lifecycle = 'unconfigured'
        return super().on_cleanup(state)

    def on_shutdown(self, state):
        self._teardown('node shutting down')
        self._lifecycle = 'finalized'
        return super().on_shutdown(state)

    def on_error(self, state):
        self._teardown('lifecycle error')
        self._lifecycle = 'unconfigured'
        return TransitionCallbackReturn.SUCCESS

    def _teardown(self, reason='stopped'):
        if self.core is None:
            return
        if self.core.running or self.core.pending is not None:
            self._apply(self.core.stop(time.monotonic(), self._stamp(), reason))
        if self.link is not None:
            self.link.close()
            self.link = None
        if self._tick_timer is not None:
            self.destroy_timer(self._tick_timer)
            self._tick_timer = None
        for pub in (self._pub_prox, self._pub_status, self._pub_joint):
            if pub is not None:
                self.destroy_lifecycle_publisher(pub)
        self._pub_prox = self._pub_status = self._pub_joint = None

    def destroy_node(self):
        self._teardown('node destroyed')
        if self.diagnostics is not None:
            self.diagnostics.destroy()
            self.diagnostics = None
        return super().destroy_node()

    # ---- services ------------------------------------------------------------------------

    def _not_active(self):
        return (f'refused: driver is {self._lifecycle}, not active (activate it through '
                '~/change_state, or start it with autostart:=true)')

    def _srv_trigger(self, request, response):
        if self._lifecycle != 'active':
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
        if request.data and self._lifecycle != 'active':
            response.success, response.message = False, self._not_active()
            return response
        ok, message, effects = self.core.enable(bool(request.data), time.monotonic())
        self._apply(effects)
        response.success, response.message = ok, message
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
        try:
            self._guard.trigger()
        except Exception:   # noqa: B902 - context already shut down; nothing left to wake
            pass

    def stop_link(self, reason):
        """Abort a cycle in flight (STOP, reported on cycle_status) and close the port."""
        self._teardown(reason)

    def close_on_exit(self):
        """Last resort after the context is gone: STOP a cycle in flight, close the port."""
        if self.link is None or self.core is None:
            return
        if self.core.pending is not None:
            try:
                self.link.write(protocol.encode(protocol.Stop()))
            except LinkError:
                pass
        self.link.close()
        self.link = None

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

    def _tick(self):
        self._apply(self.core.tick(time.monotonic(), self._stamp()))

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
            elif isinstance(effect, c.CycleFinished):
                self._publish_result(effect.result)
            elif isinstance(effect, c.Released):
                self._publish_joint(effect.stamp, effect.speed_rad_s)

    # ---- publishing ----------------------------------------------------------------------

    def _publish_result(self, result):
        if self._pub_status is None:
            self.get_logger().error(f'cycle seq {result.seq} ended while unconfigured: '
                                    f'{result.reason} (not published)')
            return
        status = DiagnosticStatus(name='cycle', hardware_id=self._p['port'])
        status.level = DiagnosticStatus.OK if result.ok else DiagnosticStatus.ERROR
        status.message = 'completed' if result.ok else result.reason
        status.values = [KeyValue(key='seq', value=str(result.seq)),
                         KeyValue(key='sensor', value=('none' if result.sensor is None
                                                       else str(result.sensor))),
                         KeyValue(key='stamp', value=f'{result.stamp // 10 ** 9}.'
                                                     f'{result.stamp % 10 ** 9:09d}')]
        if result.ok:
            rng = Range()
            rng.header.stamp = Time(nanoseconds=result.stamp).to_msg()
            rng.header.frame_id = self._p['frame_id']
            rng.radiation_type = Range.INFRARED
            rng.field_of_view = 0.0
            rng.min_range = rng.max_range = float(self._p['sensor_range_m'])
            rng.range = -math.inf if result.sensor else math.inf
            self._publish(self._pub_prox, rng)
            self._publish_joint(result.stamp, 0.0)
        self._publish(self._pub_status, status)

    def _publish(self, pub, msg):
        try:
            pub.publish(msg)
        except Exception as exc:    # noqa: B902 - e.g. the context is already shut down
            print(f'driver_node: could not publish on {pub.topic_name}: {exc}',
                  file=sys.stderr)

    def _publish_joint(self, stamp, velocity):
        if self._pub_joint is None:
            return
        js = JointState()
        js.header.stamp = Time(nanoseconds=stamp).to_msg()
        js.name = [JOINT_NAME]
        js.position = [0.0]
        js.velocity = [float(velocity)]
        js.effort = []
        self._publish(self._pub_joint, js)

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
        if self._lifecycle in ('unconfigured', 'finalized'):
            stat.summary(DiagnosticStatus.WARN, f'{self._lifecycle}: port closed')
        elif core.link == c.CONNECTED:
            stat.summary(DiagnosticStatus.OK, 'connected')
        elif core.link == c.HANDSHAKE:
            stat.summary(DiagnosticStatus.WARN, 'port open, waiting for the controller')
        else:
            stat.summary(DiagnosticStatus.ERROR, f'disconnected: {core.last_link_error}')
        stat.add('lifecycle', self._lifecycle)
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
            for kind in ('checksum', 'frame', 'overlong', 'truncated', 'unknown', 'fields'):
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
    node = None
    try:
        with rclpy.init(args=args):
            try:
                node = DriverNode()
            except ParameterError as exc:
                print(f'driver_node: error: {exc}', file=sys.stderr)
                return 2
            if node.get_parameter('autostart').value:
                if node.trigger_configure() != TransitionCallbackReturn.SUCCESS:
                    print('driver_node: error: configure failed (see the log above)',
                          file=sys.stderr)
                    return 1
                node.trigger_activate()
            executor = SingleThreadedExecutor()
            executor.add_node(node)
            try:
                executor.spin()
            except KeyboardInterrupt:
                # The context is still valid: abort a cycle in flight and report it.
                node.stop_link('interrupted (SIGINT)')
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.close_on_exit()
    return 0


if __name__ == '__main__':
    sys.exit(main())
