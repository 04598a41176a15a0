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
Lower bounds on the throws a funnelling policy needs to its first ready (issue 25, item 3).

:func:`full_knowledge_bound`: on the cell map, the fewest throws to rest on the goal edge where
the sensor may see it, with the cell known and any speed that cannot escape from it.

:func:`one_bit_bound`: what the one bit costs, point by point through the scene's model. A
policy sees only bits; until its part is first seen, every bit has been 0, so its speeds so
far are the same for every start, and each must be safe (lose no part) for every state that
is consistent with those zeros. Of those states this uses one family per stable edge, the
**continuum**: the starts on that edge from the lowest up to the sensor's window (a fresh part
may lie anywhere there). A throw at w jogs a state below the edge's lowest leaving point
phi_w outwards (f_w(R) > R) and, checked on a fine R grid, increasingly and without jumps; so
the continuum stays an interval [a, b): a, the image of the lowest start (the **front**), b at
least the image of the states just below the last speed's phi (clipped below the window, where
a 0 would have removed them). A speed is usable only when it escapes from no R of [a, b), until
the front itself leaves the edge. A Pareto search over (a, b) (a larger front and a lower top
allow every speed the other allows, and keep that order after a throw) gives, per speed, the
earliest throw at which any policy may use it for a part not yet seen; the edges' earliest
throws are iterated together to their fixed point. Then per start, a search over every speed
sequence that respects those earliest throws (the states are bins of the grid step, each
standing for all of its states: :func:`throws_to_first_ready`), nominal throws, no throw that
loses this part: the first detection on the goal edge, or on another edge plus the
full-knowledge cell bound from there. No policy that never risks the part has its first
ready sooner: nominal throws are in every error box, and a ready needs the part seen on the
goal edge.

Sampled, as the cell map is: the leaving points, escapes and monotonicity are read on a grid of
``step`` (1e-5 m), a bin's image from its two ends; an edge whose map is not increasing, not
outward or jumps more than JUMP_STEPS grid steps below a leaving point gives no constraint (a
weaker bound, said in ``notes``).
"""

from dataclasses import dataclass
import math

import numpy as np

from .sensor import seen_radii


def full_knowledge_bound(system, speeds=None):
    """
    Return per cell the fewest throws to rest on the goal edge where the sensor may see it.

    Full knowledge of the cell, any speed that cannot escape from it, any successor the cell
    map allows (optimistic): a lower bound on the throws any policy needs to its first ready
    from a start in that cell, under nominal throws or any throws within the error box (as
    far as the cell map holds them). inf: never. ``speeds``: only these speed indices.
    """
    target = system.goal & system.can_see
    dist = np.full(system.n, np.inf)
    reach = target.copy()           # cells from which "landing there" ends the count
    t = 0
    while True:
        t += 1
        pre = np.zeros(system.n, dtype=np.bool_)
        for k in range(len(system.speeds)) if speeds is None else speeds:
            pre |= system.succ[k][:, reach].any(axis=1) & ~system.escape[k]
        new = pre & ~np.isfinite(dist)
        if not new.any():
            return dist
        dist[new] = t
        reach = reach | new


# A grid step whose image is larger than this many steps is taken as a jump: the continuum's
# image could have a gap there, so the edge gives no constraint (the triangle's largest: 3).
JUMP_STEPS = 50
ONE_BIT_STEP = 1e-5


@dataclass
class OneBitBound:
    """:func:`one_bit_bound`'s answer."""

    throws: np.ndarray          # per start: no safe one-bit policy's first ready comes sooner
    first_use: np.ndarray       # per speed: earliest throw (1-based) for a part not yet seen
    constraining: list          # the edges whose continuum gave constraints
    notes: list
    step: float


@dataclass
class _Continuum:
    edge: int
    r: np.ndarray               # the grid: lowest start .. arm's end
    escapes: list               # per speed: cumulative count of escaping grid points
    leave: list                 # per speed: first grid index that leaves the edge or escapes
    image: list                 # per speed: f_w on r[:leave]
    top: int                    # highest grid index of the continuum (below the window)


