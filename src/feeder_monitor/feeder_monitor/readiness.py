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

Ready means proven now (issue 20). A verdict is never ready on an anomaly cycle, nor before a
full warm-up after one, nor while the checks are off (the first ``settle_cycles`` throws after a
full restart, start-up included), nor once a later cycle has fired
(:meth:`ReadinessMonitor.fired`).
The pattern checks are weak: a spurious detection where the limit set allows one passes them.
So a :class:`Prediction` follows the part: the orbit positions whose preceding sensor bits equal
the bits seen are the limit-set states consistent with them; a bit none of them shows is an
anomaly, and a detection is ready only if every one of them lies on the goal edge (and, while
the sensor is suspect after a sensor anomaly, even if up to two bits seen were wrong: a
missed detection followed by a spurious one reads like a normal gap). Requiring instead that
every consistent state *show* a detection would miss every ready on the triangle: its gaps
between detections vary from 12 to 22 throws whatever the bits before them.

With scene effects: a part lost off a finite arm (``finite_arm``) is never seen again, which
shows as a silence longer than the limit set allows. A noisy sensor (``sensor_noise``) makes a
detection likely, not certain, to be on the goal edge (``Rules.p_goal``); its false positives
and negatives are in the detection patterns, because the rules read the orbit through the
scene's own (seeded) sensor model.

