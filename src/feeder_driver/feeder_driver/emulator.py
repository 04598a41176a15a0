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
Feeder controller emulator: speaks the controller side of the protocol on a pty (ROS-free).

The part's state comes from the throw-map library: each accepted FIRE throws the part once
(``model.f``) and the sensor bit is the scene's reading of the state it settles in
(``scene.sense``: the geometric ``sees(part, edge, R, radius, footprint)``, with the seeded false
positives and negatives of ``sensor_noise`` if the scene names it). A throw that loses the part
off a finite arm leaves the arm empty: later throws move nothing and the sensor sees nothing
(but its false positives) until the part is put back (:meth:`Controller.request_place`,
SIGUSR1). A throw that leaves the domain of f ends its cycle with ``ERR,<seq>,FAULT``. A
stable symlink (``--link``) points at the pty's slave, so a driver can reopen the same path
after an emulated unplug. Fault switches drop replies, inject garbage, delay replies, reset
the controller or unplug the port. Two faults are random and seeded: a flaky sensor
(``--spurious-rate``: a 1 when the part is not seen; ``--miss-rate``: a 0 when it is) and bit
errors on the line (``--bit-error-rate``: each byte sent has that probability of one flipped
bit; ``--host-bit-error-rate`` the same for each byte read from the host). ``--truth-log``
writes one JSON line per FIRE received so tests can account for every cycle. The controller
sets the release speed a FIRE asks for (``FIRE,<seq>,<speed>``) within ``--speed-range``, and
says so when asked (``CAPS`` -> ``CAP,SPEED,<min>,<max>``); ``--no-speed-setpoint`` makes it a
controller without that capability, answering as the firmware before it did. CLI table:
docs/driver.md.
"""

import argparse
import collections
import fcntl
import heapq
import itertools
import json
import math
import os
import random
import select
import signal
import sys
import threading
import time
import tty

from . import protocol as p

FIRMWARE = 'feeder-emu-1.0'
# Truth records kept in memory by default (the newest); the command line keeps none.
KEEP_RECORDS = 10_000
# Release speeds the emulated arm can be set to, deg/s (--speed-range).
SPEED_RANGE_DEG_S = (60.0, 720.0)
DEFAULT_SPEED_RANGE = tuple(math.radians(v) for v in SPEED_RANGE_DEG_S)     # rad/s


class EmulatorError(Exception):
    """Bad emulator option or set-up failure; the text names the problem and the fix."""


class ThrowFailed(Exception):
    """The throw map has no answer for a throw; ``code_text`` fits an ERR frame's text."""

    def __init__(self, code_text, detail):
        self.code_text = code_text
        super().__init__(detail)


def _positive_int(name, value):
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise EmulatorError(f'{name}: must be an integer >= 1, got {value!r}')
    return value


def _rate(name, value):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or \
            not 0.0 <= value <= 1.0:
        raise EmulatorError(f'{name}: must be a probability 0..1, got {value!r}')
    return float(value)


def _speed_range_mrad(value):
    """Return (min, max) mrad/s of a speed range in rad/s (None: no capability)."""
    if value is None:
        return None
    try:
        low, high = (float(v) for v in value)
    except (TypeError, ValueError):
        raise EmulatorError(f'--speed-range: must be two numbers MIN:MAX, got {value!r}') \
            from None
    finite = math.isfinite(low) and math.isfinite(high)
    mrad = (p.speed_mrad_s(low), p.speed_mrad_s(high)) if finite else (0, 0)
    if not 0 < mrad[0] <= mrad[1] <= p.MAX_SPEED_MRAD_S:
        raise EmulatorError(f'--speed-range: needs 0 < MIN <= MAX <= '
                            f'{math.degrees(p.MAX_SPEED_MRAD_S / 1000.0):.0f} deg/s (at least '
                            f'1 mrad/s), got {math.degrees(low):g}:{math.degrees(high):g} '
                            'deg/s')
    return mrad


def parse_speed_range(text):
    """Parse ``MIN:MAX`` in deg/s (the CLI's ``--speed-range``) into (min, max) rad/s."""
    parts = str(text).split(':')
    try:
        if len(parts) != 2:
            raise ValueError
        low, high = (math.radians(float(v)) for v in parts)
    except ValueError:
        raise EmulatorError(f'--speed-range: {text!r} must be MIN:MAX in deg/s, e.g. '
                            '60:720') from None
    _speed_range_mrad((low, high))
    return low, high


def _finite_or_none(value):
    return None if value is None or not math.isfinite(value) else float(value)


def _nonneg(name, value):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value >= 0 \
            or value == float('inf'):
        raise EmulatorError(f'{name}: must be a finite number >= 0, got {value!r}')
    return float(value)


