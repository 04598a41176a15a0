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

"""The driver node in-process (own Context, own domain) against the emulator on a pty."""

import math
import os
import threading
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from feeder_common import auth, messages
from feeder_driver import protocol as p
from feeder_driver.driver_node import DriverNode
from feeder_driver.emulator import Faults
from feeder_interfaces.msg import CycleStatus
from feeder_testing import EmulatorThread
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, qos_profile_sensor_data, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState, Range
from std_srvs.srv import SetBool, Trigger

# joint_states only at the cycle events unless a test asks for the steady rate.
FAST = {'ack_timeout_s': 0.15, 'cycle_timeout_s': 1.0, 'watchdog_timeout_s': 0.8,
        'reconnect_initial_s': 0.05, 'reconnect_max_s': 0.2, 'cycle_period': 0.03,
        'joint_states_rate': 0.0}


class Harness:
    """A driver node plus a probe node that records everything the driver publishes."""

    def __init__(self, domain_id, port, **overrides):
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=domain_id)
        self.executor = SingleThreadedExecutor(context=self.ctx)
        params = dict(FAST, port=port, **overrides)
        self.node = DriverNode(context=self.ctx, namespace='/feeder',
                               parameter_overrides=[Parameter(k, value=v)
                                                    for k, v in params.items()])
        self.probe = rclpy.create_node('probe', context=self.ctx)
        self.status, self.fired, self.prox, self.joints, self.diags = [], [], [], [], []
        for topic, got in (('cycle_status', self.status), ('cycle_fired', self.fired)):
            self.probe.create_subscription(
                CycleStatus, f'/feeder/{topic}', got.append,
                QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
        self.probe.create_subscription(Range, '/feeder/proximity', self.prox.append,
                                       qos_profile_sensor_data)
        self.probe.create_subscription(JointState, '/feeder/joint_states', self.joints.append,
                                       10)
        self.probe.create_subscription(DiagnosticArray, '/diagnostics', self.diags.append,
                                       QoSProfile(depth=10,
                                                  durability=DurabilityPolicy.VOLATILE))
        self.trigger_cl = self.probe.create_client(Trigger, '/feeder/feeder_driver/trigger_cycle')
        self.enable_cl = self.probe.create_client(SetBool, '/feeder/feeder_driver/enable')
        self.executor.add_node(self.node)
        self.executor.add_node(self.probe)
        assert self.trigger_cl.wait_for_service(timeout_sec=5)

    def start(self):
        assert self.node.trigger_configure() == TransitionCallbackReturn.SUCCESS
        assert self.node.trigger_activate() == TransitionCallbackReturn.SUCCESS
        return self

    def spin_until(self, cond, timeout=5.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if cond():
                return True
            self.executor.spin_once(timeout_sec=0.01)
        return cond()

    def spin_for(self, seconds):
        self.spin_until(lambda: False, seconds)

    def call(self, client, request, timeout=5.0):
        fut = client.call_async(request)
        assert self.spin_until(fut.done, timeout), 'service call timed out'
        return fut.result()

    def trigger(self):
        return self.call(self.trigger_cl, Trigger.Request())

    def enable(self, on):
        return self.call(self.enable_cl, SetBool.Request(data=on))

    def connected(self):
        return self.node.core.link == 'connected'

    def idle(self):
        return self.node.core.pending is None

    def wait_connected(self, timeout=5.0):
        assert self.spin_until(self.connected, timeout), self.node.core.last_link_error

    def close(self):
        self.node.destroy_node()
        self.probe.destroy_node()
        self.executor.shutdown()
        rclpy.shutdown(context=self.ctx)
        self.ctx.destroy()


@pytest.fixture
def emulator(scene_path, sensor_radius, link_path):
    started = []

    def make(**kw):
        kw.setdefault('cycle_time', 0.02)
        kw.setdefault('heartbeat', 0.1)
        emu = EmulatorThread(scene_path, link_path, sensor_radius=sensor_radius, **kw)
        started.append(emu.start())
        return emu

    yield make
    for emu in started:
        emu.stop()


@pytest.fixture
def harness(domain_id):
    made = []

    def make(port, **overrides):
        h = Harness(domain_id, port, **overrides)
        made.append(h)
        return h

    yield make
    for h in made:
        h.close()


def values(status):
    return {kv.key: kv.value for kv in status.values}


def reports(h):
    """Return the driver's cycle_status messages parsed (each one must parse)."""
    return [messages.parse_cycle_status(s) for s in h.status]


def check_accounting(h, emu):
    """
    Check that every fired cycle is accounted for; return (completed, failed) reports.

    Every fired cycle has exactly one cycle_fired and then one cycle_status, both signed in
    one session; proximity comes once per completed cycle, completed bits equal the
    emulator's truth, failures carry reasons.
    """
    core = h.node.core
    fired = core.counters['fired']
    assert h.spin_until(lambda: len(h.status) == len(h.fired) == fired and h.idle(), 5)
    statuses = reports(h)
    notices = [messages.parse_cycle_fired(m) for m in h.fired]
    assert [s.seq for s in statuses] == [n.seq for n in notices] == list(range(1, fired + 1))
    sessions = {s.session for s in statuses} | {n.session for n in notices}
    assert len(sessions) == 1 and sessions != {''}
    assert all(len(r.mac) == auth.MAC_BYTES for r in statuses + notices)
    assert all(n.stamp_ns <= s.stamp_ns for n, s in zip(notices, statuses))
    ok = [s for s in statuses if s.ok]
    failed = [s for s in statuses if not s.ok]
    assert len(ok) + len(failed) == fired
    assert core.counters['completed'] == len(ok) and core.counters['failed'] == len(failed)
    assert h.spin_until(lambda: len(h.prox) == len(ok), 2)
    assert len(h.prox) == len(ok)
    truth = {}
    for rec in emu.records:
        truth.setdefault(rec['seq'], []).append(rec)
    for s in ok:
        (rec,) = truth[s.seq]
        assert s.reason == '' and rec['outcome'] == 'completed'
        assert s.sensor == bool(rec['bit'])
    # proximity and cycle_status of a completed cycle carry the same sample stamp.
    prox = {messages.time_ns(r.header.stamp): r.range for r in h.prox}
    assert len(prox) == len(h.prox)
    for s in ok:
        assert prox[s.stamp_ns] == (-math.inf if s.sensor else math.inf)
    for s in failed:
        assert s.reason and s.sensor is None
        recs = truth.get(s.seq, [])
        # Failed on the driver side: the emulator either injected a fault into that
        # cycle, refused it, or never saw the FIRE.
        assert all(r['outcome'] != 'completed' or r['faults'] for r in recs), (s.reason, recs)
    return ok, failed


def test_normal_cycles(harness, emulator, link_path):
    emu = emulator()
    h = harness(link_path, sensor_range_m=0.03, frame_id='my_sensor').start()
    h.wait_connected()
    for k in range(1, 16):
        res = h.trigger()
        assert res.success and f'seq {k}' in res.message, res.message
        assert h.spin_until(h.idle, 2)
    ok, failed = check_accounting(h, emu)
    assert len(ok) == 15 and not failed
    r = h.prox[0]
    assert r.min_range == r.max_range == pytest.approx(0.03)
    assert r.radiation_type == Range.INFRARED and r.header.frame_id == 'my_sensor'
    first = h.status[0]
    assert first.outcome == CycleStatus.OUTCOME_COMPLETED and first.reason == ''
    assert first.sensor in (CycleStatus.SENSOR_CLEAR, CycleStatus.SENSOR_DETECTED)
    assert first.hardware_id == h.fired[0].hardware_id == link_path
    assert h.spin_until(lambda: len(h.joints) >= 30, 2)
    speeds = sorted({round(j.velocity[0], 4) for j in h.joints})
    assert speeds == [0.0, 5.585]
    assert all(j.name == ['feeder_arm_joint'] and list(j.effort) == [] for j in h.joints)


def test_joint_states_swing_between_cycle_events(harness, emulator, link_path):
    """At joint_states_rate the arm winds up, passes REL at its speed and is back at rest."""
    emulator(cycle_time=0.2)        # REL 0.1 s after FIRE, SENS 0.1 s after REL
    h = harness(link_path, joint_states_rate=200.0, cycle_period=0.5).start()
    h.wait_connected()
    h.spin_for(0.2)
    idle = list(h.joints)
    assert len(idle) >= 10 and all(j.position[0] == 0.0 for j in idle)
    for k in range(3):
        assert h.trigger().success
        assert h.spin_until(h.idle, 2)
        h.spin_for(0.05)
    joints = h.joints[len(idle):]
    stamps = [j.header.stamp.sec + j.header.stamp.nanosec * 1e-9 for j in joints]
    positions = [j.position[0] for j in joints]
    w = max(j.velocity[0] for j in joints)
    assert w == pytest.approx(5.585, rel=1e-3)     # REL's speed, on the release message
    # The first cycle assumes 0.05 s phases, the next ones measured 0.1 s each.
    assert min(positions) < -0.5 * 4 / 27 * w * 0.1
    assert max(positions) > 0.5 * 4 / 27 * w * 0.1
    # Within the profile's extremes for phases of 0.1 s (+ 20 % for the pty's latency).
    assert all(abs(p) <= 4 / 27 * w * 0.12 for p in positions)
    assert positions[-1] == 0.0
    gaps = [b - a for a, b in zip(stamps, stamps[1:])]
    # Events come 0.1 s apart: a gap this long means the swing was not published between
    # them. (At 200 Hz the gaps are 5 ms; a loaded machine stretches a few to tens of ms.)
    assert max(gaps) < 0.09, 'joint_states stopped between events'
    h.node.set_parameters([Parameter('joint_states_rate', value=0.0)])
    h.spin_for(0.05)
    before = len(h.joints)
    h.spin_for(0.3)
    assert len(h.joints) == before       # 0: only at the cycle events


def test_continuous_cycling_and_diagnostics(harness, emulator, link_path):
    emu = emulator()
    h = harness(link_path).start()
    h.wait_connected()
    res = h.enable(True)
    assert res.success, res.message
    refused = h.trigger()
    assert not refused.success and 'enable' in refused.message
    assert h.spin_until(lambda: len(h.status) >= 30, 10)
    assert h.enable(False).success
    ok, failed = check_accounting(h, emu)
    assert not failed
    fired = h.node.core.counters['fired']

    def diag_caught_up():
        return any(int(values(s).get('fired', -1)) == fired for d in h.diags for s in d.status)

    assert h.spin_until(diag_caught_up, 3)
    names = {s.name: s for s in h.diags[-1].status}
    link = names['feeder/feeder_driver: serial link']
    cyc = names['feeder/feeder_driver: cycles']
    assert link.level == DiagnosticStatus.OK and link.hardware_id == link_path
    assert values(link)['firmware'] == 'feeder-emu-1.0'
    assert int(values(cyc)['fired']) == fired >= 30
    assert cyc.level == DiagnosticStatus.OK and values(cyc)['enabled'] == 'false'


def test_every_fault_kind_is_accounted_for(harness, emulator, link_path):
    faults = Faults(drop_ack_every=5, drop_sens_every=7, garbage_every=3, delay=0.3,
                    delay_every=11, reset_after=17, seed=3)
    emu = emulator(faults=faults)
    h = harness(link_path).start()
    h.wait_connected()
    assert h.enable(True).success
    assert h.spin_until(lambda: len(h.status) >= 40, 20)
    h.enable(False)
    ok, failed = check_accounting(h, emu)
    reasons = ' | '.join(s.reason for s in failed)
    assert 'no ACK' in reasons               # delayed cycles (0.3 s > ack_timeout 0.15 s)
    assert 'SENS' in reasons                 # dropped SENS: IDLE heartbeat or timeout
    assert 'controller reset during cycle' in reasons
    kinds = {f for r in emu.records for f in r['faults']}
    assert kinds == {'drop_ack', 'drop_sens', 'garbage', 'delay', 'reset'}
    # A dropped ACK alone does not lose the cycle: REL/SENS imply it.
    drop_ack_only = [r for r in emu.records if r['faults'] == ['drop_ack']]
    assert drop_ack_only and all(r['outcome'] == 'completed' for r in drop_ack_only)
    assert h.node.core.counters['acks_missing'] >= len(drop_ack_only)
    stats = h.node.link.parser.stats
    assert stats['checksum'] > 0 and stats['overlong'] > 0 and stats['garbage_bytes'] > 0
    assert len(ok) >= 25


def test_unplug_replug_reconnects(harness, emulator, link_path):
    emu = emulator(faults=Faults(unplug_after=3, unplug_for=0.6))
    h = harness(link_path).start()
    h.wait_connected()
    for k in range(1, 5):
        assert h.trigger().success
        assert h.spin_until(lambda: len(h.status) == k, 2)
    lost = reports(h)[3]
    assert (lost.ok, lost.sensor) == (False, None)
    assert 'serial link lost during cycle' in lost.reason
    res = h.trigger()
    assert not res.success and 'serial link is disconnected' in res.message, res.message
    assert not h.enable(True).success
    h.wait_connected(5)
    assert h.node.core.counters['link_losses'] == 1
    assert h.node.core.counters['open_failures'] >= 1     # the link was gone for a while
    for _ in range(3):
        assert h.trigger().success
        assert h.spin_until(h.idle, 2)
    ok, failed = check_accounting(h, emu)
    assert len(ok) == 6 and len(failed) == 1


def test_refusals_when_inactive_or_disconnected(harness, tmp_path):
    h = harness(str(tmp_path / 'no-such-port'))
    res = h.trigger()
    assert not res.success and 'unconfigured' in res.message
    assert h.node.trigger_configure() == TransitionCallbackReturn.SUCCESS
    res = h.trigger()
    assert not res.success and 'inactive' in res.message
    assert not h.enable(True).success
    assert h.node.trigger_activate() == TransitionCallbackReturn.SUCCESS
    h.spin_for(0.3)
    res = h.trigger()
    assert not res.success and 'disconnected' in res.message
    assert 'No such file' in res.message or 'could not open' in res.message, res.message
    res = h.enable(True)
    assert not res.success and 'disconnected' in res.message
    assert h.node.core.counters['fired'] == 0 and h.status == h.fired == []
    assert h.spin_until(lambda: h.diags, 3)
    link = [s for s in h.diags[-1].status if s.name.endswith('serial link')][0]
    assert link.level == DiagnosticStatus.ERROR and 'open failed' in link.message


def test_busy_refusal_and_deactivate_abort(harness, emulator, link_path):
    emu = emulator(cycle_time=0.6)
    h = harness(link_path).start()
    h.wait_connected()
    assert h.trigger().success
    res = h.trigger()
    assert not res.success and 'busy with cycle seq 1' in res.message
    h.spin_for(0.1)
    assert h.node.trigger_deactivate() == TransitionCallbackReturn.SUCCESS
    assert h.spin_until(lambda: h.status, 2)
    (aborted,) = reports(h)
    assert (aborted.seq, aborted.ok, aborted.reason) == (1, False, 'aborted: node deactivated')
    assert h.status[0].outcome == CycleStatus.OUTCOME_FAILED
    assert h.spin_until(lambda: emu.records, 2)
    assert emu.records[0]['outcome'] == 'aborted'      # the controller got STOP
    res = h.trigger()
    assert not res.success and 'inactive' in res.message


def _fake_device(path, reply_ping=True, noise=False, stop=None):
    """Serve a pty that answers PING, then stays silent (or emits only noise)."""
    master, slave = os.openpty()
    os.symlink(os.ttyname(slave), path)

    def serve():
        parser = p.Parser(p.HOST_MESSAGES)
        while not stop.is_set():
            try:
                import select
                r, _, _ = select.select([master], [], [], 0.05)
                if noise:
                    os.write(master, b'\xfe\xff\x00garbage 9600 baud?\r\n')
                if r:
                    for e in parser.feed(os.read(master, 1024)):
                        if reply_ping and isinstance(e, p.Ping):
                            os.write(master, p.encode(p.Pong(e.token)))
            except OSError:
                return

    t = threading.Thread(target=serve, daemon=True)
    t.start()
    return t, master, slave


@pytest.mark.parametrize('noise', [False, True], ids=['silent', 'noise'])
def test_watchdog_and_handshake_timeouts(harness, link_path, noise):
    stop = threading.Event()
    t, master, slave = _fake_device(link_path, reply_ping=not noise, noise=noise, stop=stop)
    try:
        h = harness(link_path).start()
        if noise:
            assert h.spin_until(lambda: h.node.core.counters['handshake_timeouts'] >= 1, 5)
            assert 'no PONG' in h.node.core.last_link_error
            assert h.node.link.parser.stats['garbage_bytes'] > 0
        else:
            h.wait_connected()
            assert h.spin_until(lambda: h.node.core.counters['watchdog_timeouts'] >= 1, 5)
            assert 'silent' in h.node.core.last_link_error
    finally:
        stop.set()
        t.join()
        os.close(master)
        os.close(slave)


def test_second_driver_cannot_open_the_same_port(harness, emulator, link_path, domain_id):
    emulator()
    h = harness(link_path).start()
    h.wait_connected()
    from feeder_driver.serial_link import LinkError, SerialLink
    other = SerialLink(link_path, 115200, lambda *a: None, lambda *a: None)
    with pytest.raises(LinkError, match='exclusively lock'):
        other.open_port()


@pytest.mark.parametrize('name, value, text', [
    ('cycle_period', -1.0, 'out of range'),
    ('cycle_period', 'fast', 'Wrong parameter type'),
    ('ack_timeout_s', 2.0, 'must be smaller than cycle_timeout_s'),
    ('reconnect_initial_s', 30.0, 'must not exceed reconnect_max_s'),
    ('frame_id', ' ', 'frame_id must not be empty'),
    ('frame_id', 'f' * 1_000_000, 'frame_id is 1000000 characters long; at most 256'),
    ('port', '/dev/other', 'read-only'),
    ('baud_rate', 9600, 'read-only'),
])
def test_bad_parameters_are_rejected_with_a_reason(harness, link_path, name, value, text):
    h = harness(link_path)
    (res,) = h.node.set_parameters([Parameter(name, value=value)])
    assert not res.successful and text in res.reason, res.reason


def test_good_parameters_apply(harness, link_path):
    h = harness(link_path)
    (res,) = h.node.set_parameters([Parameter('cycle_timeout_s', value=2.5)])
    assert res.successful
    assert h.node.core.config.cycle_timeout_s == 2.5
    res = h.node.set_parameters_atomically([Parameter('reconnect_initial_s', value=20.0),
                                            Parameter('reconnect_max_s', value=40.0)])
    assert res.successful and h.node.core.backoff.maximum == 40.0
