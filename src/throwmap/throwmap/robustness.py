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
Robustness of a design to bounded nondeterminism: a cell-mapping graph.

Every throw may use any release speed in [w - dw, w + dw] and any offset in [h - dh, h + dh]
(chosen adversarially, throw by throw). The states (edge, R) are cut into cells; each cell's
image is the hull, per landing edge, of f over samples of (R, w', h') in the cell x box,
widened by the largest jump between neighbouring R samples (so a cell's image is not taken
narrower than the samples' own spacing shows f moving). A cell whose image leaves the
covered R range, or whose throw fails, points to ESCAPE. Then "every adversarial sequence
reaches the limit set and a detection proves the goal edge" is a graph property
(:func:`check_graph`): the forward closure A* of the nominal limit set's cells has no escape,
flips only between the edges the nominal pattern flips between, shows no other edge to the
sensor; and outside A* the graph has no cycle and no escape (so every path enters A* within
the longest path's length, which bounds the transient).

What this proves and what it samples (docs/design.md): the graph logic is exact for the cell
map it is given; the cell map is sampled (K radii x 3 speeds x 3 offsets per cell, widened),
not an interval enclosure of f. The tests check it against exhaustive perturbation sequences.

The throws are the scene's own: the compiled cell map takes the scene's throw kernel
(throwmap.pipeline) and is called through its composed module (``model.composed.build_cells``,
``audit_cells``), each throw with a Context of its own speed and offset.
"""

from dataclasses import dataclass
import math

import numpy as np

from .design import _r_min
from .jit import njit
from .pipeline import with_design
from .status import OK, REC_COLS


def build_kernel(throw):
    """
    Return (build_cells, audit_cells) compiled over ``throw``, the scene's throw kernel.

    As throwmap.design.build_kernel: closures over pipeline.build's throw_one, called through
    the scene's composed module (``model.composed.build_cells``, ``audit_cells``).
    """

    @njit(cache=False)
    def build_cells(h, w, dh, dw, scene_ctx, prm, rec, r_top, m, k_r, lo, hi, succ_lo,
                    succ_hi, escape, progress, r_grasp):
        """
        Fill the cell map: succ_lo/hi[e, c, j] = range of cells on edge j (-1: none), escape[e, c].

        progress[e, c] > 0: every sample of the cell that stays on edge e jogs outwards by at least
        this much, so the cell's self-loop is progress (left within width / progress throws), and
        its image on e starts at the cell itself (a jog cannot go below its own R).

        lo[e], hi[e]: the covered R range of edge e ([largest R_min over the offsets, r_top]).
        scene_ctx, prm: the scene's Context and effect parameters.
        """
        part = scene_ctx.part
        mu = scene_ctx.mu
        n = part.n
        for e in range(n):
            lo[e] = math.nan
            hi[e] = math.nan
            if part.stable[e]:
                a, _ = _r_min(e, h - dh, mu, part)
                b, _ = _r_min(e, h + dh, mu, part)
                lo[e] = max(a, b)
                hi[e] = max(r_top, lo[e] * 1.5)
        succ_lo[:] = -1
        succ_hi[:] = -1
        escape[:] = False
        nw = 3 if dw > 0.0 else 1
        nh = 3 if dh > 0.0 else 1
        for e in range(n):
            if not part.stable[e]:
                continue
            width = (hi[e] - lo[e]) / m
            for c in range(m):
                r0 = lo[e] + c * width
                tmp_lo = r_grasp[n:2 * n]
                tmp_hi = r_grasp[2 * n:3 * n]
                for j in range(n):
                    tmp_lo[j] = math.inf
                    tmp_hi[j] = -math.inf
                jump = 0.0
                step = math.inf
                for iw in range(nw):
                    ww = w + dw * (iw - 1) if nw == 3 else w
                    for ih in range(nh):
                        hh = h + dh * (ih - 1) if nh == 3 else h
                        for j in range(n):
                            _, r_grasp[j] = _r_min(j, hh, mu, part)
                        prev_j = -1
                        prev_r = 0.0
                        for kr in range(k_r):
                            R = r0 + width * kr / (k_r - 1)
                            t = throw(e, R, 0.0, 0.0, with_design(scene_ctx, ww, hh, r_grasp[:n]),
                                      prm, rec)
                            j, r1, rot = t.edge, t.R, t.rot
                            if t.status != OK or not (lo[j] <= r1 <= hi[j]):
                                escape[e, c] = True
                                prev_j = -1
                                continue
                            if j == e:
                                if abs(rot) < math.pi and r1 > R:
                                    step = min(step, r1 - R)
                                else:
                                    step = 0.0
                            tmp_lo[j] = min(tmp_lo[j], r1)
                            tmp_hi[j] = max(tmp_hi[j], r1)
                            if prev_j == j:
                                jump = max(jump, abs(r1 - prev_r))
                            prev_j = j
                            prev_r = r1
                for j in range(n):
                    if tmp_lo[j] > tmp_hi[j]:
                        continue
                    wj = (hi[j] - lo[j]) / m
                    a = int(math.floor((tmp_lo[j] - jump - lo[j]) / wj))
                    b = int(math.floor((tmp_hi[j] + jump - lo[j]) / wj))
                    succ_lo[e, c, j] = max(0, min(m - 1, a))
                    succ_hi[e, c, j] = max(0, min(m - 1, b))
                progress[e, c] = step if 0.0 < step < math.inf else 0.0
                if progress[e, c] > 0.0:
                    succ_lo[e, c, e] = max(succ_lo[e, c, e], c)

    @njit(cache=False)
    def audit_cells(h, w, dh, dw, scene_ctx, prm, rec, lo, hi, succ_lo, succ_hi, escape,
                    progress, edges, cells, u_r, u_w, u_h, r_grasp, out):
        """
        Throw random interior samples of cell x box and count where the cell map is wrong.

        Sample k: state (edges[k], R at fraction u_r[k] of cell cells[k]), speed w + dw u_w[k],
        offset h + dh u_h[k] (u in [-1, 1]). A miss: the throw fails, lands outside the covered
        range or on an edge the cell has no successor on, lands in a cell outside the cell's
        successor range, or (a cell taken as jogging outwards) stays on its edge without moving
        out. out[0] = samples thrown, out[1] = misses, out[2] = samples below R_min (skipped).
        """
        part = scene_ctx.part
        mu = scene_ctx.mu
        n = part.n
        m = escape.shape[1]
        out[0] = 0
        out[1] = 0
        out[2] = 0
        for k in range(edges.size):
            e = edges[k]
            c = cells[k]
            hh = h + dh * u_h[k]
            ww = w + dw * u_w[k]
            R = lo[e] + (c + u_r[k]) * (hi[e] - lo[e]) / m
            for j in range(n):
                _, r_grasp[j] = _r_min(j, hh, mu, part)
            r_low, _ = _r_min(e, hh, mu, part)
            if R < r_low:
                out[2] += 1
                continue
            out[0] += 1
            t = throw(e, R, 0.0, 0.0, with_design(scene_ctx, ww, hh, r_grasp), prm, rec)
            j, r1, rot = t.edge, t.R, t.rot
            if t.status != OK or not (lo[j] <= r1 <= hi[j]) or succ_lo[e, c, j] < 0:
                out[1] += 1
                continue
            cc = int(math.floor((r1 - lo[j]) / ((hi[j] - lo[j]) / m)))
            if not (succ_lo[e, c, j] <= cc <= succ_hi[e, c, j]):
                out[1] += 1
            elif (j == e and cc == c and progress[e, c] > 0.0
                  and not (abs(rot) < math.pi and r1 > R)):
                out[1] += 1

    return build_cells, audit_cells


@dataclass(frozen=True)
class Audit:
    """audit()'s answer: random samples of cell x box checked against the cell map."""

    samples: int                # thrown
    misses: int                 # images the map does not contain
    skipped: int                # drawn below R_min at their offset
    miss_bound_95: float        # with 95 % confidence the missed fraction is below this

    def as_dict(self):
        return {'audit_samples': self.samples, 'audit_misses': self.misses,
                'audit_miss_bound_95': self.miss_bound_95}


def audit(model, h, w, dh, dw, cmap, samples=2000, seed=0):
    """
    Check the cell map on random samples of cell x box, with ``model``'s throws (a ThrowModel).

    The samples are uniform over its cells (every stable edge, every cell the map does not
    already mark as escaping) and over the error box. The cell map is sampled, not an
    enclosure of f; this says how much of cell x box it can miss: with no miss in N samples,
    the missed fraction (of the uniform measure on cell x box) is below 1 - 0.05^(1/N) (about
    3 / N) with 95 % confidence. Deterministic for a seed.
    """
    lo, hi, succ_lo, succ_hi, escape, progress = cmap
    part = model.part
    nodes = np.argwhere(~escape & np.asarray(part.stable)[:, None])
    rng = np.random.default_rng(seed)
    pick = nodes[rng.integers(0, len(nodes), samples)]
    out = np.zeros(3, dtype=np.int64)
    model.composed.audit_cells(float(h), float(w), float(dh), float(dw), model.ctx, model.prm,
                               np.empty((0, REC_COLS)), lo, hi, succ_lo, succ_hi, escape,
                               progress, pick[:, 0].astype(np.int64),
                               pick[:, 1].astype(np.int64), rng.random(samples),
                               rng.uniform(-1.0, 1.0, samples),
                               rng.uniform(-1.0, 1.0, samples), np.empty(part.n), out)
    thrown, misses = int(out[0]), int(out[1])
    bound = 1.0 - 0.05 ** (1.0 / thrown) if thrown and not misses else math.nan
    return Audit(thrown, misses, int(out[2]), bound)


def worst_case_sequences(model, h, w, dh, dw, cmap, verdict, limit, edges, radii, depth=5):
    """
    Check a robustness verdict by brute force: every sequence of ``depth`` worst-case throws.

    From each state (edges, radii) (the nominal limit set's, say), every throw at each corner
    of the error box (offset h +- dh, speed w +- dw) through the scene's own model: 4^depth
    sequences per state, independent of the cell map but for its cells. Returns counts:
    ``throws``; ``lost`` (a throw that did not come to rest in f's domain); ``outside`` (a
    state outside the closure A* the graph proved); ``seen_other`` (a state on an edge other
    than the goal whose part reaches the sensor at ``limit.x``).
    """
    lo, hi, succ_lo = cmap[0], cmap[1], cmap[2]
    width = (hi - lo) / succ_lo.shape[1]
    u_max = model.part.U.max(axis=1)
    corners = [model.at(h + sh * dh, w + sw * dw) for sh in (-1, 1) for sw in (-1, 1)]
    edges = np.asarray(edges, dtype=int)
    radii = np.asarray(radii, dtype=float)
    counts = {'throws': 0, 'lost': 0, 'outside': 0, 'seen_other': 0}

    def tally(e, r):
        cells = np.floor((r - lo[e]) / width[e]).astype(int)
        counts['outside'] += sum((a, b) not in verdict.closure for a, b in zip(e, cells))
        other = e != limit.goal
        counts['seen_other'] += int(np.sum(r[other] + u_max[e[other]] >= limit.x))

    tally(edges, radii)
    for _ in range(depth):
        outs = [c.f_batch(edges, radii) for c in corners]
        counts['throws'] += edges.size * len(corners)
        ok = [o['status'] == OK for o in outs]
        counts['lost'] += int(sum(np.sum(~k) for k in ok))
        edges = np.concatenate([o['edge'][k] for o, k in zip(outs, ok)]).astype(int)
        radii = np.concatenate([o['R'][k] for o, k in zip(outs, ok)])
        tally(edges, radii)
    return counts


@dataclass(frozen=True)
class GraphVerdict:
    """check_graph's answer: ``ok`` and, if not, the first reason; A* and the transient bound."""

    ok: bool
    reason: str
    closure_cells: int
    transient_bound: int        # longest path (throws) from any start cell into A*
    false_top: float            # highest shadow top of a non-goal cell in A* (+ footprint)
    closure: frozenset = frozenset()    # A*: its (edge, cell) nodes


def cell_map(model, h, w, dh, dw, r_top, cells=120, samples=5):
    """
    Return (lo, hi, succ_lo, succ_hi, escape, progress) of the cell map (build_cells).

    The throws are ``model``'s (a ThrowModel: its effects; with finite_arm a throw off the arm
    escapes, as one that fails).
    """
    n = model.part.n
    lo = np.empty(n)
    hi = np.empty(n)
    succ_lo = np.empty((n, cells, n), dtype=np.int64)
    succ_hi = np.empty((n, cells, n), dtype=np.int64)
    escape = np.zeros((n, cells), dtype=np.bool_)
    progress = np.zeros((n, cells))
    model.composed.build_cells(float(h), float(w), float(dh), float(dw), model.ctx, model.prm,
                               np.empty((0, REC_COLS)), float(r_top), int(cells), int(samples),
                               lo, hi, succ_lo, succ_hi, escape, progress, np.empty(3 * n))
    return lo, hi, succ_lo, succ_hi, escape, progress


def check_graph(part, cmap, bands, flips, goal, x, footprint, r_start_top):
    """
    Check the graph property (module docstring) on the cell map ``cmap``.

    ``bands``: (n, 2) nominal limit-set R band per edge (NaN: absent); ``flips``: set of (e, j)
    edge changes the nominal limit set makes; the sensor at ``x`` with half-width
    ``footprint`` must see no edge but ``goal`` in A*; starts: every cell below r_start_top.
    """
    lo, hi, succ_lo, succ_hi, escape, progress = cmap
    n, m = escape.shape
    stable = [e for e in range(n) if part.stable[e]]
    width = {e: (hi[e] - lo[e]) / m for e in stable}

    def succ(node):
        e, c = node
        for j in stable:
            a = succ_lo[e, c, j]
            if a >= 0:
                for cc in range(a, succ_hi[e, c, j] + 1):
                    if (j, cc) != node or progress[e, c] <= 0.0:
                        yield (j, cc)

    def stay(node):
        # Throws a jogging cell may keep the part before it moves on (its self-loop).
        e, c = node
        return int(math.ceil(width[e] / progress[e, c])) - 1 if progress[e, c] > 0.0 else 0

    seeds = []
    for e in stable:
        if np.isnan(bands[e, 0]):
            continue
        a = int(math.floor((bands[e, 0] - lo[e]) / width[e]))
        b = int(math.floor((bands[e, 1] - lo[e]) / width[e]))
        if a < 0 or b >= m:
            return GraphVerdict(False, f'the limit set on edge {e} lies outside the cells',
                                0, -1, math.nan)
        seeds.extend((e, c) for c in range(a, b + 1))
    closure = set(seeds)
    stack = list(seeds)
    u_max = part.U.max(axis=1)
    false_top = -math.inf
    while stack:
        node = stack.pop()
        if escape[node]:
            return GraphVerdict(False, f'from the limit set (edge {node[0]}, R near '
                                f'{lo[node[0]] + node[1] * width[node[0]]:.4g} m) a throw '
                                'escapes (fails, or leaves the covered R range)',
                                len(closure), -1, math.nan)
        for nxt in succ(node):
            if nxt[0] != node[0] and (node[0], nxt[0]) not in flips:
                return GraphVerdict(False, f'a flip {node[0]} -> {nxt[0]} the nominal limit set '
                                    'never makes', len(closure), -1, math.nan)
            if nxt not in closure:
                closure.add(nxt)
                stack.append(nxt)
    for e, c in closure:
        if e != goal:
            false_top = max(false_top, lo[e] + (c + 1) * width[e] + u_max[e] + footprint)
    if false_top >= x:
        return GraphVerdict(False, f'edge {goal} is no longer proven: another edge reaches '
                            f'{false_top:.4g} m, the sensor is at {x:.4g} m', len(closure), -1,
                            false_top)
    # Outside A*: no escape, no cycle; the longest path bounds the transient (iterative DFS).
    depth = {}
    on_path = set()
    for e in stable:
        top = int(math.floor((r_start_top - lo[e]) / width[e]))
        # Starts 1 % inside R_min, as the basin grid's (basins.default_grid): at R_min itself
        # the jog shrinks to nothing.
        first = int(math.floor(0.01 * (r_start_top - lo[e]) / width[e]))
        for c in range(first, min(m - 1, top) + 1):
            root = (e, c)
            if root in closure or root in depth:
                continue
            stack = [(root, iter(list(succ(root))))]
            on_path.add(root)
            if escape[root]:
                return GraphVerdict(False, f'from edge {e} at R near '
                                    f'{lo[e] + c * width[e]:.4g} m a throw escapes',
                                    len(closure), -1, false_top)
            best = {root: stay(root)}
            while stack:
                node, it = stack[-1]
                advanced = False
                for nxt in it:
                    if nxt in closure:
                        best[node] = max(best[node], stay(node) + 1)
                        continue
                    if nxt in on_path:
                        return GraphVerdict(False, f'a cycle outside the limit set through '
                                            f'edge {nxt[0]} at R near '
                                            f'{lo[nxt[0]] + nxt[1] * width[nxt[0]]:.4g} m: '
                                            'some sequence never reaches it', len(closure), -1,
                                            false_top)
                    if nxt in depth:
                        best[node] = max(best[node], stay(node) + depth[nxt] + 1)
                        continue
                    if escape[nxt]:
                        return GraphVerdict(False, f'a start leads to an escape (edge {nxt[0]}, '
                                            f'R near {lo[nxt[0]] + nxt[1] * width[nxt[0]]:.4g}'
                                            ' m)', len(closure), -1, false_top)
                    on_path.add(nxt)
                    best[nxt] = stay(nxt)
                    stack.append((nxt, iter(list(succ(nxt)))))
                    advanced = True
                    break
                if not advanced:
                    stack.pop()
                    on_path.discard(node)
                    depth[node] = best[node]
                    if stack:
                        parent = stack[-1][0]
                        best[parent] = max(best[parent], stay(parent) + depth[node] + 1)
    bound = max(depth.values()) if depth else 0
    return GraphVerdict(True, '', len(closure), int(bound), false_top, frozenset(closure))


@dataclass(frozen=True)
class Robustness:
    """The largest per-throw errors under which check_graph still holds (bisection)."""

    speed_error: float          # rad/s: +-dw alone
    offset_error: float         # m: +-dh alone
    joint_fraction: float       # s: +-s w and +-s d_min together
    joint_verdict: GraphVerdict
    nominal_verdict: GraphVerdict
    cells: int
    samples: int
    audit: Audit = None         # the joint box's cell map on random samples (None: nominal fails)

    def as_dict(self):
        d = {'speed_error': self.speed_error, 'offset_error': self.offset_error,
             'joint_fraction': self.joint_fraction,
             'transient_bound': self.joint_verdict.transient_bound,
             'nominal_ok': self.nominal_verdict.ok, 'nominal_reason':
             self.nominal_verdict.reason, 'cells': self.cells, 'samples': self.samples}
        if self.audit is not None:
            d.update(self.audit.as_dict())
        return d


def robust_check(model, h, w, dh, dw, limit, cells=120, samples=5, with_map=False):
    """check_graph for the box (dh, dw) around the design; ``limit``: a LimitSpec."""
    cmap = cell_map(model, h, w, dh, dw, limit.r_top, cells, samples)
    verdict = check_graph(model.part, cmap, limit.bands, limit.flips, limit.goal, limit.x,
                          limit.footprint, limit.r_start_top)
    return (verdict, cmap) if with_map else verdict


@dataclass(frozen=True)
class LimitSpec:
    """The nominal design's limit set and sensor, as check_graph needs them."""

    bands: np.ndarray
    flips: frozenset
    goal: int
    x: float
    footprint: float
    r_start_top: float      # starts: every cell up to the basin grid's top
    r_top: float            # covered range: up to this (above the grid, room to move)


# The largest error searched for, as a fraction (of w and of d_min): beyond 20 % a feeder is
# no longer the design it was computed for.
S_MAX = 0.2


def largest_error(check, s_max=S_MAX, steps=10):
    """Largest s in [0, s_max] with check(s).ok, by bisection (check(0) must hold)."""
    if check(s_max).ok:
        return s_max
    a, b = 0.0, s_max
    for _ in range(steps):
        mid = 0.5 * (a + b)
        if check(mid).ok:
            a = mid
        else:
            b = mid
    return a


def robustness(model, h, w, limit, cells=120, samples=5, s_max=S_MAX, steps=10,
               audit_samples=20000):
    """
    Largest errors: speed alone (+-s w), offset alone (+-s d_min), both at once (s).

    Errors are found on a bisection of s (10 steps: to s_max / 1024) assuming the property
    is monotone in the box (a larger box only adds samples and so edges to the graph). The
    joint box's cell map is then audited on ``audit_samples`` random samples (:func:`audit`).
    """
    def at(dh, dw, with_map=False):
        return robust_check(model, h, w, dh, dw, limit, cells, samples, with_map)

    nominal = at(0.0, 0.0)
    if not nominal.ok:
        return Robustness(0.0, 0.0, 0.0, nominal, nominal, cells, samples)
    d = float(model.part.d_min)
    s_w = largest_error(lambda s: at(0.0, s * w), s_max, steps)
    s_h = largest_error(lambda s: at(s * d, 0.0), s_max, steps)
    s_j = largest_error(lambda s: at(s * d, s * w), min(s_w, s_h), steps)
    joint, cmap = at(s_j * d, s_j * w, with_map=True)
    checked = audit(model, h, w, s_j * d, s_j * w, cmap, audit_samples)
    return Robustness(s_w * w, s_h * d, s_j, joint, nominal, cells, samples, checked)
