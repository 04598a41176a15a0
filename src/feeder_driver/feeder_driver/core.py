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
ROS-free link and cycle state machine of the feeder driver (docs/driver.md).

The core never touches a port or a clock. Every entry point takes ``now`` (monotonic
seconds) and, where a result is stamped, ``stamp`` (an opaque time value, the node passes
ROS time in nanoseconds), and returns a list of effects for the caller to carry out:

* :class:`Send` -- write a message to the port (on failure call :meth:`DriverCore.link_lost`),
* :class:`OpenLink` / :class:`CloseLink` -- open or close the port,
* :class:`Firing` -- a cycle is about to be fired (carried out before the FIRE it precedes),
* :class:`CycleFinished` -- one per fired cycle, completed or failed (never dropped),
* :class:`Released` -- the arm released the part (joint state at release).

Link states: ``disconnected`` (port closed; reopened after a capped exponential back-off),
``handshake`` (port open, ID, CAPS and PING sent, waiting for the matching PONG) and
``connected``.

Release speed (``CoreConfig.release_speed_mode``): ``fixed`` fires every cycle at the
controller's own speed (``FIRE,<seq>``); ``setpoint`` fires each cycle at the setpoint given
for it (:meth:`DriverCore.set_setpoint`; ``FIRE,<seq>,<speed mrad/s>``) when the controller
announced the capability in the handshake (``CAP,SPEED,<min>,<max>``: :attr:`speed_range`),
and waits for that setpoint rather than fire at a speed nobody chose.
"""

from dataclasses import dataclass, field
import itertools
import math
from typing import Any, Optional

from feeder_common.params import RELEASE_SPEED_MODES

from . import protocol as p

DISCONNECTED = 'disconnected'
# A gap this long between two ticks means the process was stalled (SIGSTOP, starved CPU).
STALL_S = 0.25
# How long, after a deadline (or after waking from a stall), the core waits for the reader
# to show that it has read the port past that deadline, before it trusts the clock alone.
READ_GRACE_S = 0.5
HANDSHAKE = 'handshake'
CONNECTED = 'connected'
# Release-speed modes (the parameter's choices): the controller's own speed, or a setpoint
# per cycle.
FIXED, SETPOINT = RELEASE_SPEED_MODES


@dataclass
class CoreConfig:
    """
    Timing of the link and the cycle (all seconds; see config/driver.yaml) and speed mode.

    ``release_speed_mode``: ``'fixed'`` (never send a speed: the controller's own) or
    ``'setpoint'`` (each cycle fires at the setpoint given for it, when the controller can
    set the release speed).
    """

    ack_timeout_s: float = 0.5
    cycle_timeout_s: float = 5.0
    watchdog_timeout_s: float = 3.0
    reconnect_initial_s: float = 0.5
    reconnect_max_s: float = 10.0
    cycle_period: float = 1.0
    release_speed_mode: str = FIXED

    def __post_init__(self):
        if self.release_speed_mode not in RELEASE_SPEED_MODES:
            raise ValueError(f'release_speed_mode: {self.release_speed_mode!r} must be one of '
                             f'{", ".join(RELEASE_SPEED_MODES)}')


@dataclass(frozen=True)
class Send:
    message: Any


@dataclass(frozen=True)
class OpenLink:
    pass


@dataclass(frozen=True)
class CloseLink:
    reason: str


@dataclass(frozen=True)
class CycleResult:
    """
    Outcome of one fired cycle. ``sensor`` is None when the cycle failed.

    ``release_speed``: rad/s from the controller's REL (None: no REL came);
    ``speed_setpoint``: rad/s, the setpoint the cycle was fired with, as sent (None: the
    controller's fixed speed).
    """

    seq: int
    wire_seq: int
    ok: bool
    reason: str
    sensor: Optional[int]
    stamp: Any
    fired_at: float
    duration_s: float
    release_speed: Optional[float]
    speed_setpoint: Optional[float] = None


@dataclass(frozen=True)
class CycleFinished:
    result: CycleResult


@dataclass(frozen=True)
class Firing:
    """
    Cycle ``seq`` is about to be fired: announced before the FIRE goes out.

    ``speed_setpoint``: rad/s the FIRE asks for (None: the controller's fixed speed).
    """

    seq: int
    speed_setpoint: Optional[float] = None


@dataclass(frozen=True)
class Released:
    seq: int
    speed_rad_s: float
    stamp: Any


class Backoff:
    """Capped exponential back-off: initial, 2x initial, ... up to maximum."""

    def __init__(self, initial, maximum):
        self.initial = initial
        self.maximum = maximum
        self._next = initial

    def next_delay(self):
        delay = min(self._next, self.maximum)
        self._next = min(delay * 2.0, self.maximum)
        return delay

    def reset(self):
        self._next = self.initial


@dataclass
class _Pending:
    seq: int
    wire_seq: int
    fired_at: float
    acked_at: Optional[float] = None
    released_at: Optional[float] = None
    release_speed: Optional[float] = None
    speed_setpoint: Optional[float] = None
    notes: list = field(default_factory=list)


def _fmt(x):
    return f'{x:.3g}'


class DriverCore:
    """
    State machine of the serial link and of the throw-catch cycles.

    ``log(level, text)`` receives messages with level ``debug``/``info``/``warning``/
    ``error``. Counters for diagnostics are in :attr:`counters`. :attr:`speed_range` is the
    release-speed range (min, max) in rad/s the controller announced in the handshake (None:
    it cannot set the release speed, or the handshake has not ended); :attr:`setpoint` is the
    setpoint held for cycle :attr:`next_seq` ((seq, rad/s) or None).
    """

    COUNTERS = ('fired', 'completed', 'failed', 'acks_missing', 'stale_replies',
                'controller_errors', 'controller_resets', 'link_losses', 'open_failures',
                'handshake_timeouts', 'watchdog_timeouts', 'waiting_for_setpoint',
                'setpoints_refused', 'late_caps')

    def __init__(self, config=None, log=None, first_seq=1):
        self.config = config or CoreConfig()
        self._log = log or (lambda level, text: None)
        self.link = DISCONNECTED
        self.running = False          # configured: the link is managed
        self.active = False           # lifecycle active: cycles may fire
        self.enabled = False          # continuous cycling
        self.pending = None
        self.next_seq = first_seq
        self.counters = dict.fromkeys(self.COUNTERS, 0)
        self.backoff = Backoff(self.config.reconnect_initial_s, self.config.reconnect_max_s)
        self.next_open_at = None
        self.last_link_error = 'not opened yet'
        self.last_failure = ''
        self.last_result = None
        self.firmware = ''
        self.boot_id = ''
        self.hb_state = ''
        self.hb_uptime_ms = None
        self.last_controller_error = None     # (now, code, text) of an ERR without our seq
        self._opened_at = None
        self._last_rx = None
        self._ping_token = None
        self._ping_sent_at = None
        self._ids_outstanding = 0     # ID requests whose HELLO answer has not arrived
        self._tokens = itertools.count(1)
        self._last_fire_at = None
        self._hold_until = None       # after a failure, continuous cycling waits one period
        self._last_open_error = None
        self._legacy = None           # detail of a protocol-1 frame seen since the port opened
        self._last_tick = None
        self._awake_since = None      # first tick after the last stall
        self.speed_range = None       # (min, max) rad/s from CAP,SPEED; None: fixed speed
        self._speed_range_mrad = None
        self.setpoint = None          # (seq, rad/s as sent) for cycle next_seq
        self._caps_outstanding = 0    # CAPS requests whose answer has not arrived
        self._cap = None              # the CAP,SPEED seen since the port opened
        self._caps_refused = False    # ERR,-,BADCMD answered CAPS since the port opened
        self._waiting_seq = None      # the cycle counted in waiting_for_setpoint
        self._ignored_logged = False  # 'setpoints are ignored' logged on this link

    # ---- configuration -------------------------------------------------------------------

    def reconfigure(self, config):
        """Apply new timing; takes effect for the next timeout check and back-off step."""
        self.config = config
        self.backoff.initial = config.reconnect_initial_s
        self.backoff.maximum = config.reconnect_max_s

    # ---- lifecycle -------------------------------------------------------------------------

    def start(self, now):
        """Begin managing the link (lifecycle configure): open the port now."""
        self.running = True
        self.backoff.reset()
        self.next_open_at = now
        return [OpenLink()]

    def stop(self, now, stamp, reason):
        """Stop managing the link (cleanup/shutdown): abort a pending cycle, close the port."""
        effects = self.set_active(False, now, stamp, reason)
        self.running = False
        self.next_open_at = None
        if self.link != DISCONNECTED:
            self.link = DISCONNECTED
            self.last_link_error = f'closed ({reason})'
            effects.append(CloseLink(reason))
        return effects

    def set_active(self, active, now, stamp, reason='node deactivated'):
        """Lifecycle activate/deactivate. Deactivating stops cycling and aborts a cycle."""
        effects = []
        if not active:
            self.enabled = False
            if self.pending is not None:
                if self.link != DISCONNECTED:
                    effects.append(Send(p.Stop()))
                effects += self._fail(now, stamp, f'aborted: {reason}')
        self.active = active
        return effects

    # ---- requests --------------------------------------------------------------------------

    def link_refusal(self):
        """Why the link cannot carry a cycle now (None if it can)."""
        if self.link == HANDSHAKE:
            return ('refused: serial port open, but the controller has not answered PING yet '
                    f'(last link error: {self.last_link_error})')
        if self.link != CONNECTED:
            return f'refused: serial link is disconnected ({self.last_link_error})'
        return None

    def refusal(self, now):
        """Why a cycle cannot be fired now (None if it can)."""
        if not self.active:
            return 'refused: driver is not active (lifecycle state is not active)'
        if self.link != CONNECTED:
            return self.link_refusal()
        if self.pending is not None:
            return (f'refused: busy with cycle seq {self.pending.seq} (fired '
                    f'{_fmt(now - self.pending.fired_at)} s ago)')
        return None

    def trigger(self, now):
        """Service ~/trigger_cycle: returns (success, message, effects)."""
        if self.enabled and self.active:
            return (False, 'refused: continuous cycling is enabled; call ~/enable false first',
                    [])
        why = self.refusal(now)
        if why is None:
            why = self._setpoint_refusal()
        if why is not None:
            return False, why, []
        effects = self._fire(now)
        return True, f'fired cycle seq {self.pending.seq}' + self._speed_note(), effects

    def enable(self, on, now):
        """Service ~/enable: returns (success, message, effects)."""
        if not on:
            was = self.enabled
            self.enabled = False
            tail = (f'; cycle seq {self.pending.seq} still in flight'
                    if self.pending is not None else '')
            return True, ('disabled' if was else 'already disabled') + tail, []
        if not self.active:
            return False, 'refused: driver is not active (lifecycle state is not active)', []
        if self.link != CONNECTED:
            return False, self.link_refusal(), []
        if self.enabled:
            return True, f'already enabled (every {_fmt(self.config.cycle_period)} s)', []
        self.enabled = True
        effects = self._maybe_fire_enabled(now)
        return True, f'enabled: one cycle every {_fmt(self.config.cycle_period)} s', effects

    def set_setpoint(self, now, seq, speed_rad_s):
        """
        Set the release-speed setpoint (rad/s) of cycle ``seq``: (accepted, reason, effects).

        ``seq`` must be :attr:`next_seq` (the cycle the setpoint is for; the newest setpoint
        for it wins). Refused when ``release_speed_mode`` is ``fixed``, when the speed is not
        a finite number > 0, when it lies outside the range the controller announced, and when
        the controller cannot set the release speed. While the link is not connected the range
        is not known: the setpoint is held and checked when the handshake ends. When
        continuous cycling was only waiting for this setpoint, the cycle fires now (effects).
        """
        accepted, reason = self._check_setpoint(seq, speed_rad_s)
        if not accepted:
            self.counters['setpoints_refused'] += 1
            return False, f'refused: {reason}', []
        self.setpoint = (seq, p.speed_mrad_s(speed_rad_s) / 1000.0)
        effects = self._maybe_fire_enabled(now)
        if effects:
            reason += f'; fired cycle seq {self.pending.seq}'
        return True, reason, effects

    def _check_setpoint(self, seq, speed):
        """Return (accepted, reason) for a setpoint of ``speed`` rad/s for cycle ``seq``."""
        if self.config.release_speed_mode != SETPOINT:
            return False, (f'release_speed_mode is {self.config.release_speed_mode!r}: cycles '
                           "fire at the controller's own speed; use 'setpoint' to set it")
        if isinstance(seq, bool) or not isinstance(seq, int) or seq != self.next_seq:
            pending = (f' (cycle {self.pending.seq} is in flight)'
                       if self.pending is not None else '')
            return False, (f'setpoint for cycle {seq!r}, but the next cycle is '
                           f'{self.next_seq}{pending}')
        if isinstance(speed, bool) or not isinstance(speed, (int, float)) or \
                not math.isfinite(speed) or speed <= 0.0:
            return False, (f'release-speed setpoint {speed!r} for cycle {seq}: must be a '
                           'finite number > 0 (rad/s)')
        if p.speed_mrad_s(speed) > p.MAX_SPEED_MRAD_S:
            return False, (f'release-speed setpoint {speed!r} rad/s for cycle {seq}: beyond '
                           f'the protocol limit of {p.MAX_SPEED_MRAD_S / 1000.0:g} rad/s')
        if self.link != CONNECTED:
            return True, (f'setpoint {speed:.4g} rad/s for cycle {seq} held; the link is '
                          f'{self.link}: checked against the range of the controller once it '
                          'answers')
        if self.speed_range is None:
            return False, (f'setpoint for cycle {seq} ignored: the controller cannot set the '
                           'release speed (it announced no CAP,SPEED); cycles fire at its '
                           'fixed speed')
        why = self._out_of_range(speed)
        if why:
            return False, f'release-speed setpoint for cycle {seq}: {why}'
        return True, f'setpoint {speed:.4g} rad/s for cycle {seq}'

    def _out_of_range(self, speed):
        low, high = self._speed_range_mrad
        if low <= p.speed_mrad_s(speed) <= high:
            return ''
        return (f'{speed:.4g} rad/s is outside the range of the controller, {low / 1000.0:g} .. '
                f'{high / 1000.0:g} rad/s')

    def _setpoint_needed(self):
        """Whether each cycle fires at a setpoint: mode 'setpoint' and a capable controller."""
        return self.config.release_speed_mode == SETPOINT and self.speed_range is not None

    def _has_setpoint(self):
        return self.setpoint is not None and self.setpoint[0] == self.next_seq

    def _setpoint_refusal(self):
        """Why the next cycle cannot fire for want of its setpoint (None if it can)."""
        if not self._setpoint_needed() or self._has_setpoint():
            return None
        low, high = self.speed_range
        return (f'refused: no release-speed setpoint for cycle {self.next_seq} yet; '
                "release_speed_mode is 'setpoint': give one (the controller's range is "
                f'{low:g} .. {high:g} rad/s) before firing')

    def _speed_note(self):
        speed = self.pending.speed_setpoint
        return '' if speed is None else f' at {speed:.4g} rad/s'

    # ---- link events -------------------------------------------------------------------------

    def link_opened(self, now):
        """Start the handshake on a port that has just opened."""
        self.link = HANDSHAKE
        self._opened_at = now
        self._last_rx = None
        self._ids_outstanding = 0
        self._last_open_error = None
        self._legacy = None
        self.speed_range = None
        self._speed_range_mrad = None
        self._caps_outstanding = 0
        self._cap = None
        self._caps_refused = False
        self._ignored_logged = False
        self._log('info', 'serial port open; handshake (ID, CAPS, PING) started')
        return self._send_ping(now)

    def link_open_failed(self, now, error):
        """Schedule a retry after the back-off delay: opening the port failed."""
        self.counters['open_failures'] += 1
        delay = self.backoff.next_delay()
        self.next_open_at = now + delay
        text = str(error)
        self.last_link_error = f'open failed: {text}'
        level = 'warning' if text != self._last_open_error else 'debug'
        self._last_open_error = text
        self._log(level, f'cannot open serial port: {text}; retrying in {_fmt(delay)} s')
        return []

    def link_lost(self, now, stamp, error):
        """Read/write failed, or a timeout declared the link dead: close and retry later."""
        if self.link == DISCONNECTED:
            return []
        self.counters['link_losses'] += 1
        reason = str(error)
        self.link = DISCONNECTED
        self.last_link_error = reason
        effects = [CloseLink(reason)]
        if self.pending is not None:
            effects += self._fail(now, stamp, f'serial link lost during cycle: {reason}')
        delay = self.backoff.next_delay()
        self.next_open_at = now + delay if self.running else None
        self._log('warning', f'serial link lost: {reason}; reopening in {_fmt(delay)} s')
        return effects

    def received(self, now, stamp, events):
        """Handle the events the parser decoded from one read (messages, Rejected)."""
        effects = []
        for event in events:
            if self.link == DISCONNECTED:
                break
            if isinstance(event, p.Rejected):
                if event.kind == 'legacy' and self._legacy is None:
                    # Old firmware: say so once per opening; the handshake cannot complete.
                    self._legacy = event.detail
                    self._log('error', f'controller speaks an old protocol: {event.detail}')
                self._log('debug', f'dropped frame ({event.kind}): {event.detail}')
                continue
            self._last_rx = now
            effects += self._handle(now, stamp, event)
        return effects

    # ---- timers ------------------------------------------------------------------------------

    def _read_horizon(self, now, read_until):
        """
        Time up to which every received byte has been handled: deadlines are judged on it.

        ``read_until`` is when the reader's latest completed read began (all bytes that
        arrived before it have been read and their events handled). After a stall a reply
        may sit in the port's buffer past its deadline: it is read before the cycle fails.
        Should the reader stop reporting while the ticks run on time, the clock takes over
        READ_GRACE_S late, so a cycle still ends.
        """
        if self._last_tick is None or now - self._last_tick > STALL_S:
            self._awake_since = now
        self._last_tick = now
        if read_until is None:
            return now
        if now - self._awake_since >= READ_GRACE_S:
            return min(now, max(read_until, now - READ_GRACE_S))
        return min(now, read_until)

    def tick(self, now, stamp, read_until=None):
        """
        Check timeouts, reconnects and continuous cycling (the node calls it at 50 Hz).

        ``read_until``: when the reader's latest completed read of the port began (its
        events already handed to :meth:`received`); None: everything up to ``now`` is.
        """
        cfg = self.config
        horizon = self._read_horizon(now, read_until)
        effects = []
        if self.link == DISCONNECTED:
            if self.running and self.next_open_at is not None and now >= self.next_open_at:
                self.next_open_at = None
                effects.append(OpenLink())
            return effects
        pend = self.pending
        if pend is not None:
            age = horizon - pend.fired_at
            if pend.acked_at is None and age > cfg.ack_timeout_s:
                effects.append(Send(p.Stop()))
                effects += self._fail(now, stamp, f'no ACK within {_fmt(cfg.ack_timeout_s)} s '
                                      'of FIRE' + self._controller_error_note(pend))
            elif age > cfg.cycle_timeout_s:
                effects.append(Send(p.Stop()))
                effects += self._fail(now, stamp, f'no SENS within {_fmt(cfg.cycle_timeout_s)} '
                                      f's of FIRE ({self._progress(pend)})')
        if self.link == HANDSHAKE:
            if horizon - self._opened_at > cfg.watchdog_timeout_s:
                self.counters['handshake_timeouts'] += 1
                why = (f'the controller sent {self._legacy}' if self._legacy is not None else
                       'is a feeder controller on this port, at this baud rate?')
                return effects + self.link_lost(
                    now, stamp, f'no PONG within {_fmt(cfg.watchdog_timeout_s)} s of opening '
                    f'({why})')
            if now - self._ping_sent_at > cfg.ack_timeout_s:
                effects += self._send_ping(now)
        elif self.link == CONNECTED:
            if horizon - self._last_rx > cfg.watchdog_timeout_s:
                self.counters['watchdog_timeouts'] += 1
                return effects + self.link_lost(
                    now, stamp, f'controller silent for {_fmt(now - self._last_rx)} s '
                    f'(no heartbeat; watchdog {_fmt(cfg.watchdog_timeout_s)} s)')
        effects += self._maybe_fire_enabled(now)
        return effects

    # ---- internals ---------------------------------------------------------------------------

    def _send_ping(self, now):
        # ID and CAPS first: their answers (HELLO; CAP or ERR BADCMD) arrive before the PONG
        # (the link is ordered), so the firmware, the boot id and whether the controller sets
        # the release speed are known once connected, even if the banner was missed.
        self._ping_token = f'h{next(self._tokens)}'
        self._ping_sent_at = now
        self._ids_outstanding += 1
        self._caps_outstanding += 1
        return [Send(p.Ident()), Send(p.Caps()), Send(p.Ping(self._ping_token))]

    def _handshake_done(self):
        """At the PONG: set :attr:`speed_range` from the CAPS answer seen since opening."""
        if self._cap is not None:
            cap = self._cap
            self._speed_range_mrad = (cap.min_mrad_s, cap.max_mrad_s)
            self.speed_range = (cap.min_rad_s, cap.max_rad_s)
            self._log('info', f'controller sets the release speed: {cap.min_rad_s:g} .. '
                      f'{cap.max_rad_s:g} rad/s (CAP,SPEED)')
        elif self._caps_refused:
            self._log('info', 'controller cannot set the release speed (answered CAPS with '
                      'BADCMD): fixed speed')
        else:
            # Lost on the line, or a firmware that ignores unknown commands: fixed speed.
            self._log('warning' if self.config.release_speed_mode == SETPOINT else 'info',
                      'controller did not answer CAPS before its PONG (neither CAP nor ERR '
                      'BADCMD: lost on the line, or the firmware ignores unknown commands): '
                      'fixed speed on this link')
        held = self.setpoint
        if held is not None and self._setpoint_needed() and self._out_of_range(held[1]):
            self.setpoint = None
            self.counters['setpoints_refused'] += 1
            self._log('warning', f'setpoint for cycle {held[0]} dropped: '
                      f'{self._out_of_range(held[1])}')

    def _fire(self, now):
        seq = self.next_seq
        speed = None
        if self._setpoint_needed():
            speed = self.setpoint[1]        # callers checked it is for this seq
        elif self.config.release_speed_mode == SETPOINT and not self._ignored_logged:
            self._ignored_logged = True
            self._log('warning', "release_speed_mode is 'setpoint', but the controller cannot "
                      'set the release speed: setpoints are ignored, cycles fire at its fixed '
                      'speed')
        self.setpoint = None
        self.next_seq += 1
        self.pending = _Pending(seq, seq % p.SEQ_MODULO, now, speed_setpoint=speed)
        self.counters['fired'] += 1
        self._last_fire_at = now
        self.last_controller_error = None
        fire = p.Fire(self.pending.wire_seq, None if speed is None else p.speed_mrad_s(speed))
        # The notice first: whoever holds a ready must drop it before the arm can move.
        return [Firing(seq, speed), Send(fire)]

    def _maybe_fire_enabled(self, now):
        if not (self.enabled and self.active and self.pending is None):
            return []
        if self._last_fire_at is not None and \
                now < self._last_fire_at + self.config.cycle_period:
            return []
        if self._hold_until is not None and now < self._hold_until:
            return []
        if self.link != CONNECTED:
            return []       # paused until the link is back
        if self._setpoint_refusal() is not None:
            # Never a cycle at a speed nobody chose: wait for this cycle's setpoint.
            if self._waiting_seq != self.next_seq:
                self._waiting_seq = self.next_seq
                self.counters['waiting_for_setpoint'] += 1
                self._log('debug', f'cycle {self.next_seq} waits for its release-speed '
                          'setpoint')
            return []
        return self._fire(now)

    def _progress(self, pend):
        parts = []
        if pend.acked_at is not None:
            parts.append(f'ACK at +{_fmt(pend.acked_at - pend.fired_at)} s')
        else:
            parts.append('no ACK')
        if pend.released_at is not None:
            parts.append(f'REL at +{_fmt(pend.released_at - pend.fired_at)} s')
        else:
            parts.append('no REL')
        return ', '.join(parts)

    def _controller_error_note(self, pend):
        err = self.last_controller_error
        if err is not None and err[0] >= pend.fired_at:
            return f' (controller reported ERR {err[1]}: {err[2]})'
        return ''

    def _finish(self, result):
        self.pending = None
        self.last_result = result
        if result.ok:
            self.counters['completed'] += 1
        else:
            self.counters['failed'] += 1
            self._hold_until = result.fired_at + result.duration_s + self.config.cycle_period
            self.last_failure = f'seq {result.seq}: {result.reason}'
            self._log('warning', f'cycle seq {result.seq} failed: {result.reason}')
        return [CycleFinished(result)]

    def _fail(self, now, stamp, reason):
        pend = self.pending
        return self._finish(CycleResult(pend.seq, pend.wire_seq, False, reason, None, stamp,
                                        pend.fired_at, now - pend.fired_at,
                                        pend.release_speed, pend.speed_setpoint))

    def _handle(self, now, stamp, msg):
        pend = self.pending
        mine = pend is not None and getattr(msg, 'seq', None) == pend.wire_seq
        if isinstance(msg, p.Pong):
            if self.link == HANDSHAKE and msg.token == self._ping_token:
                self.link = CONNECTED
                self.backoff.reset()
                self.last_link_error = 'none'
                self._log('info', 'controller answered PING: link connected'
                          + (f' (firmware {self.firmware}, boot {self.boot_id})'
                             if self.firmware else ''))
                self._handshake_done()
            return []
        if isinstance(msg, p.Cap):
            self._caps_outstanding = max(0, self._caps_outstanding - 1)
            if self.link == HANDSHAKE:
                self._cap = msg
            else:
                # The capability is settled by the handshake; a CAP after it (the answer to a
                # repeated CAPS, or unasked) changes nothing.
                self.counters['late_caps'] += 1
                self._log('debug', f'CAP after the handshake ignored: {msg}')
            return []
        if isinstance(msg, p.Hello):
            effects = []
            answer = self._ids_outstanding > 0 and (not self.boot_id
                                                    or msg.boot_id == self.boot_id)
            self._ids_outstanding = max(0, self._ids_outstanding - 1)
            if self.link == CONNECTED and not answer:
                # Unsolicited, or a new boot id: the controller has reset.
                self.counters['controller_resets'] += 1
                self._log('warning', f'controller reset (HELLO firmware {msg.firmware}, boot '
                          f'{msg.boot_id}; previous boot {self.boot_id or "unknown"})')
                if pend is not None:
                    effects += self._fail(now, stamp, 'controller reset during cycle (HELLO '
                                          f'firmware {msg.firmware}, boot {msg.boot_id})')
            self.firmware, self.boot_id = msg.firmware, msg.boot_id
            return effects + self._maybe_fire_enabled(now)
        if isinstance(msg, p.Hb):
            self.hb_state, self.hb_uptime_ms = msg.state, msg.uptime_ms
            if pend is not None and pend.acked_at is not None and msg.state == 'IDLE' \
                    and self.link == CONNECTED:
                # The link is ordered: an IDLE heartbeat after our ACK means the controller
                # finished (or dropped) the cycle and its SENS is lost.
                return self._fail(now, stamp, 'controller reports IDLE but sent no SENS '
                                  f'(reply lost; {self._progress(pend)})') + \
                    self._maybe_fire_enabled(now)
            return []
        if isinstance(msg, p.Err) and msg.seq is None and msg.code == 'BADCMD' and \
                self._caps_outstanding > 0:
            # The answer of a controller without the capability to CAPS: expected, no fault.
            self._caps_outstanding -= 1
            if self.link == HANDSHAKE:
                self._caps_refused = True
            self._log('debug', f'CAPS answered with ERR BADCMD ({msg.text})')
            return []
        if isinstance(msg, p.Err):
            self.counters['controller_errors'] += 1
            if mine:
                return self._fail(now, stamp, f'controller refused/aborted: ERR {msg.code}'
                                  + (f' ({msg.text})' if msg.text else '')) + \
                    self._maybe_fire_enabled(now)
            if msg.seq is None:
                self.last_controller_error = (now, msg.code, msg.text)
                self._log('warning', f'controller error {msg.code}: {msg.text}')
            else:
                self.counters['stale_replies'] += 1
            return []
        if not mine:
            self.counters['stale_replies'] += 1
            self._log('debug', f'stale or unexpected {msg.NAME} (seq '
                      f'{getattr(msg, "seq", "-")}; pending '
                      f'{pend.wire_seq if pend else "none"})')
            return []
        if pend.acked_at is None:
            pend.acked_at = now
            if not isinstance(msg, p.Ack):
                self.counters['acks_missing'] += 1
                pend.notes.append('ACK missing')
        if isinstance(msg, p.Rel):
            pend.released_at = now
            pend.release_speed = msg.speed_rad_s
            return [Released(pend.seq, msg.speed_rad_s, stamp)]
        if isinstance(msg, p.Sens):
            result = CycleResult(pend.seq, pend.wire_seq, True, 'completed', msg.bit, stamp,
                                 pend.fired_at, now - pend.fired_at, pend.release_speed,
                                 pend.speed_setpoint)
            return self._finish(result) + self._maybe_fire_enabled(now)
        return []
