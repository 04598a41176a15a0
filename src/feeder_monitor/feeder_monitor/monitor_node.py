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
monitor_node: says when a detection proves the part lies on the goal edge, signed and stamped.

ROS glue only: the rules and the state machine are feeder_monitor.readiness's, which reports it
may judge feeder_monitor.trust's, the analysis throwmap's (throwmap.scene_analysis, the same
numbers the sim uses), the contract (QoS, message builders and parsers, keys, parameters, run
helper) feeder_common's.
"""

import collections
import functools
import sys
import time

from diagnostic_msgs.msg import DiagnosticStatus
from feeder_common import auth, qos
from feeder_common.diagnostics import Updater
from feeder_common.messages import (parse_cycle_fired, parse_cycle_status, proximity_detected,
                                    signed_verdict, time_ns)
from feeder_common.node import flush, run_node, StartupError, watch_clock
from feeder_common.parameters import ParameterGate
from feeder_common.params import check_scene
from feeder_interfaces.msg import Verdict
from lifecycle_msgs.msg import TransitionEvent
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.node import Node
from sensor_msgs.msg import Range
from throwmap import analyse, load_scene, scene_analysis, ThrowmapError

from .params import MONITOR_PARAMS
from .readiness import (ANOMALY, limit_set_orbit, ReadinessMonitor, rules_from_analysis,
                        WARMING_UP)
from .trust import ReportGate

RULE_PARAMS = ('sensor_radius', 'warmup_cycles', 'settle_cycles', 'silence_margin',
               'early_margin_cycles', 'run_margin_cycles')
# Sensor bits of recent cycles, by sample stamp, for the proximity cross-check.
CROSS_CHECK_DEPTH = 256
# A heartbeat later than this many periods means the monitor itself stalled.
STALL_PERIODS = 3


class MonitorNode(Node):
    """
    Consumes cycle_status, cycle_fired, proximity; publishes edge1_ready, edge1_verdict.

    It judges only reports that prove themselves (feeder_monitor.trust: signed by ``driver_node``
    under ``key_file``, fresh, of the driver's current run, next in seq). Its statement about
    the part (``feeder_interfaces/Verdict``: the cycle's seq and stamp, ready, state) is signed
    too, republished with a fresh ``sent`` every quarter of ``ready_deadline`` while idle, and
    turned false the moment a cycle fires, the driver's liveliness lapses, it leaves its active
    state, or the monitor finds it stalled itself.
    """

    def __init__(self, **kwargs):
        super().__init__('feeder_monitor', **kwargs)
        watch_clock(self)       # a warning if use_sim_time is on and no /clock comes
        # Scenes by path, loaded once (the parameter checks load them too).
        self._load_scene = functools.lru_cache(maxsize=None)(load_scene)
        self._scene = None
        self._base = None
        self._orbit = None
        self._monitor = None
        self._params = ParameterGate(self, MONITOR_PARAMS, self._validate, self._apply)
        p = self._params
        self._scene = self._load_scene(p.declare('scene'))
        try:
            self._key = auth.node_key(p.declare('key_file'))
        except auth.KeyFileError as exc:
            raise StartupError(f'key_file: {exc}') from None
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
        self._driver = self.resolve_topic_name(self._param('driver_node'))
        self._gate = ReportGate(self._key, self._driver, self._param('max_report_age'))
        self._fqn = self.get_fully_qualified_name()
        self._session = auth.new_session()
        self._anomaly_in_period = None
        self._bad_input = 0
        self._bad_mark = 0
        self._counts = {'unsigned_fired': 0, 'disagreements': 0, 'stalls': 0,
                        'liveliness_lost': 0}
        self._recent_bits = collections.OrderedDict()       # stamp_ns -> (seq, bit)
        self._recent_proximity = collections.OrderedDict()  # stamp_ns -> bit

        # The statement on edge1_ready: (seq, stamp_ns, ready, state, anomaly).
        self._statement = (0, None, False, WARMING_UP, '')
        self._ready_pub = self.create_publisher(
            Verdict, 'edge1_ready', qos.edge1_ready(self._param('ready_deadline')))
        self._verdict_pub = self.create_publisher(Verdict, 'edge1_verdict', qos.EDGE1_VERDICT)
        self.create_subscription(TransitionEvent, f'{self._driver}/transition_event',
                                 self._on_driver_transition, qos.DEFAULT)
        self._beat_period = self._param('ready_deadline') / 4
        self._last_beat = time.monotonic()
        self.create_timer(self._beat_period, self._on_heartbeat)
        self.create_subscription(Range, 'proximity', self._on_proximity,
                                 qos.PROXIMITY_SUBSCRIPTION)
        self.create_subscription(
            DiagnosticStatus, 'cycle_status', self._on_cycle_status, qos.CYCLE_STATUS,
            event_callbacks=SubscriptionEventCallbacks(liveliness=self._on_driver_liveliness))
        self.create_subscription(DiagnosticStatus, 'cycle_fired', self._on_cycle_fired,
                                 qos.CYCLE_FIRED)
        self._diagnostics = Updater(self, self._param('diagnostic_updater.period'),
                                    self._scene.name)
        self._diagnostics.add('readiness', self._diag_readiness)
        self._diagnostics.add('inputs', self._diag_inputs)
        self._publish_statement()
        self._log_rules(rules)
        self.get_logger().info(f'judging reports of {self._driver} signed with key id '
                               f'{auth.key_id(self._key)}; verdicts signed as {self._fqn}')

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
        if 'diagnostic_updater.period' in changes:
            self._diagnostics.set_period(changes['diagnostic_updater.period'])
        if 'max_report_age' in changes:
            self._gate.max_age_ns = int(round(changes['max_report_age'] * 1e9))
        if any(n in changes for n in RULE_PARAMS):
            rules = self._rules({})
            self._monitor.set_rules(rules)
            self._log_rules(rules)
            self._set_statement(self._statement[0], self._statement[1], False,
                                self._monitor.state)

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
    def _now_ns(self):
        return self.get_clock().now().nanoseconds

    def _on_cycle_status(self, msg):
        try:
            status = parse_cycle_status(msg)
        except ValueError as exc:
            self._bad_input += 1
            self._judge(self._monitor.untrusted(self._monitor.last_seq or 0,
                                                f'malformed cycle_status: {exc}'), None)
            return
        admission = self._gate.admit(status, self._now_ns())
        if not admission.admitted:
            self._judge(self._monitor.untrusted(status.seq, admission.reason), status.stamp_ns)
            return
        if admission.new_run:
            # A restarted driver: its first cycles follow none of the old run's.
            reason = f'{self._driver} started a new run (session {status.session})'
            self._monitor.new_run(reason)
            self._note_interrupt(reason)
        if status.ok and status.sensor is not None:
            self._remember(self._recent_bits, status.stamp_ns, (status.seq, status.sensor))
            v = self._monitor.completed(status.seq, status.sensor)
        else:
            v = self._monitor.failed(status.seq, status.message if not status.ok
                                     else 'a completed cycle without a sensor bit')
        self._judge(v, status.stamp_ns)
        self._cross_check(status.stamp_ns)

    def _on_cycle_fired(self, msg):
        # Any notice lowers a ready (a forged one can only cost a ready, never make one); only
        # a signed one of the current run moves the monitor's idea of the newest cycle, so a
        # forged huge seq cannot make every later verdict look superseded.
        try:
            notice = parse_cycle_fired(msg)
        except ValueError:
            self._bad_input += 1
            notice = None
        if notice is None or self._gate.fired_authentic(notice):
            self._counts['unsigned_fired'] += 1
        elif notice.session == self._gate.session:
            self._monitor.fired(notice.seq)
        seq, stamp_ns, ready = self._statement[:3]
        if ready:
            self._set_statement(seq, stamp_ns, False, Verdict.STATE_CYCLING)

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
        self._remember(self._recent_proximity, stamp_ns, detected)
        self._cross_check(stamp_ns)

    @staticmethod
    def _remember(table, stamp_ns, value):
        if stamp_ns is None:
            return
        table[stamp_ns] = value
        while len(table) > CROSS_CHECK_DEPTH:
            table.popitem(last=False)

    def _cross_check(self, stamp_ns):
        """Interrupt when a proximity contradicts the signed bit of its cycle (a broken path)."""
        if stamp_ns is None or stamp_ns not in self._recent_bits or \
                stamp_ns not in self._recent_proximity:
            return
        seq, bit = self._recent_bits.pop(stamp_ns)
        if self._recent_proximity.pop(stamp_ns) != bit:
            self._counts['disagreements'] += 1
            self._interrupt(f'proximity contradicts the signed sensor bit of cycle {seq}')

    def _judge(self, v, stamp_ns):
        self._set_statement(v.seq, stamp_ns, v.ready, v.state, v.anomaly or '', verdict=True)
        if v.note:
            self.get_logger().warning(v.note)
        if v.anomaly:
            self._anomaly_in_period = (v.seq, v.anomaly)
            self.get_logger().warning(f'anomaly at cycle {v.seq}: {v.anomaly}',
                                      throttle_duration_sec=1.0)
        if v.ready:
            self.get_logger().debug(f'cycle {v.seq}: part proven on the goal edge')

    def _set_statement(self, seq, stamp_ns, ready, state, anomaly='', verdict=False):
        self._statement = (int(seq), stamp_ns, bool(ready), state, anomaly)
        msg = self._publish_statement()
        if verdict:
            self._verdict_pub.publish(msg)

    def _publish_statement(self):
        seq, stamp_ns, ready, state, anomaly = self._statement
        msg = signed_verdict(self._key, self._fqn, self._session, seq, stamp_ns, ready, state,
                             anomaly, self._now_ns())
        self._ready_pub.publish(msg)
        self._last_sent = time.monotonic()
        return msg

    def _on_heartbeat(self):
        now = time.monotonic()
        late = now - self._last_beat
        self._last_beat = now
        if late > STALL_PERIODS * self._beat_period:
            # Cycles may have fired while this process did not run: what it held is unproven
            # until the next report is judged (a stale backlog is refused by the gate).
            self._counts['stalls'] += 1
            seq, stamp_ns, ready = self._statement[:3]
            if ready:
                self._set_statement(seq, stamp_ns, False, ANOMALY,
                                    f'the monitor itself stalled for {late:.2f} s')
            else:
                self._publish_statement()
        elif now - self._last_sent >= self._beat_period * 0.9:
            self._publish_statement()

    def _on_driver_liveliness(self, info):
        # Any writer of cycle_status that lost its liveliness: the event does not say which
        # one, and another live writer (a forger's) must not hide a dead or stopped driver, so
        # every loss counts (a forger can only cost a ready this way).
        if info.not_alive_count_change > 0 or \
                (info.alive_count == 0 and info.alive_count_change < 0):
            self._counts['liveliness_lost'] += 1
            self._interrupt(f'{self._driver} is not alive (no liveliness within '
                            f'{qos.DRIVER_LEASE_S:g} s: it died or hangs)')

    def _on_driver_transition(self, msg):
        if msg.goal_state.label != 'active' and msg.start_state.label == 'active':
            self._interrupt(f'{self._driver} left its active state ({msg.transition.label})')

    def _interrupt(self, reason):
        """No cycle can be judged (the driver left, stopped or is unproven): false, warm up."""
        self._monitor.interrupt(reason)
        self._note_interrupt(reason)

    def _note_interrupt(self, reason):
        self._anomaly_in_period = (self._monitor.last_seq, reason)
        self.get_logger().warning(f'{reason}: edge1_ready false, warming up again')
        seq, stamp_ns = self._statement[:2]
        self._set_statement(seq, stamp_ns, False, ANOMALY, reason)

    def destroy_node(self):
        # A clean exit says false, and waits (briefly) until the readers have it.
        try:
            seq, stamp_ns = self._statement[:2]
            self._statement = (seq, stamp_ns, False, ANOMALY, 'monitor stopped')
            self._publish_statement()
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
            level, message = 'ok', f'warming up ({m.throws_to_go} throws to go)'
        else:
            level, message = 'ok', m.state
        if level != 'error' and r.provable and r.noisy_sensor:
            message = f'{message} (noisy sensor: {self._noise_note(r)})'
        stat.summary(level, message)
        stat.update({'state': m.state, 'last_seq': m.last_seq, **m.counts,
                     'trusted_driver': self._driver, 'key_id': auth.key_id(self._key),
                     'driver_session': self._gate.session or 'none',
                     'since_restart': m.since_restart, 'cycles_since_detection': m.gap,
                     'last_anomaly': m.last_anomaly, **r.as_dict(),
                     'namespace': self.get_namespace()})

    def _diag_inputs(self, stat):
        refused = {k: v for k, v in self._gate.counts.items() if k != 'admitted'}
        bad = self._bad_input + sum(refused.values()) + self._counts['disagreements'] + \
            self._counts['unsigned_fired']
        level = 'warn' if bad > self._bad_mark else 'ok'
        self._bad_mark = bad
        stat.summary(level, 'every cycle report signed, fresh and in order' if level == 'ok'
                     else 'refused reports, malformed input or a contradicting proximity')
        # Informative only: who is on the graph decides nothing (docs/security.md).
        stat.update({**self._gate.counts, **self._counts, 'bad_input': self._bad_input,
                     'cycle_status_publishers':
                         self.count_publishers(self.resolve_topic_name('cycle_status'))})


def main(args=None):
    return run_node(MonitorNode, 'monitor_node', args)


if __name__ == '__main__':
    sys.exit(main())