class Pty:
    """
    A pty whose slave is reachable through a stable symlink; can be unplugged and replugged.

    The emulator keeps its own slave fd open (in raw mode) so the master never reads EIO while
    no driver has the port open. Writes to the master are non-blocking; output is dropped
    when nobody reads, as on a real UART.
    """

    def __init__(self, link):
        self.link = os.path.abspath(link)
        self.master = None
        self.slave = None
        self.slave_name = None
        if os.path.lexists(self.link) and not os.path.islink(self.link):
            raise EmulatorError(f'--link {self.link}: exists and is not a symlink; refusing to '
                                'replace it, pick another path')
        parent = os.path.dirname(self.link)
        if not os.path.isdir(parent):
            raise EmulatorError(f'--link {self.link}: directory {parent} does not exist; '
                                'create it or pick another path')
        # One emulator per link: a second one would silently steal the symlink.
        self._lock = open(self.link + '.lock', 'a+')
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            self._lock.seek(0)
            owner = self._lock.read().strip() or 'unknown'
            self._lock.close()
            raise EmulatorError(f'--link {self.link}: in use by another controller_emulator '
                                f'(pid {owner}); stop it or pick another path') from None
        self._lock.seek(0)
        self._lock.truncate()
        self._lock.write(str(os.getpid()))
        self._lock.flush()

    @property
    def plugged(self):
        return self.master is not None

    def plug(self):
        master, slave = os.openpty()
        tty.setraw(slave)
        os.set_blocking(master, False)
        self.master, self.slave = master, slave
        self.slave_name = os.ttyname(slave)
        tmp = f'{self.link}.tmp{os.getpid()}'
        if os.path.lexists(tmp):
            os.unlink(tmp)
        os.symlink(self.slave_name, tmp)
        os.replace(tmp, self.link)

    def release(self):
        """Unplug for good and give the link up to another emulator."""
        self.unplug()
        if self._lock is not None:
            try:
                os.unlink(self.link + '.lock')
            except OSError:
                pass
            self._lock.close()
            self._lock = None

    def unplug(self):
        if os.path.islink(self.link):
            os.unlink(self.link)
        for fd in (self.master, self.slave):
            if fd is not None:
                try:
                    os.close(fd)
                except OSError:
                    pass
        self.master = self.slave = None

    def write(self, data):
        """Write what the pty takes now; return the number of bytes dropped."""
        if self.master is None:
            return len(data)
        try:
            n = os.write(self.master, data)
        except BlockingIOError:
            n = 0
        except OSError:
            return len(data)
        return len(data) - n

    def read(self):
        try:
            return os.read(self.master, 4096)
        except (BlockingIOError, InterruptedError):
            return b''
        except OSError:
            return b''


