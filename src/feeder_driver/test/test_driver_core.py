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

"""The ROS-free link and cycle state machine, driven with a fake clock."""

from feeder_driver import core as c
from feeder_driver import protocol as p
import pytest

CFG = c.CoreConfig(ack_timeout_s=0.5, cycle_timeout_s=3.0, watchdog_timeout_s=2.0,
                   reconnect_initial_s=0.1, reconnect_max_s=0.8, cycle_period=1.0)


def sent(effects):
    return [e.message for e in effects if isinstance(e, c.Send)]


def results(effects):
    return [e.result for e in effects if isinstance(e, c.CycleFinished)]


def connect(core, now=0.0):
    assert core.start(now) == [c.OpenLink()]
    ident, caps, ping = sent(core.link_opened(now))
    assert ident == p.Ident() and caps == p.Caps() and isinstance(ping, p.Ping) and \
        core.link == c.HANDSHAKE
    core.received(now, 0, [p.Hello('fw', 'B1'), p.Err(None, 'BADCMD', 'unknown'),
                           p.Pong(ping.token)])
    assert core.link == c.CONNECTED
    return core


@pytest.fixture
def core():
    k = connect(c.DriverCore(CFG))
    k.set_active(True, 0.0, 0)
    return k


def fire(core, now):
    ok, msg, eff = core.trigger(now)
    assert ok, msg
    (fire_msg,) = sent(eff)
    assert isinstance(fire_msg, p.Fire)
    return fire_msg.seq


def test_normal_cycle(core):
    seq = fire(core, 1.0)
    assert core.trigger(1.01)[0] is False and 'busy' in core.trigger(1.01)[1]
    assert core.received(1.02, 10, [p.Ack(seq)]) == []
    rel = core.received(1.1, 11, [p.Rel(seq, 5585)])
    assert rel == [c.Released(1, 5.585, 11)]
    (res,) = results(core.received(1.2, 12, [p.Sens(seq, 1)]))
    assert res.ok and res.sensor == 1 and res.stamp == 12 and res.seq == 1
    assert res.release_speed == pytest.approx(5.585)
    assert core.counters['fired'] == core.counters['completed'] == 1
    assert fire(core, 1.3) == seq + 1


def test_every_fire_is_announced_before_it_goes_out(core):
    # The monitor drops a ready on the notice: it must precede the FIRE that moves the arm,
    # whether the cycle is triggered or fired by continuous cycling.
    ok, _, eff = core.trigger(1.0)
    assert ok and [type(e) for e in eff] == [c.Firing, c.Send]
    assert eff[0].seq == 1 and isinstance(eff[1].message, p.Fire)
    core.received(1.2, 12, [p.Ack(1), p.Sens(1, 0)])
    core.enable(True, 1.3)
    eff = core.tick(2.5, 0)
    kinds = [type(e) for e in eff]
    assert c.Firing in kinds and kinds.index(c.Firing) + 1 == kinds.index(c.Send)
    assert [e.seq for e in eff if isinstance(e, c.Firing)] == [2]


def test_handshake_retries_ping_then_gives_up_and_backs_off():
    core = c.DriverCore(CFG)
    core.start(0.0)
    first = sent(core.link_opened(0.0))[2]
    again = sent(core.tick(0.6, 0))
    assert isinstance(again[2], p.Ping) and again[2].token != first.token
    # A PONG with an old token does not complete the handshake.
    core.received(0.7, 0, [p.Pong(first.token)])
    assert core.link == c.HANDSHAKE
    eff = core.tick(2.1, 0)
    assert c.CloseLink in [type(e) for e in eff] and core.link == c.DISCONNECTED
    assert 'no PONG' in core.last_link_error
    assert core.tick(2.15, 0) == []
    assert core.tick(2.21, 0) == [c.OpenLink()]


