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
Funnelling (the paper's last section; issue 25): choose each throw's release speed.

The states are the cells of throwmap.robustness's cell map (every stable edge's R range, from
R_min to the arm's end, cut into ``cells`` cells); for each speed w the actuator allows, the
cell map under the per-throw error box (every throw at any speed in w +- s w and any offset in
h +- s d_min, as the design search's robustness defines it) gives each cell's successors and
whether a throw from it may escape (fail, or leave the arm: a loss). A speed that may escape
from any cell the part may be in is never chosen.

**Knowledge** is the set of cells consistent with the speeds used and the bits seen: after a
throw at speed k and bit b it is ``succ_k(knowledge) & cells that can read b``. **A ready is
proven** when the bit is 1 and every cell of the knowledge is on the goal edge (every cell
that could have read 1 is on the goal edge): the search's and the monitor's rule ("a
detection after the warm-up proves the goal edge", where the warm-up is the time after which
no state reachable from the starts shows another edge to the sensor) with the reachable set
narrowed by the bits seen and widened by the error box.

Policies (:func:`simulate` runs them; docs/funnel.md has the measured figures):

* **fixed**: the scene's own speed every throw, readies by the rule above;
* **sensor-based**: :class:`Chooser`, a one-step rule on the knowledge: the speed after which a
  detection would prove a ready with the largest chance (the part taken as equally likely in
  any cell of the image), then the fewest cells of other edges the sensor may see, then the
  scene's own speed. A heuristic; the proof never depends on it;
* **open-loop**: the same rule on the knowledge without bits, which gives one speed sequence
  for every part (:func:`open_loop_sequence`); its readies use that bit-free knowledge too.

No exact minimax over knowledge sets: near R_min the cells are their own successors at every
speed (the jogs there are far shorter than a cell), so a knowledge set can never exclude that a
part placed there is still there, and every policy's worst case on the cell abstraction is
unbounded. The figures are measured point by point from every start of the design search's
grid through the scene's model (nominal throws, and throws drawn in the error box), every
ready checked against the true state. The lower bounds next to them (throwmap.funnel_bound):
the full-knowledge shortest path on the cells, and the one-bit bound (what any policy that reads
only the bit and never risks the part needs). :func:`policy_dict` writes the sensor-based policy
for the nodes; :class:`Tracker` runs it on line (numpy only).
"""

import copy
from dataclasses import dataclass, field
import json
import math
import os

import numpy as np

from . import design as D
from .analysis import scene_analysis
from .basins import default_grid, design_radii
from .errors import InputError
from .funnel_bound import full_knowledge_bound, one_bit_bound
from .robustness import cell_map
from .scene import Scene
from .sensor import seen_radii, sees


# ------------------------------------------------------------------------------ speeds, arm

MAX_SPEEDS = 200      # each speed is a cell map of cells x 45 throws per cell
MAX_CELLS = 2000      # cells per stable edge: the knowledge sets are sets of cells


def parse_speeds(text):
    """
    Return the allowed release speeds (rad/s, ascending) from ``A:B:STEP`` or ``A,B,...`` (deg/s).

    Raises InputError naming the problem and the fix.
    """
    fix = ('give --speeds A:B:STEP in deg/s with 0 < A <= B and STEP > 0 (e.g. 120:600:20), '
           'or a list of speeds in deg/s (e.g. 200,320,400)')
    text = str(text).strip()
    try:
        parts = [float(x) for x in (text.split(':') if ':' in text else
                                    (x for x in text.split(',') if x.strip()))]
    except ValueError:
        raise InputError('--speeds', f'{text!r} is not a number range or list', fix) from None
    if ':' in text:
        if len(parts) != 3:
            raise InputError('--speeds', f'{text!r} is not A:B:STEP', fix)
        a, b, step = parts
        if not (all(map(math.isfinite, parts)) and 0 < a <= b and step > 0):
            raise InputError('--speeds', f'bad range {text!r}', fix)
        count = math.floor((b - a) / step * (1.0 + 1e-12)) + 1    # before allocating them
        if count > MAX_SPEEDS:
            raise InputError('--speeds', f'{count} speeds: too many (each is a cell map)',
                             f'use a coarser STEP (at most {MAX_SPEEDS} speeds)')
        # the counted speeds, not np.arange's: its padded end is a span of its own when A = B
        # is huge (1e15:1e15:1 made a million speeds, 1e308 failed to allocate)
        deg = a + step * np.arange(count)
    else:
        deg = np.array(sorted(set(parts)))
        if not deg.size or not np.all(np.isfinite(deg)) or np.any(deg <= 0):
            raise InputError('--speeds', f'bad list {text!r}', fix)
    if deg.size > MAX_SPEEDS:
        raise InputError('--speeds', f'{deg.size} speeds: too many (each is a cell map)',
                         f'use a coarser STEP (at most {MAX_SPEEDS} speeds)')
    return np.radians(deg)


def arm_scene(scene, arm_length=None):
    """
    Return (scene on its arm, note): the scene with ``arm.length`` and effect finite_arm.

    ``arm_length`` (m) overrides the scene's. A scene with an arm length but without effect
    finite_arm gets the effect: a throw past the arm's end is a loss, never an allowed move.
    A scene without an arm and no ``arm_length`` is refused: the funnel needs the arm's end.
    """
    length = scene.arm_length if arm_length is None else float(arm_length)
    if length is None:
        raise InputError('arm.length', f'{scene.name} gives no arm length, and the funnel needs '
                         "the arm's end (a throw past it loses the part)",
                         "give --arm-length CM (the paper's arm: --arm-length 40), or "
                         'arm: {length_cm: ...} in the scene')
    if not (math.isfinite(length) and length > 0):
        raise InputError('arm length', f'must be > 0, got {length!r} m',
                         "give the arm's length, e.g. --arm-length 40 (cm)")
    effects = list(scene.data.get('effects') or [])
    if length == scene.arm_length and 'finite_arm' in effects:
        return scene, None
    data = copy.deepcopy(scene.data)
    data['arm'] = {k: v for k, v in data['arm'].items() if k not in ('length', 'length_cm')}
    data['arm']['length'] = length
    if 'finite_arm' not in effects:
        effects.append('finite_arm')
    data['effects'] = effects
    note = (f'on a {length * 100:.1f} cm arm with effect finite_arm'
            + ('' if scene.arm_length is None or length == scene.arm_length
               else f' (the scene says {scene.arm_length * 100:.1f} cm)'))
    return Scene(data, source=scene.source, seed=scene.seed), note


# ------------------------------------------------------------------------------ the cells

@dataclass
class CellSystem:
    """
    The cell abstraction of the feeder for a set of speeds (module docstring).

    Cells are numbered edge by edge (``edges``: the stable edges, ``m`` cells each); cell
    ``i * m + c`` of edge ``edges[i]`` covers R in [lo[i] + c width_i, lo[i] + (c + 1) width_i].
    ``succ[k, a, b]``: a throw at speed k from cell a may land in cell b; ``escape[k, a]``: it
    may fail or leave the arm. ``can_see`` / ``can_miss``: some R of the cell is / is not seen.
    """

    speeds: np.ndarray          # rad/s
    h: float
    dh: float                   # offset error bound, m
    dw: np.ndarray              # speed error bound per speed, rad/s
    robust: float               # s
    edges: list
    m: int
    lo: np.ndarray
    hi: np.ndarray
    succ: np.ndarray            # (K, N, N) bool
    escape: np.ndarray          # (K, N) bool
    can_see: np.ndarray         # (N,) bool
    can_miss: np.ndarray
    goal: np.ndarray            # (N,) bool: cells on the goal edge
    goal_edge: int
    sensor_radius: float
    footprint: float
    arm_length: float
    samples: int
    # (K, N): the cell map's least outward jog of a cell that jogs outwards (0: none), m; not
    # used by the rules yet (a clock for the knowledge near R_min: docs/funnel.md)
    progress: np.ndarray = field(default=None, repr=False)

    @property
    def n(self):
        return self.goal.size

    def _place(self, edge, R):
        """Return (i, c): edge's index and R's cell on it, c not clipped to the cells."""
        i = self.edges.index(edge)
        return i, int(math.floor((R - self.lo[i]) / ((self.hi[i] - self.lo[i]) / self.m)))

    def cell(self, edge, R):
        """Return the cell index of (edge, R), -1 outside the covered range or off the edges."""
        if edge not in self.edges:
            return -1
        i, c = self._place(edge, R)
        if not 0 <= c < self.m:
            return -1
        return i * self.m + c

    def cells_between(self, edge, r_lo, r_hi):
        """Return the slice of cell indices of edge meeting [r_lo, r_hi] (empty: none)."""
        if edge not in self.edges:
            return slice(0, 0)
        i, a = self._place(edge, r_lo)
        _, b = self._place(edge, r_hi)
        a, b = max(a, 0), min(b, self.m - 1)
        return slice(i * self.m + a, i * self.m + b + 1) if a <= b else slice(0, 0)

    def bounds(self, index):
        """Return (edge, R_low, R_high) of a cell."""
        i, c = divmod(int(index), self.m)
        width = (self.hi[i] - self.lo[i]) / self.m
        return self.edges[i], self.lo[i] + c * width, self.lo[i] + (c + 1) * width

    def allowed(self, know, k):
        """Tell whether speed k may be used: no cell of the knowledge may escape."""
        return not np.any(self.escape[k] & know)

    def image(self, know, k):
        """Return the cells a throw at speed k may reach from the knowledge set."""
        return np.any(self.succ[k][know], axis=0)

    def update(self, know, k, bit):
        """Return the knowledge after a throw at speed k that read ``bit``."""
        return self.image(know, k) & (self.can_see if bit else self.can_miss)

    def proven(self, know, bit):
        """Tell whether a reading ``bit`` with knowledge ``know`` (after it) proves a ready."""
        return bool(bit) and bool(know.any()) and not np.any(know & ~self.goal)


def build_system(scene, speeds, robust=0.005, cells=160, samples=5, sensor_radius=None,
                 goal_edge=None, footprint=None):
    """
    Build the CellSystem of ``scene`` (on its arm: :func:`arm_scene`) for ``speeds`` (rad/s).

    The cell maps are throwmap.robustness.cell_map's, one per speed, at the scene's offset h,
    with the error box dh = robust d_min, dw = robust w, covering every stable edge up to the
    arm's end. The sensor: ``sensor_radius``, ``goal_edge``, ``footprint`` (default: the
    scene's analysis, as the monitor uses it).
    """
    if not (isinstance(robust, (int, float)) and 0.0 <= robust < 0.2):
        raise InputError('--robust', f'must be in [0, 0.2), got {robust!r}',
                         'give the per-throw error bound as a fraction, e.g. 0.005')
    model = scene.model
    arm = model.arm_length
    if not math.isfinite(arm):
        raise InputError('arm.length', 'the scene has no arm end', 'call arm_scene first')
    if sensor_radius is None or goal_edge is None or footprint is None:
        an = scene_analysis(scene, sensor_radius or 0.0)
        sensor_radius = an.sensor.radius if sensor_radius is None else sensor_radius
        goal_edge = an.sensor.goal_edge if goal_edge is None else goal_edge
        footprint = an.sensor.footprint if footprint is None else footprint
    part = model.part
    edges = list(part.stable_edges)
    if goal_edge not in edges:
        raise InputError('sensor.goal_edge', f'{goal_edge!r} is not a stable edge',
                         f'use one of {edges}')
    dh = robust * float(part.d_min)
    K, E = len(speeds), len(edges)
    N = E * cells
    succ = np.zeros((K, N, N), dtype=np.bool_)
    escape = np.zeros((K, N), dtype=np.bool_)
    progress = np.zeros((K, N))
    lo = hi = None
    for k, w in enumerate(speeds):
        c_lo, c_hi, s_lo, s_hi, esc, prog = cell_map(model, model.h, float(w), dh,
                                                     robust * w, arm, cells, samples)
        if lo is None:
            lo, hi = c_lo[edges].copy(), c_hi[edges].copy()
        # The cells depend on h, dh and the arm only, so every speed's map has the same cells.
        assert np.allclose(lo, c_lo[edges]) and np.allclose(hi, c_hi[edges])
        for i, e in enumerate(edges):
            escape[k, i * cells:(i + 1) * cells] = esc[e]
            progress[k, i * cells:(i + 1) * cells] = prog[e]
            for j, f in enumerate(edges):
                a = s_lo[e, :, f]
                b = s_hi[e, :, f]
                for c in np.nonzero(a >= 0)[0]:
                    succ[k, i * cells + c, j * cells + a[c]:j * cells + b[c] + 1] = True
    width = (hi - lo) / cells
    c_idx = np.arange(cells)
    a = (lo[:, None] + c_idx[None, :] * width[:, None])
    b = a + width[:, None]
    seen_lo, seen_hi = seen_radii(part, sensor_radius, footprint)
    seen_lo, seen_hi = seen_lo[edges][:, None], seen_hi[edges][:, None]
    can_see = ((a <= seen_hi) & (b >= seen_lo)).ravel()
    can_miss = ((a < seen_lo) | (b > seen_hi)).ravel()
    goal = np.zeros(N, dtype=np.bool_)
    gi = edges.index(goal_edge)
    goal[gi * cells:(gi + 1) * cells] = True
    return CellSystem(np.asarray(speeds, dtype=float), float(model.h), dh,
                      robust * np.asarray(speeds, dtype=float), float(robust), edges, cells,
                      lo, hi, succ, escape, can_see, can_miss, goal, int(goal_edge),
                      float(sensor_radius), float(footprint), float(arm), samples, progress)


def start_grid(scene, radii_per_edge=20):
    """
    Return (edges, radii) of the design search's grid of starts at the scene's design.

    Every stable edge x ``radii_per_edge`` radii from 1 % above R_min to the top of Z
    (throwmap.basins.default_grid; the design kernel uses the same rule with 20 radii).
    """
    model = scene.model.nominal()
    return default_grid(model, radii_per_edge, design_radii(model)['R_max_all'])


def start_knowledge(system, starts):
    """Return the knowledge of a fresh part: every cell between the lowest and highest start."""
    know = np.zeros(system.n, dtype=np.bool_)
    edges, radii = starts
    for e in {int(x) for x in edges}:
        rs = radii[edges == e]
        a = system.cell(e, float(rs.min()))
        b = system.cell(e, float(rs.max()))
        if a < 0 or b < 0:
            raise InputError('starts', f'the starts on edge {e} ({rs.min():.4g}..'
                             f'{rs.max():.4g} m) lie outside the cells', 'give a longer arm')
        know[a:b + 1] = True
    return know


# ------------------------------------------------------------------------------ policies

POLICIES = ('fixed', 'open-loop', 'sensor-based')


class Chooser:
    """
    The speed rule of the open-loop and sensor-based policies: one-step, opportunistic.

    For knowledge B and each speed k that cannot escape from B: the image I = succ_k(B) and
    its cells the sensor may see, S. If every cell of S is on the goal edge, a detection after
    this throw proves a ready; its chance, were the part equally likely in any cell of I, is
    |S| / |I|. The speed with the largest such chance wins; then the one leaving the fewest
    cells of other edges the sensor may see; then the scene's own speed ``home`` (whose limit
    set the design search proved clean of other edges at the sensor), then the slowest. A
    heuristic: the proof never depends on it. Decisions are memoised per knowledge set.

    Tried and measured worse on the triangle (docs/funnel.md): the mean over I of the
    full-knowledge distance (a QMDP-like rule), which ignores that a proof needs the seen
    cells clean.
    """

    def __init__(self, system, home, home_first=False):
        self.system = system
        self.home = int(home)
        # The open-loop rule (no bits) prefers the home speed to fewer foreign cells: without
        # bits only the home speed's limit set ever clears the sensor of other edges.
        self.home_first = home_first
        self.memo = {}

    def __call__(self, know):
        key = _key(know)
        if key in self.memo:
            return self.memo[key]
        s = self.system
        best, best_k = None, -1
        for k in range(len(s.speeds)):
            if not s.allowed(know, k):
                continue
            img = s.image(know, k)
            if not img.any():
                continue
            seen = img & s.can_see
            foreign = int(np.count_nonzero(seen & ~s.goal))
            chance = (np.count_nonzero(seen) / np.count_nonzero(img)
                      if seen.any() and not foreign else 0.0)
            score = ((-round(chance, 6), k != self.home, foreign) if self.home_first
                     else (-round(chance, 6), foreign, k != self.home))
            if best is None or score < best:
                best, best_k = score, k
        self.memo[key] = best_k
        return best_k


def _key(know):
    return np.packbits(know).tobytes()


def open_loop_sequence(system, know, chooser, throws):
    """
    Return the open-loop policy's speeds (indices) for ``throws`` throws from ``know``.

    The chooser's rule applied to the knowledge without bits (each set the image of the last):
    the sequence is the same for every part; -1 where no speed is allowed.
    """
    seq = []
    for _ in range(throws):
        k = chooser(know)
        seq.append(k)
        if k < 0:
            break
        know = system.image(know, k)
    return seq + [-1] * (throws - len(seq))


@dataclass
class Run:
    """Per start: throws to the first proven ready (inf: none), and what went wrong if so."""

    throws: np.ndarray
    false_readies: int          # readies whose true state was not on the goal edge (must be 0)
    knowledge_lost: int         # the true state left the knowledge (the cell map missed it)
    lost: int                   # starts whose part left the arm or whose throw failed
    speeds_used: list           # per start, the speeds (indices) thrown
    stuck: int = 0              # starts whose knowledge reached a set no speed is safe from

    def figures(self):
        return summary(self.throws)


def summary(throws):
    """Return mean, p95 and worst of throws to the first ready (inf when some start has none)."""
    t = np.asarray(throws, dtype=float)
    if not t.size:
        return {'mean': math.nan, 'p95': math.nan, 'worst': math.nan, 'never': 0}
    never = int(np.count_nonzero(~np.isfinite(t)))
    # Linear interpolation between neighbours (np.percentile's, as the design search's p95);
    # a neighbour that never readied makes it inf (np.percentile would give nan, or a huge
    # number for a stand-in).
    ranked = np.sort(t)
    pos = 0.95 * (ranked.size - 1)
    lo, frac = int(math.floor(pos)), pos - math.floor(pos)
    if frac == 0.0 or not np.isfinite(ranked[lo + 1]):
        p95 = float(ranked[lo]) if frac == 0.0 else math.inf
    else:
        p95 = float(ranked[lo] + (ranked[lo + 1] - ranked[lo]) * frac)
    return {'mean': float(t.mean()) if not never else math.inf,
            'p95': p95, 'worst': float(t.max()), 'never': never,
            'mean_of_readied': float(t[np.isfinite(t)].mean()) if never < t.size else math.nan}


class Thrower:
    """The scene's model at each allowed speed (and at the error box's corners), memoised."""

    def __init__(self, scene, system):
        self.scene = scene
        self.system = system
        self.models = {}

    def model(self, k, u_w=0, u_h=0):
        key = (k, u_w, u_h)
        if key not in self.models:
            s = self.system
            self.models[key] = self.scene.model.at(s.h + u_h * s.dh,
                                                   float(s.speeds[k] + u_w * s.dw[k])).nominal()
        return self.models[key]

    def throw(self, k, edge, R, u_w=0, u_h=0):
        res = self.model(k, u_w, u_h).f_batch(np.array([edge]), np.array([R]))
        if res['status'][0] != 0 or res['edge'][0] < 0:
            return -1, math.nan
        return int(res['edge'][0]), float(res['R'][0])


def simulate(system, thrower, starts, policy, chooser=None, sequence=None, fixed=None,
             max_throws=200, errors=None, seed=0):
    """
    Run a policy from every start through the scene's model; return a :class:`Run`.

    ``policy``: 'fixed' (speed index ``fixed`` every throw, knowledge with the bits),
    'open-loop' (``sequence``; the proof uses the knowledge without earlier bits),
    'sensor-based' (``chooser`` on the knowledge with the bits). ``errors``: None (nominal
    throws) or 'random' (each throw at a corner, edge midpoint or the centre of the error box,
    drawn uniformly, seeded). A ready is counted only when :meth:`CellSystem.proven` says so;
    it is checked against the true state (``false_readies``).
    """
    part = thrower.scene.model.part
    rng = np.random.default_rng(seed)
    edges, radii = starts
    know0 = start_knowledge(system, starts)
    out = np.full(len(edges), np.inf)
    false_readies = knowledge_lost = lost = stuck = 0
    used = []
    for i, (e, R) in enumerate(zip(edges, radii)):
        e, R = int(e), float(R)
        know = know0.copy()
        blind = know0.copy()    # the open-loop knowledge: images only
        speeds = []
        for t in range(1, max_throws + 1):
            if policy == 'fixed':
                k = fixed if system.allowed(know, fixed) else -1
            elif policy == 'open-loop':
                k = sequence[t - 1] if t - 1 < len(sequence) else -1
            else:
                k = chooser(know)
            if k < 0:
                stuck += 1
                break
            speeds.append(k)
            u_w, u_h = ((0, 0) if errors is None
                        else (int(rng.integers(-1, 2)), int(rng.integers(-1, 2))))
            e, R = thrower.throw(k, e, R, u_w, u_h)
            if e < 0:
                lost += 1
                break
            bit = bool(sees(part, e, R, system.sensor_radius, system.footprint))
            know = system.update(know, k, bit)
            blind = system.image(blind, k)
            c = system.cell(e, R)
            if c < 0 or not know[c]:
                knowledge_lost += 1
                break
            rule = (blind & (system.can_see if bit else system.can_miss)
                    if policy == 'open-loop' else know)
            if system.proven(rule, bit):
                out[i] = t
                if e != system.goal_edge:
                    false_readies += 1
                break
        used.append(speeds)
    return Run(out, false_readies, knowledge_lost, lost, used, stuck)


# ------------------------------------------------------------------------------ the plan

@dataclass
class FunnelResult:
    """:func:`plan`'s answer: per start throws to the first ready, per policy, and the bound."""

    system: CellSystem
    starts: tuple
    home: int                   # index of the scene's own speed among the speeds (nearest)
    runs: dict                  # policy -> Run (nominal throws)
    noisy: dict                 # policy -> Run (throws drawn in the error box)
    bound: np.ndarray           # per start: full-knowledge fewest throws
    safe_bound: np.ndarray      # the same with only the speeds safe from the start set
    safe_speeds: list           # those speeds (indices)
    one_bit: object             # funnel_bound.OneBitBound, or None when not computed
    sequence: list              # the open-loop speeds (indices)
    notes: list
    search_figures: dict        # the design kernel's own first-ready figures, fixed design

    def figures(self):
        rows = {'bound': summary(self.bound), 'safe-speed bound': summary(self.safe_bound)}
        if self.one_bit is not None:
            rows['one-bit bound'] = summary(self.one_bit.throws)
        for name, run in self.runs.items():
            rows[name] = dict(run.figures(), false_readies=run.false_readies,
                              knowledge_lost=run.knowledge_lost, lost=run.lost,
                              no_safe_speed=run.stuck)
            noisy = self.noisy.get(name)
            if noisy is not None:
                rows[name + ' (errors)'] = dict(noisy.figures(),
                                                false_readies=noisy.false_readies,
                                                knowledge_lost=noisy.knowledge_lost,
                                                lost=noisy.lost, no_safe_speed=noisy.stuck)
        return rows


