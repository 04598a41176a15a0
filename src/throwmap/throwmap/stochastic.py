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
Noisy scenes (effects release_noise, sensor_noise): outcome distributions by Monte Carlo.

With noise the throw map is a random map, so a start no longer has one limit set but a
distribution of outcomes, and a sensor detection proves the goal edge only with some
probability. Each estimate here reseeds the model with seeds 0..N-1 (offset by the scene's
seed), so results are reproducible; the sensor readings use the model's own Generator.
"""

from dataclasses import dataclass
import math

from .basins import basin


def _seeds(model, count):
    base = getattr(model, 'seed', 0) or 0
    return [base * 1000 + k for k in range(count)]


def basin_distribution(model, start_edges, start_radii, throws=100, seeds=8, reference=None):
    """
    Return, per start, the fraction of seeds whose orbit ends in each limit pattern.

    Patterns include 'lost', and 'left the domain' for orbits that a noisy throw took out of
    the domain of f.

    Returns (per_start, overall): per_start a list of {signature: fraction}, overall the mean
    over starts.
    """
    counts = [{} for _ in range(len(start_edges))]
    for seed in _seeds(model, seeds):
        model.reseed(seed)
        bas = basin(model, start_edges, start_radii, throws, reference=reference)
        for k, sig in enumerate(bas.signatures):
            if sig.startswith('error'):
                sig = 'left the domain'     # a noisy throw lost the grasp (one message each)
            counts[k][sig] = counts[k].get(sig, 0) + 1
    per_start = [{s: c / seeds for s, c in row.items()} for row in counts]
    overall = {}
    for row in per_start:
        for s, f in row.items():
            overall[s] = overall.get(s, 0.0) + f / len(per_start)
    return per_start, overall


@dataclass(frozen=True)
class SensorProbability:
    """
    Monte Carlo estimate of what a detection at radius proves.

    p_goal: P(part on the goal edge | detection), with a 95 % Wilson interval (lo, hi), over
    detections detections in throws throws after warm-up. detection_rate: P(detection).
    lost_fraction: fraction of the orbits that lost the part before the end.
    """

    goal_edge: int
    radius: float
    footprint: float
    p_goal: float
    p_goal_lo: float
    p_goal_hi: float
    detections: int
    throws: int
    detection_rate: float
    false_positive: float
    false_negative: float
    lost_fraction: float

    def as_dict(self):
        return dict(vars(self))


def wilson_interval(k, n, z=1.96):
    """Return (k / n, lo, hi): the Wilson score interval of a binomial rate (z = 1.96: 95 %)."""
    if n == 0:
        return math.nan, 0.0, 1.0
    p = k / n
    den = 1 + z * z / n
    mid = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return p, max(0.0, mid - half), min(1.0, mid + half)


def sensor_probability(model, goal_edge, radius, footprint=0.0, start=None, throws=2000,
                       seeds=8, warmup=20):
    """
    Estimate P(goal edge | detection) at ``radius`` by Monte Carlo.

    ``seeds`` noisy orbits of ``throws`` throws each (the first ``warmup`` not counted);
    readings go through the scene's sensor noise when the model has it.
    """
    if start is None:
        start = (goal_edge, model.start_radius(goal_edge))
    hits = 0
    det = 0
    total = 0
    lost = 0
    for seed in _seeds(model, seeds):
        model.reseed(seed)
        e, r, _, status, done = model.orbits([start[0]], [start[1]], throws)
        n_ok = int(done[0]) + 1
        if status[0] != 0:
            lost += 1
        edges = e[0, warmup:n_ok]
        radii = r[0, warmup:n_ok]
        if edges.size == 0:
            continue
        seen = model.read_sensor(edges, radii, radius, footprint)
        det += int(seen.sum())
        hits += int((seen & (edges == goal_edge)).sum())
        total += edges.size
    p, lo, hi = wilson_interval(hits, det)
    effects = getattr(model, 'effects', None)
    noise = effects.get('sensor_noise') if effects else None
    return SensorProbability(int(goal_edge), float(radius), float(footprint), p, lo, hi, det,
                             total, det / total if total else math.nan,
                             noise.false_positive if noise else 0.0,
                             noise.false_negative if noise else 0.0, lost / seeds)


def stochastic_summary(model, sensor, start, basin_starts, throws=2000, grid_throws=100,
                       seeds=8, reference=None):
    """
    Return the noisy scene's figures for analyse().

    The basin outcome distribution and the sensor's P(goal | detection) at the designed radius.
    """
    _, overall = basin_distribution(model, basin_starts[0], basin_starts[1], grid_throws, seeds,
                                    reference)
    sp = sensor_probability(model, sensor.goal_edge, sensor.radius, sensor.footprint, start,
                            throws, seeds)
    model.reseed(model.seed)
    return {'seeds': seeds, 'basin_outcomes': overall, 'sensor': sp.as_dict()}
