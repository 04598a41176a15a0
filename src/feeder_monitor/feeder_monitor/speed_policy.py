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
Readiness under a speed policy (issue 25): each cycle's release speed chosen from the bits seen.

With a policy file (``throwmap funnel ... --out DIR``; docs/funnel.md) the fixed design's proof
(the warm-up and the limit set's patterns) no longer holds: the speeds change. The proof is the
policy's own: a detection is a ready only when every cell of the knowledge (the cells
consistent with the speeds thrown, the bits read and the error bound) is on the goal edge
(throwmap.funnel.Tracker). :class:`PolicyReadiness` keeps the monitor's cycle bookkeeping
(seq order, failed, missing and untrusted cycles, interruptions, superseded readies) and
replaces the judgement of a completed cycle, and chooses the next cycle's speed. ROS-free.

The knowledge is updated with the speed the driver says (signed) it fired the cycle at, not
the one chosen: a cycle fired at another speed (the fixed speed of a controller that cannot
set one, a stale setpoint) is followed with that speed's map, or, when the policy has none,
by forgetting every cell the bit does not allow. Whatever breaks the premise (a failed, missing
or untrusted cycle, an interruption) forgets where the part is: every cell. A new part starts
from the policy's start set.
"""

import math

from throwmap.funnel import read_policy, Tracker

from .readiness import ANOMALY, ReadinessMonitor, READY, TRACKING, Verdict


def load_tracker(path, rules, scene):
    """
    Return a Tracker of the policy file at ``path``, checked against the monitor's scene.

    throwmap.InputError (a ValueError) naming the fault: a bad file, a policy made for
    another goal edge, sensor radius, arm offset or release speed than the monitor's, or a
    noisy sensor (the policy's proof takes every bit as true).
    """
    policy = read_policy(path)
    tracker = Tracker(policy)
    s = tracker.system
    where = f'speed_policy {path}'
    problems = []
    if s.goal_edge != rules.goal_edge:
        problems.append(f"goal edge {s.goal_edge}, the monitor's is {rules.goal_edge}")
    if not math.isclose(s.sensor_radius, rules.sensor_radius, abs_tol=1e-6):
        problems.append(f"sensor at {s.sensor_radius:.6f} m, the monitor's at "
                        f'{rules.sensor_radius:.6f} m (sensor_radius)')
    if not math.isclose(s.h, scene.h, abs_tol=1e-9):
        problems.append(f"arm offset h {s.h:.6g} m, the scene's {scene.h:.6g} m")
    if not math.isclose(tracker.home_speed, scene.release_speed, rel_tol=1e-9):
        problems.append(f"home speed {tracker.home_speed:.6g} rad/s, the scene's "
                        f'{scene.release_speed:.6g} rad/s')
    if rules.noisy_sensor:
        raise ValueError(f"{where}: the scene's sensor is noisy (sensor_noise), and the "
                         "policy's proof takes every bit as true; run the fixed design's rules "
                         "(speed_policy '') or a scene with an exact sensor")
    if problems:
        raise ValueError(f'{where} was made for another feeder: ' + '; '.join(problems) +
                         f'; write it again with throwmap funnel {scene.source} --speeds '
                         'A:B:STEP --out DIR (and the same sensor)')
    return tracker


class PolicyReadiness(ReadinessMonitor):
    """ReadinessMonitor whose completed cycles are judged by a speed policy's knowledge."""

    def __init__(self, rules, tracker):
        self.tracker = tracker
        self.next_speed = None
        self.result = ''            # the Tracker's word on the last completed cycle
        super().__init__(rules)
        self.counts.update(policy_anomalies=0, unknown_speed=0, no_safe_speed=0,
                           fixed_speed_cycles=0)
        self.choose()

    # ------------------------------------------------------------------ knowledge
    def _restart_all(self, need_clear=False):
        super()._restart_all(need_clear)
        if hasattr(self, 'tracker'):
            self.tracker.forget()

    def set_rules(self, rules):
        """Take new rules: where the part is stays unknown until it is proven again."""
        self.rules = rules
        self._restart_all()
        self.ready_seq = None
        self.state = TRACKING
        self.choose()

    @property
    def knowledge_cells(self):
        """Return how many cells the part may be in."""
        return int(self.tracker.know.sum())

    def new_part(self):
        super().new_part()
        self.tracker.new_part()
        self.state = TRACKING
        self.choose()

    def choose(self):
        """
        Choose the next cycle's release speed (rad/s) from the knowledge; :attr:`next_speed`.

        When no speed is safe for every cell of the knowledge (after a forgetting, cells near
        the arm's end), the scene's own speed, whose design keeps the part on the arm from its
        invariant set (counted: ``no_safe_speed``).
        """
        speed = self.tracker.speed()
        if speed is None:
            self.counts['no_safe_speed'] += 1
            speed = self.tracker.home_speed
        self.next_speed = speed
        return speed

    @property
    def throws_to_go(self):
        """Throws before a ready can come: none is known in advance under a policy."""
        return 0

    # ------------------------------------------------------------------ judgement
    def failed(self, seq, reason):
        v = super().failed(seq, reason)
        self.choose()
        return v

    def untrusted(self, seq, reason):
        v = super().untrusted(seq, reason)
        self.choose()
        return v

    def interrupt(self, reason):
        super().interrupt(reason)
        self.choose()

    def completed(self, seq, detected, note='', speed=None):
        """
        Judge a completed cycle fired at ``speed`` (rad/s; None: the controller's own speed).

        Ready only when the policy's knowledge proves the goal edge, no anomaly came with the
        cycle, and no later cycle has fired.
        """
        detected = bool(detected)
        self.counts['cycles'] += 1
        self.counts['completed'] += 1
        self.counts['detections'] += int(detected)
        self.ready_seq = None
        self.last_judgement = None
        anomaly = None
        gap = self._check_seq(seq)
        if gap:
            anomaly = self._anomaly(seq, gap)
            self._restart_all()     # the tracker forgets the part too
        if speed is None:
            self.counts['fixed_speed_cycles'] += 1
            speed = self.tracker.home_speed
        self.result = result = self.tracker.observe(detected, speed)
        if result == 'unknown speed':
            self.counts['unknown_speed'] += 1
            self.note = (f"cycle {seq} was fired at {speed:.4f} rad/s, none of the policy's "
                         'speeds: the knowledge is every cell the bit allows')
        elif result == 'anomaly' and anomaly is None:
            self.counts['policy_anomalies'] += 1
            anomaly = self._anomaly(seq, f'{"a detection" if detected else "no detection"} '
                                         'where no state the speed policy allows can show it')
        superseded = self.fired_seq is not None and self.fired_seq > seq
        ready = result == 'ready' and anomaly is None and not superseded
        if result == 'ready' and anomaly is None and superseded:
            self.counts['superseded'] += 1
        self.choose()
        note, self.note = self.note, ''
        state = ANOMALY if anomaly else (READY if ready else TRACKING)
        if ready:
            self.counts['ready'] += 1
            self.ready_seq = seq
        self.state = state
        return Verdict(seq, ready, state, anomaly, note)