def plan(scene, speeds, robust=0.005, cells=200, samples=5, radii_per_edge=20,
         max_throws=200, noisy_seed=0, one_bit=False, progress=None):
    """
    Build the cells, the bounds and the three policies for ``scene`` on its arm; run them.

    ``scene`` must have an arm end (:func:`arm_scene`). The scene's own speed is added to
    ``speeds`` when it is not there (the fixed design). ``one_bit``: also compute
    throwmap.funnel_bound.one_bit_bound (seconds to a minute; ``progress(done, total)`` per
    start). Returns a :class:`FunnelResult`.
    """
    notes = []
    speeds = np.asarray(speeds, dtype=float)
    w0 = float(scene.model.w)
    if not np.any(np.isclose(speeds, w0, rtol=0, atol=1e-9)):
        speeds = np.sort(np.append(speeds, w0))
        notes.append(f"the scene's own speed {math.degrees(w0):.3f} deg/s was added to the "
                     'allowed speeds (the fixed design throws it)')
    home = int(np.argmin(abs(speeds - w0)))
    system = build_system(scene, speeds, robust, cells, samples)
    starts = start_grid(scene, radii_per_edge)
    know0 = start_knowledge(system, starts)
    if not any(system.allowed(know0, k) for k in range(len(speeds))):
        width = float(np.max((system.hi - system.lo) / system.m))
        raise InputError('--cells', 'every allowed speed may lose a part from the start cells '
                         '(the first cells, at R_min itself, escape in the cell map); cells '
                         f'are up to {width * 100:.3g} cm wide ({system.m} per edge up to '
                         f"the arm's end at {system.arm_length * 100:.4g} cm)",
                         'give more --cells (each then lies nearer R_min than the starts), or '
                         "check the arm's length (--arm-length is in cm)")
    dist = full_knowledge_bound(system)
    cells0 = [system.cell(int(e), float(r)) for e, r in zip(*starts)]
    bound = dist[cells0]
    # Not a bound on the policies (narrower knowledge may allow more speeds): what full
    # knowledge gives with only the speeds no start can be lost by, to show what the arm costs.
    safe = [k for k in range(len(speeds)) if system.allowed(know0, k)]
    safe_bound = full_knowledge_bound(system, safe)[cells0]
    chooser = Chooser(system, home)
    sequence = open_loop_sequence(system, know0, Chooser(system, home, home_first=True),
                                  max_throws)
    thrower = Thrower(scene, system)
    bound_1 = (one_bit_bound(system, [thrower.model(k) for k in range(len(speeds))], starts,
                             dist, max_throws=max(max_throws, 300), progress=progress)
               if one_bit else None)
    runs, noisy = {}, {}
    for name in POLICIES:
        kw = {'chooser': chooser, 'sequence': sequence, 'fixed': home, 'max_throws': max_throws}
        runs[name] = simulate(system, thrower, starts, name, **kw)
        noisy[name] = simulate(system, thrower, starts, name, errors='random', seed=noisy_seed,
                               **kw)
    res = D.evaluate_grid(scene, [scene.h], [w0], goals=[system.goal_edge], workers=1)
    k = 0
    sensor = res.sensor[k, 0, 0]
    search_figures = {'mean': float(sensor[D.S_COLS.index('first_ready_mean')]),
                      'p95': float(sensor[D.S_COLS.index('first_ready_p95')]),
                      'worst': float(sensor[D.S_COLS.index('first_ready_max')]),
                      'sensor_radius': float(sensor[D.S_COLS.index('sensor_radius')])}
    if bound_1 is not None:
        notes.extend(bound_1.notes)
    return FunnelResult(system, starts, home, runs, noisy, bound, safe_bound, safe, bound_1,
                        sequence, notes, search_figures)


