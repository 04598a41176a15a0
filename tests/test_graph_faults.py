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
Issues 10 and 20 on real DDS: forged and replayed cycles, a stale verdict, a huge seq, the
driver's last words.

A forger without the key (a process of its own that publishes ``cycle_status`` with seq =
last + 1 and sensor 1, unsigned or signed under another key, and leaves the graph at once)
never gets a ready: each forged report is an anomaly, and the monitor warms up again. A replay
of a genuine signed report is refused; a replayed ready statement reads as stale to a consumer.
"""

import signal
import subprocess
import sys
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from feeder_common import auth, qos
from feeder_common.messages import check_verdict, cycle_status
from feeder_interfaces.msg import CycleStatus, Verdict
from feeder_nodes import (CycleStatuses, Diagnostics, DRIVER, LATCHED, MONITOR, monitor,
                          PredictedStates, predictor, sim_as_hardware, start_emulator,
                          STARTUP_TIMEOUT, Statements, TRIANGLE, Verdicts, wait_for_monitor,
                          wait_reports_matched, watch_monitor)
import pytest
from rclpy.duration import Duration
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.qos import DurabilityPolicy, LivelinessPolicy, QoSProfile, ReliabilityPolicy
from std_srvs.srv import SetBool, Trigger

PERIOD = 0.01
FORGED = 50

# The forger: a process of its own, under any node name (who publishes decides nothing). It
# waits until the monitor (and the test) read its writers, publishes ``count`` reports of
# sensor 1 from seq ``first`` with a matching proximity each, unsigned or signed as the driver
# (its name and current session) under a key that is not the feeder's, waits until the readers
# acknowledged them, and leaves the graph at once (about 50 ms after its last report).
FORGER = """
import sys, time
import rclpy
from feeder_interfaces.msg import CycleStatus
from rclpy.duration import Duration
from sensor_msgs.msg import Range
from feeder_common import auth, qos
from feeder_common.messages import CycleSigner, cycle_status, proximity
mode, first, count, key_path, session, readers = sys.argv[1:7]
first, count, readers = int(first), int(count), int(readers)
rclpy.init()
node = rclpy.create_node('forger')
# the driver's own QoS (the monitor's reader asks for a liveliness lease of 1 s)
status_pub = node.create_publisher(CycleStatus, '/feeder/cycle_status', qos.CYCLE_STATUS)
prox_pub = node.create_publisher(Range, '/feeder/proximity', qos.PROXIMITY)
end = time.monotonic() + 30
while status_pub.get_subscription_count() < readers or prox_pub.get_subscription_count() < 1:
    if time.monotonic() > end:
        sys.exit('forger: the readers did not match')
    time.sleep(0.01)
signer = None
if mode == 'wrong_key':
    signer = CycleSigner(auth.load_key(key_path), '/feeder/feeder_driver', session)
t0 = node.get_clock().now().nanoseconds
for k in range(count):
    t = t0 + k * 1000
    prox_pub.publish(proximity(t, True, 0.02))
    args = (first + k, True, '', True, t, 'forged')
    status_pub.publish(signer.cycle_status(*args) if signer else cycle_status(*args))
acked = status_pub.wait_for_all_acked(Duration(seconds=10))
print(f'forger: {count} reports from seq {first}, acknowledged: {acked}', flush=True)
node.destroy_node()
rclpy.shutdown()
"""


def run_forger(tmp_path, mode, first, count, session, readers=2):
    """Run the forger to its end (it leaves the graph at once); return what it printed."""
    from feeder_testing import install_env
    other = tmp_path / 'other-keys' / 'hmac.key'
    auth.ensure_key(other)          # a key, but not the feeder's
    out = subprocess.run([sys.executable, '-c', FORGER, mode, str(first), str(count),
                          str(other), session, str(readers)], env=install_env(),
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stdout + out.stderr
    assert 'acknowledged: True' in out.stdout, out.stdout
    return out.stdout


def trigger_until_ready(ros, verdicts, limit=600):
    """Fire single cycles until the monitor's verdict is ready (the part proven on goal)."""
    for _ in range(limit):
        n = len(verdicts)
        res = ros.call(Trigger, '/feeder/feeder_driver/trigger_cycle', Trigger.Request())
        assert res.success, res.message
        ros.spin_until(lambda: len(verdicts) > n, 10.0, 'a verdict')
        if verdicts.parsed[-1].ready:
            return verdicts.parsed[-1]
    raise AssertionError(f'no ready verdict in {limit} cycles')


