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

"""Helpers of the graph tests: start the feeder's nodes, collect what they publish."""

from dataclasses import dataclass
import pathlib
from typing import Optional

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from feeder_common.diagnostics import local_name
from feeder_common.messages import check_verdict, parse_cycle_status, parse_predicted_state
from feeder_interfaces.msg import CycleStatus, PredictedState, Verdict
import pytest
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Range
from std_srvs.srv import SetBool
from throwmap import analyse, load_scene, sees

# The test's own QoS (written out here, not taken from the code under test).
RELIABLE = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)
LATCHED = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
STARTUP_TIMEOUT = 60.0
REPO = pathlib.Path(__file__).resolve().parents[1]
TRIANGLE = str(REPO / 'scenes' / 'triangle.yaml')
EXPERIMENT = str(REPO / 'scenes' / 'experiment.yaml')
SHORT_ARM = str(REPO / 'tests' / 'scenes' / 'short_arm.yaml')
NS = '/feeder'
MONITOR = '/feeder/feeder_monitor'      # the monitor whose signature the consumers check
DRIVER = '/feeder/feeder_driver'        # the driver, or the stand-in in its place
PREDICTOR = '/feeder/feeder_sim'        # the predictor beside them (predictor())
# A statement on edge1_ready counts as ready now only if the monitor sent it at most this long
# before it arrived (its idle republish is every ready_deadline / 4 = 0.25 s by default).
FRESH_S = 1.0


def sim_as_hardware(graph, *params, scene=TRIANGLE, ns='/feeder', wrapper=()):
    """standin_node in place of the driver: /feeder/feeder_driver, the driver's interface."""
    args = ['--ros-args', '-r', f'__ns:={ns}', '-r', '__node:=feeder_driver',
            '-p', f'scene:={scene}']
    for p in params:
        args += ['-p', p]
    return graph.start('feeder_sim', 'standin_node', *args, name='sim_hw', wrapper=wrapper)


def predictor(graph, *params, scene=TRIANGLE, ns='/feeder'):
    """predictor_node (/feeder/feeder_sim) beside the hardware, in the same namespace."""
    args = ['--ros-args', '-r', f'__ns:={ns}', '-p', f'scene:={scene}']
    for p in params:
        args += ['-p', p]
    return graph.start('feeder_sim', 'predictor_node', *args, name='predictor')


def monitor(graph, *params, scene=TRIANGLE, ns='/feeder', wrapper=()):
    args = ['--ros-args', '-r', f'__ns:={ns}', '-p', f'scene:={scene}']
    for p in params:
        args += ['-p', p]
    return graph.start('feeder_monitor', 'monitor_node', *args, name='monitor', wrapper=wrapper)


class Collector:
    """Messages of one topic, in arrival order."""

    def __init__(self, ros, msg_type, topic, qos=RELIABLE):
        self.msgs = []
        self.sub = ros.node.create_subscription(msg_type, topic, self.msgs.append, qos)

    def __len__(self):
        return len(self.msgs)


class Diagnostics:
    """Every DiagnosticStatus on /diagnostics, by name."""

    def __init__(self, ros):
        self.by_name = {}
        ros.node.create_subscription(DiagnosticArray, '/diagnostics', self._on, RELIABLE)

    def _on(self, msg):
        # By the name within the feeder (a test watches one feeder): 'feeder_driver: cycles'
        # for '/feeder/feeder_driver: cycles' (feeder_common.diagnostics.local_name).
        for s in msg.status:
            self.by_name.setdefault(local_name(s.name), []).append(s)

    def levels(self, name):
        return [s.level for s in self.by_name.get(name, [])]

    @staticmethod
    def values(status):
        return {kv.key: kv.value for kv in status.values}


@dataclass(frozen=True)
class Checked:
    """One Verdict as a consumer sees it: its fields and check_verdict's answer on arrival."""

    seq: int
    stamp_ns: Optional[int]     # the cycle's sample stamp; None: no cycle judged yet
    ready: bool                 # the field as sent
    state: str
    anomaly: str
    session: str
    authentic: bool             # the MAC verifies for the monitor under the test's key
    ready_now: bool             # check_verdict: signed, fresh and ready when it arrived
    reason: str                 # check_verdict's reason ('' when ready_now)
    sent_age_s: float


