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
A flaky feeder against ReadinessMonitor, with the throw map as the truth (ROS-free).

Test support (test_monitor_readiness_faults.py) and bench/readiness_faults.py. The part is
thrown by the scene's own map from the scene's start; each cycle the true bit is the geometric
sensor bit at the analysis's sensor. The monitor sees that bit with faults drawn from a seeded
generator: a spurious detection (0 read as 1) and a missed one (1 read as 0), each at its
rate, and seq jumps (the part thrown unseen) and seqs that go back. Counted against the truth:

* false readies: ready while the part is not on the goal edge (the issue's definition);
* spurious readies: ready while the true bit is 0 (the part on the goal edge but not under
  the sensor; not false by that definition, counted to show what the rules let through);
* missed readies: a true detection on the goal edge, read as one, not ready (after the first
  ``settle_cycles`` cycles, which no rule may use).
"""

from dataclasses import dataclass, field
import time

from feeder_monitor.readiness import ANOMALY, ReadinessMonitor
import numpy as np
from throwmap import sees


@dataclass
class FaultRun:
    """Counts of one run (see the module docstring)."""

    cycles: int = 0
    true_detections: int = 0        # on the goal edge, read as detections, after settling
    readies: int = 0
    false_readies: int = 0
    spurious_readies: int = 0
    missed_readies: int = 0
    anomalies: int = 0
    anomaly_and_ready: int = 0      # verdicts with both (must stay 0)
    faults: dict = field(default_factory=lambda: dict.fromkeys(
        ('spurious', 'missed', 'jumps', 'backs'), 0))
    # What two other ready rules would have given on the same run (see Judgement).
    alt: dict = field(default_factory=lambda: {
        'allowed': {'readies': 0, 'false': 0, 'spurious': 0, 'missed': 0},
        'expected': {'readies': 0, 'false': 0, 'spurious': 0, 'missed': 0}})
    seconds_per_cycle: float = 0.0

    def line(self):
        miss = self.missed_readies / self.true_detections if self.true_detections else 0.0
        return (f'{self.cycles} cycles: readies {self.readies}, false {self.false_readies}, '
                f'spurious {self.spurious_readies}, missed {self.missed_readies}/'
                f'{self.true_detections} ({100 * miss:.1f} %), anomalies {self.anomalies}, '
                f'{1e6 * self.seconds_per_cycle:.1f} us/cycle')


def truth_orbit(scene, start, throws):
    """(edges, radii) of ``throws`` throws of the scene's own map from ``start``."""
    edges, radii, _ = scene.model.orbit_arrays(*start, throws)
    return np.asarray(edges[1:]), np.asarray(radii[1:])


def run_faults(scene, rules, cycles, spurious=0.0, missed=0.0, jumps=0.0, backs=0.0, seed=0,
               start=None, truth=None, resettle_on_any_anomaly=False):
    """
    Feed ``cycles`` faulty cycles of the scene's part to a new ReadinessMonitor.

    Faults at the given rates; counted against the truth (:class:`FaultRun`). ``truth``: a
    precomputed (edges, radii) from :func:`truth_orbit`, long enough for the jumps.
    """
    rng = np.random.default_rng(seed)
    if truth is None:
        truth = truth_orbit(scene, start or scene.default_start(), int(cycles * 1.2) + 100)
    edges, radii = truth
    bits = np.asarray(sees(scene.part, edges, radii, rules.sensor_radius, 0.0), dtype=bool)
    monitor = ReadinessMonitor(rules, resettle_on_any_anomaly=resettle_on_any_anomaly)
    out = FaultRun()
    seq, k = 0, -1          # k: index of the part's true state after this cycle's throw
    busy = 0.0
    for cycle in range(cycles):
        draw = rng.random(4)
        if draw[2] < jumps:
            step = int(rng.integers(2, 40))
            seq += step
            k += step           # the part was thrown in the cycles nobody saw
            out.faults['jumps'] += 1
        elif draw[3] < backs and seq > 1:
            seq = int(rng.integers(0, seq))
            k += 1
            out.faults['backs'] += 1
        else:
            seq += 1
            k += 1
        if k >= edges.size:
            break
        true_bit, on_goal = bool(bits[k]), int(edges[k]) == rules.goal_edge
        seen = true_bit
        if true_bit and draw[1] < missed:
            seen = False
            out.faults['missed'] += 1
        elif not true_bit and draw[0] < spurious:
            seen = True
            out.faults['spurious'] += 1
        t0 = time.perf_counter()
        verdict = monitor.completed(seq, seen)
        busy += time.perf_counter() - t0
        out.cycles += 1
        out.anomalies += verdict.anomaly is not None
        out.anomaly_and_ready += verdict.ready and (
            verdict.state == ANOMALY or verdict.anomaly is not None)
        counted = cycle >= rules.settle_cycles and true_bit and seen and on_goal
        out.true_detections += counted
        if verdict.ready:
            out.readies += 1
            out.false_readies += not on_goal
            out.spurious_readies += not true_bit
        elif counted:
            out.missed_readies += 1
        judged = monitor.last_judgement
        for name in ('allowed', 'expected'):
            alt = out.alt[name]
            ok = bool(judged and judged.conditions and
                      (getattr(judged, name) is not False))
            alt['readies'] += ok
            alt['false'] += ok and not on_goal
            alt['spurious'] += ok and not true_bit
            alt['missed'] += counted and not ok
    out.seconds_per_cycle = busy / max(out.cycles, 1)
    return out