# ------------------------------------------------------------------------------ the file

POLICY_FORMAT = 'throwmap-funnel-policy/1'


def policy_dict(result, scene_path=''):
    """
    Return the sensor-based policy as a plain dict (JSON) the nodes can load.

    It holds what :class:`Tracker` needs: the cells (per edge lo, hi, m), per speed and cell
    the successor range on each edge (-1: none) and whether the throw may escape, the sensor
    masks, the goal edge, and the rule's ``home`` speed: the knowledge is tracked and each
    speed chosen on line, by the same code as here.
    """
    s = result.system
    K, N = s.succ.shape[:2]
    E, m = len(s.edges), s.m
    ranges = np.full((K, N, E, 2), -1, dtype=np.int64)
    for k in range(K):
        for j in range(E):
            block = s.succ[k][:, j * m:(j + 1) * m]
            has = block.any(axis=1)
            first = np.argmax(block, axis=1)
            last = m - 1 - np.argmax(block[:, ::-1], axis=1)
            ranges[k, has, j, 0] = first[has]
            ranges[k, has, j, 1] = last[has]
    return {'format': POLICY_FORMAT, 'scene': scene_path, 'rule': 'sensor-based',
            'speeds_rad_s': s.speeds.tolist(), 'home': result.home, 'h': s.h,
            'robust': s.robust, 'edges': s.edges, 'cells_per_edge': m, 'lo': s.lo.tolist(),
            'hi': s.hi.tolist(), 'arm_length': s.arm_length, 'goal_edge': s.goal_edge,
            'sensor_radius': s.sensor_radius, 'footprint': s.footprint,
            'start_knowledge': np.nonzero(start_knowledge(s, result.starts))[0].tolist(),
            'successors': ranges.tolist(), 'escape': s.escape.astype(int).tolist(),
            'can_see': s.can_see.astype(int).tolist(),
            'can_miss': s.can_miss.astype(int).tolist()}


