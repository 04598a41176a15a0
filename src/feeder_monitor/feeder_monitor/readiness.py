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
When a one-bit detection proves that the part lies on the goal edge (ROS-free).

The argument (paper section V.B, computed by throwmap): once the part has been thrown
``warmup`` times from any start of the analysis grid, the sensor at a radius beyond the
guarantee radius can only see it on the goal edge. So a detection after the warm-up proves the
goal edge, provided the model describes the feeder. The monitor checks that premise on the fly:
a long orbit in the limit set fixes which detection patterns can occur (longest run of
detections, shortest and longest stretch without one); anything else, a failed cycle or a gap in
the cycle numbers is an anomaly, after which the warm-up starts again.

With scene effects: a part lost off a finite arm (``finite_arm``) is never seen again, which
shows as a silence longer than the limit set allows. A noisy sensor (``sensor_noise``) makes a
detection likely, not certain, to be on the goal edge (``Rules.p_goal``); its false positives
and negatives are in the detection patterns, because the rules read the orbit through the
scene's own (seeded) sensor model.

:class:`CyclePairer` joins the two inputs of a cycle (``proximity`` and ``cycle_status``, matched
by their sample stamps) into one :class:`Cycle`; :class:`ReadinessMonitor` turns cycles into
verdicts.
"""

from collections import deque
from dataclasses import dataclass
import math
from typing import Optional

import numpy as np
from throwmap import PartOnArm

WARMING_UP = 'warming up'
TRACKING = 'tracking'
READY = 'ready'
ANOMALY = 'anomaly'


@dataclass(frozen=True)
class DetectionPattern:
    """Statistics of a bit sequence: runs of detections and the stretches between them."""

    throws: int
    detections: int
    max_run: int                # most consecutive detections (0 if none)
    min_gap: Optional[int]      # fewest non-detections between two detections
    max_gap: Optional[int]      # most non-detections between two detections

    @property
    def rate(self):
        return self.detections / self.throws if self.throws else 0.0


def detection_pattern(bits):
    """Compute the DetectionPattern of sensor bits (gaps count only between detections)."""
    b = np.asarray(bits, dtype=bool)
    if not b.any():
        return DetectionPattern(int(b.size), 0, 0, None, None)
    # Run boundaries: +1 where a run of detections starts, -1 after it ends.
    edges = np.diff(np.concatenate(([0], b.astype(np.int8), [0])))
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1)
    runs = ends - starts
    gaps = starts[1:] - ends[:-1]
    return DetectionPattern(int(b.size), int(b.sum()), int(runs.max()),
                            int(gaps.min()) if gaps.size else None,
                            int(gaps.max()) if gaps.size else None)


def combine_patterns(patterns):
    """Combine the DetectionPatterns of separate bit sequences (no run or gap spans two)."""
    def pick(fn, values):
        values = [v for v in values if v is not None]
        return fn(values) if values else None

    patterns = list(patterns)
    return DetectionPattern(sum(p.throws for p in patterns),
                            sum(p.detections for p in patterns),
                            max((p.max_run for p in patterns), default=0),
                            pick(min, [p.min_gap for p in patterns]),
                            pick(max, [p.max_gap for p in patterns]))


@dataclass(frozen=True)
class Rules:
    """What the limit set allows, at one sensor placement (see :func:`rules_from_analysis`)."""

    goal_edge: int
    sensor_radius: float
    guarantee_radius: float
    provable: bool              # sensor beyond the guarantee radius
    warmup_cycles: int          # completed throws before a detection proves the goal edge
    proven_warmup: int          # the analysis's warm-up at this radius (warmup_cycles >= it)
    settle_cycles: int          # throws before the pattern checks apply (orbit in the set)
    pattern: DetectionPattern   # of the long limit-set orbit
    max_run: Optional[int]      # allowed consecutive detections (None: no check)
    min_gap: Optional[int]      # allowed fewest non-detections between detections
    max_silence: Optional[int]  # allowed non-detections in a row (None: no check)
    noisy_sensor: bool = False  # sensor_noise: a detection is evidence, not proof
    p_goal: Optional[float] = None  # P(goal edge | detection) of a noisy sensor (analysis)
    arm_length: Optional[float] = None  # finite_arm: the part can be lost off the end

    def as_dict(self):
        return {'goal_edge': self.goal_edge, 'sensor_radius': self.sensor_radius,
                'guarantee_radius': self.guarantee_radius, 'provable': self.provable,
                'warmup_cycles': self.warmup_cycles, 'settle_cycles': self.settle_cycles,
                'max_run': self.max_run, 'min_gap': self.min_gap,
                'max_silence': self.max_silence, 'orbit_throws': self.pattern.throws,
                'orbit_detection_rate': round(self.pattern.rate, 6),
                'noisy_sensor': self.noisy_sensor, 'p_goal_given_detection': self.p_goal,
                'arm_length': self.arm_length}


def limit_set_orbit(scene, analysis, throws, attempts=20):
    """
    Continue the analysis's limit-set orbit by ``throws`` throws (throwmap.PartOnArm.orbit).

    With scene effects an orbit may end early: the part is lost off a finite arm, or a noisy
    throw leaves the domain of f. The states before that are kept as one segment and, when the
    map is random (release_noise), the orbit starts again from the limit set's last state, up
    to ``attempts`` times. Random maps draw from the scene's seed, so the result is the same on
    every call.
    """
    ls = analysis.limit_set
    part = PartOnArm(scene, seed=scene.seed if scene.stochastic else None)
    return part.orbit(throws, start=(int(ls.tail_edges[-1]), float(ls.tail_radii[-1])),
                      attempts=attempts)


def orbit_readings(scene, orbit, radius, footprint):
    """
    Sensor bits along ``orbit`` at ``radius``: the scene's sensor model, noise included.

    A noisy sensor (sensor_noise) draws from the scene's seed, so the bits are the same on
    every call; otherwise the bits are the geometric ones.
    """
    part = PartOnArm(scene, sensor_radius=radius, footprint=footprint,
                     seed=scene.seed if scene.noisy_sensor else None)
    return part.readings(orbit[0], orbit[1])


def settle_throws(analysis):
    """Count the throws any grid start reaching the analysed limit set needs to stay in it."""
    bas = analysis.basin
    same = np.array([s == analysis.limit_set.signature for s in bas.signatures], dtype=bool)
    t = bas.transients[same & (bas.transients >= 0)]
    return int(t.max()) if t.size else 0


def rules_from_analysis(scene, analysis, orbit, warmup_cycles=-1, settle_cycles=-1,
                        silence_margin=1.5, early_margin=2, run_margin=0):
    """
    Derive the rules at the analysis's sensor (``analysis.sensor``; throwmap.scene_analysis).

    ``orbit``: the limit set's states (:func:`limit_set_orbit`). ``warmup_cycles`` and
    ``settle_cycles`` < 0 take the analysis's values. Margins: a silence may last
    ``silence_margin`` x the longest one in the orbit; a detection may come ``early_margin``
    cycles sooner than the orbit's shortest gap; a run may be ``run_margin`` longer.
    """
    sensor = analysis.sensor
    bits = orbit_readings(scene, orbit, sensor.radius, sensor.footprint)
    segments = getattr(orbit, 'segments', None) or ((0, len(bits)),)
    pattern = combine_patterns(detection_pattern(bits[a:b]) for a, b in segments)
    proven = int(sensor.warmup_throws)
    warmup = proven if warmup_cycles < 0 else int(warmup_cycles)
    if warmup < proven:
        raise ValueError(f'warmup_cycles = {warmup} is below the proven warm-up of {proven} '
                         f'throws at sensor radius {sensor.radius:.4f} m')
    settle = settle_throws(analysis) if settle_cycles < 0 else int(settle_cycles)
    max_run = pattern.max_run + int(run_margin) if pattern.detections else None
    min_gap = max(pattern.min_gap - int(early_margin), 0) if pattern.min_gap is not None \
        else None
    max_silence = int(math.ceil(pattern.max_gap * float(silence_margin))) \
        if pattern.max_gap is not None else None
    noisy = scene.noisy_sensor
    p_goal = None
    stoch = (analysis.stochastic or {}).get('sensor') if noisy else None
    if stoch and math.isclose(stoch['radius'], sensor.radius, rel_tol=0, abs_tol=1e-9):
        p_goal = float(stoch['p_goal'])
    arm = scene.arm_length if scene.arm_length is not None and \
        math.isfinite(scene.arm_length) else None
    return Rules(int(sensor.goal_edge), float(sensor.radius), float(sensor.guarantee_radius),
                 bool(sensor.feasible and sensor.radius > sensor.guarantee_radius), warmup,
                 proven, settle, pattern, max_run, min_gap, max_silence, noisy, p_goal, arm)


@dataclass(frozen=True)
class Cycle:
    """One fired cycle as the monitor sees it (a completed one has a sensor bit)."""

    seq: int
    completed: bool
    detected: Optional[bool] = None
    reason: str = ''            # failure reason of a failed cycle
    note: str = ''              # '', 'proximity lost' or 'sensor disagreement'


@dataclass(frozen=True)
class Verdict:
    """The monitor's answer for one cycle."""

    seq: int
    ready: bool
    state: str
    anomaly: Optional[str] = None   # set on the cycle that revealed an anomaly


