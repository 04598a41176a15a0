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
Basins of the throw map, the grid of starts they use, and the design radii (Prop. IV.4).

A basin iterates f from a grid of starts (every stable edge x radii from R_min to R_max) and
says which limit set each start reaches and after how many throws.
"""

from dataclasses import dataclass
import math

import numpy as np

from .errors import NumericalError
from .orbits import flip_pattern, limit_set_from_orbit
from .status import LOST, OK


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
        lo, top = model.r_min(i), model.r_max(i)
        if not lo < top:
            continue        # no domain on this edge (finite_carry)
        hi = max(r_max, lo * 1.5)
        # Start 1 % of the range inside R_min: right at the toe-stub bound the hop, and with it
        # the jog, shrinks to nothing (an unstable fixed point that takes ages to leave). A
        # domain bounded above (finite_carry) ends 1 % inside its upper end.
        if hi >= top:
            hi = top - 0.01 * (top - lo)
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
        if status[s] != OK:
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
    flips = np.flatnonzero(res['kind'] == 'flip')
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
    # Edges on which f has no domain at all (finite_carry) can be landed on, never thrown from.
    stable = [i for i in part.stable_edges if model.r_min(i) < model.r_max(i)]
    # R_min, moved 1e-12 m inside the domain where the toe-stub bound (an open end) binds.
    lo = {i: max(model.r_min(i), -part.u_l[i] + 1e-12) for i in stable}
    r_flip = {}
    top = {i: model.r_max(i) for i in stable}
    for i in stable:
        hi = min(max(lo[i] * 2, lo[i] + 4 * part.r), top[i])
        found = None
        for _ in range(40):
            found, _ = _first_flip(model, i, lo[i], hi, samples)
            if found is not None or hi >= top[i]:
                break
            hi = min(2 * hi, top[i])
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
            ok = (res['status'] == OK) | lost
            if not ok.all():
                bad = int(np.flatnonzero(~ok)[0])
                raise NumericalError(model.error_message(int(res['status'][bad]), i,
                                                         float(rs[bad])))
            for j in stable:
                sel = res['edge'] == j
                if sel.any():
                    high = float(res['R'][sel].max())
                    low = float(res['R'][sel].min())
                    if low < lo[j]:
                        escapes.append((i, j, low))
                    if high > top[j]:
                        # lands beyond the domain's upper end (finite_carry): f stops there
                        escapes.append((i, j, high))
                        high = top[j]
                    if high > r_max[j] * (1 + 1e-12):
                        r_max[j] = high
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