class Faults:
    """Which cycles get which fault (cycle numbers count accepted FIREs from 1)."""

    def __init__(self, drop_ack_every=None, drop_sens_every=None, garbage_every=None,
                 delay=0.0, delay_every=None, reset_after=None, unplug_after=None,
                 unplug_for=1.0, seed=0, spurious_rate=0.0, miss_rate=0.0,
                 bit_error_rate=0.0, host_bit_error_rate=0.0):
        self.drop_ack_every = _positive_int('--drop-ack-every', drop_ack_every)
        self.drop_sens_every = _positive_int('--drop-sens-every', drop_sens_every)
        self.garbage_every = _positive_int('--garbage-every', garbage_every)
        self.delay = _nonneg('--delay', delay)
        self.delay_every = _positive_int('--delay-every', delay_every)
        if self.delay_every is not None and self.delay == 0:
            raise EmulatorError('--delay-every: needs --delay S > 0 (the delay to apply)')
        if reset_after is not None and (isinstance(reset_after, bool) or reset_after < 0):
            raise EmulatorError(f'--reset-after: must be an integer >= 0, got {reset_after!r}')
        if unplug_after is not None and (isinstance(unplug_after, bool) or unplug_after < 0):
            raise EmulatorError(f'--unplug-after: must be an integer >= 0, got '
                                f'{unplug_after!r}')
        self.reset_after = reset_after
        self.unplug_after = unplug_after
        self.unplug_for = _nonneg('--unplug-for', unplug_for)
        self.rng = random.Random(seed)
        self.spurious_rate = _rate('--spurious-rate', spurious_rate)
        self.miss_rate = _rate('--miss-rate', miss_rate)
        self.bit_error_rate = _rate('--bit-error-rate', bit_error_rate)
        self.host_bit_error_rate = _rate('--host-bit-error-rate', host_bit_error_rate)
        # One generator per random fault, each seeded from ``seed``: switching one fault on
        # does not change the draws of another.
        self._flaky_rng = random.Random(f'{seed}:flaky-sensor')
        self._tx_rng = random.Random(f'{seed}:bit-errors-tx')
        self._rx_rng = random.Random(f'{seed}:bit-errors-rx')
        self.flaky = {'spurious': 0, 'miss': 0}
        self.flipped = {'tx': 0, 'rx': 0}     # bytes with a flipped bit, each direction

    def flaky_bit(self, bit):
        """
        Report the reading ``bit`` through the flaky sensor: (bit sent, None/spurious/miss).

        One draw per reading, whatever the rates, so a run's draws do not depend on the part.
        """
        u = self._flaky_rng.random()
        if not bit and u < self.spurious_rate:
            self.flaky['spurious'] += 1
            return 1, 'spurious'
        if bit and u < self.miss_rate:
            self.flaky['miss'] += 1
            return 0, 'miss'
        return bit, None

    @staticmethod
    def _flip(data, rate, rng):
        if rate <= 0.0 or not data:
            return data, 0
        out = bytearray(data)
        n = 0
        for i in range(len(out)):
            if rng.random() < rate:
                out[i] ^= 1 << rng.randrange(8)
                n += 1
        return bytes(out), n

    def corrupt_tx(self, data):
        """Bytes sent to the host, each with one bit flipped at ``bit_error_rate``: (data, n)."""
        data, n = self._flip(data, self.bit_error_rate, self._tx_rng)
        self.flipped['tx'] += n
        return data, n

    def corrupt_rx(self, data):
        """Bytes read from the host, with ``host_bit_error_rate``: (data, n flipped)."""
        data, n = self._flip(data, self.host_bit_error_rate, self._rx_rng)
        self.flipped['rx'] += n
        return data, n

    @staticmethod
    def _every(n, k):
        return n is not None and k % n == 0

    def for_cycle(self, k):
        """Names of the faults injected into cycle k."""
        names = []
        if self._every(self.drop_ack_every, k):
            names.append('drop_ack')
        if self._every(self.drop_sens_every, k):
            names.append('drop_sens')
        if self._every(self.garbage_every, k):
            names.append('garbage')
        if self.delay > 0 and (self.delay_every is None or k % self.delay_every == 0):
            names.append('delay')
        if self.reset_after is not None and k == self.reset_after + 1:
            names.append('reset')
        if self.unplug_after is not None and k == self.unplug_after + 1:
            names.append('unplug')
        return names

    def garbage(self):
        """Noise of the kinds a real line produces: random bytes, a cut frame, a bad sum."""
        noise = bytes(self.rng.choice([b for b in range(256) if b not in (0x24,)])
                      for _ in range(self.rng.randint(3, 24)))
        bad_sum = bytearray(p.encode(p.Sens(self.rng.randrange(p.SEQ_MODULO), 1)))
        check = slice(-2 - p.CHECK_DIGITS, -2)      # the hex digits before CR LF
        bad_sum[check] = b'%0*X' % (p.CHECK_DIGITS, (int(bad_sum[check], 16) + 1) % 65536)
        cut = p.encode(p.Ack(self.rng.randrange(p.SEQ_MODULO)))[:5]
        overlong = b'$' + b'X' * (p.MAX_LINE + 10) + b'\r\n'
        return noise + bytes(bad_sum) + cut + noise[:5] + overlong + b'\xff\xfe\r\n' + cut


class _Cycle:
    def __init__(self, k, seq, faults, now):
        self.k = k
        self.seq = seq
        self.faults = faults
        self.fired_at = now
        self.setpoint = None        # rad/s the FIRE asked for (None: the scene's own speed)
        self.release_speed = None   # rad/s the arm released at (None: no throw)
        self.thrown = False
        self.sent = {'ack': False, 'rel': False, 'sens': False}
        self.edge = self.R = self.kind = self.bit = self.seen = self.edge0 = None
        self.error = None
        self.flaky = None           # 'spurious' or 'miss': the flaky sensor changed the bit
        self.flips = {}             # frame -> bytes with a flipped bit (sent by the emulator)