def trigger_one(ros, verdicts):
    """Fire one cycle; return its verdict."""
    n = len(verdicts)
    res = ros.call(Trigger, '/feeder/feeder_driver/trigger_cycle', Trigger.Request())
    assert res.success, res.message
    ros.spin_until(lambda: len(verdicts) > n, 10.0, 'a verdict')
    return verdicts.parsed[-1]


def no_ready_from(ready, first_seq):
    """From the first statement about a cycle >= ``first_seq`` on, none is ready (checked)."""
    start = next(i for i, c in enumerate(ready.checked) if c.seq >= first_seq)
    late = [c for c in ready.checked[start:] if c.ready or c.ready_now]
    assert not late, late[:3]
    return start


@pytest.mark.parametrize('mode', ['unsigned', 'wrong_key'])
def test_a_forger_without_the_key_that_leaves_at_once_never_makes_a_ready(graph, ros, tmp_path,
                                                                          mode):
    """Issue 20 attack 1 (hit and run), a burst of 50: every forged report an anomaly."""
    sim_as_hardware(graph, f'cycle_period:={PERIOD}')
    monitor(graph)
    ready, verdicts, statuses = watch_monitor(ros)
    last = trigger_until_ready(ros, verdicts)
    session = statuses.parsed[-1].session
    assert ready.checked[-1].ready_now
    n_verdicts = len(verdicts)

    run_forger(tmp_path, mode, last.seq + 1, FORGED, session)
    ros.spin_until(lambda: len(verdicts) >= n_verdicts + FORGED, 10.0, f'{FORGED} verdicts')
    ros.spin_until(lambda: ros.node.count_publishers('/feeder/cycle_status') == 1, 20.0,
                   'the forger to leave')
    ros.spin_for(1.0)       # long after the forger left (the hit-and-run window of issue 20)
    forged = verdicts.parsed[n_verdicts:]
    assert [v.seq for v in forged] == list(range(last.seq + 1, last.seq + 1 + FORGED))
    assert all(v.authentic and not v.ready and v.state == Verdict.STATE_ANOMALY
               for v in forged), forged[:3]
    why = 'unsigned report' if mode == 'unsigned' else 'bad MAC'
    assert all('not trusted' in v.anomaly and why in v.anomaly for v in forged), forged[0]
    # edge1_ready: false from the first forged report on, and it stays false while idle.
    no_ready_from(ready, last.seq + 1)
    assert ready.checked[-1].state == Verdict.STATE_ANOMALY

    # The driver's next cycle is its own seq (the forged ones did not count), judged as
    # trusted; the monitor warms up and settles again and proves the goal edge anew.
    nxt = trigger_one(ros, verdicts)
    assert nxt.seq == last.seq + 1 and nxt.authentic and 'not trusted' not in nxt.anomaly
    assert not nxt.ready
    again = trigger_until_ready(ros, verdicts)
    assert again.seq > last.seq + 1
    assert len(statuses) >= again.seq + FORGED


