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
throwmap's (throwmap.scene_analysis, the same numbers the sim uses).
"""

import functools
import math
import sys
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from feeder_sim.params import check_changes
from feeder_sim.ros_glue import (CYCLE_STATUS_QOS, declare, diagnostic_array, diagnostic_status,
                                 DIAGNOSTICS_QOS, LATCHED_QOS, ParameterGate, run_node,
                                 stamp_seconds, StartupError)
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import Range
from std_msgs.msg import Bool
from throwmap import analyse, load_scene, scene_analysis, ThrowmapError

from .params import MONITOR_PARAMS
from .readiness import (ANOMALY, CyclePairer, limit_set_orbit, ReadinessMonitor,
                        rules_from_analysis, WARMING_UP)

RULE_PARAMS = ('sensor_radius', 'warmup_cycles', 'settle_cycles', 'silence_margin',
               'early_margin_cycles', 'run_margin_cycles')


class MonitorNode(Node):
    """Consumes proximity and cycle_status; publishes edge1_ready and /diagnostics."""

    def __init__(self, **kwargs):
        super().__init__('feeder_monitor', **kwargs)
        self._specs = {s.name: s for s in MONITOR_PARAMS}
        # Scenes by path, loaded once (the parameter checks load them too).
        self._load_scene = functools.lru_cache(maxsize=None)(load_scene)
        self._scene = None
        self._base = None
        self._orbit = None
        self._monitor = None
        self._pairer = None
        ParameterGate(self, self._validate, self._apply)
        self._scene = self._load_scene(declare(self, self._specs['scene']))
        orbit_throws = declare(self, self._specs['orbit_throws'])
        try:
            self._base = analyse(self._scene)
            self._orbit = limit_set_orbit(self._scene, self._base, orbit_throws)
            for name in RULE_PARAMS + ('stamp_tolerance', 'pair_timeout',
                                       'diagnostics_period'):
                declare(self, self._specs[name])
            rules = self._rules({})
        except ThrowmapError as exc:
            raise StartupError(f'scene {self._scene.source}: {exc}') from None
        except ValueError as exc:       # a rule parameter the analysis rejects
            raise StartupError(str(exc)) from None
        self._monitor = ReadinessMonitor(rules)
        self._pairer = CyclePairer(self._param('stamp_tolerance'), self._param('pair_timeout'))
        self._anomaly_in_period = None
        self._lost_mark = 0
        self._bad_input = 0

        self._ready_pub = self.create_publisher(Bool, 'edge1_ready', LATCHED_QOS)
        self._diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', DIAGNOSTICS_QOS)
        self.create_subscription(Range, 'proximity', self._on_proximity, qos_profile_sensor_data)
        self.create_subscription(DiagnosticStatus, 'cycle_status', self._on_cycle_status,
                                 CYCLE_STATUS_QOS)
        # Runs only while a cycle waits for its other half (see _decide).
        self._expire_timer = self.create_timer(min(0.1, self._param('pair_timeout') / 2),
                                               self._on_expire)
        self._expire_timer.cancel()
        self.create_timer(self._param('diagnostics_period'), self._publish_diagnostics)
        self._ready_pub.publish(Bool(data=False))
        self._log_rules(rules)

    # ------------------------------------------------------------------ parameters
    def _param(self, name):
        return self.get_parameter(name).value

    def _rules(self, changes):
        """Rules from the current parameters overridden by ``changes``; ValueError if invalid."""
        def value(name):
            return changes[name] if name in changes else self._param(name)

        an = scene_analysis(self._scene, value('sensor_radius'), self._base)
        return rules_from_analysis(self._scene, an, self._orbit, value('warmup_cycles'),
                                   value('settle_cycles'), value('silence_margin'),
                                   value('early_margin_cycles'), value('run_margin_cycles'))

    def _validate(self, changes):
        reason = check_changes(self._specs, changes, self._load_scene)
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
        r = msg.range
        if math.isnan(r):
            self._bad_input += 1
            return
        detected = r < 0 if math.isinf(r) else msg.min_range <= r <= msg.max_range
        self._decide(self._pairer.add_proximity(stamp_seconds(msg.header.stamp), detected,
                                                time.monotonic()))

    def _on_cycle_status(self, msg):
        values = {kv.key: kv.value for kv in msg.values}
        try:
            seq = int(values['seq'])
        except (KeyError, ValueError):
            self._bad_input += 1
            self.get_logger().warning(f'cycle_status without a valid seq: {values}',
                                      throttle_duration_sec=5.0)
            return
        detected = {'1': True, '0': False}.get(values.get('sensor'))
        try:
            stamp = float(values['stamp'])
        except (KeyError, ValueError):
            stamp = None
        self._decide(self._pairer.add_status(seq, msg.level == DiagnosticStatus.OK, detected,
                                             stamp, msg.message, time.monotonic()))

    def _on_expire(self):
        self._decide(self._pairer.expire(time.monotonic()))

    def _decide(self, cycles):
        if self._pairer.pending == (0, 0):
            self._expire_timer.cancel()
        elif self._expire_timer.is_canceled():
            self._expire_timer.reset()
        for c in cycles:
            if c.completed:
                v = self._monitor.completed(c.seq, c.detected, c.note)
            else:
                v = self._monitor.failed(c.seq, c.reason)
            self._ready_pub.publish(Bool(data=v.ready))
            if v.anomaly:
                self._anomaly_in_period = (v.seq, v.anomaly)
                self.get_logger().warning(f'anomaly at cycle {v.seq}: {v.anomaly}',
                                          throttle_duration_sec=1.0)
            if v.ready:
                self.get_logger().debug(f'cycle {v.seq}: part proven on the goal edge')

    # ------------------------------------------------------------------ diagnostics
    def _publish_diagnostics(self):
        m = self._monitor
        r = m.rules
        name = self.get_name()
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
        values = {'state': m.state, 'last_seq': m.last_seq, **m.counts,
                  'since_restart': m.since_restart, 'cycles_since_detection': m.gap,
                  'last_anomaly': m.last_anomaly, **r.as_dict()}
        statuses = [diagnostic_status(f'{name}: readiness', level, message, self._scene.name,
                                      values)]
        p = self._pairer
        lost = p.counts['proximity_lost']
        pending = p.pending
        in_level = 'warn' if lost > self._lost_mark or self._bad_input else 'ok'
        self._lost_mark = lost
        statuses.append(diagnostic_status(
            f'{name}: inputs', in_level,
            'proximity and cycle_status paired' if in_level == 'ok' else
            'proximity messages lost or malformed input', self._scene.name,
            {**p.counts, 'pending_status': pending[0], 'pending_proximity': pending[1],
             'bad_input': self._bad_input}))
        self._diag_pub.publish(diagnostic_array(self.get_clock().now().to_msg(), statuses))


def main(args=None):
    return run_node(MonitorNode, 'monitor_node', args)


if __name__ == '__main__':
    sys.exit(main())