class Controller:
    """
    The emulated controller: protocol, cycle timing, part state and faults.

    ``throw()`` returns ``(edge, R, kind)`` of the next resting state (edge -1 and R None: no
    part on the arm), or ``(edge, R, kind, release_speed)`` with the speed the arm released at
    (rad/s; nan or None: no part was thrown), or raises :class:`ThrowFailed`;
    ``throw(release_speed)`` (rad/s) throws at a FIRE's setpoint. ``speed_range``: (min, max)
    rad/s of the setpoints the controller takes and announces (``CAP,SPEED``); None: a
    controller without that capability (CAPS is an unknown command, a FIRE with a speed field
    has the wrong number of fields). ``sense(edge, R)`` gives its sensor bit,
    ``sees(edge, R)`` (optional, for the truth log) whether the part is in the sensor's view,
    ``place()`` (optional) puts a part back at the start; all come from the throw-map library
    in :func:`from_scene`.
    """

    def __init__(self, link, throw, sense, release_speed, state=None, cycle_time=0.1,
                 heartbeat=1.0, faults=None, truth_log=None, firmware=FIRMWARE, header=None,
                 log=None, clock=time.monotonic, sees=None, place=None,
                 keep_records=KEEP_RECORDS, speed_range=DEFAULT_SPEED_RANGE):
        self._throw = throw
        self._sense = sense
        self._sees = sees
        self._place = place
        self._place_requested = threading.Event()
        self.release_speed = float(release_speed)
        self.speed_range_mrad = _speed_range_mrad(speed_range)
        self.state = state
        self.cycle_time = _nonneg('--cycle-time', cycle_time)
        self.heartbeat = _nonneg('--heartbeat', heartbeat)
        if self.heartbeat == 0:
            raise EmulatorError('--heartbeat: must be > 0 s (the protocol needs one)')
        self.faults = faults or Faults()
        try:
            p.encode(p.Hello(firmware, 'A'))
        except p.ProtocolError as exc:
            raise EmulatorError(f'--firmware: {exc}') from None
        self.firmware = firmware
        self.header = header or {}
        self._log = log or (lambda text: None)
        self._clock = clock
        self._truth = open(truth_log, 'w', encoding='utf-8') if truth_log else None
        self.pty = Pty(link)        # last of the checks: it takes the link's lock
        # A controller without the speed capability does not know CAPS (BADCMD).
        self.parser = p.Parser(p.HOST_MESSAGES if self.speed_range_mrad is not None else
                               {k: v for k, v in p.HOST_MESSAGES.items() if v is not p.Caps})
        self.cycle = None
        self.cycles = 0
        self.unplugs = 0
        self.resets = 0
        # The newest truth records, in memory for in-process users (tests); bounded, or a long
        # run grows by one record (about 0.8 KB) per cycle. The truth log keeps them all.
        self.records = collections.deque(maxlen=keep_records)
        self._boot = 0
        self._boot_t0 = clock()
        self._events = []
        self._counter = itertools.count()
        self._epoch = 0     # bumps on reset/unplug: scheduled actions of older epochs lapse
        self._wake_r, self._wake_w = os.pipe()
        self._stop = threading.Event()
        f = self.faults
        self.header.update(spurious_rate=f.spurious_rate, miss_rate=f.miss_rate,
                           bit_error_rate=f.bit_error_rate,
                           host_bit_error_rate=f.host_bit_error_rate,
                           speed_range=None if self.speed_range_mrad is None else
                           [v / 1000.0 for v in self.speed_range_mrad])
        if self._truth:
            self._write_truth(dict({'type': 'header', 'firmware': firmware}, **self.header))

    # ---- set-up ------------------------------------------------------------------------------

    @property
    def boot_id(self):
        return f'{os.getpid() & 0xffff:04X}{self._boot:04X}'

    def start(self):
        self.pty.plug()
        self._power_up()

    def close(self):
        self.pty.release()
        if self._truth:
            self._truth.close()
            self._truth = None
        for fd in (self._wake_r, self._wake_w):
            try:
                os.close(fd)
            except OSError:
                pass

    def stop(self):
        """Ask :meth:`run` to return (thread- and signal-safe)."""
        self._stop.set()
        self._wake()

    def request_place(self):
        """Ask :meth:`run` to put a part back at the start state (thread- and signal-safe)."""
        self._place_requested.set()
        self._wake()

    def _wake(self):
        try:
            os.write(self._wake_w, b'x')
        except OSError:
            pass

    def _place_part(self):
        self._place_requested.clear()
        if self._place is None:
            return
        edge, R = self._place()
        self._log(f'part placed on edge {edge} at R {R:.4f} m')
        self._write_truth({'type': 'place', 'edge': edge, 'R': R, 't': self._clock()})

    def _power_up(self):
        self._boot += 1
        self._boot_t0 = self._clock()
        self.cycle = None
        self._epoch += 1
        self._send(p.Hello(self.firmware, self.boot_id))
        self._schedule(self.heartbeat, self._heartbeat, self._epoch)

    # ---- main loop ---------------------------------------------------------------------------

    def run(self, max_time=None):
        """Serve until :meth:`stop` (or ``max_time`` s)."""
        end = None if max_time is None else self._clock() + max_time
        while not self._stop.is_set():
            now = self._clock()
            if end is not None and now >= end:
                break
            timeout = 0.5
            if self._events:
                timeout = min(timeout, max(0.0, self._events[0][0] - now))
            fds = [self._wake_r] + ([self.pty.master] if self.pty.plugged else [])
            try:
                ready, _, _ = select.select(fds, [], [], timeout)
            except InterruptedError:
                continue
            if self._wake_r in ready:
                os.read(self._wake_r, 64)
            if self._place_requested.is_set():
                self._place_part()
            if self.pty.plugged and self.pty.master in ready:
                data, flipped = self.faults.corrupt_rx(self.pty.read())
                if flipped:
                    self._write_truth({'type': 'rx_bit_errors', 'bytes': flipped,
                                       't': self._clock()})
                for event in self.parser.feed(data):
                    self._on_host(event)
            self._run_due()

    def _schedule(self, delay, action, epoch, *args):
        heapq.heappush(self._events, (self._clock() + delay, next(self._counter), action,
                                      epoch, args))

    def _run_due(self):
        now = self._clock()
        while self._events and self._events[0][0] <= now:
            _, _, action, epoch, args = heapq.heappop(self._events)
            if epoch == self._epoch:
                action(*args)

    def _send(self, message, cyc=None):
        if self.pty.plugged:
            data, flipped = self.faults.corrupt_tx(p.encode(message))
            if flipped and cyc is not None:
                name = type(message).__name__.lower()
                cyc.flips[name] = cyc.flips.get(name, 0) + flipped
            self.pty.write(data)

    def _heartbeat(self):
        uptime = int((self._clock() - self._boot_t0) * 1000) & p.UINT32_MAX
        self._send(p.Hb(uptime, 'BUSY' if self.cycle is not None else 'IDLE'))
        self._schedule(self.heartbeat, self._heartbeat, self._epoch)

    # ---- host commands -----------------------------------------------------------------------

    def _on_host(self, event):
        if isinstance(event, p.Fire) and event.speed_mrad_s is not None and \
                self.speed_range_mrad is None:
            # The parser of a controller without the capability knows FIRE with one field:
            # it drops this frame as it would any with a wrong field count.
            self.parser.stats['lines'] -= 1
            self.parser.stats['fields'] += 1
            event = p.Rejected('fields', 'FIRE: expected 1 field(s) (FIRE,<seq>), got 2',
                               command='FIRE')
        if isinstance(event, p.Rejected):
            self._log(f'rejected host frame ({event.kind}): {event.detail}')
            self._send(p.Err(None, p.REJECT_CODES[event.kind], event.kind))
        elif isinstance(event, p.Ping):
            self._send(p.Pong(event.token))
        elif isinstance(event, p.Ident):
            self._send(p.Hello(self.firmware, self.boot_id))
        elif isinstance(event, p.Caps):
            self._send(p.Cap('SPEED', *self.speed_range_mrad))
        elif isinstance(event, p.Stop):
            self._stop_cycle()
        elif isinstance(event, p.Fire):
            self._fire(event.seq, event.speed_mrad_s)

    def _fire(self, seq, speed_mrad_s=None):
        now = self._clock()
        if speed_mrad_s is not None:
            low, high = self.speed_range_mrad
            if not low <= speed_mrad_s <= high:
                self._write_truth({'type': 'fire', 'seq': seq, 'cycle': None,
                                   'outcome': 'bad_speed', 'faults': [], 'throw': False,
                                   'setpoint': speed_mrad_s / 1000.0, 't': now})
                self._send(p.Err(seq, 'BADARG', 'speed out of range'))
                return
        if self.cycle is not None:
            self._write_truth({'type': 'fire', 'seq': seq, 'cycle': None, 'outcome': 'busy',
                               'faults': [], 'throw': False, 't': now,
                               'setpoint': None if speed_mrad_s is None else
                               speed_mrad_s / 1000.0})
            self._send(p.Err(seq, 'BUSY', f'cycle {self.cycle.seq} in progress'))
            return
        self.cycles += 1
        cyc = _Cycle(self.cycles, seq, self.faults.for_cycle(self.cycles), now)
        if speed_mrad_s is not None:
            cyc.setpoint = speed_mrad_s / 1000.0
        self.cycle = cyc
        delay = self.faults.delay if 'delay' in cyc.faults else 0.0
        ep = self._epoch
        self._schedule(delay, self._ack, ep, cyc)
        self._schedule(delay + self.cycle_time / 2, self._release, ep, cyc)
        self._schedule(delay + self.cycle_time, self._settled, ep, cyc)

    def _garbage(self, cyc):
        if 'garbage' in cyc.faults:
            self.pty.write(self.faults.garbage())

    def _ack(self, cyc):
        if self.cycle is not cyc:
            return
        self._garbage(cyc)
        if 'drop_ack' not in cyc.faults:
            self._send(p.Ack(cyc.seq), cyc)
            cyc.sent['ack'] = True
        if 'reset' in cyc.faults:
            # The controller resets before the arm moves: no throw, the cycle is forgotten.
            self.resets += 1
            self._finish(cyc, 'reset')
            self._power_up()

    def _release(self, cyc):
        if self.cycle is not cyc:
            return
        if self.state is not None:
            cyc.edge0 = self.state()[0]
        try:
            thrown = self._throw() if cyc.setpoint is None else self._throw(cyc.setpoint)
        except ThrowFailed as exc:
            # The arm moved, the throw map has no answer (or the part cannot be held at the
            # setpoint): the cycle ends with ERR FAULT.
            cyc.error = exc
            self._log(f'cycle {cyc.k}: {exc}')
        else:
            cyc.edge, cyc.R, cyc.kind = thrown[:3]
            cyc.release_speed = _finite_or_none(thrown[3]) if len(thrown) > 3 else None
            cyc.thrown = True
            cyc.bit = int(bool(self._sense(cyc.edge, cyc.R)))
            if self._sees is not None:
                cyc.seen = bool(self._sees(cyc.edge, cyc.R))
            cyc.bit, cyc.flaky = self.faults.flaky_bit(cyc.bit)
        # REL: the speed the arm released at; without a part thrown, the speed it was set to.
        speed = cyc.release_speed
        if speed is None:
            speed = self.release_speed if cyc.setpoint is None else cyc.setpoint
        self._send(p.Rel(cyc.seq, p.speed_mrad_s(speed)), cyc)
        cyc.sent['rel'] = True
        if 'unplug' in cyc.faults:
            # Unplugged while the part is in flight: the throw happens, SENS never leaves.
            self.unplugs += 1
            self._finish(cyc, 'unplug')
            self._epoch += 1
            self.pty.unplug()
            self._log(f'unplugged for {self.faults.unplug_for} s')
            self._schedule(self.faults.unplug_for, self._replug, self._epoch)

    def _replug(self):
        self.pty.plug()
        self._log(f'replugged: {self.pty.link} -> {self.pty.slave_name}')
        self._power_up()

    def _settled(self, cyc):
        if self.cycle is not cyc:
            return
        self._garbage(cyc)
        if 'drop_sens' in cyc.faults:
            self._finish(cyc, 'sens_dropped')
            return
        if cyc.error is not None:
            self._finish(cyc, 'fault')
            self._send(p.Err(cyc.seq, 'FAULT', cyc.error.code_text), cyc)
            return
        # Log before sending, so a reader of the log never sees a SENS it cannot account for;
        # the bit errors of the SENS are drawn first, so the log can name them too.
        cyc.sent['sens'] = True
        sens = p.Sens(cyc.seq, cyc.bit)
        data, flipped = self.faults.corrupt_tx(p.encode(sens))
        if flipped:
            cyc.flips['sens'] = cyc.flips.get('sens', 0) + flipped
        self._finish(cyc, 'completed')
        if self.pty.plugged:
            self.pty.write(data)

    def _stop_cycle(self):
        cyc = self.cycle
        if cyc is None:
            return
        self._finish(cyc, 'aborted')
        self._send(p.Err(cyc.seq, 'ABORTED', 'stopped by host'))

    def _finish(self, cyc, outcome):
        self.cycle = None
        rec = {'type': 'fire', 'seq': cyc.seq, 'cycle': cyc.k, 'outcome': outcome,
               'faults': cyc.faults, 'throw': cyc.thrown, 'edge': cyc.edge, 'R': cyc.R,
               'kind': cyc.kind, 'bit': cyc.bit, 'seen': cyc.seen, 'edge0': cyc.edge0,
               'sent': dict(cyc.sent), 't': cyc.fired_at, 'flaky': cyc.flaky,
               'bit_errors': dict(cyc.flips), 'setpoint': cyc.setpoint,
               'release_speed': cyc.release_speed}
        if cyc.error is not None:
            rec['error'] = str(cyc.error)
        if not cyc.thrown and self.state is not None:
            rec['edge'], rec['R'] = self.state()
        self._write_truth(rec)

    def _write_truth(self, rec):
        self.records.append(rec)
        if self._truth:
            self._truth.write(json.dumps(rec) + '\n')
            self._truth.flush()