def _continuum(models, edge, r_low, r_high, r_seen, arm, step, notes):
    """Build the grid of one edge's continuum; None (with a note) where the argument fails."""
    r = np.arange(r_low, arm, step)
    top = min(int(np.searchsorted(r, min(r_high, r_seen), side='left')) - 1, r.size - 1)
    if top < 0:
        return None
    escapes, leave, image = [], [], []
    for m in models:
        res = m.f_batch(np.full(r.size, edge), r)
        esc = (res['status'] != 0) | (res['edge'] < 0)
        leaves = esc | (res['edge'] != edge)
        i = int(np.argmax(leaves)) if leaves.any() else r.size
        f = res['R'][:i]
        if i > 1:
            d = np.diff(f)
            if not (np.all(d > 0) and np.all(f > r[:i]) and d.max() <= JUMP_STEPS * step):
                notes.append(f'edge {edge}: the jog at {math.degrees(m.w):.1f} deg/s is not '
                             'increasing, outward and without jumps below its leaving point; '
                             'its continuum gives no constraint')
                return None
        escapes.append(np.concatenate([[0], np.cumsum(esc)]))
        leave.append(i)
        image.append(f)
    return _Continuum(edge, r, escapes, leave, image, top)


def _earliest(c, first_use, max_throws):
    """Per speed: the earliest throw count after which edge c's continuum allows it."""
    K = len(c.escapes)
    states = {(0, c.top)}
    allowed_after = np.full(K, np.inf)
    for t in range(max_throws):
        nxt = set()
        for a, b in states:
            for k in range(K):
                if c.escapes[k][b + 1] - c.escapes[k][a] > 0:
                    continue            # a state of the continuum may be lost at this speed
                allowed_after[k] = min(allowed_after[k], t)
                if first_use[k] > t + 1:
                    continue            # another edge's continuum forbids it at throw t + 1
                if a >= c.leave[k]:
                    # The front leaves the edge: nothing of the continuum is left to forbid.
                    allowed_after[:] = np.minimum(allowed_after, t + 1)
                    continue
                na = int(np.searchsorted(c.r, c.image[k][a]))
                nb = int(np.searchsorted(c.r, c.image[k][min(b, c.leave[k] - 1)],
                                         side='right')) - 1
                if na > c.top:
                    # The front is at the window: seen there, the history is no longer all 0.
                    allowed_after[:] = np.minimum(allowed_after, t + 1)
                    continue
                nxt.add((na, max(na, min(nb, c.top))))
        if not nxt or np.all(np.isfinite(allowed_after)):
            break
        # Keep the Pareto front: (a, b) is dominated by (a', b') with a' >= a and b' <= b.
        keep, best_b = set(), math.inf
        for a, b in sorted(nxt, key=lambda p: (-p[0], p[1])):
            if b < best_b:
                keep.add((a, b))
                best_b = b
        states = keep
    return allowed_after


def first_use(system, models, starts, step=ONE_BIT_STEP, max_throws=300):
    """
    Return (first_use, constraining edges, notes): per speed, its earliest usable throw.

    Throw numbers from 1: a speed with first_use n may be thrown at throw n at the earliest by
    any policy that reads only the bit and never risks the part, for a part not yet seen
    (module docstring). The edges' constraints are iterated together to a fixed point.
    """
    K = len(system.speeds)
    edges, radii = starts
    r_seen, _ = seen_radii(models[0].part, system.sensor_radius, system.footprint)
    notes = []
    conts = []
    for e in sorted({int(v) for v in edges}):
        rs = radii[edges == e]
        # Below the lowest R of edge e the sensor sees, a state always reads 0.
        c = _continuum(models, e, float(rs.min()), float(rs.max()), float(r_seen[e]),
                       system.arm_length, step, notes)
        if c is not None:
            conts.append(c)
    first = np.ones(K)
    for _ in range(20):
        new = np.ones(K)
        for c in conts:
            new = np.maximum(new, _earliest(c, first, max_throws) + 1)
        if np.array_equal(new, first):
            break
        first = new
    return first, [c.edge for c in conts], notes


def one_bit_bound(system, models, starts, dist=None, step=ONE_BIT_STEP, max_throws=300,
                  progress=None):
    """
    Return a :class:`OneBitBound` (module docstring) for the starts of the grid.

    ``system``: the funnel's CellSystem (speeds, sensor, goal, cells for the bound after a
    detection); ``models``: per speed, the scene's nominal model at that speed (on its arm);
    ``starts``: (edges, radii); ``dist``: full_knowledge_bound(system) when the caller has it;
    ``progress(done, total)`` after each start.
    """
    first, constraining, notes = first_use(system, models, starts, step, max_throws)
    if dist is None:
        dist = full_knowledge_bound(system)
    edges, radii = starts
    out = np.full(len(edges), np.inf)
    for i, (e0, r0) in enumerate(zip(edges, radii)):
        out[i] = throws_to_first_ready(system, models, int(e0), float(r0), first, dist, step,
                                       max_throws)
        if progress:
            progress(i + 1, len(edges))
    return OneBitBound(out, first, constraining, notes, step)