# A throw's speed is the policy's when within this (rad/s): half a mrad/s, the serial
# protocol's resolution (docs/serial-protocol.md); 5 % of the error box at 120 deg/s, s 0.005.
SPEED_RESOLUTION = 5e-4
# A policy file larger than this is refused before it is read (26 speeds x 600 cells: 0.6 MB).
MAX_POLICY_BYTES = 64 * 2 ** 20


def read_policy(path):
    """
    Read and check a policy file of :func:`policy_dict`; InputError naming the fault and fix.

    Refused: a missing or unreadable file, one over MAX_POLICY_BYTES, JSON that does not parse
    or nests too deep, another format, and any field of the wrong type or shape (checked by
    building the cell system from it).
    """
    fix = 'write it again with throwmap funnel SCENE --speeds A:B:STEP --out DIR'
    try:
        size = os.path.getsize(path)
        if size <= MAX_POLICY_BYTES:
            with open(path, encoding='utf-8') as fh:
                d = json.load(fh)
    except OSError as exc:
        raise InputError('policy file', f'{path}: cannot read it ({exc.strerror})',
                         'give the path of a <scene>_funnel_policy.json') from None
    except (ValueError, RecursionError) as exc:
        raise InputError('policy file', f'{path}: not JSON ({str(exc)[:200]})', fix) from None
    if size > MAX_POLICY_BYTES:
        raise InputError('policy file', f'{path}: {size} bytes, more than the '
                         f'{MAX_POLICY_BYTES} a policy can need', fix)
    system_from_dict(d)
    return d