def _err_text(exc):
    """Text of the ERR frame for a throw the map cannot compute (<= 48 chars, no , $ *)."""
    what = getattr(exc, 'condition', None) or type(exc).__name__
    text = f'throw outside the throw map: {what}'
    return ''.join(c for c in text if c not in ',$*')[:48]


def from_scene(scene_path, sensor_radius=None, seed=None, **kwargs):
    """
    Build a Controller whose part follows the scene's throw map from its start state.

    ``seed`` seeds the scene's random effects (release_noise, sensor_noise); None: the scene's
    ``noise.seed``. Without ``sensor_radius`` the sensor is throwmap's design, which needs the
    scene's analysis: a scene whose analysis fails (the part is lost from its start, the
    orbit leaves the domain of f, no finite sensor radius) is an EmulatorError.
    """
    import math
    import numpy as np
    from throwmap import analyse, InputError, load_scene, PartOnArm, ThrowmapError
    try:
        scene = load_scene(scene_path)
    except InputError as exc:
        raise EmulatorError(f'--scene: {exc}') from None
    model = scene.model
    footprint = scene.sensor_footprint
    header = {'scene': os.path.abspath(scene_path), 'goal_edge': scene.goal_edge,
              'release_speed': scene.release_speed}
    if sensor_radius is None:
        try:
            an = analyse(scene)
        except ThrowmapError as exc:
            raise EmulatorError(f'--scene: {scene_path}: analysis failed: {exc}') from None
        sensor_radius = an.sensor.radius
        footprint = an.sensor.footprint
        if not math.isfinite(sensor_radius):
            raise EmulatorError(f'--scene: {scene_path}: the sensor design gives no finite '
                                'radius for this scene; give --sensor-radius')
        header.update(goal_edge=an.sensor.goal_edge, warmup_throws=an.sensor.warmup_throws,
                      bands={str(k): list(v) for k, v in an.limit_set.bands.items()},
                      sensor_feasible=an.sensor.feasible)
    elif not (isinstance(sensor_radius, (int, float)) and np.isfinite(sensor_radius)
              and sensor_radius > 0):
        raise EmulatorError(f'--sensor-radius: must be a number > 0 (m), got {sensor_radius!r}')
    start = scene.default_start()
    try:
        model.f(*start)     # compile the throw map now (numba), not during the first cycle
    except ThrowmapError:
        pass
    seed = scene.seed if seed is None else int(seed)
    # The part (throwmap.PartOnArm), seeded after the analysis and the warm-up, which draw from
    # the scene's generator: each throw draws its release noise, then its sensor reading.
    part = PartOnArm(scene, *start, sensor_radius=sensor_radius, footprint=footprint, seed=seed)
    arm = scene.arm_length
    header.update(sensor_radius=float(sensor_radius), footprint=float(footprint),
                  start=list(start), seed=seed, noisy_sensor=part.noisy_sensor,
                  arm_length=arm if arm is not None and math.isfinite(arm) else None)
    last = {}

    def state():
        return part.edge, (None if part.lost else part.R)

    def throw(release_speed=None):
        try:
            # No part on the arm: an empty throw, kind 'lost'. A speed at which the part
            # cannot be held raises throwmap.DomainError: the cycle's ERR FAULT.
            t = part.throw(release_speed=release_speed)
        except ThrowmapError as exc:
            raise ThrowFailed(_err_text(exc), str(exc)) from None
        last['state'], last['bit'] = state(), t.detected
        return state() + (t.kind, t.release_speed)

    def seen(edge, R):
        return part.sees(edge, R)

    def sense(edge, R):
        # The reading taken of the part at rest after the throw (sensor noise included).
        if last.get('state') == (edge, R):
            return last['bit']
        return part.read(edge, math.nan if R is None else R)

    def place():
        part.place(*start)
        return start

    return Controller(throw=throw, sense=sense, release_speed=scene.release_speed,
                      state=state, header=header, sees=seen, place=place, **kwargs)