class Statements(Collector):
    """
    Signed Verdicts of one topic (edge1_ready by default), each checked when it arrives.

    ``checked`` holds what check_verdict said of each (under the test's key, for ``monitor``,
    at the test node's clock), so ``ready_now`` is what a consumer would have acted on.
    """

    def __init__(self, ros, topic='/feeder/edge1_ready', qos=LATCHED, monitor=MONITOR,
                 max_age_s=FRESH_S, event_callbacks=None):
        self.ros, self.monitor, self.max_age_s = ros, monitor, max_age_s
        self.msgs, self.checked = [], []
        self.sub = ros.node.create_subscription(Verdict, topic, self._on, qos,
                                                event_callbacks=event_callbacks)

    def _on(self, msg):
        now = self.ros.node.get_clock().now().nanoseconds
        c = check_verdict(msg, self.ros.key, self.monitor, now, self.max_age_s)
        self.msgs.append(msg)
        self.checked.append(Checked(int(msg.seq), c.stamp_ns, bool(msg.ready), msg.state,
                                    msg.anomaly, msg.session, c.authentic, c.ready_now,
                                    c.reason, c.sent_age_s))

    @property
    def ready_now(self):
        return [c.ready_now for c in self.checked]

    def any_ready(self, start=0):
        return any(c.ready_now for c in self.checked[start:])

    def wait_matched(self, n=1):
        """Wait until the monitor's writer matched this reader (edge1_verdict is volatile)."""
        self.ros.wait_matched(self.sub, n, STARTUP_TIMEOUT)


class Verdicts(Statements):
    """
    The monitor's per-cycle verdicts (edge1_verdict), checked: one per judged cycle.

    Count them by seq (``by_seq``): edge1_ready is the current statement, republished while
    idle, so only edge1_verdict can be matched to cycles.
    """

    def __init__(self, ros, topic='/feeder/edge1_verdict', monitor=MONITOR):
        # A verdict is read later than it was sent: freshness is edge1_ready's business.
        super().__init__(ros, topic, RELIABLE, monitor, max_age_s=3600.0)

    @property
    def parsed(self):
        return list(self.checked)

    @property
    def by_seq(self):
        """{seq: [verdicts of that seq, in arrival order]}."""
        out = {}
        for c in self.checked:
            out.setdefault(c.seq, []).append(c)
        return out


class PredictedStates(Collector):
    """The predictor's per-cycle states (predicted/state, PredictedState), parsed."""

    def __init__(self, ros, ns='/feeder'):
        super().__init__(ros, PredictedState, f'{ns}/predicted/state')

    @property
    def parsed(self):
        return [parse_predicted_state(m) for m in self.msgs]


class CycleStatuses(Collector):
    """
    The driver's (or stand-in's) cycle reports on cycle_status (CycleStatus), in order.

    ``parsed``: each as feeder_common.messages.parse_cycle_status reads it (a ValueError if
    the driver wrote one the contract does not take).
    """

    def __init__(self, ros, topic='/feeder/cycle_status', qos=RELIABLE):
        super().__init__(ros, CycleStatus, topic, qos)

    @property
    def parsed(self):
        return [parse_cycle_status(m) for m in self.msgs]

    @property
    def seqs(self):
        return [s.seq for s in self.parsed]


def wait_for_monitor(ros, ready):
    """
    Wait for the monitor's latched initial statement on edge1_ready.

    It is signed by the monitor under the test's key, about no cycle yet (seq 0, no stamp),
    not ready.
    """
    ros.spin_until(lambda: len(ready) >= 1, STARTUP_TIMEOUT, 'latched edge1_ready')
    first = ready.checked[0]
    assert first.authentic, first.reason
    assert (first.seq, first.stamp_ns, first.ready) == (0, None, False), first
    assert first.state in (Verdict.STATE_WARMING_UP, Verdict.STATE_TRACKING), first