def throws_to_first_ready(system, models, edge, R, first, dist, step=ONE_BIT_STEP,
                          max_throws=300):
    """
    Return the fewest throws from (edge, R) to a first ready over every admissible sequence.

    Admissible: speed k from throw ``first[k]`` on, none that loses this part (nominal throws).
    The count ends at the first detection: there on the goal edge, or on another edge plus
    ``dist`` (full_knowledge_bound) of its cell. The states are bins of width ``step`` on each
    edge, each standing for every R in it: a bin's image is the hull of the images of its two
    ends (each end on its own when they land on different edges), widened by a bin on each
    side; a bin that may be seen counts as a detection and, unless wholly seen, goes on. So a
    bin holds every state a sequence can reach (as far as its ends show the map) and merging
    never loses the fastest path (merging points did: two speeds 0.003 deg/s apart gave 28
    throws where one of them takes 27). max_throws + 1 when no detection comes within
    max_throws (at least that many); inf when every sequence loses the part first.
    """
    seen_lo, seen_hi = seen_radii(models[0].part, system.sensor_radius, system.footprint)
    E = np.array([edge], dtype=np.int64)
    J = np.array([int(math.floor(R / step))], dtype=np.int64)
    best = math.inf
    for t in range(1, max_throws + 1):
        if t >= best or not E.size:
            break
        ne, nlo, nhi = [], [], []
        lo = J * step
        hi = lo + step
        for k, m in enumerate(models):
            if first[k] > t:
                continue
            a = m.f_batch(E, lo)
            b = m.f_batch(E, hi)
            ok_a = (a['status'] == 0) & (a['edge'] >= 0)
            ok_b = (b['status'] == 0) & (b['edge'] >= 0)
            same = ok_a & ok_b & (a['edge'] == b['edge'])
            ne.append(a['edge'][same])
            nlo.append(np.minimum(a['R'], b['R'])[same])
            nhi.append(np.maximum(a['R'], b['R'])[same])
            for res, ok in ((a, ok_a & ~same), (b, ok_b & ~same)):
                ne.append(res['edge'][ok])
                nlo.append(res['R'][ok])
                nhi.append(res['R'][ok])
        E = np.concatenate(ne).astype(np.int64)
        r_lo = np.concatenate(nlo) - step
        r_hi = np.concatenate(nhi) + step
        meets = (r_lo <= seen_hi[E]) & (r_hi >= seen_lo[E])
        if np.any(meets & (E == system.goal_edge)):
            best = min(best, t)
        for e, a_, b_ in {(int(e), float(x), float(y)) for e, x, y in zip(
                E[meets], np.maximum(r_lo, seen_lo[E])[meets],
                np.minimum(r_hi, seen_hi[E])[meets]) if e != system.goal_edge}:
            best = min(best, t + _least_dist(system, dist, e, a_, b_))
        keep = ~((r_lo >= seen_lo[E]) & (r_hi <= seen_hi[E]))     # not wholly seen
        E, r_lo, r_hi = E[keep], r_lo[keep], r_hi[keep]
        j0 = np.floor(r_lo / step).astype(np.int64)
        n = np.floor(r_hi / step).astype(np.int64) - j0 + 1
        E = np.repeat(E, n)
        J = np.repeat(j0, n) + (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n))
        _, keep = np.unique(E * (1 << 40) + J, return_index=True)
        E, J = E[keep], J[keep]
    if math.isinf(best) and E.size:
        return float(max_throws + 1)
    return best


def _least_dist(system, dist, edge, r_lo, r_hi):
    """Return the least full-knowledge bound over the cells of edge meeting [r_lo, r_hi]."""
    cells = system.cells_between(edge, r_lo, r_hi)
    # Outside the cells (or off the stable edges) nothing is known: the least is 0.
    return float(dist[cells].min()) if cells.stop > cells.start else 0.0
