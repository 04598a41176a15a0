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
Orbits of the throw map and their forward limit sets (paper section IV).

An orbit iterates f from a start; with effects it may end early with a 'lost' state (-1, nan):
the part left a finite arm, or came to rest outside the domain of f (:func:`loss_reason`).
Its limit set is read off its tail: the edges visited by flips, the R band on each edge, the
jog counts, the cycle lengths and the transient.
"""

from dataclasses import dataclass
import math

import numpy as np

from .catch import is_jog, throw_kind
from .errors import InputError, PartLost


@dataclass(frozen=True)
class Orbit:
    """States (edge, R) after 0..N throws; ``kinds[k]`` is the throw that led to state k."""

    edges: np.ndarray
    radii: np.ndarray
    kinds: tuple            # kinds[0] is None (the start)
    rotations: np.ndarray

    def rows(self):
        return [{'throw': k, 'edge': int(e), 'R': float(r), 'kind': kd}
                for k, (e, r, kd) in enumerate(zip(self.edges, self.radii, self.kinds))]


def orbit(model, edge, R, throws):
    """Iterate f; with effect finite_arm the orbit may end early with a 'lost' state (-1, nan)."""
    if isinstance(throws, bool) or not isinstance(throws, (int, np.integer)) or throws < 1:
        raise InputError('throws', f'must be an integer >= 1, got {throws!r}',
                         'give the number of throws to simulate')
    edges, radii, rots = model.orbit_arrays(edge, R, int(throws))
    kinds = [None] + [('lost' if edges[k] < 0 else throw_kind(edges[k - 1], edges[k], rots[k]))
                      for k in range(1, len(edges))]
    return Orbit(edges, radii, tuple(kinds), rots)


def loss_reason(model, edge, R):
    """
    Say why the throw from (edge, R) lost the part, as the noise-free model throws it.

    '' where that throw does not lose it (a noisy throw did).
    """
    res = model.nominal().throw(int(edge), float(R))
    return res.lost_reason


def flip_pattern(edges, rotations):
    """Edges landed on by flips, in order (jogs dropped)."""
    flips = [int(edges[k]) for k in range(1, len(edges))
             if not is_jog(edges[k - 1], edges[k], rotations[k])]
    return flips


def minimal_cycle(seq):
    """Shortest repeating unit of a sequence that is periodic (None if none is visible)."""
    n = len(seq)
    for p in range(1, n // 2 + 1):
        if all(seq[k] == seq[k + p] for k in range(n - p)):
            return list(seq[:p])
    return None


def canonical_cycle(cycle):
    """Rotation of a cyclic pattern that is smallest lexicographically (a stable name)."""
    if not cycle:
        return ()
    rots = [tuple(cycle[k:] + cycle[:k]) for k in range(len(cycle))]
    return min(rots)


@dataclass(frozen=True)
class LimitSet:
    """
    The forward limit set seen from one start, read off a long orbit.

    ``pattern``: edges visited by flips around one cycle (canonical rotation), with ``jogs``
    the range of jog counts on each edge before it flips on. ``bands``: per edge (min R,
    max R) in the limit set. ``transient``: throws before the orbit stays inside the bands.
    ``cycle_lengths``: throws per cycle, over the cycles seen in the tail.
    """

    pattern: tuple
    bands: dict
    jogs: dict
    transient: int
    cycle_lengths: tuple
    tail_edges: np.ndarray
    tail_radii: np.ndarray
    periodic: bool
    band_tol: float

    @property
    def signature(self):
        return '-'.join(str(e) for e in self.pattern) if self.pattern else 'no-flip'

    def as_dict(self):
        cl = np.array(self.cycle_lengths) if self.cycle_lengths else np.array([np.nan])
        return {'pattern': list(self.pattern),
                'bands': {str(k): list(v) for k, v in sorted(self.bands.items())},
                'jogs': {str(k): list(v) for k, v in sorted(self.jogs.items())},
                'transient': self.transient,
                'cycle_length': {'min': float(np.nanmin(cl)), 'max': float(np.nanmax(cl)),
                                 'mean': float(np.nanmean(cl))},
                'periodic': self.periodic}

    def contains(self, edge, R, tol=None):
        tol = self.band_tol if tol is None else tol
        band = self.bands.get(int(edge))
        return band is not None and band[0] - tol <= R <= band[1] + tol


def limit_set_from_orbit(edges, radii, rotations, tail_fraction=0.5, band_tol=None):
    """
    Read the limit set off an orbit: its last ``tail_fraction`` is taken as recurrent.

    The transient is the first throw from which every state lies within ``band_tol`` of its
    edge's band (default: 1 % of the limit set's overall R extent, because a quasi-periodic
    orbit fills its bands only slowly and an exact test would call that a transient).
    """
    n = len(edges)
    start = int(n * (1.0 - tail_fraction))
    te, tr, trot = edges[start:], radii[start:], rotations[start:]
    bands = {}
    for e in np.unique(te):
        sel = tr[te == e]
        bands[int(e)] = (float(sel.min()), float(sel.max()))
    if band_tol is None:
        band_tol = 0.01 * (float(tr.max() - tr.min()) if tr.size else 0.0) + 1e-12
    inside = np.array([int(e) in bands and bands[int(e)][0] - band_tol <= r
                       <= bands[int(e)][1] + band_tol for e, r in zip(edges, radii)])
    outside = np.flatnonzero(~inside)
    transient = int(outside[-1] + 1) if outside.size else 0
    flips = [k for k in range(1, len(te)) if not is_jog(te[k - 1], te[k], trot[k])]
    flip_edges = [int(te[k]) for k in flips]
    cycle = minimal_cycle(flip_edges) if len(flip_edges) >= 4 else None
    periodic = cycle is not None
    if cycle is None:
        cycle = sorted(set(flip_edges))
    pattern = canonical_cycle(cycle)
    # Jog counts between flips, per edge; cycle lengths between returns to the same flip.
    jogs = {}
    for a, b in zip(flips, flips[1:]):
        e = int(te[a])
        lo, hi = jogs.get(e, (b - a - 1, b - a - 1))
        jogs[e] = (min(lo, b - a - 1), max(hi, b - a - 1))
    lengths = []
    if pattern:
        p = len(pattern)
        key = pattern[0]
        marks = [flips[k] for k in range(len(flips)) if flip_edges[k] == key]
        if p and len(marks) >= 2:
            # With a pattern that visits `key` more than once per cycle, step over whole cycles.
            per_cycle = max(1, sum(1 for e in pattern if e == key))
            lengths = [marks[k + per_cycle] - marks[k]
                       for k in range(0, len(marks) - per_cycle, per_cycle)]
    if not flips:
        # No flip in the tail: a fixed point or a drift on one edge.
        pattern = ()
    return LimitSet(pattern, bands, jogs, transient, tuple(int(x) for x in lengths), te, tr,
                    periodic, float(band_tol))


def limit_set(model, edge, R, throws=2000, tail_fraction=0.5):
    """Return the LimitSet of the orbit from (edge, R); PartLost if the part is lost on the way."""
    orb = orbit(model, edge, R, throws)
    if orb.edges[-1] < 0:
        why = loss_reason(model, orb.edges[-2], orb.radii[-2]) or 'a noisy throw lost it'
        raise PartLost(f'from ({edge}, {R:.6g} m) the part was lost at throw '
                       f'{len(orb.edges) - 1} ({why}): there is no limit set; start elsewhere '
                       'or change the design (arm.length, release speed, offset)',
                       after=len(orb.edges) - 2)
    return limit_set_from_orbit(orb.edges, orb.radii, orb.rotations, tail_fraction)


def pull_share(model, ls, throws=400):
    """
    Count the limit set's throws whose rolls need the arm to pull (min_normal_force < 0).

    The last ``throws`` states of the limit set's tail are thrown again (noise-free: the
    deterministic map) with their full results. Returns {'throws', 'pulling', 'share', 'worst'
    (the smallest normal force per unit mass, m/s^2)}, or None where the model's catch does not
    carry the normal force (the event simulator's).
    """
    nominal = model.nominal()
    edges = ls.tail_edges[-throws:]
    radii = ls.tail_radii[-throws:]
    if not edges.size or math.isnan(nominal.throw(int(edges[0]),
                                                  float(radii[0])).min_normal_force):
        return None
    low = np.array([nominal.throw(int(e), float(r)).min_normal_force
                    for e, r in zip(edges, radii)])
    pulling = int(np.sum(low < 0.0))
    return {'throws': int(low.size), 'pulling': pulling, 'share': pulling / low.size,
            'worst': float(low.min())}
