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
release_speed_setpoint: a setpoint is used only when it proves itself, for one cycle at most.

Signed by the speed source under the key, fresh, addressed to the driver's next cycle (or to
no run yet); a forged, replayed, stale or misaddressed one leaves the cycle waiting.
"""

import copy
import math

from feeder_common import messages
from feeder_common.setpoints import SetpointInbox
import pytest

KEY = bytes(range(32))
OTHER_KEY = bytes([7]) * 32
MONITOR = '/feeder/feeder_monitor'
NS = messages.NS
T0 = 1795362335 * NS


def setpoint(seq=5, driver_session='d1', speed=6.0, sent_ns=T0, key=KEY, sender=MONITOR):
    return messages.signed_setpoint(key, sender, 'aa11', seq, driver_session, speed, sent_ns)


def test_a_signed_setpoint_checks_and_every_changed_field_does_not():
    msg = setpoint()
    chk = messages.check_setpoint(msg, KEY, MONITOR, T0 + NS // 2)
    assert chk.usable and (chk.seq, chk.driver_session, chk.speed) == (5, 'd1', 6.0)
    for name, value in (('seq', 6), ('driver_session', 'd2'), ('speed', 6.000001),
                        ('session', 'aa12')):
        forged = copy.copy(msg)
        setattr(forged, name, value)
        chk = messages.check_setpoint(forged, KEY, MONITOR, T0)
        assert not chk.usable and 'not signed by' in chk.reason, name
    assert 'not signed by' in messages.check_setpoint(msg, OTHER_KEY, MONITOR, T0).reason
    assert 'not signed by' in messages.check_setpoint(msg, KEY, '/other/monitor', T0).reason
    unsigned = copy.copy(msg)
    unsigned.mac = []
    assert messages.check_setpoint(unsigned, KEY, MONITOR, T0).reason == 'unsigned setpoint'


@pytest.mark.parametrize('speed', [0.0, -1.0, math.nan, math.inf])
def test_a_setpoint_that_is_no_speed_is_never_usable(speed):
    with pytest.raises(ValueError, match='finite speed > 0'):
        setpoint(speed=speed)
    msg = setpoint()
    msg.speed = speed
    chk = messages.check_setpoint(msg, KEY, MONITOR, T0)
    assert not chk.usable and 'malformed' in chk.reason


def test_an_old_or_future_setpoint_is_not_usable():
    msg = setpoint()
    assert 'ago, more than 1 s' in messages.check_setpoint(msg, KEY, MONITOR, T0 + 2 * NS).reason
    assert 'in the future' in messages.check_setpoint(msg, KEY, MONITOR, T0 - 2 * NS).reason


def test_the_inbox_gives_a_setpoint_to_its_cycle_once():
    inbox = SetpointInbox(KEY, MONITOR, 1.0)
    assert inbox.for_cycle(5, 'd1', T0)[0] is None          # none yet
    assert inbox.offer(setpoint(), T0) == ''
    assert inbox.for_cycle(5, 'd1', T0) == (6.0, '')
    speed, why = inbox.for_cycle(6, 'd1', T0)
    assert speed is None and 'for cycle 5 of run d1' in why
    assert inbox.for_cycle(5, 'd2', T0)[0] is None          # another run
    inbox.used()
    speed, why = inbox.for_cycle(5, 'd1', T0)
    assert speed is None and 'was used' in why
    # The sender republishes the same setpoint (a fresh sent): still for cycle 5 only.
    inbox.offer(setpoint(sent_ns=T0 + NS // 4), T0 + NS // 4)
    assert inbox.for_cycle(6, 'd1', T0 + NS // 4)[0] is None
    # Stale by the time of the cycle.
    inbox.offer(setpoint(seq=6, sent_ns=T0 + NS // 2), T0 + NS // 2)
    speed, why = inbox.for_cycle(6, 'd1', T0 + 2 * NS)
    assert speed is None and 'old' in why
    assert inbox.for_cycle(6, 'd1', T0 + NS) == (6.0, '')


def test_the_inbox_refuses_forgeries_and_keeps_the_newest():
    inbox = SetpointInbox(KEY, MONITOR, 1.0)
    inbox.offer(setpoint(speed=5.0, sent_ns=T0 + 10), T0)
    assert 'not signed' in inbox.offer(setpoint(speed=9.0, key=OTHER_KEY), T0)
    assert 'older' in inbox.offer(setpoint(speed=7.0, sent_ns=T0), T0)
    assert inbox.for_cycle(5, 'd1', T0) == (5.0, '')
    assert inbox.counts['refused'] == 1
    # Addressed to no run yet: the next cycle of whatever run.
    inbox.offer(setpoint(seq=0, driver_session='', speed=4.0, sent_ns=T0 + 20), T0)
    assert inbox.for_cycle(77, 'd9', T0) == (4.0, '')


def test_a_restarted_drivers_first_cycle_takes_the_setpoint_of_the_old_run():
    # The sender has seen only the old run (d1, up to cycle 40): its newest setpoint is for
    # cycle 41 of d1. The new run d2 starts at cycle 1 and takes it; its cycle 2 does not.
    inbox = SetpointInbox(KEY, MONITOR, 1.0)
    inbox.offer(setpoint(seq=41, driver_session='d1', speed=5.5), T0)
    assert inbox.for_cycle(1, 'd2', T0) == (5.5, '')
    assert inbox.for_cycle(2, 'd2', T0)[0] is None
    inbox.used()
    assert inbox.for_cycle(1, 'd2', T0)[0] is None      # used once