def system_from_dict(d):
    """Rebuild the CellSystem and the start knowledge from :func:`policy_dict`'s dict."""
    if not isinstance(d, dict) or d.get('format') != POLICY_FORMAT:
        got = d.get('format') if isinstance(d, dict) else type(d).__name__
        raise InputError('policy file', f'format {got!r} is not {POLICY_FORMAT}',
                         'write it again with throwmap funnel --out DIR')
    try:
        return _system_from_dict(d)
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise InputError('policy file', f'malformed {POLICY_FORMAT} ({type(exc).__name__}: '
                         f'{str(exc)[:200]})',
                         'write it again with throwmap funnel --out DIR') from None


def _system_from_dict(d):
    m = int(d['cells_per_edge'])
    edges = [int(e) for e in d['edges']]
    E = len(edges)
    speeds = np.asarray(d['speeds_rad_s'], dtype=float)
    K, N = speeds.size, E * m
    if m < 1 or E < 1 or K < 1 or speeds.ndim != 1 or not np.all(np.isfinite(speeds)) or \
            np.any(speeds <= 0):
        raise ValueError('speeds, edges and cells_per_edge must be non-empty, speeds > 0')
    ranges = np.asarray(d['successors'], dtype=np.int64)
    if ranges.shape != (K, N, E, 2) or ranges.min() < -1 or ranges.max() >= m:
        raise ValueError(f'successors has shape {ranges.shape}, not {(K, N, E, 2)}, or a '
                         'cell index out of range')
    succ = np.zeros((K, N, N), dtype=np.bool_)
    for k, a, j in zip(*np.nonzero(ranges[..., 0] >= 0)):
        lo, hi = ranges[k, a, j]
        succ[k, a, j * m + lo:j * m + hi + 1] = True
    goal = np.zeros(N, dtype=np.bool_)
    gi = edges.index(int(d['goal_edge']))
    goal[gi * m:(gi + 1) * m] = True
    masks = {}
    for name, shape in (('escape', (K, N)), ('can_see', (N,)), ('can_miss', (N,))):
        masks[name] = np.asarray(d[name], dtype=np.int64).astype(np.bool_)
        if masks[name].shape != shape:
            raise ValueError(f'{name} has shape {masks[name].shape}, not {shape}')
    lo, hi = np.asarray(d['lo'], dtype=float), np.asarray(d['hi'], dtype=float)
    if lo.shape != (E,) or hi.shape != (E,) or not np.all(hi > lo):
        raise ValueError('lo and hi must give one range per edge, hi > lo')
    home = int(d['home'])
    if not 0 <= home < K:
        raise ValueError(f'home {home} is not a speed index (0..{K - 1})')
    robust = float(d['robust'])
    system = CellSystem(speeds, float(d['h']), math.nan, robust * speeds, robust, edges, m,
                        lo, hi, succ, masks['escape'], masks['can_see'], masks['can_miss'],
                        goal, int(d['goal_edge']), float(d['sensor_radius']),
                        float(d['footprint']), float(d['arm_length']), 0)
    know = np.zeros(N, dtype=np.bool_)
    start = np.asarray(d['start_knowledge'], dtype=np.int64)
    if start.ndim != 1 or start.size == 0 or start.min() < 0 or start.max() >= N:
        raise ValueError('start_knowledge must list cell indices')
    know[start] = True
    return system, know