def wait_for_readers(ros, topic, count):
    """
    Wait until ``count`` readers of ``topic`` are on the graph (ours included).

    On the graph is not matched: a writer may not reach them yet. For our own endpoints use
    ``ros.wait_matched``; for the monitor's readers of the driver's reports,
    :func:`wait_monitor_matched`.
    """
    ros.spin_until(lambda: ros.node.count_subscribers(topic) >= count, STARTUP_TIMEOUT,
                   f'{count} readers of {topic} on the graph')


def wait_for_publishers(ros, topic, count):
    """Wait until ``count`` writers of ``topic`` are on the graph (see wait_for_readers)."""
    ros.spin_until(lambda: ros.node.count_publishers(topic) >= count, STARTUP_TIMEOUT,
                   f'{count} publishers of {topic} on the graph')


def wait_reports_matched(ros, status_readers, proximity_readers, fired_readers=1,
                         verdict_readers=1, driver=DRIVER, monitor=MONITOR):
    """
    Wait until the driver's (stand-in's) and the monitor's writers matched their readers.

    Their own accounts (each node's ``endpoints`` status, feeder_common.diagnostics): the
    driver's cycle_status, proximity and cycle_fired writers matched at least so many readers
    (the monitor's, ours, a predictor's...), the monitor's edge1_verdict writer
    ``verdict_readers``. Only then do the first cycles' volatile reports reach every reader.
    """
    ros.wait_remote_matched(driver, readers={
        f'{NS}/cycle_status': status_readers, f'{NS}/proximity': proximity_readers,
        f'{NS}/cycle_fired': fired_readers})
    if verdict_readers:
        ros.wait_remote_matched(monitor, readers={f'{NS}/edge1_verdict': verdict_readers})


def watch_monitor(ros):
    """
    Collect edge1_ready, edge1_verdict and cycle_status beside one monitor and the stand-in.

    Returns (ready, verdicts, statuses) once the monitor's latched edge1_ready came, its
    verdict writer matched, and cycle_status and proximity have their readers.
    """
    ready = Statements(ros)
    verdicts = Verdicts(ros)
    statuses = CycleStatuses(ros)
    wait_for_monitor(ros, ready)
    # cycle_status: the monitor's reader and ours; proximity, cycle_fired: the monitor's.
    wait_reports_matched(ros, status_readers=2, proximity_readers=1)
    ros.wait_active(DRIVER)
    return ready, verdicts, statuses


def run_cycles(ros, cycles, statuses, period):
    """Enable cycling until ``statuses`` holds ``cycles`` messages, then disable it."""
    ros.wait_active(DRIVER)
    res = ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=True))
    assert res.success, res.message
    ros.spin_until(lambda: len(statuses) >= cycles, 20 + 3 * cycles * period,
                   f'{cycles} cycles')
    res = ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=False))
    assert res.success, res.message


def monitor_rules(ros, diags):
    """
    (warm-up, settle) throws of the running monitor, from its readiness diagnostics.

    A detection can be ready only once more than ``settle`` throws have been judged since the
    monitor (re)started and at least ``warm-up`` since its last anomaly (issue 20: never while a
    pattern check is off).
    """
    name = 'feeder_monitor: readiness'
    ros.spin_until(lambda: diags.by_name.get(name), STARTUP_TIMEOUT, 'the monitor diagnostics')
    values = diags.values(diags.by_name[name][-1])
    return int(values['warmup_cycles']), int(values['settle_cycles'])


def check_statements(ready, verdicts):
    """
    What edge1_ready said agrees with the per-cycle verdicts, and never held a ready too long.

    Every statement is signed by the monitor; a statement that was ready on arrival names a
    cycle whose verdict was ready (with that cycle's stamp); once a statement about a later
    cycle came, no ready about an earlier one follows (a ready holds until the next cycle).
    """
    assert all(c.authentic for c in ready.checked), \
        [c.reason for c in ready.checked if not c.authentic][:3]
    ready_verdicts = {v.seq: v.stamp_ns for v in verdicts.checked if v.ready}
    latest = 0
    for c in ready.checked:
        if c.ready_now:
            assert ready_verdicts.get(c.seq, 'no') == c.stamp_ns, \
                f'edge1_ready true for cycle {c.seq} without a ready verdict of that cycle'
            assert c.seq >= latest, f'a ready for cycle {c.seq} after a statement on {latest}'
        latest = max(latest, c.seq)