def test_a_controller_of_protocol_1_is_refused_with_the_reason():
    core = c.DriverCore(CFG)
    core.start(0.0)
    core.link_opened(0.0)
    body = b'HELLO,old-fw,1A2B'
    line = b'$' + body + b'*%02X\r\n' % p.legacy_checksum(body)
    core.received(0.1, 0, p.Parser().feed(line))
    assert core.link == c.HANDSHAKE
    core.tick(2.1, 0)
    assert core.link == c.DISCONNECTED
    assert 'protocol 1' in core.last_link_error and 'update the controller firmware' in \
        core.last_link_error, core.last_link_error


def test_backoff_doubles_and_caps():
    core = c.DriverCore(CFG)
    core.start(0.0)
    t, delays = 0.0, []
    for _ in range(6):
        core.link_open_failed(t, OSError('No such file or directory'))
        delays.append(round(core.next_open_at - t, 6))
        t = core.next_open_at
        assert core.tick(t, 0) == [c.OpenLink()]
    assert delays == [0.1, 0.2, 0.4, 0.8, 0.8, 0.8]
    assert core.counters['open_failures'] == 6
    connect(core, t)
    core.link_lost(t, 0, 'unplugged')
    assert core.next_open_at - t == pytest.approx(0.1)    # reset by the successful handshake


def test_ack_timeout_fails_the_cycle_and_sends_stop(core):
    seq = fire(core, 1.0)
    assert core.tick(1.4, 0) == []
    core.received(1.45, 0, [p.Err(None, 'BADSUM', 'checksum')])
    eff = core.tick(1.6, 99)
    assert p.Stop() in sent(eff)
    (res,) = results(eff)
    assert not res.ok and res.sensor is None and 'no ACK within 0.5 s' in res.reason
    assert 'BADSUM' in res.reason
    # A late reply for that cycle is stale and changes nothing.
    assert core.received(1.7, 0, [p.Sens(seq, 1)]) == []
    assert core.counters['stale_replies'] == 1
    assert core.counters['fired'] == 1 and core.counters['failed'] == 1


def test_sens_timeout(core):
    seq = fire(core, 1.0)
    core.received(1.1, 0, [p.Ack(seq), p.Hb(5, 'BUSY')])
    for t in (1.5, 2.0, 2.5, 3.0, 3.5):
        core.received(t, 0, [p.Hb(5, 'BUSY')])
        assert results(core.tick(t, 0)) == []
    (res,) = results(core.tick(4.1, 0))
    assert 'no SENS within 3 s' in res.reason and 'ACK at' in res.reason


def test_idle_heartbeat_after_ack_means_sens_was_lost(core):
    seq = fire(core, 1.0)
    # An IDLE heartbeat before the ACK may predate the FIRE: ignored.
    assert results(core.received(1.01, 0, [p.Hb(1, 'IDLE')])) == []
    core.received(1.02, 0, [p.Ack(seq), p.Rel(seq, 5585)])
    (res,) = results(core.received(1.5, 0, [p.Hb(2, 'IDLE')]))
    assert not res.ok and 'IDLE' in res.reason and 'SENS' in res.reason


def test_missing_ack_is_implied_by_rel_and_counted(core):
    seq = fire(core, 1.0)
    core.received(1.1, 0, [p.Rel(seq, 5585)])
    (res,) = results(core.received(1.2, 0, [p.Sens(seq, 0)]))
    assert res.ok and res.sensor == 0
    assert core.counters['acks_missing'] == 1


def test_controller_error_for_our_seq_fails_the_cycle(core):
    seq = fire(core, 1.0)
    (res,) = results(core.received(1.01, 0, [p.Err(seq, 'BUSY', 'cycle 3 in progress')]))
    assert 'ERR BUSY' in res.reason and 'cycle 3' in res.reason


def test_hello_mid_cycle_is_a_reset(core):
    seq = fire(core, 1.0)
    core.received(1.01, 0, [p.Ack(seq)])
    (res,) = results(core.received(1.02, 0, [p.Hello('fw', 'B2')]))
    assert 'controller reset during cycle' in res.reason and 'B2' in res.reason
    assert core.counters['controller_resets'] == 1 and core.boot_id == 'B2'
    assert core.link == c.CONNECTED