def build_arg_parser():
    ap = argparse.ArgumentParser(
        prog='controller_emulator',
        description='Emulated feeder controller on a pty: speaks docs/serial-protocol.md, '
                    'takes its sensor bits from the throw map of a scene.')
    ap.add_argument('--scene', required=True, help='scene YAML (e.g. scenes/triangle.yaml)')
    ap.add_argument('--link', default='/tmp/feeder-tty',
                    help='stable symlink to the pty slave; give it to the driver as `port` '
                         '(default %(default)s)')
    ap.add_argument('--sensor-radius', type=float, default=None,
                    help='sensor position on the arm, m (default: throwmap sensor design)')
    ap.add_argument('--cycle-time', type=float, default=0.1,
                    help='FIRE to SENS, s; REL at half of it (default %(default)s)')
    ap.add_argument('--heartbeat', type=float, default=1.0,
                    help='HB period, s (default %(default)s)')
    ap.add_argument('--drop-ack-every', type=int, metavar='N',
                    help='do not send the ACK of every Nth cycle')
    ap.add_argument('--drop-sens-every', type=int, metavar='N',
                    help='do not send the SENS of every Nth cycle (the throw still happens)')
    ap.add_argument('--garbage-every', type=int, metavar='N',
                    help='write noise, a cut frame, a bad checksum and an overlong line '
                         'before the ACK and the SENS of every Nth cycle')
    ap.add_argument('--delay', type=float, default=0.0, metavar='S',
                    help='hold every reply of a delayed cycle back by S seconds')
    ap.add_argument('--delay-every', type=int, metavar='N',
                    help='delay only every Nth cycle (default: all cycles when --delay > 0)')
    ap.add_argument('--reset-after', type=int, metavar='N',
                    help='after N cycles, reset during the next one (HELLO right after its '
                         'ACK, no throw, cycle forgotten)')
    ap.add_argument('--unplug-after', type=int, metavar='N',
                    help='after N cycles, unplug during the next one (after its REL)')
    ap.add_argument('--unplug-for', type=float, default=1.0, metavar='S',
                    help='seconds unplugged (default %(default)s)')
    ap.add_argument('--spurious-rate', type=float, default=0.0, metavar='P',
                    help='flaky sensor: report 1 with probability P when the reading is 0 '
                         '(default 0)')
    ap.add_argument('--miss-rate', type=float, default=0.0, metavar='P',
                    help='flaky sensor: report 0 with probability P when the reading is 1 '
                         '(default 0)')
    ap.add_argument('--bit-error-rate', type=float, default=0.0, metavar='P',
                    help='each byte sent to the host has one bit flipped with probability P '
                         '(default 0)')
    ap.add_argument('--host-bit-error-rate', type=float, default=0.0, metavar='P',
                    help='each byte read from the host has one bit flipped with probability '
                         'P before it is parsed (default 0)')
    ap.add_argument('--seed', type=int, default=None,
                    help='seed of the garbage, the flaky sensor and the bit errors (default '
                         "0) and of the scene's random effects, release_noise and "
                         "sensor_noise (default: the scene's noise.seed)")
    ap.add_argument('--truth-log', metavar='FILE',
                    help='one JSON line per FIRE received (and a header line)')
    ap.add_argument('--firmware', default=FIRMWARE, help='firmware name in HELLO')
    ap.add_argument('--speed-range', default='%g:%g' % SPEED_RANGE_DEG_S, metavar='MIN:MAX',
                    help='release speeds a FIRE may set, deg/s, announced as CAP,SPEED in '
                         'mrad/s (default %(default)s)')
    ap.add_argument('--no-speed-setpoint', action='store_true',
                    help='a controller without the release-speed setpoint: CAPS gets ERR '
                         'BADCMD, a FIRE with a speed field ERR BADARG (the fixed speed of the '
                         'scene only)')
    ap.add_argument('--max-time', type=float, default=None,
                    help='exit after this many seconds (default: run until SIGINT/SIGTERM)')
    ap.add_argument('-q', '--quiet', action='store_true', help='log nothing to stderr')
    return ap


