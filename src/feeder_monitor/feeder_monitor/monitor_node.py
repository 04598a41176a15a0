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

from feeder_common import auth, qos
from feeder_common.diagnostics import Updater
from feeder_common.messages import (parse_cycle_fired, parse_cycle_status, proximity_detected,
                                    signed_setpoint, signed_verdict, time_ns)
from feeder_common.node import FeederLifecycleNode, flush, publish, run_node
from feeder_common.parameters import ParameterGate
from feeder_common.params import check_scene
from feeder_interfaces.msg import CycleStatus, SpeedSetpoint, Verdict
from lifecycle_msgs.msg import TransitionEvent
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.lifecycle import TransitionCallbackReturn
from sensor_msgs.msg import Range
from std_srvs.srv import Trigger
from throwmap import analyse, load_scene, scene_analysis, ThrowmapError

from .params import MONITOR_PARAMS
from .readiness import (ANOMALY, limit_set_orbit, ReadinessMonitor, rules_from_analysis,
                        WARMING_UP)
from .speed_policy import load_tracker, PolicyReadiness
from .trust import ReportGate

RULE_PARAMS = ('sensor_radius', 'warmup_cycles', 'settle_cycles', 'silence_margin',
               'early_margin_cycles', 'run_margin_cycles')
# Sensor bits of recent cycles, by sample stamp, for the proximity cross-check.
CROSS_CHECK_DEPTH = 256
# A heartbeat later than this many periods means the monitor itself stalled.
STALL_PERIODS = 3
# Analyses (by sensor radius) and rule sets (by the rule parameters) kept per configuration.
ANALYSIS_CACHE = 16