def test_a_replayed_report_is_refused_and_a_replayed_ready_reads_stale(graph, ros):
    """Genuine signed reports sent again (at once, and later), and an old ready statement."""
    sim_as_hardware(graph, f'cycle_period:={PERIOD}')
    monitor(graph)
    ready, verdicts, statuses = watch_monitor(ros)
    last = trigger_until_ready(ros, verdicts)
    genuine = next(m for m in statuses.msgs if m.seq == last.seq)     # signed, as sent
    ready_stmt = next(m for m, c in zip(ready.msgs, ready.checked)
                      if c.ready_now and c.seq == last.seq)
    pub = ros.node.create_publisher(CycleStatus, '/feeder/cycle_status', qos.CYCLE_STATUS)
    ros.spin_until(lambda: pub.get_subscription_count() >= 2, 20.0, 'the monitor')

    # At once: the same seq again (a duplicate) is refused.
    n = len(verdicts)
    pub.publish(genuine)
    ros.spin_until(lambda: len(verdicts) > n, 10.0, 'the verdict of the replay')
    dup = verdicts.parsed[-1]
    assert (dup.seq, dup.ready, dup.state) == (last.seq, False, Verdict.STATE_ANOMALY)
    assert 'replayed or duplicate' in dup.anomaly, dup.anomaly
    # Later (beyond max_report_age, 1 s), after more cycles: refused as stale.
    for _ in range(3):
        trigger_one(ros, verdicts)
    ros.spin_for(1.5)
    n = len(verdicts)
    pub.publish(genuine)
    ros.spin_until(lambda: len(verdicts) > n, 10.0, 'the verdict of the late replay')
    late = verdicts.parsed[-1]
    assert (late.seq, late.ready, late.state) == (last.seq, False, Verdict.STATE_ANOMALY)
    assert 'stale report' in late.anomaly or 'replayed' in late.anomaly, late.anomaly
    ros.spin_for(0.5)
    assert not ready.any_ready(len(ready) - 5) and not ready.checked[-1].ready

    # The monitor's own ready statement, sent again on edge1_ready by another writer: signed,
    # but its sent time is old, so a consumer's check says not ready.
    rogue = ros.node.create_publisher(Verdict, '/feeder/edge1_ready', LATCHED)
    ros.spin_until(lambda: rogue.get_subscription_count() >= 1, 20.0, 'our own reader')
    n = len(ready)
    rogue.publish(ready_stmt)
    # (the monitor's own idle republish names the same seq, as an anomaly since the late
    # replay: the replayed statement is the one that says ready)
    ros.spin_until(lambda: any(c.seq == last.seq and c.ready for c in ready.checked[n:]),
                   10.0, 'the replayed statement')
    replayed = next(c for c in ready.checked[n:] if c.seq == last.seq and c.ready)
    assert replayed.authentic and not replayed.ready_now
    assert 'ago' in replayed.reason, replayed.reason


def test_a_verdict_is_live_false_on_exit_and_a_killed_monitor_shows(graph, ros):
    """
    edge1_ready: republished while idle well within the deadline with a fresh signed sent
    time, false on SIGINT; on SIGKILL liveliness goes, and the last true reads stale.
    """
    sim_as_hardware(graph, f'cycle_period:={PERIOD}')
    mon_a = monitor(graph, 'ready_deadline:=0.2')
    mon_b = graph.start('feeder_monitor', 'monitor_node', '--ros-args', '-r', '__ns:=/feeder',
                        '-r', '__node:=feeder_monitor_b', '-r', 'edge1_ready:=edge1_ready_b',
                        '-r', 'edge1_verdict:=edge1_verdict_b',
                        '-p', f'scene:={TRIANGLE}', '-p', 'ready_deadline:=0.2',
                        name='monitor_b')
    ready = Statements(ros)
    verdicts = Verdicts(ros)
    alive = []
    # A consumer as docs/interfaces.md tells it: deadline and lease >= the offered 0.2 s.
    watch = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL,
                       liveliness=LivelinessPolicy.AUTOMATIC)
    watch.liveliness_lease_duration = watch.deadline = Duration(seconds=0.5)
    ready_b = Statements(ros, '/feeder/edge1_ready_b', watch, '/feeder/feeder_monitor_b',
                         max_age_s=0.5, event_callbacks=SubscriptionEventCallbacks(
                             liveliness=lambda e: alive.append(e.alive_count)))
    wait_for_monitor(ros, ready)
    ros.spin_until(lambda: ready_b.msgs, 60.0, "monitor b's edge1_ready")
    assert ready_b.checked[0].authentic     # signed as /feeder/feeder_monitor_b
    # Monitor b's statements do not pass as monitor a's (the signature names the monitor).
    assert not check_verdict(ready_b.msgs[0], ros.key, MONITOR,
                             ros.node.get_clock().now().nanoseconds).authentic
    # the driver's reports: monitors a and b; edge1_verdict (monitor a's): ours
    wait_reports_matched(ros, status_readers=2, proximity_readers=2, fired_readers=2)
    trigger_until_ready(ros, verdicts)

    # Idle: the true statement is republished every ready_deadline / 4, each fresh.
    n = len(ready)
    t0 = time.monotonic()
    arrivals = []
    while time.monotonic() - t0 < 1.0:
        k = len(ready)
        ros.spin_for(0.01)
        arrivals += [time.monotonic()] * (len(ready) - k)
    assert len(ready) - n >= 10 and all(c.ready_now for c in ready.checked[n:])
    gaps = [b - a for a, b in zip(arrivals, arrivals[1:])]
    assert max(gaps) < 0.2, f'a gap of {max(gaps):.3f} s: the 0.2 s deadline missed'
    ros.spin_until(lambda: ready_b.checked[-1].ready_now, 5.0, 'monitor b ready')

    # A clean exit says false.
    mon_a.send_signal(signal.SIGINT)
    assert mon_a.wait(10) == 0
    ros.spin_for(0.3)
    assert ready.checked[-1].ready is False and ready.checked[-1].authentic

    # A killed monitor's true stays in the reader's cache, but its liveliness goes, and its
    # signed sent time tells a consumer it is stale.
    assert alive and alive[-1] == 1
    mon_b.send_signal(signal.SIGKILL)
    mon_b.wait(10)
    ros.spin_until(lambda: alive[-1] == 0, 5.0, 'liveliness lost')
    cached = ready_b.msgs[-1]
    assert cached.ready is True     # what a consumer must not trust without a check
    ros.spin_for(0.6)
    later = check_verdict(cached, ros.key, '/feeder/feeder_monitor_b',
                          ros.node.get_clock().now().nanoseconds, max_age_s=0.5)
    assert later.authentic and not later.ready_now and 'ago' in later.reason