def test_link_lost_mid_cycle_fails_it_and_refuses_until_reconnected(core):
    fire(core, 1.0)
    eff = core.link_lost(1.1, 5, 'read failed: device disconnected')
    assert c.CloseLink('read failed: device disconnected') in eff
    (res,) = results(eff)
    assert 'serial link lost during cycle' in res.reason
    ok, msg, _ = core.trigger(1.2)
    assert not ok and 'disconnected' in msg and 'device disconnected' in msg
    assert core.link_lost(1.3, 0, 'again') == []    # already down: nothing more
    assert core.tick(1.21, 0) == [c.OpenLink()]


def test_watchdog_declares_a_silent_link_lost(core):
    core.received(1.0, 0, [p.Hb(1, 'IDLE')])
    assert core.tick(2.9, 0) == []
    eff = core.tick(3.1, 0)
    assert any(isinstance(e, c.CloseLink) for e in eff)
    assert 'silent' in core.last_link_error and core.counters['watchdog_timeouts'] == 1


def test_garbage_does_not_feed_the_watchdog(core):
    core.received(1.0, 0, [p.Hb(1, 'IDLE')])
    core.received(2.5, 0, [p.Rejected('checksum', 'bad', b'')])
    assert any(isinstance(e, c.CloseLink) for e in core.tick(3.1, 0))


def test_refusals_say_why():
    core = c.DriverCore(CFG)
    ok, msg, eff = core.trigger(0.0)
    assert not ok and 'not active' in msg and eff == []
    core.set_active(True, 0.0, 0)
    ok, msg, _ = core.trigger(0.0)
    assert not ok and 'serial link is disconnected' in msg
    ok, msg, _ = core.enable(True, 0.0)
    assert not ok and 'disconnected' in msg
    assert core.counters['fired'] == 0


def test_enable_fires_every_period_and_refuses_triggers(core):
    ok, msg, eff = core.enable(True, 1.0)
    assert ok and 'every 1 s' in msg
    seq = sent(eff)[0].seq
    ok, msg, _ = core.trigger(1.1)
    assert not ok and 'enabled' in msg
    core.received(1.2, 0, [p.Ack(seq), p.Sens(seq, 0)])
    assert sent(core.tick(1.5, 0)) == []
    (nxt,) = sent(core.tick(2.0, 0))
    assert nxt.seq == seq + 1
    ok, msg, _ = core.enable(False, 2.1)
    assert ok and 'still in flight' in msg
    core.received(2.2, 0, [p.Ack(nxt.seq), p.Sens(nxt.seq, 1)])
    assert sent(core.tick(5.0, 0)) == []


def test_enable_pauses_while_disconnected_and_resumes(core):
    core.enable(True, 1.0)
    core.link_lost(1.05, 0, 'unplugged')
    assert core.counters['failed'] == 1
    assert core.tick(2.0, 0) == [c.OpenLink()]
    assert core.tick(2.5, 0) == []
    core.link_opened(3.0)
    ping = core._ping_token
    core.received(3.0, 0, [p.Pong(ping)])
    assert [type(m) for m in sent(core.tick(3.1, 0))] == [p.Fire]


def test_deactivate_aborts_a_cycle_with_stop(core):
    fire(core, 1.0)
    eff = core.set_active(False, 1.1, 0, 'node deactivated')
    assert p.Stop() in sent(eff)
    (res,) = results(eff)
    assert res.reason == 'aborted: node deactivated'
    assert not core.trigger(1.2)[0]


def test_stop_closes_the_link_and_stops_reopening(core):
    eff = core.stop(1.0, 0, 'cleanup')
    assert c.CloseLink('cleanup') in eff and core.link == c.DISCONNECTED
    assert core.tick(100.0, 0) == []


def test_sequence_numbers_wrap_on_the_wire():
    core = connect(c.DriverCore(CFG, first_seq=65535))
    core.set_active(True, 0.0, 0)
    assert fire(core, 1.0) == 65535
    core.received(1.1, 0, [p.Ack(65535), p.Sens(65535, 1)])
    assert fire(core, 1.2) == 0
    assert core.pending.seq == 65536


