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
monitor_node: raises edge1_ready when a detection proves the part lies on the goal edge.

ROS glue only: the rules and the state machine are feeder_monitor.readiness's, the analysis is
throwmap's (throwmap.scene_analysis, the same numbers the sim uses), the contract (QoS,
message parsers, parameters, run helper) feeder_common's.
"""

import functools
import sys
import time

from diagnostic_msgs.msg import DiagnosticStatus
from feeder_common import qos
from feeder_common.diagnostics import Updater
from feeder_common.graph import PublisherGuard
from feeder_common.messages import (edge_verdict, parse_cycle_status, proximity_detected,
                                    time_ns)
from feeder_common.node import flush, run_node, StartupError
from feeder_common.parameters import ParameterGate
from feeder_common.params import check_scene
from feeder_common.stamps import ns_seconds
from lifecycle_msgs.msg import TransitionEvent
from rclpy.node import Node
from sensor_msgs.msg import Range
from std_msgs.msg import Bool
from throwmap import analyse, load_scene, scene_analysis, ThrowmapError

from .params import MONITOR_PARAMS
from .readiness import (ANOMALY, CyclePairer, limit_set_orbit, ReadinessMonitor,
                        rules_from_analysis, WARMING_UP)

RULE_PARAMS = ('sensor_radius', 'warmup_cycles', 'settle_cycles', 'silence_margin',
               'early_margin_cycles', 'run_margin_cycles')


class MonitorNode(Node):
    """
    Consumes proximity and cycle_status; publishes edge1_ready, edge1_verdict, /diagnostics.

    It decides only on cycles from the one node it trusts (``driver_node``): a cycle that
    arrives while another node publishes ``cycle_status`` or ``proximity`` is an anomaly, and
    a detection is judged only after the publishers were checked to be exactly the pinned
    driver (feeder_common.graph). ``edge1_ready`` is live (deadline and liveliness lease
    ``ready_deadline``), false on a clean exit, when the driver leaves the graph or leaves its
    active state.
    """

    def __init__(self, **kwargs):
        super().__init__('feeder_monitor', **kwargs)
        # Scenes by path, loaded once (the parameter checks load them too).
        self._load_scene = functools.lru_cache(maxsize=None)(load_scene)
        self._scene = None
        self._base = None
        self._orbit = None
        self._monitor = None
        self._pairer = None
        self._params = ParameterGate(self, MONITOR_PARAMS, self._validate, self._apply)
        p = self._params
        self._scene = self._load_scene(p.declare('scene'))
        orbit_throws = p.declare('orbit_throws')
        try:
            self._base = analyse(self._scene)
            self._orbit = limit_set_orbit(self._scene, self._base, orbit_throws)
            p.declare_all()
            rules = self._rules({})
        except ThrowmapError as exc:
            raise StartupError(f'scene {self._scene.source}: {exc}') from None
        except ValueError as exc:       # a rule parameter the analysis rejects
            raise StartupError(str(exc)) from None
        for name in p.unknown_given():
            self.get_logger().warning(f'parameter {name} is not a parameter of monitor_node; '
                                      'ignored (docs/nodes.md lists them)')
        self._monitor = ReadinessMonitor(rules)
        self._pairer = CyclePairer(self._param('stamp_tolerance'), self._param('pair_timeout'))
        self._anomaly_in_period = None
        self._lost_mark = 0
        self._bad_input = 0

        self._ready = False
        self._ready_sent = 0.0          # time.monotonic() of the last edge1_ready
        self._ready_pub = self.create_publisher(
            Bool, 'edge1_ready', qos.edge1_ready(self._param('ready_deadline')))
        self._verdict_pub = self.create_publisher(DiagnosticStatus, 'edge1_verdict',
                                                  qos.EDGE1_VERDICT)
        driver = self.resolve_topic_name(self._param('driver_node'))
        self._guard = PublisherGuard(self, (self.resolve_topic_name('cycle_status'),
                                            self.resolve_topic_name('proximity')), driver)
        self._distrust = None           # why the publishers are not trusted now, or None
        self.create_subscription(TransitionEvent, f'{driver}/transition_event',
                                 self._on_driver_transition, qos.DEFAULT)
        # Keeps edge1_ready's deadline while idle; checks who publishes the driver's topics.
        self.create_timer(self._param('ready_deadline') / 2, self._on_heartbeat)
        self.create_subscription(Range, 'proximity', self._on_proximity,
                                 qos.PROXIMITY_SUBSCRIPTION)
        self.create_subscription(DiagnosticStatus, 'cycle_status', self._on_cycle_status,
                                 qos.CYCLE_STATUS)
        # Runs only while a cycle waits for its other half (see _decide).
        self._expire_timer = self.create_timer(min(0.1, self._param('pair_timeout') / 2),
                                               self._on_expire)
        self._expire_timer.cancel()
        self._diagnostics = Updater(self, self._param('diagnostics_period'), self._scene.name)
        self._diagnostics.add('readiness', self._diag_readiness)
        self._diagnostics.add('inputs', self._diag_inputs)
        self._publish_ready(False)
        self._log_rules(rules)

    # ------------------------------------------------------------------ parameters
    def _param(self, name):
        return self._params.values[name]

    def _rules(self, changes):
        """Rules from the current parameters overridden by ``changes``; ValueError if invalid."""
        def value(name):
            return changes[name] if name in changes else self._param(name)

        an = scene_analysis(self._scene, value('sensor_radius'), self._base)
        return rules_from_analysis(self._scene, an, self._orbit, value('warmup_cycles'),
                                   value('settle_cycles'), value('silence_margin'),
                                   value('early_margin_cycles'), value('run_margin_cycles'))

    def _validate(self, changes, current):
        if 'scene' in changes:
            reason = check_scene(changes['scene'], self._load_scene)
            if reason:
                return reason
        # At start-up (no monitor yet) the rules are checked once all are declared.
        if self._monitor is not None and any(n in changes for n in RULE_PARAMS):
            try:
                self._rules(changes)
            except ValueError as exc:
                return str(exc)
        return None

    def _apply(self, changes):
        if self._monitor is None:
            return
        if 'diagnostics_period' in changes:
            self._diagnostics.set_period(changes['diagnostics_period'])
        if any(n in changes for n in RULE_PARAMS):
            rules = self._rules({})
            self._monitor.set_rules(rules)
            self._log_rules(rules)
        self._pairer.tolerance = self._param('stamp_tolerance')
        self._pairer.timeout = self._param('pair_timeout')

    def _log_rules(self, r):
        self.get_logger().info(
            f'{self._scene.name}: goal edge {r.goal_edge}, sensor {r.sensor_radius:.4f} m '
            f'(guarantee {r.guarantee_radius:.4f} m, provable: {r.provable}), warm-up '
            f'{r.warmup_cycles}, settle {r.settle_cycles}, max run {r.max_run}, min gap '
            f'{r.min_gap}, max silence {r.max_silence}')
        if not r.provable:
            self.get_logger().warning('the sensor is not beyond the guarantee radius: no '
                                      'detection can prove the goal edge; edge1_ready stays '
                                      'false')
        elif r.noisy_sensor:
            self.get_logger().warning(f'noisy sensor (sensor_noise): {self._noise_note(r)}')

    @staticmethod
    def _noise_note(r):
        p = 'not computed at this radius' if r.p_goal is None else f'{r.p_goal:.4f}'
        return f'a detection is on the goal edge with probability {p}, not proven'

    # ------------------------------------------------------------------ inputs
    def _on_proximity(self, msg):
        try:
            detected = proximity_detected(msg)
            stamp_ns = time_ns(msg.header.stamp)
            problem = None if detected is not None else 'proximity without a reading (NaN)'
        except ValueError as exc:
            problem = str(exc)
        if problem:
            self._bad_input += 1
            self.get_logger().warning(f'{problem}; ignored', throttle_duration_sec=5.0)
            return
        self._decide(self._pairer.add_proximity(ns_seconds(stamp_ns), detected,
                                                time.monotonic()))

    def _on_cycle_status(self, msg):
        try:
            status = parse_cycle_status(msg)
        except ValueError as exc:
            self._bad_input += 1
            self.get_logger().warning(f'{exc}; ignored', throttle_duration_sec=5.0)
            return
        stamp = None if status.stamp_ns is None else ns_seconds(status.stamp_ns)
        self._decide(self._pairer.add_status(status.seq, status.ok, status.sensor, stamp,
                                             status.message, time.monotonic(),
                                             status.stamp_ns))

    def _on_expire(self):
        self._decide(self._pairer.expire(time.monotonic()))

    def _decide(self, cycles):
        if self._pairer.pending == (0, 0):
            self._expire_timer.cancel()
        elif self._expire_timer.is_canceled():
            self._expire_timer.reset()
        for c in cycles:
            # A second publisher costs one graph lookup per cycle to see; the full identity
            # check (GIDs) runs before a detection is judged, the only cycles that can be ready.
            # It sees a second publisher too, so a detection skips the cheap lookup: the
            # lookups lie between the cycle_status and edge1_ready (bench/monitor_hop.py).
            if c.completed and c.detected:
                distrust = self._guard.check()
            else:
                distrust = self._guard.crowded()
            if distrust is not None:
                v = self._monitor.untrusted(c.seq, distrust)
            elif c.completed:
                v = self._monitor.completed(c.seq, c.detected, c.note)
            else:
                v = self._monitor.failed(c.seq, c.reason)
            self._publish_ready(v.ready)
            self._verdict_pub.publish(edge_verdict(v.seq, c.stamp_ns, v.ready, v.state,
                                                   v.anomaly, self._scene.name))
            if v.note:
                self.get_logger().warning(v.note)
            if v.anomaly:
                self._anomaly_in_period = (v.seq, v.anomaly)
                self.get_logger().warning(f'anomaly at cycle {v.seq}: {v.anomaly}',
                                          throttle_duration_sec=1.0)
            if v.ready:
                self.get_logger().debug(f'cycle {v.seq}: part proven on the goal edge')

    def _publish_ready(self, ready):
        self._ready = bool(ready)
        self._ready_sent = time.monotonic()
        self._ready_pub.publish(Bool(data=self._ready))

    def _on_heartbeat(self):
        distrust = self._guard.check()
        if distrust != self._distrust:
            self._distrust = distrust
            if distrust:
                self.get_logger().info(f'publishers: {distrust}')
        if distrust and self._ready:
            self._interrupt(distrust)
        elif time.monotonic() - self._ready_sent >= self._param('ready_deadline') / 2:
            self._publish_ready(self._ready)

    def _on_driver_transition(self, msg):
        if msg.goal_state.label != 'active' and msg.start_state.label == 'active':
            self._interrupt(f'{self._guard.trusted_node} left its active state '
                            f'({msg.transition.label})')

    def _interrupt(self, reason):
        """No cycle can be judged (the driver left or stopped): false, warm up again."""
        self._monitor.interrupt(reason)
        self._anomaly_in_period = (self._monitor.last_seq, reason)
        self.get_logger().warning(f'{reason}: edge1_ready false, warming up again')
        self._publish_ready(False)

    def destroy_node(self):
        # A clean exit says false, and waits (briefly) until the readers have it.
        try:
            self._publish_ready(False)
            flush(self._ready_pub)
        except Exception:   # noqa: B902 - context already gone: nothing can be said
            pass
        return super().destroy_node()

    # ------------------------------------------------------------------ diagnostics
    def _diag_readiness(self, stat):
        m = self._monitor
        r = m.rules
        anomaly = self._anomaly_in_period
        self._anomaly_in_period = None
        if anomaly or m.state == ANOMALY:
            level = 'error'
            seq, reason = anomaly or m.last_anomaly or (m.last_seq, 'anomaly')
            message = f'anomaly: {reason} (cycle {seq})'
        elif not r.provable:
            level, message = 'warn', (f'{m.state}; sensor at {r.sensor_radius:.4f} m is not '
                                      f'beyond the guarantee radius {r.guarantee_radius:.4f} m: '
                                      'cannot prove the goal edge')
        elif m.state == WARMING_UP:
            level, message = 'ok', f'warming up ({m.since_restart}/{r.warmup_cycles} throws)'
        else:
            level, message = 'ok', m.state
        if level != 'error' and r.provable and r.noisy_sensor:
            message = f'{message} (noisy sensor: {self._noise_note(r)})'
        stat.summary(level, message)
        stat.update({'state': m.state, 'last_seq': m.last_seq, **m.counts,
                     'trusted_publisher': self._guard.trusted_node,
                     'publishers': self._distrust or 'trusted',
                     'since_restart': m.since_restart, 'cycles_since_detection': m.gap,
                     'last_anomaly': m.last_anomaly, **r.as_dict(),
                     'namespace': self.get_namespace()})

    def _diag_inputs(self, stat):
        p = self._pairer
        lost = p.counts['proximity_lost']
        pending = p.pending
        level = 'warn' if lost > self._lost_mark or self._bad_input else 'ok'
        self._lost_mark = lost
        stat.summary(level, 'proximity and cycle_status paired' if level == 'ok' else
                     'proximity messages lost or malformed input')
        stat.update({**p.counts, 'pending_status': pending[0], 'pending_proximity': pending[1],
                     'bad_input': self._bad_input})


def main(args=None):
    return run_node(MonitorNode, 'monitor_node', args)


if __name__ == '__main__':
    sys.exit(main())