class ReadinessMonitor:
    """State machine: warming up -> tracking <-> ready; anomaly on a broken premise."""

    def __init__(self, rules):
        self.rules = rules
        self.last_seq = None
        self.counts = {'cycles': 0, 'completed': 0, 'failed': 0, 'detections': 0, 'ready': 0,
                       'anomalies': 0}
        self.last_anomaly = None
        self.state = WARMING_UP
        self._restart()

    def _restart(self, need_clear=False):
        self.since_restart = 0      # completed throws since (re)start
        self.run = 0                # current run of detections (after settling)
        self.gap = 0                # non-detections since the last detection (after settling)
        self.seen_detection = False  # a detection since settling
        self.need_clear = need_clear  # after an impossible run: wait for a non-detection
        self.silent = False

    def set_rules(self, rules):
        """Take new rules (e.g. the sensor moved): the warm-up starts again; no anomaly."""
        self.rules = rules
        self._restart()
        self.state = WARMING_UP

    @property
    def settled(self):
        return self.since_restart > self.rules.settle_cycles

    def _check_seq(self, seq):
        last, self.last_seq = self.last_seq, seq
        if last is None or seq == last + 1:
            return None
        if seq > last + 1:
            return f'missing cycles: seq jumped from {last} to {seq} ({seq - last - 1} missing)'
        return f'seq went back from {last} to {seq} (driver restarted?)'

    def _anomaly(self, seq, reason):
        self.counts['anomalies'] += 1
        self.last_anomaly = (seq, reason)
        return reason

    def failed(self, seq, reason):
        """Judge a fired cycle that failed: the part may be anywhere; warm up again."""
        self.counts['cycles'] += 1
        self.counts['failed'] += 1
        gap = self._check_seq(seq)
        text = f'cycle {seq} failed: {reason}' + (f'; {gap}' if gap else '')
        anomaly = self._anomaly(seq, text)
        self._restart()
        self.state = ANOMALY
        return Verdict(seq, False, ANOMALY, anomaly)

    def completed(self, seq, detected, note=''):
        """Judge a completed cycle with sensor bit ``detected``: goal edge proven or not."""
        self.counts['cycles'] += 1
        self.counts['completed'] += 1
        if detected:
            self.counts['detections'] += 1
        anomaly = None
        gap = self._check_seq(seq)
        if gap:
            anomaly = self._anomaly(seq, gap)
            self._restart()
        if note == 'sensor disagreement':
            anomaly = self._anomaly(seq, 'proximity and cycle_status disagree on the sensor bit')
            self._restart(need_clear=bool(detected))
            return self._verdict(seq, False, anomaly)
        if self.need_clear:
            if detected:                # the impossible run goes on
                return self._verdict(seq, False, anomaly)
            self.need_clear = False     # this throw is the first of the new warm-up
        self.since_restart += 1
        if self.settled:
            found = self._check_pattern(detected)
            if found:
                anomaly = self._anomaly(seq, found)
                if detected and not self.silent:    # impossible detection pattern
                    self._restart(need_clear=True)
                    return self._verdict(seq, False, anomaly)
        if detected and self.silent:
            # First detection after a silence the limit set cannot produce: the part may have
            # been removed and put back anywhere; this detection starts a new warm-up.
            self._restart()
            self.since_restart = 1
            return self._verdict(seq, False, anomaly)
        r = self.rules
        ready = bool(detected and r.provable and self.since_restart >= r.warmup_cycles)
        if ready:
            self.counts['ready'] += 1
        return self._verdict(seq, ready, anomaly)

    def _check_pattern(self, detected):
        """Update run/gap after settling; the reason if the limit set cannot produce them."""
        r = self.rules
        if detected:
            reason = None
            if self.seen_detection and r.min_gap is not None and self.gap < r.min_gap:
                reason = (f'detection after only {self.gap} cycles without one; the limit set '
                          f'needs at least {r.min_gap}')
            self.run += 1
            if r.max_run is not None and self.run > r.max_run:
                reason = (f'{self.run} consecutive detections; the limit set allows at most '
                          f'{r.max_run}')
            self.seen_detection = True
            self.gap = 0
            return reason
        self.run = 0
        self.gap += 1
        if r.max_silence is not None and self.gap > r.max_silence and not self.silent:
            self.silent = True
            hint = "; the part may have fallen off the arm's end" if r.arm_length else ''
            return (f'no detection for {self.gap} cycles; the limit set allows at most '
                    f'{r.max_silence}{hint}')
        return None

    def _verdict(self, seq, ready, anomaly):
        if anomaly or self.need_clear or self.silent:
            state = ANOMALY
        elif self.since_restart < self.rules.warmup_cycles:
            state = WARMING_UP
        else:
            state = READY if ready else TRACKING
        self.state = state
        return Verdict(seq, ready, state, anomaly)


