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

"""The controller emulator on a pty, talked to through pyserial like the driver does."""

import json
import os
import pathlib
import subprocess
import sys
import time

from feeder_driver import protocol as p
from feeder_driver.emulator import EmulatorError, Faults
from feeder_testing import EmulatorThread
import pytest
import serial
from throwmap import load_scene, sees

REPO = pathlib.Path(__file__).resolve().parents[3]


class Client:
    """Host side: write commands, collect decoded replies."""

    def __init__(self, path):
        self.ser = serial.serial_for_url(path, baudrate=115200, timeout=0.02, exclusive=True)
        self.ser.reset_input_buffer()
        self.parser = p.Parser()
        self.events = []

    def send(self, msg):
        self.ser.write(p.encode(msg) if not isinstance(msg, bytes) else msg)

    def wait(self, pred, timeout=3.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            for e in self.parser.feed(self.ser.read(4096)):
                self.events.append(e)
            hit = [e for e in self.events if pred(e)]
            if hit:
                return hit
        raise AssertionError(f'timed out; got {self.events[-10:]}')

    def close(self):
        self.ser.close()


@pytest.fixture
def emu_factory(scene_path, sensor_radius, link_path):
    started = []

    def make(**kw):
        kw.setdefault('cycle_time', 0.02)
        kw.setdefault('heartbeat', 0.2)
        emu = EmulatorThread(scene_path, link_path, sensor_radius=sensor_radius, **kw).start()
        started.append(emu)
        return emu

    yield make
    for emu in started:
        emu.stop()
    assert not os.path.lexists(link_path)


def test_banner_ping_and_heartbeat(emu_factory, link_path):
    emu = emu_factory()
    assert os.path.islink(link_path) and os.readlink(link_path).startswith('/dev/pts/')
    cl = Client(link_path)
    cl.send(p.Ping('t1'))
    assert cl.wait(lambda e: e == p.Pong('t1'))
    cl.send(p.Ident())
    assert cl.wait(lambda e: e == p.Hello('feeder-emu-1.0', emu.controller.boot_id))
    hb = cl.wait(lambda e: isinstance(e, p.Hb))[0]
    assert hb.state == 'IDLE'
    assert emu.controller.boot_id
    cl.close()


def test_cycles_follow_the_throw_map(emu_factory, link_path, scene_path, sensor_radius):
    emu = emu_factory()
    cl = Client(link_path)
    scene = load_scene(scene_path)
    edge, R = scene.default_start()
    for seq in range(1, 41):
        cl.send(p.Fire(seq))
        sens = cl.wait(lambda e, s=seq: isinstance(e, p.Sens) and e.seq == s)[0]
        edge, R, kind = scene.model.f(edge, R)
        assert sens.bit == int(bool(sees(scene.part, edge, R, sensor_radius, 0.0)))
    replies = [type(e).__name__ for e in cl.events if not isinstance(e, p.Hb)]
    assert replies == ['Ack', 'Rel', 'Sens'] * 40
    rel = [e for e in cl.events if isinstance(e, p.Rel)][0]
    assert rel.speed_mrad_s == round(scene.release_speed * 1000)
    recs = emu.records
    assert [r['seq'] for r in recs] == list(range(1, 41))
    assert all(r['outcome'] == 'completed' and r['throw'] for r in recs)
    assert recs[-1]['edge'] == edge and recs[-1]['R'] == pytest.approx(R)
    assert any(r['bit'] for r in recs), 'the designed sensor should fire within 40 throws'
    cl.close()


def test_busy_stop_and_bad_frames(emu_factory, link_path):
    emu = emu_factory(cycle_time=0.5)
    cl = Client(link_path)
    cl.send(p.Fire(1))
    cl.wait(lambda e: e == p.Ack(1))
    cl.send(p.Fire(2))
    assert cl.wait(lambda e: isinstance(e, p.Err) and e.seq == 2)[0].code == 'BUSY'
    cl.send(p.Stop())
    assert cl.wait(lambda e: isinstance(e, p.Err) and e.seq == 1)[0].code == 'ABORTED'
    cl.send(b'$FIRE,3*0000\r\n')
    assert cl.wait(lambda e: isinstance(e, p.Err) and e.seq is None)[0].code == 'BADSUM'
    cl.send(b'$JUMP*%04X\r\n' % p.checksum(b'JUMP'))
    cl.wait(lambda e: isinstance(e, p.Err) and e.code == 'BADCMD')
    cl.send(b'$FIRE,x*%04X\r\n' % p.checksum(b'FIRE,x'))
    cl.wait(lambda e: isinstance(e, p.Err) and e.code == 'BADARG')
    # A host of protocol 1 (XOR *HH) is told its frame is bad, and nothing fires.
    cl.send(b'$FIRE,4*%02X\r\n' % p.legacy_checksum(b'FIRE,4'))
    err = cl.wait(lambda e: isinstance(e, p.Err) and e.code == 'BADFRAME')[0]
    assert err.text == 'legacy'
    time.sleep(0.6)
    outcomes = [(r['seq'], r['outcome']) for r in emu.records]
    assert outcomes == [(2, 'busy'), (1, 'aborted')]
    assert emu.controller.cycles == 1
    cl.close()


def test_fault_switches(emu_factory, link_path):
    emu = emu_factory(faults=Faults(drop_ack_every=2, drop_sens_every=3, garbage_every=4,
                                    delay=0.1, delay_every=5))
    cl = Client(link_path)
    for seq in range(1, 7):
        cl.send(p.Fire(seq))
        cl.wait(lambda e, s=seq: isinstance(e, p.Rel) and e.seq == s)
        time.sleep(0.05)
        cl.wait(lambda e: isinstance(e, p.Hb) and e.state == 'IDLE')
    got = {(type(e).__name__, e.seq) for e in cl.events if hasattr(e, 'seq')}
    assert ('Ack', 2) not in got and ('Ack', 4) not in got and ('Ack', 1) in got
    assert ('Sens', 3) not in got and ('Sens', 6) not in got and ('Sens', 5) in got
    assert cl.parser.dropped_frames >= 3 and cl.parser.stats['garbage_bytes'] > 0
    faults = {r['seq']: r['faults'] for r in emu.records}
    assert faults[4] == ['drop_ack', 'garbage'] and faults[5] == ['delay']
    assert faults[6] == ['drop_ack', 'drop_sens']
    outcomes = [r['outcome'] for r in emu.records]
    assert outcomes == ['completed', 'completed', 'sens_dropped', 'completed', 'completed',
                        'sens_dropped']
    cl.close()


def test_reset_mid_cycle(emu_factory, link_path):
    emu = emu_factory(faults=Faults(reset_after=1))
    cl = Client(link_path)
    boot = emu.controller.boot_id
    cl.send(p.Fire(1))
    cl.wait(lambda e: isinstance(e, p.Sens))
    cl.send(p.Fire(2))
    hello = cl.wait(lambda e: isinstance(e, p.Hello))[0]
    assert hello.boot_id != boot
    time.sleep(0.1)
    assert not [e for e in cl.events if isinstance(e, (p.Rel, p.Sens)) and e.seq == 2]
    rec = emu.records[-1]
    assert rec['outcome'] == 'reset' and not rec['throw']
    assert (rec['edge'], rec['R']) == (emu.records[0]['edge'], emu.records[0]['R'])
    cl.send(p.Fire(3))
    cl.wait(lambda e: isinstance(e, p.Sens) and e.seq == 3)
    cl.close()


def test_unplug_and_replug_behind_the_same_link(emu_factory, link_path):
    emu = emu_factory(faults=Faults(unplug_after=1, unplug_for=0.4))
    cl = Client(link_path)
    first = os.readlink(link_path)
    assert first.startswith('/dev/pts/')
    cl.send(p.Fire(1))
    cl.wait(lambda e: isinstance(e, p.Sens))
    cl.send(p.Fire(2))
    # The pty vanishes right after REL (which may or may not get through first).
    with pytest.raises(serial.SerialException, match='disconnected'):
        cl.wait(lambda e: isinstance(e, p.Sens) and e.seq == 2)
    cl.close()
    assert not os.path.lexists(link_path)
    end = time.monotonic() + 3
    while not os.path.lexists(link_path) and time.monotonic() < end:
        time.sleep(0.02)
    assert os.path.islink(link_path)
    cl = Client(link_path)
    cl.send(p.Ping('back'))
    cl.wait(lambda e: e == p.Pong('back'))
    rec = emu.records[-1]
    assert rec['outcome'] == 'unplug' and rec['throw'] and rec['sent']['sens'] is False
    assert emu.controller.unplugs == 1
    cl.close()


def test_truth_log_file(scene_path, sensor_radius, link_path, tmp_path):
    log = tmp_path / 'truth.jsonl'
    with EmulatorThread(scene_path, link_path, sensor_radius=sensor_radius, cycle_time=0.01,
                        truth_log=str(log)):
        cl = Client(link_path)
        for seq in (5, 6):
            cl.send(p.Fire(seq))
            cl.wait(lambda e, s=seq: isinstance(e, p.Sens) and e.seq == s)
        cl.close()
    lines = [json.loads(x) for x in log.read_text().splitlines()]
    assert lines[0]['type'] == 'header' and lines[0]['sensor_radius'] == sensor_radius
    assert [(x['seq'], x['cycle']) for x in lines[1:]] == [(5, 1), (6, 2)]
    assert set(lines[1]) >= {'edge', 'R', 'kind', 'bit', 'faults', 'outcome'}


def _fire_all(emu, cl, seqs, timeout=5.0):
    """
    Send FIREs one by one without waiting for their replies (some may be corrupted).

    Each waits for the emulator to have logged the one before and to be idle (its cycle
    time is no promise under load: a FIRE that overtook a slow cycle would be refused BUSY),
    then every reply is read until the link has been quiet for 0.3 s.
    """
    ctl = emu.controller
    for seq in seqs:
        logged = len(ctl.records)
        cl.send(p.Fire(seq))
        end = time.monotonic() + timeout
        while (len(ctl.records) == logged or ctl.cycle is not None) and time.monotonic() < end:
            cl.events.extend(cl.parser.feed(cl.ser.read(4096)))
    quiet_since = time.monotonic()
    while time.monotonic() - quiet_since < 0.3:
        data = cl.ser.read(4096)
        if data:
            cl.events.extend(cl.parser.feed(data))
            quiet_since = time.monotonic()


def test_flaky_sensor_is_seeded_and_logged(scene_path, sensor_radius, link_path, tmp_path):
    runs = []
    for run in range(2):
        log = tmp_path / f'truth{run}.jsonl'
        faults = Faults(spurious_rate=0.2, miss_rate=0.3, seed=7)
        with EmulatorThread(scene_path, link_path, sensor_radius=sensor_radius,
                            cycle_time=0.002, faults=faults, truth_log=str(log)):
            cl = Client(link_path)
            for seq in range(1, 151):
                cl.send(p.Fire(seq))
                cl.wait(lambda e, s=seq: isinstance(e, p.Sens) and e.seq == s)
            cl.close()
        lines = [json.loads(x) for x in log.read_text().splitlines()]
        assert lines[0]['spurious_rate'] == 0.2 and lines[0]['miss_rate'] == 0.3
        recs = lines[1:]
        sens = {e.seq: e.bit for e in cl.events if isinstance(e, p.Sens)}
        for r in recs:
            assert sens[r['seq']] == r['bit'], 'the log holds the bit that was sent'
            if r['flaky'] is None:
                assert r['bit'] == int(r['seen'])
            elif r['flaky'] == 'spurious':
                assert not r['seen'] and r['bit'] == 1
            else:
                assert r['flaky'] == 'miss' and r['seen'] and r['bit'] == 0
        kinds = [r['flaky'] for r in recs]
        assert kinds.count('spurious') > 0 and kinds.count('miss') > 0
        runs.append(kinds)
    assert runs[0] == runs[1], 'the same seed gives the same flaky readings'


def test_bit_errors_flip_one_bit_per_hit_byte_seeded():
    data = bytes(range(256)) * 4
    out, n = Faults(bit_error_rate=1.0, seed=3).corrupt_tx(data)
    assert n == len(data)
    assert all(bin(a ^ b).count('1') == 1 for a, b in zip(data, out))
    assert Faults(bit_error_rate=0.0).corrupt_tx(data) == (data, 0)
    a = Faults(bit_error_rate=0.01, seed=5).corrupt_tx(data)
    assert a == Faults(bit_error_rate=0.01, seed=5).corrupt_tx(data) and 0 < a[1] < 60
    assert a != Faults(bit_error_rate=0.01, seed=6).corrupt_tx(data)
    rx, m = Faults(host_bit_error_rate=1.0, seed=3).corrupt_rx(data)
    assert m == len(data) and rx != data


def test_bit_errors_are_refused_by_the_crc(scene_path, sensor_radius, link_path, tmp_path):
    log = tmp_path / 'truth.jsonl'
    with EmulatorThread(scene_path, link_path, sensor_radius=sensor_radius, cycle_time=0.004,
                        faults=Faults(bit_error_rate=0.02, seed=11),
                        truth_log=str(log)) as emu:
        cl = Client(link_path)
        _fire_all(emu, cl, range(1, 121))
        cl.close()
        flipped = emu.controller.faults.flipped['tx']
    recs = [json.loads(x) for x in log.read_text().splitlines()][1:]
    assert [r['seq'] for r in recs] == list(range(1, 121))
    got = {(type(e).__name__.lower(), e.seq) for e in cl.events if hasattr(e, 'seq')}
    hit = [(frame, r['seq']) for r in recs for frame in r['bit_errors']]
    assert hit and flipped >= len(hit)
    # A frame with a flipped bit never arrives (nor a wrong one: every bit is as logged);
    # every other reply does.
    for frame, seq in hit:
        assert (frame, seq) not in got
    for r in recs:
        for frame in ('ack', 'rel', 'sens'):
            if frame not in r['bit_errors']:
                assert (frame, r['seq']) in got
    bits = {e.seq: e.bit for e in cl.events if isinstance(e, p.Sens)}
    assert all(bits[r['seq']] == r['bit'] for r in recs if r['seq'] in bits)
    # A hit frame is rejected (a dropped frame), or, when the flip hit its '$', read as
    # garbage bytes outside any frame: at least one byte for each such frame.
    missing = len(hit) - cl.parser.dropped_frames
    assert 0 < cl.parser.dropped_frames and missing <= cl.parser.stats['garbage_bytes'], \
        (cl.parser.stats, len(hit))


def test_host_bit_errors_refuse_the_fire(scene_path, sensor_radius, link_path, tmp_path):
    log = tmp_path / 'truth.jsonl'
    with EmulatorThread(scene_path, link_path, sensor_radius=sensor_radius, cycle_time=0.004,
                        faults=Faults(host_bit_error_rate=1.0, seed=2),
                        truth_log=str(log)) as emu:
        cl = Client(link_path)
        _fire_all(emu, cl, range(1, 6))
        cl.close()
    lines = [json.loads(x) for x in log.read_text().splitlines()][1:]
    assert lines and all(x['type'] == 'rx_bit_errors' for x in lines)
    assert not any(isinstance(e, (p.Ack, p.Sens)) for e in cl.events)
    assert any(isinstance(e, p.Err) and e.seq is None for e in cl.events)


@pytest.mark.parametrize('kwargs, text', [
    ({'drop_ack_every': 0}, '--drop-ack-every'),
    ({'delay': -1.0}, '--delay'),
    ({'delay_every': 3}, '--delay-every: needs --delay'),
    ({'reset_after': -2}, '--reset-after'),
    ({'spurious_rate': 1.5}, '--spurious-rate'),
    ({'miss_rate': -0.1}, '--miss-rate'),
    ({'bit_error_rate': 'x'}, '--bit-error-rate'),
])
def test_bad_fault_options(kwargs, text):
    with pytest.raises(EmulatorError, match=text):
        Faults(**kwargs)


def test_one_emulator_per_link(emu_factory, scene_path, sensor_radius, link_path):
    emu_factory()
    with pytest.raises(EmulatorError, match='in use by another controller_emulator'):
        EmulatorThread(scene_path, link_path, sensor_radius=sensor_radius)
    with pytest.raises(EmulatorError, match='--firmware'):
        EmulatorThread(scene_path, link_path + '2', sensor_radius=sensor_radius,
                       firmware='a,b')


def test_link_that_is_a_regular_file_is_refused(scene_path, sensor_radius, tmp_path):
    path = tmp_path / 'file'
    path.write_text('x')
    with pytest.raises(EmulatorError, match='not a symlink'):
        EmulatorThread(scene_path, str(path), sensor_radius=sensor_radius)


def _run_cli(*args):
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join(
        [os.path.dirname(os.path.dirname(p.__file__)), env.get('PYTHONPATH', '')])
    return subprocess.run([sys.executable, '-m', 'feeder_driver.emulator', *args],
                          capture_output=True, text=True, timeout=60, env=env)


def test_cli_errors_are_clear(tmp_path):
    res = _run_cli('--scene', str(tmp_path / 'missing.yaml'), '--link', str(tmp_path / 'l'))
    assert res.returncode == 2 and 'no such file' in res.stderr and 'scene' in res.stderr
    res = _run_cli('--scene', 'x.yaml', '--drop-sens-every', 'two')
    assert res.returncode == 2 and 'invalid int value' in res.stderr


def test_cli_runs_and_cleans_up(tmp_path, scene_path, sensor_radius):
    link = str(tmp_path / 'tty')
    res = _run_cli('--scene', scene_path, '--link', link, '--sensor-radius',
                   str(sensor_radius), '--max-time', '0.5')
    assert res.returncode == 0, res.stderr
    assert 'ready on' in res.stdout and not os.path.lexists(link)


# ------------------------------------------------------------------ scene effects
SHORT_ARM = REPO / 'tests' / 'scenes' / 'short_arm.yaml'
HOUSE = REPO / 'scenes' / 'house.yaml'


def fire(cl, seq):
    """Fire one cycle; return its last reply (SENS or ERR)."""
    cl.send(p.Fire(seq))
    return cl.wait(lambda e: isinstance(e, (p.Sens, p.Err)) and e.seq == seq)[0]


def strict_json(line):
    def refuse(name):
        raise ValueError(f'{name} in the truth log')
    return json.loads(line, parse_constant=refuse)


def test_a_part_lost_off_the_arm_end(tmp_path, link_path):
    # The short arm with the part placed near its end: the first throw loses it.
    scene = tmp_path / 'near_end.yaml'
    scene.write_text(SHORT_ARM.read_text().replace('start: {edge: 1, R: 0.12}',
                                                   'start: {edge: 1, R: 0.32}'))
    log = tmp_path / 'truth.jsonl'
    with EmulatorThread(str(scene), link_path, sensor_radius=0.2672, cycle_time=0.01,
                        heartbeat=0.2, truth_log=str(log)) as emu:
        cl = Client(link_path)
        bits = [fire(cl, seq).bit for seq in range(1, 5)]
        emu.controller.request_place()          # a part is put back at the start
        time.sleep(0.1)
        bits.append(fire(cl, 5).bit)
        cl.close()
    assert bits == [0] * 5
    lines = [strict_json(x) for x in log.read_text().splitlines()]
    assert lines[0]['arm_length'] == pytest.approx(0.33) and not lines[0]['noisy_sensor']
    fires = [x for x in lines if x['type'] == 'fire']
    # Lost at the first throw; empty throws (no part before them: edge0 -1) until the part is
    # put back, then lost again.
    assert [(x['edge0'], x['kind'], x['edge'], x['R'], x['seen']) for x in fires] == \
        [(1, 'lost', -1, None, False)] + [(-1, 'lost', -1, None, False)] * 3 + \
        [(1, 'lost', -1, None, False)]
    assert all(x['outcome'] == 'completed' and x['throw'] for x in fires)
    placed = [x for x in lines if x['type'] == 'place']
    assert len(placed) == 1 and (placed[0]['edge'], placed[0]['R']) == (1, 0.32)
    assert lines.index(placed[0]) == lines.index(fires[4]) - 1


@pytest.mark.parametrize('seed', [7, 11])
def test_noisy_scene_bits_follow_the_seed(link_path, seed):
    from throwmap import ThrowmapError
    radius, footprint = 0.2129, 0.005
    with EmulatorThread(str(HOUSE), link_path, sensor_radius=radius, seed=seed,
                        cycle_time=0.002, heartbeat=0.2) as emu:
        cl = Client(link_path)
        replies = [fire(cl, seq) for seq in range(1, 81)]
        cl.close()
        records = emu.records
    # Independently: the scene seeded alike, each throw (release_noise) then its reading
    # (sensor_noise) drawn from the scene's generator, in that order.
    scene = load_scene(str(HOUSE))
    scene.model.reseed(seed)
    state = scene.default_start()
    for reply, rec in zip(replies, records):
        try:
            edge, R, kind = scene.model.f(*state)
        except ThrowmapError as exc:        # the cycle ends with ERR FAULT, the part stays
            assert isinstance(reply, p.Err) and reply.code == 'FAULT', reply
            assert rec['outcome'] == 'fault' and rec['error'] == str(exc)
            continue
        state = (edge, R)
        bit = int(bool(scene.sense(edge, R, radius, footprint)))
        assert isinstance(reply, p.Sens) and reply.bit == bit
        assert (rec['edge'], rec['kind'], rec['bit']) == (edge, kind, bit)
        assert rec['seen'] == bool(sees(scene.part, edge, R, radius, footprint))
    # Both seeds give sensor errors (a bit that is not the geometry's) within 80 throws.
    assert any(r['bit'] != r['seen'] for r in records if r['outcome'] == 'completed')


def test_a_throw_the_map_cannot_compute_ends_with_err_fault(link_path):
    from feeder_driver.emulator import Controller, ThrowFailed
    import threading

    def throw():
        raise ThrowFailed('throw outside the throw map: grasp_noise', 'no dynamic grasp ...')

    ctl = Controller(link_path, throw=throw, sense=lambda e, r: True, release_speed=5.0,
                     state=lambda: (1, 0.12), cycle_time=0.01, heartbeat=0.2)
    ctl.start()
    thread = threading.Thread(target=ctl.run, daemon=True)
    thread.start()
    try:
        cl = Client(link_path)
        err = fire(cl, 1)
        assert (err.code, err.text) == ('FAULT', 'throw outside the throw map: grasp_noise')
        assert [type(e).__name__ for e in cl.events if not isinstance(e, p.Hb)] == \
            ['Ack', 'Rel', 'Err']
        cl.close()
    finally:
        ctl.stop()
        thread.join(timeout=5)
        ctl.close()
    rec = ctl.records[-1]
    assert (rec['outcome'], rec['throw'], rec['edge'], rec['R'], rec['bit']) == \
        ('fault', False, 1, 0.12, None)
    assert rec['error'] == 'no dynamic grasp ...'


def test_a_scene_whose_analysis_fails_is_refused(tmp_path):
    res = _run_cli('--scene', str(REPO / 'scenes' / 'hard' / 'fast_spin.yaml'), '--link',
                   str(tmp_path / 'l'))
    assert res.returncode == 2
    assert 'analysis failed' in res.stderr and 'outside the domain of f' in res.stderr


def test_memory_stays_flat_over_many_cycles(emu_factory, link_path):
    """Issue 10: the emulator grew about 0.8 KB per cycle (every truth record kept)."""
    import gc
    import tracemalloc
    emu = emu_factory(cycle_time=0.0, keep_records=100)
    cl = Client(link_path)

    def run(first, count):
        for seq in range(first, first + count):
            cl.send(p.Fire(seq))
            cl.wait(lambda e, s=seq: isinstance(e, p.Sens) and e.seq == s)
            cl.events.clear()

    run(1, 300)                     # past the kept records and every warm-up allocation
    tracemalloc.start()
    try:
        # Live memory only: a full collection first empties what CPython keeps for reuse
        # (about 40 KB per 1000 throw results before one, none after; it does not grow).
        gc.collect()
        before = tracemalloc.get_traced_memory()[0]
        run(301, 1000)
        gc.collect()
        grown = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert grown < 100_000, f'{grown} bytes more after 1000 cycles'
    assert [r['seq'] for r in emu.records] == list(range(1201, 1301))
    cl.close()


# ------------------------------------------------------------------ release-speed setpoint
def test_caps_is_answered_with_the_speed_range(emu_factory, link_path):
    emu_factory()
    cl = Client(link_path)
    cl.send(p.Caps())
    (cap,) = cl.wait(lambda e: isinstance(e, p.Cap))
    assert cap == p.Cap('SPEED', 1047, 12566)     # the default 60:720 deg/s
    cl.close()


def test_a_fire_with_a_speed_throws_at_that_speed(emu_factory, link_path, scene_path,
                                                  sensor_radius):
    # The same seed and start, thrown independently with throwmap.PartOnArm at each speed.
    from throwmap import PartOnArm
    emu = emu_factory()
    cl = Client(link_path)
    scene = load_scene(scene_path)
    part = PartOnArm(scene, *scene.default_start(), sensor_radius=sensor_radius,
                     seed=scene.seed)
    fixed = PartOnArm(load_scene(scene_path), *scene.default_start(),
                      sensor_radius=sensor_radius, seed=scene.seed)
    speeds = [None, 8.0, 4.0, 6.5, None, 10.0, 3.0, 12.5]
    differs = False
    for seq, w in enumerate(speeds, 1):
        cl.send(p.Fire(seq, None if w is None else int(round(w * 1000))))
        sens = cl.wait(lambda e, s=seq: isinstance(e, p.Sens) and e.seq == s)[0]
        rel = cl.wait(lambda e, s=seq: isinstance(e, p.Rel) and e.seq == s)[0]
        t = part.throw(release_speed=w)
        f = fixed.throw()
        differs |= (t.edge, t.kind) != (f.edge, f.kind) or t.R != pytest.approx(f.R)
        rec = emu.records[-1]
        assert (rec['seq'], rec['outcome'], rec['setpoint']) == (seq, 'completed', w)
        assert sens.bit == int(t.detected)
        assert rec['edge'] == t.edge and rec['kind'] == t.kind
        assert (rec['R'] is None) if t.edge < 0 else rec['R'] == pytest.approx(t.R)
        expect = scene.release_speed if w is None else w
        if t.edge0 >= 0:            # a part was thrown: the speed the arm released at
            assert rec['release_speed'] == pytest.approx(t.release_speed)
            expect = t.release_speed
        assert rel.speed_mrad_s == round(expect * 1000)
    assert differs, 'the setpoints should change the throws'
    assert emu.records[-1]['kind'] == 'lost'     # 12.5 rad/s throws the part off the arm
    cl.close()


def test_a_speed_outside_the_range_is_refused_and_fires_nothing(emu_factory, link_path):
    emu = emu_factory(speed_range=(2.0, 9.0))
    cl = Client(link_path)
    cl.send(p.Caps())
    assert cl.wait(lambda e: isinstance(e, p.Cap))[0] == p.Cap('SPEED', 2000, 9000)
    for seq, mrad in ((1, 1999), (2, 9001), (3, -5000)):
        cl.send(p.Fire(seq, mrad))
        (err,) = cl.wait(lambda e, s=seq: isinstance(e, p.Err) and e.seq == s)
        assert (err.code, err.text) == ('BADARG', 'speed out of range')
    cl.send(p.Fire(4, 2000))
    cl.wait(lambda e: isinstance(e, p.Sens) and e.seq == 4)
    assert [type(e) for e in cl.events if isinstance(e, (p.Ack, p.Rel))] == [p.Ack, p.Rel]
    assert emu.controller.cycles == 1
    assert [(r['seq'], r['outcome'], r['setpoint']) for r in emu.records] == \
        [(1, 'bad_speed', 1.999), (2, 'bad_speed', 9.001), (3, 'bad_speed', -5.0),
         (4, 'completed', 2.0)]
    cl.close()


def test_no_speed_setpoint_answers_as_an_old_controller(emu_factory, link_path):
    emu = emu_factory(speed_range=None)
    cl = Client(link_path)
    cl.send(p.Caps())
    (err,) = cl.wait(lambda e: isinstance(e, p.Err))
    assert err == p.Err(None, 'BADCMD', 'unknown')
    cl.events.clear()
    cl.send(p.Fire(1, 6000))
    (err,) = cl.wait(lambda e: isinstance(e, p.Err))
    assert err == p.Err(None, 'BADARG', 'fields')       # the old parser's answer
    cl.send(p.Fire(2))
    rel = cl.wait(lambda e: isinstance(e, p.Rel))[0]
    cl.wait(lambda e: isinstance(e, p.Sens) and e.seq == 2)
    assert rel == p.Rel(2, 5585)
    assert emu.controller.cycles == 1 and emu.records[-1]['setpoint'] is None
    stats = emu.controller.parser.stats
    assert (stats['unknown'], stats['fields']) == (1, 1)
    cl.close()


def test_a_speed_the_part_cannot_be_held_at_ends_with_err_fault(emu_factory, link_path,
                                                                monkeypatch):
    import throwmap
    real = throwmap.PartOnArm.throw

    def throw(self, release_speed=None):
        if release_speed is not None and release_speed > 11.0:
            raise throwmap.DomainError('grasp_bound_2', 'the part slides off at this speed')
        return real(self, release_speed)

    monkeypatch.setattr(throwmap.PartOnArm, 'throw', throw)
    emu = emu_factory()
    cl = Client(link_path)
    cl.send(p.Fire(1, 12000))
    (err,) = cl.wait(lambda e: isinstance(e, p.Err) and e.seq == 1)
    assert (err.code, err.text) == ('FAULT', 'throw outside the throw map: grasp_bound_2')
    assert cl.wait(lambda e: isinstance(e, p.Rel))[0] == p.Rel(1, 12000)
    rec = emu.records[-1]
    assert (rec['outcome'], rec['throw'], rec['setpoint'], rec['release_speed']) == \
        ('fault', False, 12.0, None)
    assert 'slides off' in rec['error']
    cl.send(p.Fire(2, 6000))
    cl.wait(lambda e: isinstance(e, p.Sens) and e.seq == 2)
    cl.close()


def test_the_truth_log_records_setpoint_and_release_speed(scene_path, sensor_radius,
                                                          link_path, tmp_path):
    log = tmp_path / 'truth.jsonl'
    with EmulatorThread(scene_path, link_path, sensor_radius=sensor_radius, cycle_time=0.01,
                        truth_log=str(log)):
        cl = Client(link_path)
        fire(cl, 1)
        cl.send(p.Fire(2, 7000))
        cl.wait(lambda e: isinstance(e, p.Sens) and e.seq == 2)
        cl.close()
    lines = [strict_json(x) for x in log.read_text().splitlines()]
    assert lines[0]['speed_range'] == [1.047, 12.566]
    assert [(x['setpoint'], x['release_speed']) for x in lines[1:]] == \
        [(None, load_scene(scene_path).release_speed), (7.0, 7.0)]


def test_core_handshake_with_the_emulator(emu_factory, link_path):
    """Handshake of DriverCore over the pty: CAP gives speed_range, an old controller None."""
    from feeder_driver import core as c
    for speed_range, expect in ((None, None), ((2.0, 9.0), (2.0, 9.0))):
        emu = emu_factory(speed_range=speed_range)
        cl = Client(link_path)
        logs = []
        core = c.DriverCore(c.CoreConfig(release_speed_mode='setpoint'),
                            log=lambda level, text: logs.append((level, text)))
        core.start(0.0)
        for eff in core.link_opened(0.0):
            cl.send(eff.message)
        cl.wait(lambda e: isinstance(e, p.Pong))
        core.received(0.1, 0, cl.events)
        assert core.link == c.CONNECTED and core.speed_range == expect
        assert core.counters['controller_errors'] == 0
        assert not [t for level, t in logs if level in ('warning', 'error')], logs
        core.set_active(True, 0.2, 0)
        if expect is not None:
            assert core.set_setpoint(0.2, 1, 3.0)[0]
        ok, msg, eff = core.trigger(0.3)
        assert ok, msg
        cl.events.clear()
        for e in eff:
            if isinstance(e, c.Send):
                cl.send(e.message)
        cl.wait(lambda e: isinstance(e, p.Sens))
        (res,) = [e.result for e in core.received(0.4, 0, cl.events)
                  if isinstance(e, c.CycleFinished)]
        assert res.ok and res.speed_setpoint == (None if expect is None else 3.0)
        assert res.release_speed == pytest.approx(5.585 if expect is None else 3.0, abs=1e-3)
        cl.close()
        emu.stop()


@pytest.mark.parametrize('text, error', [
    ('720:60', '0 < MIN <= MAX'), ('0:60', '0 < MIN <= MAX'), ('-5:60', '0 < MIN <= MAX'),
    ('60', 'MIN:MAX in deg/s'), ('a:b', 'MIN:MAX in deg/s'), ('1:2:3', 'MIN:MAX'),
    ('60:1e9', '<= 572958 deg/s'), ('60:inf', '0 < MIN'),
])
def test_bad_speed_ranges_are_refused(text, error):
    from feeder_driver.emulator import parse_speed_range
    with pytest.raises(EmulatorError, match='--speed-range') as info:
        parse_speed_range(text)
    assert error in str(info.value)


def test_cli_speed_options(tmp_path, scene_path, sensor_radius):
    from feeder_driver.emulator import parse_speed_range
    assert parse_speed_range('60:720') == pytest.approx((1.0471976, 12.566371))
    res = _run_cli('--scene', scene_path, '--link', str(tmp_path / 'l'), '--speed-range', '9:5')
    assert res.returncode == 2 and '--speed-range' in res.stderr
    link = str(tmp_path / 'tty')
    res = _run_cli('--scene', scene_path, '--link', link, '--sensor-radius', str(sensor_radius),
                   '--no-speed-setpoint', '--max-time', '0.3')
    assert res.returncode == 0 and 'fixed release speed' in res.stdout, res.stderr
    res = _run_cli('--scene', scene_path, '--link', link, '--sensor-radius', str(sensor_radius),
                   '--speed-range', '30:400', '--max-time', '0.3')
    assert res.returncode == 0 and 'release speed setpoints 30:400 deg/s' in res.stdout