:class:`ReadinessMonitor` turns the cycles the node admits (feeder_monitor.trust) into
verdicts.
"""

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


# Flags of a bit history in a Prediction table: what the cycle after that history can show.
MAY_MISS = 1        # the sensor can read 0
MAY_SEE = 2         # the sensor can read 1
OFF_GOAL = 4        # the part can lie on another edge than the goal edge
# After a sensor anomaly (a bit the limit set cannot produce there) the sensor stays suspect
# this many judged cycles (about 9 detections of the triangle): a ready then needs the goal
# edge even if up to SUSPECT_FLIPS bits in the history were wrong. 150 and 2: the least of
# (0, 50, 80, 150, 500) x (1, 2) that gave no false ready at spurious = missed rate 0.05 over
# 8 seeds of 20,000 cycles (bench/readiness_faults.py; one flip left 1, 80 cycles left 3).
SUSPECT_CYCLES = 150
SUSPECT_FLIPS = 2
# A prediction whose histories prove at least this share of the orbit's detections needs that
# proof for every ready; below it, only while the sensor is suspect (scenes/experiment.yaml:
# its 8-bit histories prove none, so the rule would cost every ready of a sound sensor).
GOAL_SURE_SHARE = 0.9
HISTORY_CHOICES = (32, 28, 24, 20, 16, 12, 8, 6, 4, 3, 2, 1)   # longest first


@dataclass(frozen=True)
class Prediction:
    """
    What the limit set lets the next cycle show, given the sensor bits of the cycles before it.

    A table read off the limit-set orbit (the scene's own map, effects included; see
    :func:`build_prediction`): for every run of ``length`` <= ``history`` consecutive bits the
    orbit shows, the flags of the cycles that follow such a run: whether the sensor may read 0
    (MAY_MISS), may read 1 (MAY_SEE), and whether the part may then lie on another edge than the
    goal edge (OFF_GOAL). Following a part is then one dictionary look-up per cycle: the states
    of the orbit consistent with the bits seen so far are the orbit positions that follow the
    same bits, and a bit none of them shows is one the limit set cannot produce.

    It is sampled, like the detection patterns: the orbit holds ``orbit_throws`` states and
    ``history`` is the longest run of bits whose every continuation in the orbit's second half
    was already in its first half (:func:`choose_history`), so that a longer orbit would not
    have added cases.
    """

    history: int                # longest run of bits looked at
    tables: tuple               # tables[length]: {bits as an int, last at bit 0: flags}
    orbit_throws: int
    goal_sure_share: float = 0.0    # of the orbit's detections, those its history proves

    def flags(self, length, word):
        """Return the flags of the cycle after ``length`` bits ``word`` (None: not seen)."""
        return self.tables[length].get(word)

    def as_dict(self):
        return {'history': self.history, 'histories': sum(len(t) for t in self.tables),
                'goal_sure_share': round(self.goal_sure_share, 4)}


def _history_words(bits, segments, history):
    """
    Pack, for each cycle i, the ``history`` bits before it into an int (bit i-1 at bit 0).

    Also returns how many of them lie in i's own segment (no history spans a break).
    """
    b = np.asarray(bits, dtype=np.uint64)
    words = np.zeros(b.size, dtype=np.uint64)
    available = np.zeros(b.size, dtype=np.int64)
    for a, z in segments:
        available[a:z] = np.minimum(np.arange(z - a), history)
        for back in range(1, min(history, z - a - 1) + 1):
            words[a + back:z] |= b[a:z - back] << np.uint64(back - 1)
    return words, available


def _mask(length):
    return np.uint64((1 << length) - 1)


def _cycle_flags(bits, edges, goal_edge):
    return (np.where(bits, MAY_SEE, MAY_MISS) |
            np.where(np.asarray(edges) != goal_edge, OFF_GOAL, 0)).astype(np.int64)


def _table(words, available, flags, length):
    chosen = available >= length
    keys = words[chosen] & _mask(length)
    unique, inverse = np.unique(keys, return_inverse=True)
    merged = np.zeros(unique.size, dtype=np.int64)
    np.bitwise_or.at(merged, inverse, flags[chosen])
    return dict(zip(unique.tolist(), merged.tolist()))


def _clip_segments(segments, lo, hi):
    return tuple((max(a, lo), min(z, hi)) for a, z in segments if min(z, hi) > max(a, lo))


def choose_history(bits, edges, goal_edge, segments, choices=HISTORY_CHOICES):
    """
    Return the longest history (in ``choices``) the orbit samples completely, 0 if none.

    Read the table off the first half of the orbit and follow the second half: the history
    passes when no cycle there shows a bit the table excludes, nor lies off the goal edge where
    the table says it cannot. Too long a history has cases the orbit holds only once; those
    show as misses here, and in the monitor they would be false anomalies or, worse, false
    certainty about the edge.
    """
    bits = np.asarray(bits, dtype=bool)
    half = bits.size // 2
    flags = _cycle_flags(bits, edges, goal_edge)
    for history in choices:
        words, available = _history_words(bits, _clip_segments(segments, 0, half), history)
        table = _table(words[:half], available[:half], flags[:half], history)
        words, available = _history_words(bits, _clip_segments(segments, half, bits.size),
                                          history)
        test = np.flatnonzero(available[half:] >= history) + half
        if test.size == 0:
            continue
        known = np.array([table.get(w, 0) for w in (words[test] & _mask(history)).tolist()],
                         dtype=np.int64)
        seen = flags[test]
        bit_ok = (known & seen & (MAY_SEE | MAY_MISS)) != 0
        edge_ok = ((seen & OFF_GOAL) == 0) | ((known & OFF_GOAL) != 0)
        if bit_ok.all() and edge_ok.all():
            return history
    return 0


def build_prediction(bits, edges, goal_edge, segments=None, history=None):
    """
    Build the :class:`Prediction` of an orbit's sensor ``bits`` and ``edges``.

    None if no history passes :func:`choose_history`. ``segments``: the orbit's unbroken
    stretches.
    """
    bits = np.asarray(bits, dtype=bool)
    segments = tuple(segments) if segments else ((0, bits.size),)
    if history is None:
        history = choose_history(bits, edges, goal_edge, segments)
    if history <= 0:
        return None
    words, available = _history_words(bits, segments, history)
    flags = _cycle_flags(bits, edges, goal_edge)
    tables = tuple(_table(words, available, flags, length) for length in range(history + 1))
    # How often the bits before a detection already put every consistent state on the goal
    # edge (the triangle: all but a few; a part whose edges the bits do not tell: none).
    full = np.flatnonzero(bits & (available >= history))
    sure = [not tables[history][w] & OFF_GOAL for w in (words[full] & _mask(history)).tolist()]
    share = float(np.mean(sure)) if sure else 0.0
    return Prediction(int(history), tables, int(bits.size), share)


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
    prediction: Optional[Prediction] = None     # None: the pattern checks alone
    prediction_off: str = ''    # why there is no prediction

    def as_dict(self):
        return {'goal_edge': self.goal_edge, 'sensor_radius': self.sensor_radius,
                'guarantee_radius': self.guarantee_radius, 'provable': self.provable,
                'warmup_cycles': self.warmup_cycles, 'settle_cycles': self.settle_cycles,
                'max_run': self.max_run, 'min_gap': self.min_gap,
                'max_silence': self.max_silence, 'orbit_throws': self.pattern.throws,
                'orbit_detection_rate': round(self.pattern.rate, 6),
                'noisy_sensor': self.noisy_sensor, 'p_goal_given_detection': self.p_goal,
                'arm_length': self.arm_length,
                'prediction_history': self.prediction.history if self.prediction else None,
                'prediction_off': self.prediction_off}


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
    prediction, off = None, ''
    if noisy:
        # The orbit's bits hold the noise of one seeded run: a table of them would call most
        # other runs impossible. The pattern checks (read through the noise) stay.
        off = 'sensor_noise: the pattern checks alone'
    else:
        prediction = build_prediction(bits, orbit[0], int(sensor.goal_edge), segments)
        if prediction is None:
            off = 'the orbit samples no history completely: the pattern checks alone'
    return Rules(int(sensor.goal_edge), float(sensor.radius), float(sensor.guarantee_radius),
                 bool(sensor.feasible and sensor.radius > sensor.guarantee_radius), warmup,
                 proven, settle, pattern, max_run, min_gap, max_silence, noisy, p_goal, arm,
                 prediction, off)


@dataclass(frozen=True)
class Verdict:
    """The monitor's answer for one cycle (``ready`` is never true with state anomaly)."""

    seq: int
    ready: bool
    state: str
    anomaly: Optional[str] = None   # set on the cycle that revealed an anomaly
    note: str = ''                  # worth a word, not an anomaly (e.g. a late first seq)