class Tracker:
    """
    The policy on line, for a node: ``speed()`` for the next throw, ``observe(bit)`` after it.

    ``observe`` returns 'ready' (proven), 'tracking', 'anomaly' (the bit contradicts every
    cell the knowledge allows: the cell map missed the throw, or the part is not where the
    model says) or 'unknown speed' (the throw's speed is none of the policy's); after either
    of the last two the knowledge is every cell that can read the bit (never a ready from it
    unless every such cell is on the goal edge).
    ``new_part()`` starts again.
    """

    def __init__(self, policy):
        self.system, self.start = system_from_dict(policy)
        self.home = int(policy['home'])
        self.chooser = Chooser(self.system, self.home)
        self.new_part()

    def new_part(self):
        self.know = self.start.copy()
        self.last = -1

    def forget(self):
        """Forget where the part is (a failed or unseen throw, an interruption): every cell."""
        self.know = np.ones_like(self.start)
        self.last = -1

    def _lose_track(self, bit):
        """Forget where the part is: every cell that can read ``bit``."""
        s = self.system
        self.know = s.can_see.copy() if bit else s.can_miss.copy()
        self.last = -1

    def random_starts(self, parts, rng):
        """Return ``parts`` random states (edge, R) of the start set: a cell, R uniform in it."""
        cells = np.nonzero(self.start)[0]
        out = []
        for _ in range(parts):
            edge, lo, hi = self.system.bounds(rng.choice(cells))
            out.append((int(edge), float(rng.uniform(lo, hi))))
        return out

    @property
    def home_speed(self):
        """Return the scene's own release speed, rad/s (the fixed design's)."""
        return float(self.system.speeds[self.home])

    def speed(self):
        """Choose the next throw's release speed, rad/s; None when no speed is safe."""
        self.last = self.chooser(self.know)
        return None if self.last < 0 else float(self.system.speeds[self.last])

    def speed_index(self, speed):
        """
        Return the index of the policy speed nearest ``speed`` (rad/s), or -1 if none is near.

        Near: within SPEED_RESOLUTION, half the serial protocol's step (setpoints travel to the
        controller in whole mrad/s), plus a relative 1e-9.
        """
        speeds = self.system.speeds
        k = int(np.argmin(np.abs(speeds - speed)))
        return k if abs(speeds[k] - speed) <= SPEED_RESOLUTION + 1e-9 * speeds[k] else -1

    def observe(self, bit, speed=None):
        """
        Take the bit read after a throw; ``speed``: the setpoint it was thrown at (rad/s).

        None: the speed :meth:`speed` chose. A speed not among the policy's cannot be followed:
        the knowledge becomes every cell that can read ``bit`` ('unknown speed').
        """
        k = self.last if speed is None else self.speed_index(float(speed))
        self.last = -1
        if speed is None and k < 0:
            raise RuntimeError('observe() before speed(): no throw was chosen')
        if k < 0:
            self._lose_track(bit)
            return 'unknown speed'
        know = self.system.update(self.know, k, bool(bit))
        if not know.any():
            self._lose_track(bit)
            return 'anomaly'
        self.know = know
        return 'ready' if self.system.proven(know, bit) else 'tracking'


