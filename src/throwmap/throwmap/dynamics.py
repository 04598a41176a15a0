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

"""Dynamics of the throw map (paper section IV): orbits, limit sets, basins, design radii."""

from dataclasses import dataclass
import math

import numpy as np

from . import kernel
from .errors import InputError, NumericalError

LOST = 20   # effect_model.LOST: the part left the finite arm (kept here to avoid an import cycle)


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
    kinds = [None] + [('lost' if edges[k] < 0 else
                       'jog' if edges[k] == edges[k - 1] and abs(rots[k]) < math.pi else 'flip')
                      for k in range(1, len(edges))]
    return Orbit(edges, radii, tuple(kinds), rots)


def flip_pattern(edges, rotations):
    """Edges landed on by flips, in order (jogs dropped)."""
    flips = [int(edges[k]) for k in range(1, len(edges))
             if edges[k] != edges[k - 1] or abs(rotations[k]) >= math.pi]
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
    flips = [k for k in range(1, len(te)) if te[k] != te[k - 1] or abs(trot[k]) >= math.pi]
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
    orb = orbit(model, edge, R, throws)
    if orb.edges[-1] < 0:
        from .effect_model import PartLost
        raise PartLost(f'from ({edge}, {R:.6g} m) the part was lost (fell off the arm) at throw '
                       f'{len(orb.edges) - 1}: there is no limit set; start elsewhere or '
                       'lengthen arm.length', after=len(orb.edges) - 2)
    return limit_set_from_orbit(orb.edges, orb.radii, orb.rotations, tail_fraction)


@dataclass(frozen=True)
class Basin:
    """Orbits from a grid of starts: which limit pattern each start reaches, and when."""

    start_edges: np.ndarray
    start_radii: np.ndarray
    edges: np.ndarray           # (starts, throws + 1)
    radii: np.ndarray
    rotations: np.ndarray
    status: np.ndarray
    signatures: tuple
    transients: np.ndarray      # throws until the orbit stays in the reference limit set

    def summary(self):
        counts = {}
        for s in self.signatures:
            counts[s] = counts.get(s, 0) + 1
        return counts


def default_grid(model, radii_per_edge=50, r_max=None):
    """
    Return the starts of a basin grid: every stable edge x ``radii_per_edge`` radii.

    Radii run from just above R_min (R_grasp or the toe-stub bound) to r_max (default: the
    largest R_max of design_radii, which bounds the invariant set Z of Prop. IV.4).
    """
    part = model.part
    if r_max is None:
        r_max = design_radii(model)['R_max_all']
    starts_e, starts_r = [], []
    for i in part.stable_edges:
        lo = max(model.r_grasp[i], -part.u_l[i])
        hi = max(r_max, lo * 1.5)
        # Start 1 % of the range inside R_min: right at the toe-stub bound the hop, and with it
        # the jog, shrinks to nothing (an unstable fixed point that takes ages to leave).
        rs = np.linspace(lo + 0.01 * (hi - lo), hi, radii_per_edge)
        starts_e.extend([i] * radii_per_edge)
        starts_r.extend(rs.tolist())
    return np.array(starts_e), np.array(starts_r)


def basin(model, start_edges, start_radii, throws=100, reference=None, progress=None,
          chunk=256):
    """
    Iterate f from every start.

    ``reference`` (a LimitSet) sets which bands count as 'in'. A start whose orbit ends inside
    them, flipping only as the reference's pattern does, is labelled with the reference's
    signature, however few throws are left after its transient; one that never gets inside is
    'not converged'. Without a reference each orbit's own tail names its limit set.
    ``progress(done, total)`` is called after each chunk of starts.
    """
    start_edges = np.asarray(start_edges)
    start_radii = np.asarray(start_radii, dtype=float)
    parts = []
    for a in range(0, len(start_edges), chunk):
        parts.append(model.orbits(start_edges[a:a + chunk], start_radii[a:a + chunk], throws))
        if progress:
            progress(min(a + chunk, len(start_edges)), len(start_edges))
    e, r, rot, status, done = (np.concatenate(x) for x in zip(*parts))
    sigs = []
    transients = np.full(len(start_edges), -1)
    for s in range(len(start_edges)):
        if status[s] == LOST:
            sigs.append('lost')
            continue
        if status[s] != kernel.OK:
            sigs.append('error: ' + model.error_message(int(status[s]), int(e[s, done[s]]),
                                                        float(r[s, done[s]])))
            continue
        ls = limit_set_from_orbit(e[s], r[s], rot[s])
        ref = reference or ls
        inside = np.array([ref.contains(a, b) for a, b in zip(e[s], r[s])])
        outside = np.flatnonzero(~inside)
        transients[s] = int(outside[-1] + 1) if outside.size else 0
        if reference is None:
            sigs.append(ls.signature)
        elif transients[s] >= e.shape[1]:
            sigs.append('not converged')
        elif _follows(flip_pattern(e[s, transients[s]:], rot[s, transients[s]:]),
                      reference.pattern):
            sigs.append(reference.signature)
        else:
            sigs.append(ls.signature)
    return Basin(np.asarray(start_edges), np.asarray(start_radii), e, r, rot, status,
                 tuple(sigs), transients)