@dataclass
class _Status:
    seq: int
    ok: bool
    detected: Optional[bool]
    stamp: Optional[float]
    reason: str
    arrival: float


class CyclePairer:
    """
    Joins ``proximity`` and ``cycle_status`` of each cycle, in cycle order.

    ``cycle_status`` says that a cycle happened (and its seq); ``proximity`` carries the bit.
    They are matched by sample stamp (within ``tolerance`` s; FIFO when a status has no stamp).
    A completed status whose proximity does not come (a newer one arrives first, or ``timeout``
    s pass) is decided on the status's own bit (note ``proximity lost``); a proximity whose
    status never comes is dropped (``orphans``): the seq gap tells the monitor.
    """

    def __init__(self, tolerance=1e-3, timeout=0.5):
        self.tolerance = float(tolerance)
        self.timeout = float(timeout)
        self._statuses = deque()
        self._proximities = deque()     # (stamp, detected, arrival)
        self.counts = {'proximity_lost': 0, 'orphans': 0, 'disagreements': 0}

    def add_proximity(self, stamp, detected, now):
        self._proximities.append((float(stamp), bool(detected), float(now)))
        return self._drain(now)

    def add_status(self, seq, ok, detected, stamp, reason, now):
        self._statuses.append(_Status(int(seq), bool(ok), detected,
                                      None if stamp is None else float(stamp), str(reason),
                                      float(now)))
        return self._drain(now)

    def expire(self, now):
        """Decide statuses that waited too long; drop proximities nobody claimed."""
        out = self._drain(now)
        if not self._statuses:
            while self._proximities and now - self._proximities[0][2] > self.timeout:
                self._proximities.popleft()
                self.counts['orphans'] += 1
        return out

    @property
    def pending(self):
        return len(self._statuses), len(self._proximities)

    def _drain(self, now):
        out = []
        while self._statuses:
            st = self._statuses[0]
            if not st.ok:
                self._statuses.popleft()
                out.append(Cycle(st.seq, False, None, st.reason))
                continue
            prox = self._match(st)
            if prox is not None:
                self._statuses.popleft()
                self._proximities.popleft()
                note = ''
                if st.detected is not None and st.detected != prox[1]:
                    note = 'sensor disagreement'
                    self.counts['disagreements'] += 1
                out.append(Cycle(st.seq, True, prox[1], '', note))
                continue
            newer = bool(self._proximities)     # _match dropped every older one
            if (newer or now - st.arrival > self.timeout) and st.detected is not None:
                self._statuses.popleft()
                self.counts['proximity_lost'] += 1
                out.append(Cycle(st.seq, True, st.detected, '', 'proximity lost'))
                continue
            if newer or now - st.arrival > self.timeout:
                # Neither a bit in the status nor a proximity: report it as a failed cycle.
                self._statuses.popleft()
                out.append(Cycle(st.seq, False, None, 'no sensor bit for a completed cycle'))
                continue
            break
        return out

    def _match(self, st):
        """Find the proximity of status ``st`` (dropping older unclaimed ones), or None."""
        if st.stamp is None:
            return self._proximities[0] if self._proximities else None
        while self._proximities and self._proximities[0][0] < st.stamp - self.tolerance:
            self._proximities.popleft()
            self.counts['orphans'] += 1
        if self._proximities and abs(self._proximities[0][0] - st.stamp) <= self.tolerance:
            return self._proximities[0]
        return None