def test_a_huge_seq_does_not_hang_the_predictor(graph, ros):
    """
    A seq of 2**62 after seq 1: an anomaly in /diagnostics, and the next cycle is followed.

    A seq of 2**63 or more (the uint64 field holds up to 2**64 - 1) is no seq at all
    (feeder_common.messages): a bad status, counted.
    """
    pred = predictor(graph)
    states = PredictedStates(ros)
    diags = Diagnostics(ros)
    pub = ros.node.create_publisher(CycleStatus, '/feeder/cycle_status', qos.CYCLE_STATUS)
    ros.spin_until(lambda: pub.get_subscription_count() >= 1, 60.0, 'the predictor')
    ros.spin_for(0.5)
    stamp = ros.node.get_clock().now().nanoseconds
    for k, seq in enumerate((1, 2 ** 64 - 1, 2 ** 62, 2 ** 62 + 1)):
        pub.publish(cycle_status(seq, True, '', False, stamp + k, 'test'))
    ros.spin_until(lambda: len(states) >= 2, 10.0, 'predictions of seq 1 and 2**62 + 1')
    name = 'feeder_sim: sensor agreement'
    ros.spin_until(lambda: any(s.level == DiagnosticStatus.ERROR
                               for s in diags.by_name.get(name, [])), 5.0, 'the anomaly')
    err = next(s for s in diags.by_name[name] if s.level == DiagnosticStatus.ERROR)
    assert f'seq jumped from 1 to {2 ** 62}' in err.message
    assert Diagnostics.values(err)['implausible_jumps'] == '1'
    assert Diagnostics.values(err)['bad_status'] == '1'
    assert [p.seq for p in states.parsed] == [1, 2 ** 62 + 1] and pred.poll() is None


def start_emulator_and_driver(graph, tmp_path, *emulator_args):
    link = tmp_path / 'feeder-tty'
    emu = start_emulator(graph, link, '--heartbeat', '0.2', *emulator_args)
    drv = graph.start('feeder_driver', 'driver_node', '--ros-args', '-r', '__ns:=/feeder',
                      '-p', f'port:={link}', '-p', 'cycle_timeout_s:=30.0',
                      '-p', 'watchdog_timeout_s:=5.0', name='driver')
    return emu, drv