def test_every_fired_cycle_ends_exactly_once(core):
    # A mixed run: each cycle ends by SENS, ERR, reset, timeout or link loss.
    endings = []
    t = 1.0
    for k in range(30):
        seq = fire(core, t)
        mode = k % 5
        if mode == 0:
            endings += results(core.received(t + 0.1, 0, [p.Ack(seq), p.Sens(seq, k % 2)]))
        elif mode == 1:
            endings += results(core.received(t + 0.1, 0, [p.Err(seq, 'FAULT', 'stall')]))
        elif mode == 2:
            endings += results(core.received(t + 0.1, 0, [p.Ack(seq), p.Hello('fw', 'X')]))
        elif mode == 3:
            core.received(t + 0.1, 0, [p.Hb(1, 'BUSY')])
            endings += results(core.tick(t + 0.6, 0))
        else:
            endings += results(core.link_lost(t + 0.1, 0, 'gone'))
            core.tick(t + 1.0, 0)
            core.link_opened(t + 1.0)
            core.received(t + 1.0, 0, [p.Pong(core._ping_token)])
        # Late or duplicate replies never end a cycle twice.
        endings += results(core.received(t + 1.1, 0, [p.Sens(seq, 1), p.Ack(seq)]))
        core.received(t + 1.2, 0, [p.Hb(1, 'IDLE')])
        t += 2.0
    assert [r.seq for r in endings] == list(range(1, 31))
    assert core.counters['completed'] + core.counters['failed'] == core.counters['fired'] == 30
    assert all(r.reason for r in endings if not r.ok)


def test_a_late_answer_to_a_repeated_id_is_not_a_reset():
    core = c.DriverCore(CFG)
    core.start(0.0)
    core.link_opened(0.0)
    token = sent(core.tick(0.6, 0))[2].token      # ID + PING repeated: two IDs outstanding
    core.received(0.61, 0, [p.Hello('fw', 'B1'), p.Pong(token)])
    assert core.link == c.CONNECTED
    core.received(0.62, 0, [p.Hello('fw', 'B1')])   # answer to the second ID
    assert core.counters['controller_resets'] == 0
    core.received(0.63, 0, [p.Hello('fw', 'B1')])   # nothing outstanding: a reset
    assert core.counters['controller_resets'] == 1
    core.received(0.64, 0, [p.Hello('fw', 'B2')])
    assert core.counters['controller_resets'] == 2


def test_a_sens_waiting_in_the_buffer_after_a_stall_completes_the_cycle(core):
    # Issue 20, attack 6: the driver is paused (SIGSTOP) right after firing; the controller's
    # SENS arrives while it sleeps and waits in the port's buffer. On waking, the tick comes
    # first, 5 s later; the reader has not read since it was stopped (read_until = 1.06).
    seq = fire(core, 1.0)
    core.received(1.05, 0, [p.Ack(seq)])
    assert core.tick(1.06, 0, read_until=1.05) == []
    assert core.tick(8.0, 0, read_until=1.06) == []          # neither a timeout nor link loss
    assert core.link == c.CONNECTED and core.pending is not None
    # The reader wakes too and hands over the SENS it found.
    (res,) = results(core.received(8.01, 80, [p.Sens(seq, 1)]))
    assert res.ok and res.sensor == 1 and res.stamp == 80
    assert core.tick(8.02, 0, read_until=8.005) == []
    assert core.counters['failed'] == 0 and core.counters['watchdog_timeouts'] == 0


def test_after_a_stall_a_missing_sens_fails_once_the_port_is_read(core):
    seq = fire(core, 1.0)
    core.received(1.05, 0, [p.Ack(seq)])
    core.tick(1.06, 0, read_until=1.05)
    assert core.tick(8.0, 0, read_until=1.06) == []
    eff = core.tick(8.02, 0, read_until=8.0)      # read after the deadline: nothing came
    (res,) = results(eff)
    assert not res.ok and 'no SENS within 3 s' in res.reason and p.Stop() in sent(eff)