class MonitorNode(FeederLifecycleNode):
    """
    Consumes cycle_status, cycle_fired, proximity; publishes edge1_ready, edge1_verdict.

    A lifecycle node. Configure loads the key and runs the analysis (limit set, sensor design,
    limit-set orbit, rules; a failure is a failed configure with the reason) and creates the
    subscriptions and the (lifecycle) publishers; activate starts judging afresh (warm-up and
    settling) with the statement false; deactivate, cleanup and shutdown leave a final false
    statement. edge1_ready is never true unless the node is active and judged the cycle ready.

    It judges only reports that prove themselves (feeder_monitor.trust: signed by ``driver_node``
    under ``key_file``, fresh, of the driver's current run, next in seq). Its statement about
    the part (``feeder_interfaces/Verdict``: the cycle's seq and stamp, ready, state) is signed
    too, republished with a fresh ``sent`` every quarter of ``ready_deadline`` while idle, and
    turned false the moment a cycle fires, the driver's liveliness lapses, it leaves its active
    state, or the monitor finds it stalled itself.
    """

    def __init__(self, **kwargs):
        # Set before Node.__init__: a context shutdown may destroy a half-built node.
        self._active = False
        self._ready_pub = self._verdict_pub = self._setpoint_pub = None
        self._beat_timer = None
        self._tracker = None        # the speed policy (speed_policy set), configured
        # The driver's run and its newest cycle the driver signed a report of (admitted or
        # refused as stale): the next setpoint is for the cycle after it. None: not known.
        self._last_driver_cycle = None
        super().__init__('feeder_monitor', **kwargs)
        # Scenes by path, loaded once (the parameter checks load them too).
        self._load_scene = functools.lru_cache(maxsize=None)(load_scene)
        self._scene = None
        # Configured (on_configure .. cleanup): the key, the analysis, the rules, the gate.
        self._key = None
        self._base = None
        self._orbit = None
        self._rules_now = None
        self._gate = None
        self._session = None
        # scene_analysis by sensor_radius and rules by the rule parameters, for this
        # configuration: a parameter file sets its parameters one at a time (the validate and
        # the apply of each), and all of them share one analysis.
        self._analyses = collections.OrderedDict()
        self._rule_sets = collections.OrderedDict()
        self._work = {'analyses': 0, 'rule_builds': 0}
        self._rules_pending = False     # rule parameters changed, rules not rebuilt yet
        self._rebuild_queued = False
        # Active (on_activate .. deactivate): the judging.
        self._monitor = None
        self._subs = []
        self._params = ParameterGate(self, MONITOR_PARAMS, self._validate, self._apply)
        p = self._params
        p.declare_all(names=('autostart', 'scene'))
        self._scene = self._load_scene(p.values['scene'])
        p.declare_all()
        for name in p.unknown_given():
            self.get_logger().warning(f'parameter {name} is not a parameter of monitor_node; '
                                      'ignored (docs/nodes.md lists them)')
        self._driver = self.resolve_topic_name(self._param('driver_node'))
        self._fqn = self.get_fully_qualified_name()
        self._anomaly_in_period = None
        self._bad_input = 0
        self._bad_mark = 0
        self._counts = {'unsigned_fired': 0, 'disagreements': 0, 'stalls': 0,
                        'liveliness_lost': 0}
        self._recent_bits = collections.OrderedDict()       # stamp_ns -> (seq, bit)
        self._recent_proximity = collections.OrderedDict()  # stamp_ns -> bit
        # The statement on edge1_ready: (seq, stamp_ns, ready, state, anomaly).
        self._statement = (0, None, False, WARMING_UP, '')
        self._beat_period = self._param('ready_deadline') / 4
        self._last_beat = self._last_sent = time.monotonic()
        # Diagnostics exist in every lifecycle state (an unconfigured monitor says so).
        self._diagnostics = Updater(self, self._param('diagnostic_updater.period'),
                                    self._scene.name)
        self._diagnostics.add('readiness', self._diag_readiness)
        self._diagnostics.add('inputs', self._diag_inputs)
        # In every state, so that a refusal can say why. Unsigned: a call can only lower the
        # statement and cost readies, never make one.
        self.create_service(Trigger, '~/new_part', self._on_new_part)

    # ------------------------------------------------------------------ lifecycle
    def on_configure(self, state):
        scene = self._scene
        try:
            key = auth.node_key(self._param('key_file'))
        except auth.KeyFileError as exc:
            return self._configure_failed(f'key_file: {exc}')
        try:
            self._base = analyse(scene)
            self._orbit = limit_set_orbit(scene, self._base, self._param('orbit_throws'))
            rules = self._rules({})
        except ThrowmapError as exc:
            return self._configure_failed(f'scene {scene.source}: {exc}')
        except ValueError as exc:       # a rule parameter the analysis rejects
            return self._configure_failed(str(exc))
        if self._param('speed_policy'):
            try:
                self._tracker = load_tracker(self._param('speed_policy'), rules, scene)
            except ValueError as exc:   # throwmap.InputError included
                return self._configure_failed(str(exc))
        self._key = key
        self._rules_now = rules
        self._rules_pending = False
        self._gate = ReportGate(key, self._driver, self._param('max_report_age'))
        self._session = auth.new_session()
        self._statement = (0, None, False, WARMING_UP, '')
        pub = self.create_lifecycle_publisher
        self._ready_pub = pub(Verdict, 'edge1_ready',
                              qos.edge1_ready(self._param('ready_deadline')))
        self._verdict_pub = pub(Verdict, 'edge1_verdict', qos.EDGE1_VERDICT)
        if self._tracker is not None:
            self._setpoint_pub = pub(SpeedSetpoint, 'release_speed_setpoint',
                                     qos.RELEASE_SPEED_SETPOINT)
        sub = self.create_subscription
        self._subs = [
            sub(TransitionEvent, f'{self._driver}/transition_event',
                self._on_driver_transition, qos.DEFAULT),
            sub(Range, 'proximity', self._on_proximity, qos.PROXIMITY_SUBSCRIPTION),
            sub(CycleStatus, 'cycle_status', self._on_cycle_status, qos.CYCLE_STATUS,
                event_callbacks=SubscriptionEventCallbacks(
                    liveliness=self._on_driver_liveliness)),
            sub(CycleStatus, 'cycle_fired', self._on_cycle_fired, qos.CYCLE_FIRED),
        ]
        self._log_rules(rules)
        if self._tracker is not None:
            t = self._tracker.system
            self.get_logger().info(
                f'speed policy {self._param("speed_policy")}: {t.speeds.size} speeds '
                f'{t.speeds.min():.3f}..{t.speeds.max():.3f} rad/s, {t.n} cells, error bound '
                f's = {t.robust:g}; readies by its knowledge, setpoints on '
                f'{self.resolve_topic_name("release_speed_setpoint")}')
        self.get_logger().info(f'judging reports of {self._driver} signed with key id '
                               f'{auth.key_id(self._key)}; verdicts signed as {self._fqn}')
        return super().on_configure(state)

    def _configure_failed(self, reason):
        self._forget_analysis()
        self.configure_error = reason
        self.get_logger().error(f'configure failed: {reason}')
        return TransitionCallbackReturn.FAILURE

    def on_activate(self, state):
        self._flush_rules()
        # Judging starts afresh: cycles may have fired while inactive.
        self._monitor = (ReadinessMonitor(self._rules_now) if self._tracker is None else
                         PolicyReadiness(self._rules_now, self._tracker))
        result = super().on_activate(state)     # the publishers send from here on
        self._active = True
        self._statement = (0, None, False, WARMING_UP, '')
        self._publish_statement()
        self._publish_setpoint()
        self._last_beat = time.monotonic()
        self._beat_timer = self.create_timer(self._beat_period, self._on_heartbeat)
        return result

    def on_deactivate(self, state):
        self._stop_judging('monitor deactivated: not judging')
        return super().on_deactivate(state)

    def on_cleanup(self, state):
        self._release()
        return super().on_cleanup(state)

    def on_shutdown(self, state):
        self._stop_judging('monitor stopped')
        self._release()
        return super().on_shutdown(state)

    def on_error(self, state):
        self._stop_judging('monitor error')
        self._release()
        return TransitionCallbackReturn.SUCCESS

    def _stop_judging(self, why):
        """Stop judging; say false while the publisher can still send, and wait for readers."""
        self._active = False
        if self._beat_timer is not None:
            self.destroy_timer(self._beat_timer)
            self._beat_timer = None
        pub = self._ready_pub
        if pub is None or not pub.is_activated:
            return      # the last statement sent was already false (or none was sent)
        seq, stamp_ns = self._statement[:2]
        self._statement = (seq, stamp_ns, False, ANOMALY, why)
        try:
            self._publish_statement()
            flush(pub)
        except Exception:   # noqa: B902 - context already gone: nothing can be said
            pass

    def _release(self):
        self._stop_judging('monitor stopped')
        for s in self._subs:
            self.destroy_subscription(s)
        self._subs = []
        for pub in (self._ready_pub, self._verdict_pub, self._setpoint_pub):
            if pub is not None:
                self.destroy_lifecycle_publisher(pub)
        self._ready_pub = self._verdict_pub = self._setpoint_pub = None
        self._tracker = None
        self._monitor = self._gate = self._key = None
        self._last_driver_cycle = None
        self._recent_bits.clear()
        self._recent_proximity.clear()
        self._forget_analysis()

    def _forget_analysis(self):
        self._base = self._orbit = self._rules_now = None
        self._analyses.clear()
        self._rule_sets.clear()
        self._rules_pending = False

    def destroy_node(self):
        # A clean exit says false, and waits (briefly) until the readers have it.
        self._stop_judging('monitor stopped')
        return super().destroy_node()

    # ------------------------------------------------------------------ parameters
    def _param(self, name):
        return self._params.values[name]

    def _analysis_at(self, sensor_radius):
        """Return throwmap.scene_analysis at ``sensor_radius``, computed once per configure."""
        an = self._analyses.get(sensor_radius)
        if an is None:
            an = scene_analysis(self._scene, sensor_radius, self._base)
            self._work['analyses'] += 1
            self._analyses[sensor_radius] = an
            while len(self._analyses) > ANALYSIS_CACHE:
                self._analyses.popitem(last=False)
        return an

    def _rules(self, changes):
        """Rules from the current parameters overridden by ``changes``; ValueError if invalid."""
        values = tuple(changes[n] if n in changes else self._param(n) for n in RULE_PARAMS)
        rules = self._rule_sets.get(values)
        if rules is None:
            radius, *rest = values
            rules = rules_from_analysis(self._scene, self._analysis_at(radius), self._orbit,
                                        *rest)
            self._work['rule_builds'] += 1
            self._rule_sets[values] = rules
            while len(self._rule_sets) > ANALYSIS_CACHE:
                self._rule_sets.popitem(last=False)
        return rules

    def _validate(self, changes, current):
        if 'scene' in changes:
            reason = check_scene(changes['scene'], self._load_scene)
            if reason:
                return reason
        if self._tracker is not None and 'sensor_radius' in changes:
            return (f'sensor_radius cannot change while speed_policy is set: the policy was made '
                    f'for the sensor at {self._tracker.system.sensor_radius:.6f} m (clean up '
                    'the monitor, then configure it with a policy made for the new sensor)')
        # Unconfigured (no analysis yet) the rules are checked at configure.
        if self._base is not None and any(n in changes for n in RULE_PARAMS):
            try:
                self._rules(changes)
            except ValueError as exc:
                return str(exc)
        return None

    def _apply(self, changes):
        if 'diagnostic_updater.period' in changes:
            self._diagnostics.set_period(changes['diagnostic_updater.period'])
        if 'max_report_age' in changes and self._gate is not None:
            self._gate.max_age_ns = int(round(changes['max_report_age'] * 1e9))
        if self._base is not None and any(n in changes for n in RULE_PARAMS):
            # New rules: no ready holds from now on (the rebuild restarts the warm-up). The
            # rebuild waits until the parameter service call is done (``ros2 param load`` sets
            # one parameter at a time): one rebuild, log and statement per file. Any cycle
            # judged meanwhile rebuilds first.
            self._rules_pending = True
            seq, stamp_ns, ready = self._statement[:3]
            if ready:
                self._set_statement(seq, stamp_ns, False, WARMING_UP)
            self._queue_rebuild()

    def _queue_rebuild(self):
        if self._rebuild_queued:
            return
        executor = self.executor
        if executor is None:        # not spun: nothing to wait for
            self._flush_rules()
            return
        self._rebuild_queued = True
        executor.create_task(self._on_rebuild)

    def _on_rebuild(self):
        self._rebuild_queued = False
        self._flush_rules()

    def _flush_rules(self):
        """Take the rules of the current parameters if they changed since the last time."""
        if not self._rules_pending or self._base is None:
            return
        self._rules_pending = False
        rules = self._rules({})
        self._rules_now = rules
        self._log_rules(rules)
        if self._monitor is not None:
            self._monitor.set_rules(rules)
            if self._active:
                seq, stamp_ns = self._statement[:2]
                self._set_statement(seq, stamp_ns, False, self._monitor.state)

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
        if not self._active:
            return      # not judging: the statement is false
        self._flush_rules()     # rule parameters set just now apply to this cycle
        try:
            status = parse_cycle_status(msg)
        except ValueError as exc:
            self._bad_input += 1
            self._judge(self._monitor.untrusted(self._monitor.last_seq or 0,
                                                f'malformed cycle_status: {exc}'), None)
            return
        admission = self._gate.admit(status, self._now_ns())
        if admission.authentic:
            self._driver_cycle(status.session, status.seq)
        if not admission.admitted:
            self._judge(self._monitor.untrusted(status.seq, admission.reason), status.stamp_ns)
            self._publish_setpoint()
            return
        if admission.new_run:
            # A restarted driver: its first cycles follow none of the old run's.
            reason = f'{self._driver} started a new run (session {status.session})'
            self._monitor.new_run(reason)
            self._note_interrupt(reason)
        if status.ok and status.sensor is not None:
            self._remember(self._recent_bits, status.stamp_ns, (status.seq, status.sensor))
            if self._tracker is not None:
                v = self._monitor.completed(status.seq, status.sensor,
                                            speed=status.release_speed)
            else:
                v = self._monitor.completed(status.seq, status.sensor)
        else:
            v = self._monitor.failed(status.seq, status.reason)
        self._judge(v, status.stamp_ns)
        self._publish_setpoint()
        self._cross_check(status.stamp_ns)

    def _on_cycle_fired(self, msg):
        # Any notice lowers a ready (a forged one can only cost a ready, never make one); only
        # a signed one of the current run moves the monitor's idea of the newest cycle, so a
        # forged huge seq cannot make every later verdict look superseded.
        if not self._active:
            return
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
        if not self._active:
            return
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
        if verdict and msg is not None:
            publish(self._verdict_pub, msg, self.get_logger())

    def _publish_statement(self):
        """Sign and publish the statement (a lifecycle publisher: sent only while active)."""
        if self._ready_pub is None:
            return None
        seq, stamp_ns, ready, state, anomaly = self._statement
        msg = signed_verdict(self._key, self._fqn, self._session, seq, stamp_ns, ready, state,
                             anomaly, self._now_ns())
        if publish(self._ready_pub, msg, self.get_logger()):
            # (a refused statement leaves _last_sent: the heartbeat sends it again soon)
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
        self._publish_setpoint()

    def _on_driver_liveliness(self, info):
        if not self._active:
            return
        # Any writer of cycle_status that lost its liveliness: the event does not say which
        # one, and another live writer (a forger's) must not hide a dead or stopped driver, so
        # every loss counts (a forger can only cost a ready this way).
        if info.not_alive_count_change > 0 or \
                (info.alive_count == 0 and info.alive_count_change < 0):
            self._counts['liveliness_lost'] += 1
            self._interrupt(f'{self._driver} is not alive (no liveliness within '
                            f'{qos.DRIVER_LEASE_S:g} s: it died or hangs)')

    def _on_driver_transition(self, msg):
        if not self._active:
            return
        if msg.goal_state.label != 'active' and msg.start_state.label == 'active':
            self._interrupt(f'{self._driver} left its active state ({msg.transition.label})')

    def _on_new_part(self, request, response):
        if not self._active:
            response.success = False
            response.message = (f'refused: the monitor is {self.lifecycle_state}, not active '
                                '(it judges nothing: a part placed now is judged from its '
                                'activation)')
            return response
        self._monitor.new_part()
        seq, stamp_ns = self._statement[:2]
        self._set_statement(seq, stamp_ns, False, self._monitor.state)
        self._publish_setpoint()
        response.success = True
        if self._tracker is not None:
            response.message = ('new part: edge1_ready false; the speed policy starts from its '
                                f'start set, next speed {self._monitor.next_speed:.4f} rad/s')
        else:
            response.message = (f'new part: edge1_ready false; warm-up and settling start again '
                                f'({self._monitor.throws_to_go} throws before a ready can come)')
        self.get_logger().info(response.message)
        return response

    def _interrupt(self, reason):
        """No cycle can be judged (the driver left, stopped or is unproven): false, warm up."""
        self._monitor.interrupt(reason)
        self._note_interrupt(reason)
        self._publish_setpoint()

    def _publish_setpoint(self):
        """
        Sign and publish the next cycle's release speed (speed policy only; while active).

        Addressed to the cycle after the newest the driver's run signed a report of (judged, or
        refused as stale: either way it fired, and a setpoint for it would never be used);
        before any, to the next cycle of any run (driver_session ''): the cycle's signed report
        says the speed it was fired at, and the knowledge follows that speed.
        """
        if self._setpoint_pub is None or not self._active or \
                not isinstance(self._monitor, PolicyReadiness):
            return
        last = self._last_driver_cycle
        seq, session = (last[1] + 1, last[0]) if last is not None else (0, '')
        publish(self._setpoint_pub, signed_setpoint(
            self._key, self._fqn, self._session, seq, session, self._monitor.next_speed,
            self._now_ns()), self.get_logger())

    def _driver_cycle(self, session, seq):
        """Note a cycle the driver signed (a report refused as stale too: it fired)."""
        last = self._last_driver_cycle
        if session != self._gate.session:
            return      # an ended run's: the current run's numbering stands
        if last is None or last[0] != session or seq > last[1]:
            self._last_driver_cycle = (session, seq)

    def _note_interrupt(self, reason):
        self._anomaly_in_period = (self._monitor.last_seq, reason)
        self.get_logger().warning(f'{reason}: edge1_ready false, warming up again')
        seq, stamp_ns = self._statement[:2]
        self._set_statement(seq, stamp_ns, False, ANOMALY, reason)

    # ------------------------------------------------------------------ diagnostics
    def _diag_readiness(self, stat):
        lifecycle = self.lifecycle_state
        common = {'lifecycle': lifecycle, 'trusted_driver': self._driver,
                  'key_id': auth.key_id(self._key) if self._key else 'none', **self._work}
        if not self._active:
            # Not judging: edge1_ready is false (or was never sent); the rules, once analysed.
            r = self._rules_now
            stat.summary('warn', f'{lifecycle}: not judging, edge1_ready false' +
                         ('' if r is not None else ' (not configured: no analysis)'))
            stat.update({'state': lifecycle, **common, **(r.as_dict() if r else {}),
                         'namespace': self.get_namespace()})
            return
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
        stat.update({'state': m.state, 'last_seq': m.last_seq, **m.counts, **common,
                     'driver_session': self._gate.session or 'none',
                     'since_restart': m.since_restart, 'cycles_since_detection': m.gap,
                     'last_anomaly': m.last_anomaly, **r.as_dict(),
                     'namespace': self.get_namespace(), **self._policy_diag(m)})

    def _policy_diag(self, m):
        if not isinstance(m, PolicyReadiness):
            return {'speed_policy': 'none (the fixed design)'}
        return {'speed_policy': self._param('speed_policy'),
                'next_release_speed': f'{m.next_speed:.4f}',
                'knowledge_cells': m.knowledge_cells, 'last_policy_word': m.result or 'none'}

    def _diag_inputs(self, stat):
        gate_counts = self._gate.counts if self._gate is not None else {}
        refused = {k: v for k, v in gate_counts.items() if k != 'admitted'}
        bad = self._bad_input + sum(refused.values()) + self._counts['disagreements'] + \
            self._counts['unsigned_fired']
        level = 'warn' if bad > self._bad_mark else 'ok'
        self._bad_mark = bad
        stat.summary(level, 'every cycle report signed, fresh and in order' if level == 'ok'
                     else 'refused reports, malformed input or a contradicting proximity')
        # Informative only: who is on the graph decides nothing (docs/security.md).
        stat.update({**gate_counts, **self._counts, 'bad_input': self._bad_input,
                     'cycle_status_publishers':
                         self.count_publishers(self.resolve_topic_name('cycle_status'))})


def main(args=None):
    return run_node(MonitorNode, 'monitor_node', args)


if __name__ == '__main__':
    sys.exit(main())