def plot_throws(result, path, title=''):
    """Write a PNG: throws to the first proven ready per start of the grid, per policy."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    edges, radii = result.starts
    order = np.lexsort((radii, edges))
    x = np.arange(len(order))
    fig, ax = plt.subplots(figsize=(10, 4.5))
    cap = 0.0
    series = [('full-knowledge bound', result.bound, 'k', 'v')]
    if result.one_bit is not None:
        series.append(('one-bit bound', result.one_bit.throws, 'tab:red', '^'))
    series += [(name, result.runs[name].throws, color, marker) for name, color, marker in
               (('fixed', 'tab:blue', 'o'), ('open-loop', 'tab:orange', 's'),
                ('sensor-based', 'tab:green', 'D'))]
    for _, t, _, _ in series:
        finite = t[np.isfinite(t)]
        cap = max(cap, float(finite.max()) if finite.size else 0.0)
    cap = 1.1 * cap + 1.0
    for name, t, color, marker in series:
        shown = np.where(np.isfinite(t), t, cap)[order]
        f = summary(t)
        label = (f'{name}: mean {f["mean"]:.1f}, p95 {f["p95"]:.0f}, worst {f["worst"]:.0f}'
                 + (f' ({f["never"]} never, drawn at the top)' if f['never'] else ''))
        ax.plot(x, shown, marker=marker, ms=3.5, lw=0.8, color=color, label=label)
    ticks = [i for i in range(len(order)) if i == 0 or edges[order[i]] != edges[order[i - 1]]]
    ax.set_xticks(ticks, [f'edge {edges[order[i]]}' for i in ticks])
    ax.set_xlabel('start of the grid (by edge, then R from R_min up)')
    ax.set_ylabel('throws to the first proven ready')
    ax.set_yscale('log')
    ax.set_ylim(0.8, cap * 1.3)
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