def test_a_reader_that_stops_reporting_does_not_hold_a_cycle_forever(core):
    # The ticks run on time but the reader never reports: the clock takes over, late by
    # READ_GRACE_S at most, so the cycle still ends (and the silent link is declared lost).
    seq = fire(core, 1.0)
    core.received(1.05, 0, [p.Ack(seq)])
    t, ended = 1.06, None
    while t < 6.0 and ended is None:
        for res in results(core.tick(t, 0, read_until=1.05)):
            ended = (t, res)
        t = round(t + 0.02, 6)
    assert ended is not None
    t, res = ended
    # Silent since 1.05: the watchdog (2 s) judged by the clock, READ_GRACE_S late.
    assert 1.05 + CFG.watchdog_timeout_s < t <= 1.05 + CFG.watchdog_timeout_s + \
        c.READ_GRACE_S + 0.03
    assert not res.ok and 'serial link lost during cycle' in res.reason


# ---- release-speed setpoints (issue 25 item 5) ---------------------------------------------

SPEED_CFG = c.CoreConfig(ack_timeout_s=0.5, cycle_timeout_s=3.0, watchdog_timeout_s=2.0,
                         reconnect_initial_s=0.1, reconnect_max_s=0.8, cycle_period=1.0,
                         release_speed_mode='setpoint')
CAP = p.Cap('SPEED', 1047, 12566)      # 60 .. 720 deg/s


def speed_core(answer=CAP, config=SPEED_CFG, log=None):
    """Return an active core whose controller answered CAPS with ``answer`` (None: nothing)."""
    core = c.DriverCore(config, log=log)
    core.start(0.0)
    ident, caps, ping = sent(core.link_opened(0.0))
    assert caps == p.Caps()
    replies = [p.Hello('fw', 'B1')] + ([answer] if answer is not None else [])
    core.received(0.01, 0, replies + [p.Pong(ping.token)])
    assert core.link == c.CONNECTED
    core.set_active(True, 0.0, 0)
    return core


def test_cap_in_the_handshake_means_the_controller_sets_the_speed():
    logs = []
    core = speed_core(log=lambda level, text: logs.append((level, text)))
    assert core.speed_range == (1.047, 12.566)
    assert any('1.047 .. 12.566 rad/s' in t for _, t in logs), logs
    assert core.counters['controller_errors'] == 0


def test_badcmd_to_caps_means_fixed_speed_and_is_no_controller_fault():
    logs = []
    core = speed_core(p.Err(None, 'BADCMD', 'unknown'),
                      log=lambda level, text: logs.append((level, text)))
    assert core.speed_range is None
    assert core.counters['controller_errors'] == 0 and core.last_controller_error is None
    assert ('info', 'controller cannot set the release speed (answered CAPS with BADCMD): '
            'fixed speed') in logs
    assert not any(level in ('warning', 'error') and 'BADCMD' in t for level, t in logs)
    # In 'setpoint' mode an old controller fires at its own speed, said once per link.
    ok, msg, eff = core.trigger(1.0)
    assert ok, msg
    (fire_msg,) = sent(eff)
    assert fire_msg == p.Fire(1) and p.encode(fire_msg) == p.encode(p.Fire(1, None))
    assert [e.speed_setpoint for e in eff if isinstance(e, c.Firing)] == [None]
    ok, msg, _ = core.set_setpoint(1.1, 2, 5.0)
    assert not ok and 'cannot set the release speed' in msg
    core.received(1.2, 0, [p.Ack(1), p.Rel(1, 5585), p.Sens(1, 1)])
    assert fire(core, 1.3) == 2
    ignored = [t for level, t in logs if 'setpoints are ignored' in t]
    assert len(ignored) == 1
    # A BADCMD that answers no CAPS is a controller error as before.
    core.received(1.4, 0, [p.Err(None, 'BADCMD', 'unknown')])
    assert core.counters['controller_errors'] == 1


