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
A design's predicted feed rate against a run's verdicts and the part's true states (ROS-free).

The prediction is the monitor's own: the design scene's analysis (throwmap.scene_analysis, its
sensor) and the rules the monitor node derives from it; proven readies per cycle in the limit
set = the sensor's detection rate there (after the warm-up every detection is proven). A run
gives one verdict per cycle (seq -> ready, anomaly) and the true state per cycle (the hardware
stand-in's truth log, or the library's own throws); :func:`judge_feed` counts false readies
(ready while the part is not seen on the goal edge) and the readies per cycle after the
warm-up, with a Wilson interval. Used by src/feeder_monitor/test/test_design_feed.py (library
level), tests/test_graph_design.py and bench/design_graph.py (the node graph).
"""

from dataclasses import dataclass

from throwmap import scene_analysis, wilson_interval

from .readiness import limit_set_orbit, rules_from_analysis


def design_prediction(scene, orbit_throws=3000):
    """Return (analysis, rules) of a design scene, as the monitor node derives them."""
    an = scene_analysis(scene)
    return an, rules_from_analysis(scene, an, limit_set_orbit(scene, an, orbit_throws))


@dataclass(frozen=True)
class FeedReport:
    """What a run measured against the prediction."""

    cycles: int             # cycles with a verdict
    judged: int             # of them after the warm-up (seq > warm-up)
    readies: int            # ready verdicts among the judged cycles
    rate: float             # readies / judged
    lo: float               # Wilson interval of rate at z
    hi: float
    z: float
    predicted: float        # proven readies per cycle in the limit set
    false_readies: int      # ready while the true part is not seen on the goal edge
    anomalies: int          # verdicts that carry an anomaly
    failed: int             # cycles whose throw failed (truth: error)
    missing_truth: int      # verdicts without a true state

    @property
    def consistent(self):
        """Whether the prediction lies inside the measured interval."""
        return self.lo <= self.predicted <= self.hi

    def line(self):
        return (f'{self.cycles} cycles ({self.judged} after the warm-up): '
                f'{self.readies} readies = {self.rate:.4f} per cycle '
                f'[{self.lo:.4f}, {self.hi:.4f}] (Wilson, z {self.z:g}), predicted '
                f'{self.predicted:.4f} ({"inside" if self.consistent else "OUTSIDE"}); '
                f'{self.false_readies} false readies, {self.anomalies} anomalies, '
                f'{self.failed} failed throws, {self.missing_truth} without truth')


def judge_feed(verdicts, truth, goal_edge, predicted, warmup, z=1.96):
    """
    Judge a run: ``verdicts`` {seq: (ready, anomaly text or None/empty)}, ``truth`` {seq: rec}.

    A truth record has ``edge`` and ``seen`` (the geometric sensor bit of the true state) or
    ``error`` (the throw failed). A ready verdict is false unless the true part rests on
    ``goal_edge`` in the sensor's view. Rates count the cycles with seq > ``warmup`` (the
    monitor's warm-up: none is ready before).
    """
    judged = readies = false = anomalies = failed = missing = 0
    for seq, (ready, anomaly) in verdicts.items():
        rec = truth.get(seq)
        anomalies += bool(anomaly)
        if rec is None:
            missing += 1
        elif 'error' in rec:
            failed += 1
        true_ready = rec is not None and 'error' not in rec and rec['edge'] == goal_edge \
            and bool(rec['seen'])
        false += bool(ready) and not true_ready
        if seq > warmup:
            judged += 1
            readies += bool(ready)
    rate, lo, hi = wilson_interval(readies, judged, z)
    return FeedReport(len(verdicts), judged, readies, rate, lo, hi, z, float(predicted), false,
                      anomalies, failed, missing)


def truth_from_throw(edge, seen):
    """Return the truth record of a throw computed in-process (library-level runs)."""
    return {'edge': int(edge), 'seen': bool(seen)}


__all__ = ['design_prediction', 'FeedReport', 'judge_feed', 'truth_from_throw']
