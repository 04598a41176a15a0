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
Which cycle reports the monitor may judge (ROS-free; docs/security.md).

A report is admitted only on what it proves about itself: its MAC verifies under the shared key
and names the trusted driver, it was sampled within ``max_age`` of now, it belongs to the
driver's current run (session) and its seq is above every seq seen in that run. Who is on the
DDS graph, and when, plays no part: a forger that leaves the graph at once, or one that names
itself like the driver, still cannot sign.

A new session is a new run of the driver (it restarted): admitted when its report is fresh and
signed; the run it replaces is retired for good, so its reports cannot be replayed later.
"""

from dataclasses import dataclass
from typing import Optional

from feeder_common import auth

NS = 1_000_000_000
RETIRED_SESSIONS = 64       # ended runs remembered (a report of one is refused)


@dataclass(frozen=True)
class Admission:
    """
    The gate's answer: admitted or not (``reason``), and whether a new run began.

    ``authentic``: the report is signed by the driver (also when refused as stale, replayed
    or of an ended run): its session and seq are the driver's own.
    """

    admitted: bool
    reason: str = ''
    new_run: bool = False
    authentic: bool = False


class ReportGate:
    """Admits signed, fresh, in-order cycle reports of one driver (see module doc)."""

    def __init__(self, key, driver_node, max_age_s):
        self.key = key
        self.driver_node = driver_node
        self.max_age_ns = int(round(float(max_age_s) * NS))
        self.session = None
        self.high_seq = None
        self._retired = []
        self.counts = {'admitted': 0, 'unsigned': 0, 'bad_mac': 0, 'stale': 0,
                       'replayed': 0, 'ended_run': 0}

    def _refuse(self, kind, reason, authentic=False):
        self.counts[kind] += 1
        return Admission(False, reason, authentic=authentic)

    def _age_problem(self, stamp_ns, now_ns):
        if stamp_ns is None:
            return 'report without a sample stamp'
        age = now_ns - stamp_ns
        if age > self.max_age_ns:
            return (f'stale report: sampled {age / NS:.3f} s ago, more than max_report_age '
                    f'{self.max_age_ns / NS:g} s (a stalled monitor, a replay, or clocks '
                    'apart)')
        if age < -self.max_age_ns:
            return (f'report stamped {-age / NS:.3f} s in the future (clocks apart by more '
                    f'than max_report_age {self.max_age_ns / NS:g} s)')
        return None

    def _authentic(self, label, fields, tag):
        """None if ``tag`` signs ``fields``; else (count kind, reason)."""
        if not tag:
            return 'unsigned', 'unsigned report (no mac): not from a driver that holds the key'
        if not auth.mac_ok(self.key, label, fields, tag):
            return 'bad_mac', (f'report with a bad MAC: not signed by {self.driver_node} under '
                               f"this monitor's key (key id {auth.key_id(self.key)}); the "
                               'driver and the monitor must share one key file')
        return None

    def admit(self, report, now_ns):
        """
        Judge ``report`` (feeder_common.messages.CycleStatus with ``session`` and ``mac``).

        Admitted reports advance the run's high-water seq; refused ones change nothing.
        """
        outcome = 'completed' if report.ok else 'failed'
        sensor = {True: '1', False: '0', None: 'none'}[report.sensor]
        fields = auth.cycle_fields(self.driver_node, report.session, report.seq,
                                   report.stamp_ns, outcome, sensor, report.reason,
                                   report.release_speed)
        bad = self._authentic(auth.CYCLE_LABEL, fields, report.mac)
        if bad:
            return self._refuse(*bad)
        problem = self._age_problem(report.stamp_ns, now_ns)
        if problem:
            return self._refuse('stale', problem, authentic=True)
        if report.session in self._retired:
            return self._refuse('ended_run', f'report of an ended driver run (session '
                                             f'{report.session}): a replay', authentic=True)
        new_run = report.session != self.session
        if not new_run and self.high_seq is not None and report.seq <= self.high_seq:
            return self._refuse('replayed', f'replayed or duplicate report: seq {report.seq}, '
                                            f'reports up to {self.high_seq} already seen',
                                authentic=True)
        if new_run:
            if self.session is not None:
                self._retired.append(self.session)
                del self._retired[:-RETIRED_SESSIONS]
            self.session = report.session
        self.high_seq = report.seq
        self.counts['admitted'] += 1
        return Admission(True, new_run=new_run and len(self._retired) > 0, authentic=True)

    def fired_authentic(self, notice) -> Optional[str]:
        """None if a fired notice is signed by the driver; else why not (it still lowers)."""
        fields = auth.fired_fields(self.driver_node, notice.session, notice.seq,
                                   notice.stamp_ns)
        bad = self._authentic(auth.FIRED_LABEL, fields, notice.mac)
        return bad[1] if bad else None