def test_no_answer_to_caps_means_fixed_speed():
    core = speed_core(None)
    assert core.speed_range is None
    assert fire(core, 1.0) == 1


def test_a_late_cap_changes_nothing_and_is_counted():
    core = speed_core(p.Err(None, 'BADCMD', 'unknown'))
    core.received(0.5, 0, [p.Cap('SPEED', 1000, 2000)])
    assert core.speed_range is None and core.counters['late_caps'] == 1


def test_the_capability_is_forgotten_when_the_link_reopens():
    core = speed_core()
    core.link_lost(1.0, 0, 'unplugged')
    ident, caps, ping = sent(core.link_opened(1.2))
    assert core.speed_range is None
    core.received(1.3, 0, [p.Err(None, 'BADCMD', 'unknown'), p.Pong(ping.token)])
    assert core.speed_range is None and core.link == c.CONNECTED


def test_trigger_without_a_setpoint_is_refused_with_the_reason():
    core = speed_core()
    ok, msg, eff = core.trigger(1.0)
    assert not ok and eff == [] and core.counters['fired'] == 0
    assert msg.startswith('refused: no release-speed setpoint for cycle 1 yet;'), msg
    ok, msg, eff = core.set_setpoint(1.1, 1, 6.0)
    assert ok and eff == [], msg
    ok, msg, eff = core.trigger(1.2)
    assert ok and msg == 'fired cycle seq 1 at 6 rad/s'
    firing, send = eff
    assert firing == c.Firing(1, 6.0) and send.message == p.Fire(1, 6000)
    assert p.encode(send.message) == b'$FIRE,1,6000*%04X\r\n' % p.checksum(b'FIRE,1,6000')
    # The setpoint is consumed by its cycle: the next one needs its own.
    core.received(1.3, 5, [p.Ack(1), p.Rel(1, 6010), p.Sens(1, 1)])
    assert core.setpoint is None
    ok, msg, _ = core.trigger(1.4)
    assert not ok and 'cycle 2' in msg


def test_the_setpoint_is_in_the_fire_frame_and_in_the_cycle_result():
    core = speed_core()
    core.set_setpoint(1.0, 1, 3.14159)      # sent rounded to mrad/s
    ok, _, eff = core.trigger(1.0)
    (fire_msg,) = sent(eff)
    assert fire_msg.speed_mrad_s == 3142 and fire_msg.speed_rad_s == pytest.approx(3.142)
    (res,) = results(core.received(1.2, 7, [p.Ack(1), p.Rel(1, 3150), p.Sens(1, 0)]))
    assert res.ok and res.speed_setpoint == pytest.approx(3.142)
    assert res.release_speed == pytest.approx(3.150)
    # A failed cycle keeps its setpoint too.
    core.set_setpoint(1.3, 2, 2.0)
    core.trigger(1.3)
    (res,) = results(core.received(1.4, 8, [p.Err(2, 'FAULT', 'arm stalled')]))
    assert not res.ok and res.speed_setpoint == 2.0


@pytest.mark.parametrize('speed, text', [
    (0.0, 'finite number > 0'), (-3.0, 'finite number > 0'), (float('nan'), 'finite'),
    (float('inf'), 'finite'), (True, 'finite'), ('5', 'finite'),
    (1.0, 'outside the range of the controller, 1.047 .. 12.566 rad/s'),
    (12.6, 'outside the range of the controller'), (1e5, 'beyond the protocol limit'),
])
def test_bad_or_out_of_range_setpoints_are_refused(speed, text):
    core = speed_core()
    ok, msg, eff = core.set_setpoint(1.0, 1, speed)
    assert not ok and eff == [] and msg.startswith('refused: ') and text in msg, msg
    assert core.setpoint is None and core.counters['setpoints_refused'] == 1
    # The range's ends are in it (compared on the wire value, mrad/s).
    assert core.set_setpoint(1.0, 1, 1.0466)[0] and core.set_setpoint(1.0, 1, 12.566)[0]