def wait_for_handshake(ros):
    end = time.monotonic() + STARTUP_TIMEOUT
    while True:
        res = ros.call(Trigger, '/feeder/feeder_driver/trigger_cycle', Trigger.Request())
        if res.success:
            return res
        assert 'refused' in res.message and time.monotonic() < end, res.message
        ros.spin_for(0.1)


def fire_the_first_cycle(ros):
    """Once the driver and a reader of its cycle_status are up, fire cycle 1."""
    ros.wait_remote_matched(DRIVER, readers={'/feeder/cycle_status': 1})
    res = wait_for_handshake(ros)
    assert 'seq 1' in res.message, res.message


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_the_cycle_a_signal_aborts_reaches_cycle_status(graph, ros, tmp_path, sig):
    """The driver sends STOP and reports the aborted cycle before it leaves (issue 10, item 6)."""
    emu, drv = start_emulator_and_driver(graph, tmp_path, '--cycle-time', '20')
    statuses = CycleStatuses(ros)
    fire_the_first_cycle(ros)            # it takes 20 s (--cycle-time)
    ros.spin_for(0.3)
    drv.send_signal(sig)
    assert drv.wait(10) == 0, graph.log(drv)
    ros.spin_until(lambda: statuses.msgs, 5.0, 'the aborted cycle')
    (st,) = statuses.parsed
    assert (st.seq, st.ok, st.sensor) == (1, False, None)
    assert statuses.msgs[0].outcome == CycleStatus.OUTCOME_FAILED
    assert st.reason == f'aborted: interrupted ({sig.name})'
    assert emu.poll() is None


# A reliable reader in a process of its own (so that it can be stopped): one line per
# message it takes, the reason of a cycle_status or the message of each status of a
# /diagnostics.
# Deep, so that nothing is lost on its side while it catches up.
SLOW_READER = """
import sys
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from feeder_interfaces.msg import CycleStatus
from rclpy.qos import QoSProfile, ReliabilityPolicy
rclpy.init()
node = rclpy.create_node('slow_reader')
topic = sys.argv[1]
def on(msg):
    for text in ([s.message for s in msg.status] if topic == '/diagnostics' else [msg.reason]):
        print(text, flush=True)
node.create_subscription(DiagnosticArray if topic == '/diagnostics' else CycleStatus,
                         topic, on, QoSProfile(depth=5000,
                                               reliability=ReliabilityPolicy.RELIABLE))
try:
    rclpy.spin(node)
except BaseException:
    pass
"""


def start_slow_reader(topic, out):
    import subprocess
    import sys
    from feeder_testing import install_env
    with open(out, 'w') as fh:
        return subprocess.Popen([sys.executable, '-c', SLOW_READER, topic], stdout=fh,
                                stderr=subprocess.STDOUT, env=install_env())


def test_the_aborted_cycle_reaches_a_reader_that_is_slow_to_acknowledge(graph, ros, tmp_path):
    """
    The driver waits for its readers before its writers go (issue 10, item 6).

    While a reader is stopped (SIGSTOP) the driver reports the aborted cycle and waits for the
    acknowledgement (up to its flush timeout) instead of destroying its writers at once, which
    can lose the report for that reader; once the reader goes on (SIGCONT), it gets the report
    and the driver leaves. The driver before commit 8028cd5 (no flush) fails it: it leaves at
    once.
    """
    import subprocess
    emu, drv = start_emulator_and_driver(graph, tmp_path, '--cycle-time', '20')
    out = tmp_path / 'reader.out'
    reader = start_slow_reader('/feeder/cycle_status', out)
    try:
        fire_the_first_cycle(ros)        # it takes 20 s (--cycle-time)
        ros.spin_for(0.5)
        reader.send_signal(signal.SIGSTOP)
        drv.send_signal(signal.SIGINT)
        # A driver that waits for its readers is still waiting 0.3 s later (for up to
        # FLUSH_TIMEOUT_S, 0.5 s, after its report); one that does not is gone by then.
        try:
            drv.wait(0.3)
            left_early = True
        except subprocess.TimeoutExpired:
            left_early = False
        reader.send_signal(signal.SIGCONT)
        assert drv.wait(10) == 0, graph.log(drv)
        assert not left_early, 'the driver left before its reader acknowledged the report'
        end = time.monotonic() + 5.0
        while 'aborted' not in out.read_text() and time.monotonic() < end:
            time.sleep(0.05)
        assert 'aborted: interrupted (SIGINT)' in out.read_text(), \
            (out.read_text(), graph.log(drv))
    finally:
        reader.send_signal(signal.SIGCONT)
        reader.send_signal(signal.SIGINT)
        reader.wait(10)


