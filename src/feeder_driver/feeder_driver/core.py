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
``handshake`` (port open, PING sent, waiting for the matching PONG) and ``connected``.
"""

from dataclasses import dataclass, field
import itertools
from typing import Any, Optional

from . import protocol as p

DISCONNECTED = 'disconnected'
# A gap this long between two ticks means the process was stalled (SIGSTOP, starved CPU).
STALL_S = 0.25
# How long, after a deadline (or after waking from a stall), the core waits for the reader
# to show that it has read the port past that deadline, before it trusts the clock alone.
READ_GRACE_S = 0.5
HANDSHAKE = 'handshake'
CONNECTED = 'connected'


@dataclass
class CoreConfig:
    """Timing of the link and the cycle (all seconds); see config/driver.yaml."""

    ack_timeout_s: float = 0.5
    cycle_timeout_s: float = 5.0
    watchdog_timeout_s: float = 3.0
    reconnect_initial_s: float = 0.5
    reconnect_max_s: float = 10.0
    cycle_period: float = 1.0


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
    """Outcome of one fired cycle. ``sensor`` is None when the cycle failed."""

    seq: int
    wire_seq: int
    ok: bool
    reason: str
    sensor: Optional[int]
    stamp: Any
    fired_at: float
    duration_s: float
    release_speed: Optional[float]


@dataclass(frozen=True)
class CycleFinished:
    result: CycleResult


@dataclass(frozen=True)
class Firing:
    """Cycle ``seq`` is about to be fired: announced before the FIRE goes out."""

    seq: int


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
    notes: list = field(default_factory=list)


def _fmt(x):
    return f'{x:.3g}'


class DriverCore:
    """
    State machine of the serial link and of the throw-catch cycles.

    ``log(level, text)`` receives messages with level ``debug``/``info``/``warning``/
    ``error``. Counters for diagnostics are in :attr:`counters`.
    """

    COUNTERS = ('fired', 'completed', 'failed', 'acks_missing', 'stale_replies',
                'controller_errors', 'controller_resets', 'link_losses', 'open_failures',
                'handshake_timeouts', 'watchdog_timeouts')

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
        if why is not None:
            return False, why, []
        effects = self._fire(now)
        return True, f'fired cycle seq {self.pending.seq}', effects

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

    # ---- link events -------------------------------------------------------------------------

    def link_opened(self, now):
        """Start the handshake on a port that has just opened."""
        self.link = HANDSHAKE
        self._opened_at = now
        self._last_rx = None
        self._ids_outstanding = 0
        self._last_open_error = None
        self._legacy = None
        self._log('info', 'serial port open; handshake (PING) started')
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
        # ID first: its HELLO answer arrives before the PONG (the link is ordered), so the
        # firmware and boot id are known once connected, even if the banner was missed.
        self._ping_token = f'h{next(self._tokens)}'
        self._ping_sent_at = now
        self._ids_outstanding += 1
        return [Send(p.Ident()), Send(p.Ping(self._ping_token))]

    def _fire(self, now):
        seq = self.next_seq
        self.next_seq += 1
        self.pending = _Pending(seq, seq % p.SEQ_MODULO, now)
        self.counters['fired'] += 1
        self._last_fire_at = now
        self.last_controller_error = None
        # The notice first: whoever holds a ready must drop it before the arm can move.
        return [Firing(seq), Send(p.Fire(self.pending.wire_seq))]

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
                                        pend.release_speed))

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
                                 pend.fired_at, now - pend.fired_at, pend.release_speed)
            return self._finish(result) + self._maybe_fire_enabled(now)
        return []