def test_a_setpoint_for_another_cycle_is_refused():
    core = speed_core()
    ok, msg, _ = core.set_setpoint(1.0, 2, 5.0)
    assert not ok and 'setpoint for cycle 2, but the next cycle is 1' in msg
    core.set_setpoint(1.0, 1, 5.0)
    fire(core, 1.0)
    ok, msg, _ = core.set_setpoint(1.1, 1, 5.0)
    assert not ok and 'next cycle is 2 (cycle 1 is in flight)' in msg
    assert core.set_setpoint(1.1, 2, 5.0)[0]


def test_the_newest_setpoint_wins():
    core = speed_core()
    assert core.set_setpoint(1.0, 1, 5.0)[0] and core.set_setpoint(1.0, 1, 7.0)[0]
    assert sent(core.trigger(1.1)[2]) == [p.Fire(1, 7000)]


def test_enabled_cycling_waits_for_the_setpoint_then_fires_on_arrival():
    core = speed_core()
    ok, msg, eff = core.enable(True, 1.0)
    assert ok and eff == [] and core.counters['waiting_for_setpoint'] == 1
    assert core.tick(1.5, 0) == []
    core.received(2.0, 0, [p.Hb(1, 'IDLE')])
    assert core.tick(3.0, 0) == []
    assert core.counters['waiting_for_setpoint'] == 1      # once per cycle that waits
    ok, msg, eff = core.set_setpoint(3.1, 1, 4.0)
    assert ok and 'fired cycle seq 1' in msg
    assert sent(eff) == [p.Fire(1, 4000)] and core.pending.speed_setpoint == 4.0
    core.received(3.2, 0, [p.Ack(1), p.Sens(1, 1)])
    # A setpoint that comes early waits for the period; no wait is counted.
    ok, msg, eff = core.set_setpoint(3.3, 2, 5.0)
    assert ok and eff == [] and 'fired' not in msg
    assert core.tick(3.9, 0) == []
    assert sent(core.tick(4.1, 0)) == [p.Fire(2, 5000)]
    assert core.counters['waiting_for_setpoint'] == 1
    core.received(4.2, 0, [p.Ack(2), p.Sens(2, 1)])
    assert core.tick(5.2, 0) == [] and core.counters['waiting_for_setpoint'] == 2


def test_a_setpoint_held_while_disconnected_is_checked_at_the_handshake():
    core = c.DriverCore(SPEED_CFG)
    core.set_active(True, 0.0, 0)
    ok, msg, _ = core.set_setpoint(0.0, 1, 20.0)
    assert ok and 'held' in msg
    core.start(0.0)
    ping = sent(core.link_opened(0.0))[2]
    core.received(0.1, 0, [CAP, p.Pong(ping.token)])
    assert core.setpoint is None and core.counters['setpoints_refused'] == 1
    assert core.set_setpoint(0.2, 1, 6.0)[0]
    assert sent(core.trigger(0.3)[2]) == [p.Fire(1, 6000)]


def test_fixed_mode_never_sends_a_speed(core):
    core_fixed = speed_core(config=CFG)
    assert core_fixed.speed_range == (1.047, 12.566)      # known, for diagnostics
    ok, msg, _ = core_fixed.set_setpoint(0.5, 1, 5.0)
    assert not ok and "release_speed_mode is 'fixed'" in msg
    ok, msg, eff = core_fixed.trigger(1.0)
    assert ok and msg == 'fired cycle seq 1' and sent(eff) == [p.Fire(1)]
    assert sent(eff)[0].speed_mrad_s is None
    (res,) = results(core_fixed.received(1.2, 0, [p.Ack(1), p.Sens(1, 1)]))
    assert res.speed_setpoint is None
    core_fixed.enable(True, 1.3)
    assert sent(core_fixed.tick(2.3, 0)) == [p.Fire(2)]
    assert core_fixed.counters['waiting_for_setpoint'] == 0


def test_release_speed_mode_is_checked():
    with pytest.raises(ValueError, match='release_speed_mode'):
        c.CoreConfig(release_speed_mode='fast')