def reference_readies(scene_path, seqs, bits):
    """
    The readies of feeder_monitor.readiness itself, in-process, for these judged cycles.

    The same rules as the node derives them by default (throwmap.scene_analysis, a limit-set
    orbit of 20000 throws), each cycle announced as fired before it is judged.
    """
    from feeder_monitor.readiness import (limit_set_orbit, ReadinessMonitor,
                                          rules_from_analysis)
    from throwmap import scene_analysis
    sc = load_scene(scene_path)
    base = analyse(sc)
    m = ReadinessMonitor(rules_from_analysis(sc, scene_analysis(sc, 0.0, base),
                                             limit_set_orbit(sc, base, 20000)))
    out = []
    for seq, bit in zip(seqs, bits):
        if hasattr(m, 'fired'):
            m.fired(seq)
        out.append(bool(m.completed(seq, bit).ready))
    return out


def check_ready_correctness(graph, ros, scene, cycles, period, min_ready, complete=True):
    """
    Run the sim as hardware, a predictor and the monitor on ``scene``; check every verdict.

    ``cycles``: cycles after the first one that can be ready (the monitor's warm-up and
    settling, read from its diagnostics, come on top). Every cycle completes once, with one
    proximity and one prediction; the sensor bit is the sensor geometry of the predicted state
    (the scene is deterministic: the predictor's state is the simulated part's); every verdict
    is signed; a verdict is ready only for a cycle whose part is seen on the goal edge once the
    warm-up and the settling are done, exactly as feeder_monitor.readiness says in-process for
    the same bits (at least ``min_ready`` of them), and edge1_ready agrees; the monitor reports
    no anomaly and counts the same. ``complete``: moreover every cycle seen on the goal edge
    after the warm-up and settling is ready (where the scene's prediction is sure of the edge
    after every detection, as on the triangle; the experiment's is not always).
    """
    sim = sim_as_hardware(graph, f'cycle_period:={period}', scene=scene)
    pred = predictor(graph, scene=scene)
    mon = monitor(graph, scene=scene)
    sc = load_scene(scene)
    an = analyse(sc)
    goal, radius = an.sensor.goal_edge, an.sensor.radius
    footprint = an.sensor.footprint

    ready = Statements(ros)
    verdict_stream = Verdicts(ros)
    statuses = CycleStatuses(ros)
    prox = Collector(ros, Range, '/feeder/proximity')
    states = PredictedStates(ros)
    diags = Diagnostics(ros)
    wait_for_monitor(ros, ready)
    # cycle_status: the monitor's, the predictor's and our readers; proximity: the monitor's
    # and ours; the predictor's predicted/state: ours.
    wait_reports_matched(ros, status_readers=3, proximity_readers=2)
    ros.wait_remote_matched(PREDICTOR, readers={f'{NS}/predicted/state': 1})
    warmup, settle = monitor_rules(ros, diags)
    assert warmup >= an.sensor.warmup_throws
    first_ready = max(warmup, settle + 1)       # judged throws before a detection can count

    run_cycles(ros, first_ready + cycles, statuses, period)
    ros.spin_until(lambda: len(states) >= len(statuses), 10.0, 'the predictor')
    ros.spin_for(1.5)                           # let the monitor finish the last cycles
    n = len(statuses)
    assert n >= first_ready + cycles
    reports = statuses.parsed
    seqs = [s.seq for s in reports]
    assert seqs == list(range(seqs[0], seqs[0] + n))
    assert all(s.ok and s.reason == '' for s in reports)
    assert all(m.outcome == CycleStatus.OUTCOME_COMPLETED for m in statuses.msgs)
    predicted = states.parsed
    assert len(prox) == n and [p.seq for p in predicted] == seqs

    # The sim's sensor bit is the sensor geometry applied to its predicted state.
    truth = [bool(sees(sc.part, p.edge, p.R, radius, footprint)) for p in predicted]
    assert [p.range == float('-inf') for p in prox.msgs] == truth
    assert [s.sensor for s in reports] == truth
    for p in prox.msgs:
        assert p.radiation_type == Range.INFRARED and p.header.frame_id == 'feeder_sensor'
        assert p.min_range == p.max_range == pytest.approx(0.02, rel=1e-6)     # float32

    # One signed verdict per cycle on edge1_verdict, each naming its cycle's seq and sample
    # stamp (the monitor may have missed the very first cycles while discovery finished).
    parsed = verdict_stream.parsed
    missed = n - len(parsed)
    assert 0 <= missed <= 3, f'{len(parsed)} verdicts for {n} cycles'
    assert [v.seq for v in parsed] == seqs[missed:]
    assert [v.stamp_ns for v in parsed] == [s.stamp_ns for s in reports[missed:]]
    assert all(v.authentic for v in parsed), [v.reason for v in parsed if not v.authentic][:3]
    assert len({v.session for v in parsed} | {c.session for c in ready.checked}) == 1
    verdicts = [v.ready for v in parsed]
    assert not any(v.ready and v.state != Verdict.STATE_READY for v in parsed)
    # edge1_ready (the current statement) ends as the last verdict, and agrees throughout.
    last = ready.checked[-1]
    assert (last.seq, last.ready) == (parsed[-1].seq, verdicts[-1])
    check_statements(ready, verdict_stream)
    on_goal = 0
    for j, verdict in enumerate(verdicts):
        k = j + missed
        edge, R = predicted[k].edge, predicted[k].R
        seen_on_goal = truth[k] and edge == goal
        if verdict:
            assert seen_on_goal, f'edge1_ready at cycle {seqs[k]} but the part is on edge ' \
                f'{edge} at R {R:.4f} m (sensor sees it: {truth[k]})'
            assert j + 1 >= first_ready, f'cycle {seqs[k]} ready after {j + 1} judged ' \
                f'throws: the warm-up ({warmup}) and settling ({settle}) are not done'
        if seen_on_goal and j + 1 >= first_ready:
            on_goal += 1
            assert verdict or not complete, \
                f'cycle {seqs[k]}: part seen on the goal edge, not reported'
    assert verdicts == reference_readies(scene, seqs[missed:], truth[missed:])
    assert sum(verdicts) >= min_ready and (sum(verdicts) == on_goal or not complete)

    # The monitor saw nothing the limit set cannot produce, and counted the same.
    ros.spin_for(1.2)
    name = 'feeder_monitor: readiness'
    assert diags.levels(name), 'no monitor diagnostics'
    assert DiagnosticStatus.ERROR not in diags.levels(name), \
        [s.message for s in diags.by_name[name] if s.level == DiagnosticStatus.ERROR]
    last = diags.values(diags.by_name[name][-1])
    assert int(last['ready']) == sum(verdicts) and int(last['anomalies']) == 0
    assert int(last['completed']) == len(verdicts)
    assert sim.poll() is None and mon.poll() is None and pred.poll() is None


def funnel_policy(out_dir, speeds='120:600:20', robust=0.005, scene=TRIANGLE):
    """Write the policy of ``throwmap funnel SCENE --speeds SPEEDS`` in ``out_dir``; return it."""
    import json
    from throwmap import funnel as F
    arm, _ = F.arm_scene(load_scene(scene), None)
    result = F.plan(arm, F.parse_speeds(speeds), robust=robust, cells=200, one_bit=False)
    path = pathlib.Path(out_dir) / f'{arm.name}_funnel_policy.json'
    path.write_text(json.dumps(F.policy_dict(result, scene)))
    return path


def start_emulator(graph, link, *args, scene=TRIANGLE):
    """Start controller_emulator on a pty at ``link``; return its process once the link exists."""
    import os
    import time
    emu = graph.start('feeder_driver', 'controller_emulator', '--scene', scene, '--link', link,
                      *args, name='emulator')
    end = time.monotonic() + STARTUP_TIMEOUT
    while not os.path.islink(link):
        assert emu.poll() is None, graph.log(emu)
        assert time.monotonic() < end, 'the emulator did not create its pty link'
        time.sleep(0.05)
    return emu