@dataclass(frozen=True)
class Judgement:
    """
    Why a completed cycle was or was not ready (for benchmarks and diagnostics).

    ``conditions``: every rule but the prediction's held (a detection, provable sensor, warm-up
    and settling done, no anomaly, no later cycle fired). ``allowed``: the prediction lets the
    cycle show a detection; ``goal_sure``: every orbit state consistent with the bits before the
    cycle lies on the goal edge; ``expected``: every one of them shows a detection. Without a
    prediction (or before it applies) the three are None.
    """

    conditions: bool
    allowed: Optional[bool] = None
    goal_sure: Optional[bool] = None
    expected: Optional[bool] = None


class ReadinessMonitor:
    """
    State machine: warming up -> tracking <-> ready; anomaly on a broken premise.

    What a node calls, in cycle order: :meth:`fired` when a cycle starts (the held ready drops
    at once), then exactly one of :meth:`completed`, :meth:`failed` or :meth:`untrusted` for
    that cycle; :meth:`interrupt` when the premise breaks between cycles; :meth:`set_rules` for
    new rules. :attr:`ready_seq` is the seq whose ready still holds (None: publish false).

    Two restarts. A *full* one (start-up, a failed, missing, repeated or untrusted cycle, an
    interruption, new rules, a detection after an impossible silence): the part may be anywhere,
    so the warm-up and the settling (``settle_cycles`` throws with every check off, the basin's
    longest transient) start again. A *sensor* one (a bit the limit set cannot produce at that
    point: an impossible run, an early detection, a bit the prediction excludes, a disagreement
    of the two inputs): nothing moved the part, the bits are in doubt, so the warm-up and the
    prediction's history start again while the checks stay on. ``resettle_on_any_anomaly``
    makes every restart a full one (costlier; for comparison in bench/readiness_faults.py).

    A verdict is ready only when the cycle's sensor fired, the sensor is beyond the guarantee
    radius, ``warmup_cycles`` throws have been judged since the last anomaly, the checks are on
    (settled), the cycle revealed no anomaly, no later cycle has fired (:meth:`fired`), and,
    with a prediction, the detection is one the limit set allows after the bits seen and every
    state consistent with those bits lies on the goal edge.
    """

    def __init__(self, rules, resettle_on_any_anomaly=False, suspect_cycles=SUSPECT_CYCLES,
                 suspect_flips=SUSPECT_FLIPS):
        self.rules = rules
        self.suspect_flips = int(suspect_flips)
        self.resettle_on_any_anomaly = bool(resettle_on_any_anomaly)
        self.suspect_cycles = int(suspect_cycles)
        self.suspect_left = 0       # cycles the sensor stays suspect (after an anomaly)
        self.suspect_now = False    # the cycle being judged is one of them
        self.last_seq = None
        self.fired_seq = None       # highest seq reported fired
        self.ready_seq = None       # seq of the cycle whose ready still holds
        self.counts = {'cycles': 0, 'completed': 0, 'failed': 0, 'detections': 0, 'ready': 0,
                       'anomalies': 0, 'untrusted': 0, 'unexpected': 0, 'not_goal_sure': 0,
                       'superseded': 0}
        self.note = ''
        self.last_anomaly = None
        self.last_judgement = None
        self.state = WARMING_UP
        self._restart_all()

    # ----------------------------------------------------------------- restarts
    def _restart_all(self, need_clear=False):
        """Full restart: warm-up, settling, pattern counters and prediction history."""
        self.since_settle = 0       # completed throws since the last full restart
        self._restart_sensor(need_clear)

    def _restart_sensor(self, need_clear=False, keep_pattern=False):
        """Sensor restart: warm-up and prediction history (pattern counters unless kept)."""
        if self.resettle_on_any_anomaly:
            self.since_settle = 0
        self.since_restart = 0      # completed throws since the last anomaly (the warm-up)
        self.history_word = 0       # prediction: the bits since it applies, last at bit 0
        self.history_length = 0
        self.need_clear = need_clear  # after an impossible run: wait for a non-detection
        if not keep_pattern:
            self.run = 0            # current run of detections (after settling)
            self.gap = 0            # non-detections since the last detection (after settling)
            self.seen_detection = False  # a detection since settling
            self.silent = False

    # ----------------------------------------------------------------- inputs
    def fired(self, seq):
        """
        Take the news that cycle ``seq`` fired: the part moves, so no earlier ready holds.

        Returns :attr:`ready_seq` afterwards (None: the node publishes false at once). A verdict
        on a cycle before ``seq`` that arrives later is never ready (it would be stale).
        """
        seq = int(seq)
        if self.fired_seq is None or seq > self.fired_seq:
            self.fired_seq = seq
        if self.ready_seq is not None and seq > self.ready_seq:
            self.ready_seq = None
        return self.ready_seq

    def interrupt(self, reason):
        """Restart the warm-up: the premise broke between cycles (the driver left or stopped)."""
        self._anomaly(self.last_seq, reason)
        self._restart_all()
        self.ready_seq = None
        self.state = ANOMALY

    def new_run(self, reason):
        """
        Take a new run of the driver (it restarted): an anomaly, and its seqs start afresh.

        Nothing of the old run's numbering carries over: neither the last seq judged nor the
        highest seq reported fired.
        """
        self.interrupt(reason)
        self.last_seq = None
        self.fired_seq = None

    def set_rules(self, rules):
        """Take new rules (e.g. the sensor moved): the warm-up starts again; no anomaly."""
        self.rules = rules
        self.new_part()

    def new_part(self):
        """Take a part put on the arm: warm-up and settling start again; no anomaly."""
        self._restart_all()
        self.ready_seq = None
        self.state = WARMING_UP

    @property
    def settled(self):
        """Whether the checks apply: more than ``settle_cycles`` throws since a full restart."""
        return self.since_settle > self.rules.settle_cycles

    @property
    def throws_to_go(self):
        """Completed throws still needed before a detection can be ready (warm-up, settling)."""
        r = self.rules
        return max(r.warmup_cycles - self.since_restart, r.settle_cycles + 1 - self.since_settle,
                   0)

    def _check_seq(self, seq):
        last, self.last_seq = self.last_seq, seq
        if last is None:
            if seq > 1:
                self.note = (f'first cycle seen is seq {seq}: cycles 1..{seq - 1} were not '
                             'seen (the monitor started after the driver); warming up')
            return None
        if seq == last + 1:
            return None
        if seq > last + 1:
            return f'missing cycles: seq jumped from {last} to {seq} ({seq - last - 1} missing)'
        return f'seq went back from {last} to {seq} (driver restarted?)'

    def _anomaly(self, seq, reason):
        self.counts['anomalies'] += 1
        self.last_anomaly = (seq, reason)
        return reason

    def untrusted(self, seq, reason):
        """
        Judge a cycle whose source is in doubt (another publisher on the driver's topics).

        An anomaly: no verdict can rest on it, the warm-up starts again, and its seq does not
        count (the driver's next cycle is then judged against the last trusted one).
        """
        self.counts['cycles'] += 1
        self.counts['untrusted'] += 1
        anomaly = self._anomaly(seq, f'cycle {seq} not trusted: {reason}')
        self._restart_all()
        self.ready_seq = None
        self.last_judgement = None
        self.state = ANOMALY
        return Verdict(seq, False, ANOMALY, anomaly)

    def failed(self, seq, reason):
        """Judge a fired cycle that failed: the part may be anywhere; warm up again."""
        self.counts['cycles'] += 1
        self.counts['failed'] += 1
        gap = self._check_seq(seq)
        text = f'cycle {seq} failed: {reason}' + (f'; {gap}' if gap else '')
        anomaly = self._anomaly(seq, text)
        self._restart_all()
        self.ready_seq = None
        self.last_judgement = None
        self.state = ANOMALY
        return Verdict(seq, False, ANOMALY, anomaly)

    def completed(self, seq, detected, note=''):
        """Judge a completed cycle with sensor bit ``detected``: goal edge proven or not."""
        detected = bool(detected)
        self.counts['cycles'] += 1
        self.counts['completed'] += 1
        if detected:
            self.counts['detections'] += 1
        self.ready_seq = None
        self.last_judgement = None
        anomaly = None
        # This cycle is judged as suspect if it is one of the suspect_cycles after an anomaly.
        self.suspect_now = self.suspect_left > 0
        if self.settled:
            # While the checks are off nothing would show a flaky sensor: the suspicion waits.
            self.suspect_left = max(self.suspect_left - 1, 0)
        gap = self._check_seq(seq)
        if gap:
            # Throws the monitor did not see: for it, the part may be anywhere.
            anomaly = self._anomaly(seq, gap)
            self._restart_all()
        if note == 'sensor disagreement':
            anomaly = self._anomaly(seq, 'proximity and cycle_status disagree on the sensor bit')
            self._restart_sensor(need_clear=detected)
            self.suspect_left = self.suspect_cycles
            return self._verdict(seq, False, anomaly)
        if self.need_clear:
            if detected:                # the impossible run goes on
                return self._verdict(seq, False, anomaly)
            self.need_clear = False     # this throw is the first of the new warm-up
        self.since_restart += 1
        self.since_settle += 1
        allowed = goal_sure = expected = None
        if self.settled:
            found = self._check_pattern(detected)
            if found:
                anomaly = self._anomaly(seq, found)
                self.suspect_left = self.suspect_cycles
                if detected and not self.silent:    # impossible detection pattern
                    self._restart_sensor(need_clear=True)
                    return self._verdict(seq, False, anomaly)
        if detected and self.silent:
            # First detection after a silence the limit set cannot produce: the part may have
            # been removed and put back anywhere; this detection starts a new warm-up.
            self._restart_all()
            self.since_restart = self.since_settle = 1
            return self._verdict(seq, False, anomaly)
        if self.settled and self.rules.prediction is not None and not self.silent:
            unexpected, allowed, goal_sure, expected = self._predict(detected)
            if unexpected and anomaly is None:
                anomaly = self._anomaly(seq, unexpected)
                self.counts['unexpected'] += 1
                self.suspect_left = self.suspect_cycles
        r = self.rules
        conditions = bool(detected and r.provable and anomaly is None and
                          self.since_restart >= r.warmup_cycles and self.settled)
        superseded = self.fired_seq is not None and self.fired_seq > seq
        ready = conditions and not superseded and goal_sure is not False
        if conditions and goal_sure is False:
            self.counts['not_goal_sure'] += 1
        if conditions and superseded and goal_sure is not False:
            self.counts['superseded'] += 1
        self.last_judgement = Judgement(conditions and not superseded, allowed, goal_sure,
                                        expected)
        return self._verdict(seq, ready, anomaly)

    def _predict(self, detected):
        """
        Follow the part with the prediction one cycle.

        Returns (anomaly text or None, allowed, goal_sure, expected) and moves the history on
        (or restarts it after an anomaly).
        """
        pred = self.rules.prediction
        flags = pred.flags(self.history_length, self.history_word)
        flags = 0 if flags is None else flags
        allowed = bool(flags & MAY_SEE)
        goal_sure = not flags & OFF_GOAL
        expected = not flags & MAY_MISS
        if not flags & (MAY_SEE if detected else MAY_MISS):
            what = 'a detection' if detected else 'no detection'
            reason = (f'{what} where the limit set cannot show one after the last '
                      f'{self.history_length} sensor bits')
            # A spurious detection must not spoil the run and gap rules for the next real one;
            # a missed detection leaves them counting (the silence rule keeps watching).
            self._restart_sensor(keep_pattern=not detected)
            return reason, allowed, goal_sure, expected
        if detected and goal_sure and self.suspect_now:
            goal_sure = self._goal_sure_despite_faults(pred)
        elif detected and not goal_sure and not self.suspect_now and \
                pred.goal_sure_share < GOAL_SURE_SHARE:
            # The bits seldom tell this part's edge before a detection: while the sensor has
            # shown no fault, a detection the limit set allows is proof enough (the guarantee
            # radius: no limit-set state off the goal edge reaches the sensor).
            goal_sure = None
        self.history_word = ((self.history_word << 1) | int(detected)) & ((1 << pred.history) - 1)
        self.history_length = min(self.history_length + 1, pred.history)
        return None, allowed, goal_sure, expected

    def _goal_sure_despite_faults(self, pred):
        """
        Tell whether the part is on the goal edge even if ``suspect_flips`` bits seen were wrong.

        A missed detection hides the part's flip off the goal edge; a spurious detection a few
        cycles later then reads exactly like the next real one (the limit set's gaps vary by 10
        cycles), and would be a false ready. A spurious detection in the history, taken for
        the last real one, shifts the phase the same way. So every history the orbit shows
        that differs from the one seen in at most ``suspect_flips`` bits must put the part on
        the goal edge too.
        """
        length, word = self.history_length, self.history_word
        variants = [word]
        for _ in range(self.suspect_flips):
            variants = {v ^ (1 << back) for v in variants for back in range(length)}
            for variant in variants:
                flags = pred.flags(length, variant)
                if flags is not None and flags & OFF_GOAL:
                    return False
        return True

    def _check_pattern(self, detected):
        """Update run/gap after settling; the reason if the limit set cannot produce them."""
        r = self.rules
        if detected:
            reason = None
            # min_gap is the fewest non-detections between two runs: it judges the first
            # detection of a run (the run rule judges the ones after it).
            if self.run == 0 and self.seen_detection and r.min_gap is not None and \
                    self.gap < r.min_gap:
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
        """Make the verdict; the one place where state and ready are tied together."""
        note, self.note = self.note, ''
        if anomaly or self.need_clear or self.silent:
            state = ANOMALY
        elif self.since_restart < self.rules.warmup_cycles or not self.settled:
            state = WARMING_UP
        else:
            state = READY if ready else TRACKING
        ready = state == READY
        if ready:
            self.counts['ready'] += 1
            self.ready_seq = seq
        self.state = state
        return Verdict(seq, ready, state, anomaly, note)