def _follows(flips, pattern):
    """Tell whether each flip in ``flips`` goes to the edge that follows in cyclic ``pattern``."""
    if not pattern:
        return not flips
    nxt = {pattern[k]: pattern[(k + 1) % len(pattern)] for k in range(len(pattern))}
    if len(nxt) != len(pattern):    # an edge visited twice per cycle: compare as a sequence
        text = ','.join(map(str, pattern * (len(flips) // len(pattern) + 2)))
        return ','.join(map(str, flips)) in text
    return all(f in nxt for f in flips) and all(nxt[a] == b for a, b in zip(flips, flips[1:]))


def _first_flip(model, edge, lo, hi, samples):
    rs = np.linspace(lo, hi, samples)
    res = model.f_batch(np.full(samples, edge), rs)
    flips = np.flatnonzero((res['kind'] == 'flip'))
    if flips.size == 0:
        return None, res
    k = int(flips[0])
    if k == 0:
        return float(rs[0]), res
    a, b = float(rs[k - 1]), float(rs[k])
    for _ in range(60):
        mid = 0.5 * (a + b)
        if model.f(edge, mid)[2] == 'flip':
            b = mid
        else:
            a = mid
        if b - a <= 1e-12 * max(1.0, b):
            break
    return b, res


def design_radii(model, samples=400, max_rounds=50):
    """
    R_grasp, R_flip and R_max per stable edge (Proposition IV.4), computed numerically.

    R_min^i: lower end of the domain of f on E^i: R_grasp^i, or the toe-stub bound -u_l^i
    (the left vertex must start right of the pivot) when that is larger.
    R_flip^i: smallest R >= R_min^i whose throw flips (scan, then bisection).
    R_max^i: smallest bounds such that Z = U_i [R_grasp^i, R_max^i] is mapped into itself,
    found by growing the bounds until f(Z) lies in Z (dense sampling of each interval).
    ``invariant`` says whether that succeeded and every flip lands inside some grasp range.
    """
    part = model.part
    stable = part.stable_edges
    lo = {i: max(model.r_grasp[i], -part.u_l[i] + 1e-12) for i in stable}
    r_flip = {}
    for i in stable:
        hi = max(lo[i] * 2, lo[i] + 4 * part.r)
        found = None
        for _ in range(40):
            found, _ = _first_flip(model, i, lo[i], hi, samples)
            if found is not None:
                break
            hi *= 2
        r_flip[i] = found if found is not None else math.inf
    r_max = {i: (r_flip[i] if math.isfinite(r_flip[i]) else lo[i]) for i in stable}
    invariant = True
    escapes = []
    for _ in range(max_rounds):
        grew = False
        escapes = []
        for i in stable:
            rs = np.linspace(lo[i], r_max[i], samples)
            res = model.f_batch(np.full(samples, i), rs)
            lost = res['status'] == LOST
            if lost.any():
                # Lost states (effect finite_arm) leave every invariant set.
                escapes.append((i, -1, float(rs[np.flatnonzero(lost)[0]])))
            ok = (res['status'] == kernel.OK) | lost
            if not ok.all():
                bad = int(np.flatnonzero(~ok)[0])
                raise NumericalError(model.error_message(int(res['status'][bad]), i,
                                                         float(rs[bad])))
            for j in stable:
                sel = res['edge'] == j
                if sel.any():
                    top = float(res['R'][sel].max())
                    low = float(res['R'][sel].min())
                    if low < lo[j]:
                        escapes.append((i, j, low))
                    if top > r_max[j] * (1 + 1e-12):
                        r_max[j] = top
                        grew = True
            landed_unknown = ~np.isin(res['edge'][~lost], stable)
            if landed_unknown.any():   # pragma: no cover - settled edges are stable
                invariant = False
        if not grew:
            break
    else:
        invariant = False
    if escapes:
        invariant = False
    rows = []
    for i in stable:
        rows.append({'edge': i, 'R_grasp': float(model.r_grasp[i]), 'R_min': float(lo[i]),
                     'R_flip': r_flip[i], 'R_max': r_max[i]})
    return {'edges': rows, 'invariant': invariant, 'escapes': escapes,
            'R_max_all': max(r_max.values())}


@dataclass(frozen=True)
class SensorDesign:
    """
    Where a one-bit sensor proves the part is on the goal edge (paper section V.B).

    The sensor at arm coordinate x sees the part when the part's shadow on the arm,
    [R + u_min, R + u_max] of its resting edge, overlaps [x - footprint, x + footprint].
    ``guarantee_radius``: beyond it no limit-set state on another edge is seen.
    ``reach_radius``: beyond it no limit-set state is seen at all; the sensor must sit between.
    ``radius``: the chosen position; ``warmup_throws``: throws after which, from every start
    of the grid, no other edge is ever seen there; ``detection_rate``: fraction of limit-set
    throws the sensor fires at ``radius``.
    """

    goal_edge: int
    footprint: float
    guarantee_radius: float
    reach_radius: float
    radius: float
    warmup_throws: int
    detection_rate: float
    feasible: bool

    def as_dict(self):
        return dict(vars(self))


def sees(part, edge, R, x, footprint=0.0):
    """Tell whether a sensor at arm coordinate x (half-width footprint) detects the part."""
    u_min = part.U.min(axis=1)[edge]
    u_max = part.U.max(axis=1)[edge]
    return (R + u_min <= x + footprint) & (R + u_max >= x - footprint)


def sensor_design(model, ls, goal_edge, footprint=0.0, radius=None, basin_result=None):
    part = model.part
    u_max = part.U.max(axis=1)
    other_top = -math.inf
    goal_top = -math.inf
    for e, (_, hi) in ls.bands.items():
        top = hi + u_max[e]
        if e == goal_edge:
            goal_top = max(goal_top, top)
        else:
            other_top = max(other_top, top)
    guarantee = other_top + footprint
    reach = goal_top + footprint
    feasible = goal_edge in ls.bands and reach > guarantee
    if radius is None:
        if feasible and math.isinf(guarantee):
            # Only the goal edge recurs: any spot its shadow covers proves it; take the middle
            # of the window the goal states' shadows span.
            goal_low = ls.bands[goal_edge][0] + part.U.min(axis=1)[goal_edge] - footprint
            radius = 0.5 * (goal_low + reach)
        elif feasible:
            # Beyond the guarantee, with a margin of a quarter of the usable window.
            radius = guarantee + 0.25 * (reach - guarantee)
        else:
            radius = guarantee
    tail_seen = sees(part, ls.tail_edges, ls.tail_radii, radius, footprint)
    detection_rate = float(tail_seen.mean()) if tail_seen.size else 0.0
    warmup = 0
    if basin_result is not None:
        seen = sees(part, np.maximum(basin_result.edges, 0), basin_result.radii, radius,
                    footprint) & (basin_result.edges >= 0)
        wrong = seen & (basin_result.edges != goal_edge)
        idx = np.argwhere(wrong)
        warmup = int(idx[:, 1].max() + 1) if idx.size else 0
    return SensorDesign(int(goal_edge), float(footprint), float(guarantee), float(reach),
                        float(radius), warmup, detection_rate, bool(feasible))


@dataclass(frozen=True)
class Analysis:
    """
    Everything the nodes and the CLI derive from a scene.

    That is: the limit set, the design radii, a basin and the sensor placement.
    """

    start: tuple
    limit_set: LimitSet
    radii: dict
    basin: Basin
    sensor: SensorDesign
    stochastic: dict = None     # noisy scenes: outcome distribution, P(goal | detection)

    def as_dict(self):
        d = {'start': {'edge': self.start[0], 'R': self.start[1]},
             'limit_set': self.limit_set.as_dict(), 'design': self.radii,
             'basin': self.basin.summary(), 'sensor': self.sensor.as_dict()}
        if self.stochastic is not None:
            d['stochastic'] = self.stochastic
        return d


def analyse(scene, throws=10_000, grid_radii=50, grid_throws=200, progress=None):
    """
    Limit set from the scene's start, R_flip/R_max, a basin grid and the sensor design.

    The goal edge is the scene's ``sensor.goal_edge``, else the edge that reaches furthest
    out in the limit set (the only one a far sensor can prove).
    """
    model = scene.model
    start = scene.default_start()
    noisy = getattr(scene, 'stochastic', False)
    if noisy:
        model.reseed(scene.seed)
    ls = limit_set(model, start[0], start[1], throws)
    # Design radii are properties of the deterministic map: noise is taken out for them.
    radii = design_radii(model.nominal() if noisy else model)
    e, r = default_grid(model, grid_radii, radii['R_max_all'])
    bas = basin(model, e, r, grid_throws, reference=ls, progress=progress)
    goal = scene.goal_edge
    if goal is None:
        u_max = model.part.U.max(axis=1)
        goal = max(ls.bands, key=lambda k: ls.bands[k][1] + u_max[k])
    sensor = sensor_design(model, ls, goal, scene.sensor_footprint, scene.sensor_radius, bas)
    stoch = None
    if noisy:
        from .stochastic import stochastic_summary
        stoch = stochastic_summary(model, sensor, start, (e, r), throws=min(throws, 2000),
                                   grid_throws=grid_throws, seeds=8, reference=ls)
    return Analysis(start, ls, radii, bas, sensor, stoch)
