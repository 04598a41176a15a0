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
The report gate says whether a report is the driver's own, admitted or not.

A report refused as stale or replayed is still signed by the driver: its seq is one the
driver fired (the speed policy's next setpoint is for the cycle after it); an unsigned or
forged one proves nothing.
"""

from feeder_common import messages
from feeder_monitor.trust import ReportGate

KEY = bytes(range(32))
DRIVER = '/feeder/feeder_driver'
NS = 1_000_000_000
T0 = 1795362335 * NS


def report(seq, stamp_ns, key=KEY, session='ab12'):
    signer = messages.CycleSigner(key, DRIVER, session)
    return messages.parse_cycle_status(signer.cycle_status(seq, True, '', True, stamp_ns,
                                                           'sim', 5.5))


def test_admitted_stale_and_replayed_reports_are_the_drivers_forged_ones_not():
    gate = ReportGate(KEY, DRIVER, 1.0)
    first = gate.admit(report(1, T0), T0)
    assert first.admitted and first.authentic
    stale = gate.admit(report(2, T0), T0 + 5 * NS)
    assert not stale.admitted and stale.authentic and 'stale' in stale.reason
    replayed = gate.admit(report(1, T0 + NS), T0 + NS)
    assert not replayed.admitted and replayed.authentic and 'replayed' in replayed.reason
    forged = gate.admit(report(3, T0 + NS, key=bytes(32)), T0 + NS)
    assert not forged.admitted and not forged.authentic
    unsigned = report(3, T0 + NS)
    unsigned = messages.CycleStatus(**{**unsigned.__dict__, 'mac': b''})
    assert not gate.admit(unsigned, T0 + NS).authentic