def main(argv=None):
    args = build_arg_parser().parse_args(argv)

    def log(text):
        if not args.quiet:
            print(f'controller_emulator: {text}', file=sys.stderr, flush=True)

    try:
        faults = Faults(args.drop_ack_every, args.drop_sens_every, args.garbage_every,
                        args.delay, args.delay_every, args.reset_after, args.unplug_after,
                        args.unplug_for, 0 if args.seed is None else args.seed,
                        args.spurious_rate, args.miss_rate, args.bit_error_rate,
                        args.host_bit_error_rate)
        speed_range = None if args.no_speed_setpoint else parse_speed_range(args.speed_range)
        ctl = from_scene(args.scene, args.sensor_radius, args.seed, link=args.link,
                         cycle_time=args.cycle_time, heartbeat=args.heartbeat, faults=faults,
                         truth_log=args.truth_log, firmware=args.firmware, log=log,
                         keep_records=0, speed_range=speed_range)
    except (EmulatorError, OSError) as exc:
        print(f'controller_emulator: error: {exc}', file=sys.stderr)
        return 2

    def on_signal(signum, frame):
        ctl.stop()

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGUSR1, lambda signum, frame: ctl.request_place())
    try:
        ctl.start()
        h = ctl.header
        speeds = ('fixed release speed' if speed_range is None else
                  f'release speed setpoints {args.speed_range} deg/s')
        print(f'controller_emulator: ready on {ctl.pty.link} -> {ctl.pty.slave_name} '
              f'(sensor radius {h["sensor_radius"]:.4f} m, goal edge {h["goal_edge"]}, '
              f'{speeds})', flush=True)
        ctl.run(args.max_time)
    finally:
        ctl.close()
        # Stopped: a further SIGINT/SIGTERM (a terminal's Ctrl-C reaches the whole group and
        # ros2 launch forwards one more) must not end the exit by the signal once the
        # interpreter resets its handlers to the default; as feeder_common.node.run_node.
        for s in (signal.SIGINT, signal.SIGTERM):
            signal.signal(s, signal.SIG_IGN)
    f = ctl.faults
    log(f'stopped after {ctl.cycles} cycles (flaky sensor: {f.flaky["spurious"]} spurious, '
        f'{f.flaky["miss"]} missed; bytes with a bit error: {f.flipped["tx"]} sent, '
        f'{f.flipped["rx"]} read)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