def test_an_error_that_lasted_one_period_reaches_a_slow_diagnostics_reader(ros, tmp_path):
    """
    /diagnostics keeps the last messages for a reader that has not acknowledged (issue 10, 7).

    A node's diagnostics say ERROR in one update and OK in the next while a reader is stopped
    (SIGSTOP) and its transport queue is full: the reader must still see the ERROR once it
    goes on (reliable repair from the writer's history). With the writer's depth 1
    (diagnostic_updater's; ours before) the OK replaced the ERROR: 3 of 3 runs lost it.
    """
    from feeder_common.diagnostics import Updater
    out = tmp_path / 'reader.out'
    reader = start_slow_reader('/diagnostics', out)
    level = {'now': 'ok'}
    updater = Updater(ros.node, period=3600.0, hardware_id='test')
    updater.add('pulse', lambda st: st.summary(level['now'], f'pulse {level["now"]}'))
    try:
        ros.wait_matched(updater.pub, 1, 60.0, 'the slow reader to match our /diagnostics')
        updater.force_update()
        end = time.monotonic() + 30.0       # the reader's subscription matched and took one
        while 'pulse ok' not in out.read_text():
            assert time.monotonic() < end, out.read_text()
            updater.force_update()
            ros.spin_for(0.2)
        reader.send_signal(signal.SIGSTOP)

        def pulses():
            return [x for x in out.read_text().splitlines() if x.startswith('pulse')]

        # The reader may have printed more than one OK before it stopped: wait for the three
        # pulses sent while it was stopped (not for three OKs in all, which can come first).
        expected = ['pulse error', 'pulse ok', 'pulse ok']
        # Fill the stopped reader's transport queue from another writer, so that what the
        # node sends next is not delivered at once and must come from the writer's history.
        flood = ros.node.create_publisher(DiagnosticArray, '/diagnostics', 1)
        for _ in range(3000):
            flood.publish(DiagnosticArray(status=[DiagnosticStatus(message='flood')]))
        for now in ('error', 'ok', 'ok'):
            level['now'] = now
            updater.force_update()
            ros.spin_for(0.05)
        reader.send_signal(signal.SIGCONT)
        end = time.monotonic() + 10.0
        while pulses()[-3:] != expected and time.monotonic() < end:
            ros.spin_for(0.1)
        lines = pulses()
        assert lines[-3:] == expected, lines
    finally:
        updater.destroy()
        reader.send_signal(signal.SIGCONT)
        reader.send_signal(signal.SIGINT)
        reader.wait(10)


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_a_signal_while_cycling_reports_every_fired_cycle(graph, ros, tmp_path, sig):
    """At 100 Hz, a signal aborts the cycle in flight: it is the last cycle_status."""
    emu, drv = start_emulator_and_driver(graph, tmp_path, '--cycle-time', '0.05')
    statuses = CycleStatuses(ros)
    ros.wait_remote_matched(DRIVER, readers={'/feeder/cycle_status': 1})    # ours
    wait_for_handshake(ros)
    ros.set_parameters('/feeder/feeder_driver', {'cycle_period': 0.01})
    res = ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=True))
    assert res.success, res.message
    ros.spin_until(lambda: len(statuses) >= 20, 20.0, '20 cycles')
    drv.send_signal(sig)
    assert drv.wait(10) == 0, graph.log(drv)
    ros.spin_for(1.0)
    reports = statuses.parsed
    seqs = [s.seq for s in reports]
    assert seqs == list(range(1, len(seqs) + 1))
    last = reports[-1]
    assert (last.ok, last.reason) == (False, f'aborted: interrupted ({sig.name})'), \
        (last, graph.log(drv))
