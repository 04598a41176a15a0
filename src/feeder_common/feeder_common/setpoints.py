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
The driver's side of ``release_speed_setpoint``: which setpoint, if any, a cycle is fired at.

The driver and its stand-in (``release_speed_mode: setpoint``) fire cycle N of run S only at a
setpoint that proves itself: signed by ``speed_source`` under the key, sent at most
``max_setpoint_age`` ago, and addressed to (S, N), or to no run yet (``driver_session`` '':
the sender has not seen this driver's cycles, after its start). The first cycle of a run
takes the newest fresh setpoint whatever run it names: after a driver's restart the sender
still addresses the old run's next cycle until it sees the new run's first report, and that
speed is the one it chose for the part's next throw. Each setpoint message is used for one
cycle at most. Whatever setpoint a cycle was fired at, the
cycle's signed report says it, and the monitor follows the part with that speed: a wrong
setpoint can cost throws, never make a ready.
"""

from .messages import check_setpoint


class SetpointInbox:
    """The newest usable setpoint; :meth:`offer` each message, :meth:`for_cycle` at a fire."""

    def __init__(self, key, sender, max_age_s):
        self.key = key
        self.sender = sender
        self.max_age_s = float(max_age_s)
        self._newest = None         # (seq, driver_session, speed, sent_ns, sender session)
        self._used = None           # (sent_ns, sender session) of the last one fired at
        self.counts = {'setpoints': 0, 'refused': 0, 'used': 0, 'waited': 0}
        self.last_refusal = ''

    def offer(self, msg, now_ns):
        """Take a ``SpeedSetpoint`` message; return ('' or the reason it is not taken)."""
        self.counts['setpoints'] += 1
        chk = check_setpoint(msg, self.key, self.sender, now_ns, self.max_age_s)
        if not chk.usable:
            self.counts['refused'] += 1
            self.last_refusal = chk.reason
            return chk.reason
        if self._newest is not None and chk.sent_ns < self._newest[3]:
            return 'older than the setpoint held'
        self._newest = (chk.seq, chk.driver_session, chk.speed, chk.sent_ns, str(msg.session))
        return ''

    def for_cycle(self, seq, session, now_ns):
        """
        Return (speed rad/s or None, why none) for cycle ``seq`` of driver run ``session``.

        Does not use it up: :meth:`used` after the cycle is fired.
        """
        held = self._newest
        if held is None:
            return None, f'no release-speed setpoint from {self.sender} yet'
        want_seq, want_session, speed, sent_ns, sender_session = held
        age = (int(now_ns) - sent_ns) * 1e-9
        if (sent_ns, sender_session) == self._used:
            return None, (f'the last setpoint (cycle {want_seq}) was used; waiting for the one '
                          f'of cycle {seq}')
        if age > self.max_age_s:
            return None, (f'the newest setpoint is {age:.2f} s old (max_setpoint_age '
                          f'{self.max_age_s:g} s): {self.sender} stalled or stopped')
        if want_session and seq != 1 and (want_session != session or want_seq != seq):
            return None, (f'the newest setpoint is for cycle {want_seq} of run {want_session}, '
                          f'this is cycle {seq} of run {session}')
        return speed, ''

    def used(self):
        """Mark the setpoint :meth:`for_cycle` returned as fired at (one cycle per message)."""
        if self._newest is not None:
            self._used = (self._newest[3], self._newest[4])
            self.counts['used'] += 1
