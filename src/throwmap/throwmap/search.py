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
Design search: a (h, speed) grid, then refinement; ranked by an objective under a robustness floor.

:func:`search` evaluates the grid with throwmap.design's compiled kernel (every goal edge and
sensor position at once), keeps the designs whose every start reaches one limit set that holds
the goal edge with a sensor that fits, computes the robustness (throwmap.robustness) of the
best ``top`` of them and of the scene's own design, refines around the best that meets the
floor, and returns the ranking and the Pareto front of the objective against robustness. The
objective (:data:`OBJECTIVES`) is the feed a cell sees, mean seconds from a part's arrival to
its first proven ready (``part_time``, the default), or proven readies per second in the limit
set (``ready_rate``), which counts the same part detected again and again.
:func:`design_scene` writes the chosen design as a scene file. :func:`run_catalogue` runs a
folder of scenes on Dask (a local cluster on 127.0.0.1, or a scheduler's address).
"""

import copy
from dataclasses import dataclass, field
import math
import os

import numpy as np
import yaml

from . import design as D
from .catch import is_jog
from .errors import InputError, ThrowmapError
from .orbits import limit_set
from .robustness import LimitSpec, robustness
from .scene import load_scene, Scene
from .sensor import sensor_design


# What a design is ranked by: the figure a user chooses, as the output and the plots name it
# (docs/design.md section 4). part_time's ties go to the smaller p95.
OBJECTIVES = {
    'part_time': 'mean seconds from arrival to first proven ready',
    'ready_rate': 'proven readies per second in the limit set',
}


def check_objective(objective):
    """Return ``objective`` or raise InputError naming the choices."""
    if objective not in OBJECTIVES:
        raise InputError('objective', f'unknown objective {objective!r}',
                         f'choose one of {", ".join(OBJECTIVES)}')
    return objective


def merit(figures, objective):
    """
    Return a design's merit under ``objective`` as a tuple, larger is better.

    A figure that is not a number (no ready, no sensor) ranks last.
    """
    def signed(name, sign):
        x = figures.get(name)
        return -math.inf if x is None or math.isnan(x) else sign * float(x)
    if objective == 'part_time':
        return (signed('part_seconds_mean', -1), signed('part_seconds_p95', -1))
    return (signed('readies_per_second', 1),)


@dataclass
class Candidate:
    """One design (h, speed, goal edge, sensor position) with its figures."""

    h: float
    w: float
    goal: int
    fraction: float
    figures: dict
    robustness: dict = None
    stage: str = 'grid'

    def feed(self):
        return float(self.figures['readies_per_second'])

    def merit(self, objective):
        return merit(self.figures, objective)

    def score(self, objective):
        """Return the objective's figure as plotted: s per part, or readies per second."""
        return float(self.figures['part_seconds_mean' if objective == 'part_time'
                                  else 'readies_per_second'])

    def robust(self):
        return -1.0 if self.robustness is None else float(self.robustness['joint_fraction'])

    def as_dict(self):
        return {'h': self.h, 'release_speed': self.w, 'release_speed_deg': math.degrees(self.w),
                'goal_edge': self.goal, 'sensor_fraction': self.fraction, 'stage': self.stage,
                'figures': self.figures, 'robustness': self.robustness}


@dataclass
class SearchResult:
    grid: D.GridResult
    shape: tuple                # (offsets, speeds)
    candidates: list            # every design whose robustness was computed
    chosen: Candidate
    reference: Candidate        # the scene's own design
    pareto: list
    floor: float
    refined: D.GridResult = None
    notes: list = field(default_factory=list)
    objective: str = 'part_time'


def _figures(res, k, gi, fi):
    row = dict(zip(D.D_COLS, (float(x) for x in res.design[k])))
    row.update(zip(D.S_COLS, (float(x) for x in res.sensor[k, gi, fi])))
    return row


def eligible(res):
    """(designs, goals, fractions) mask: one attractor from every start, goal proven, fits."""
    d = res.design
    one = ((d[:, D.D_STATUS] == D.ST_OK) & (d[:, D.D_SHARE] == 1.0)
           & (d[:, D.D_ATTRACTORS] == 1))[:, None, None]
    s = res.sensor
    return (one & (s[..., D.S_FEASIBLE] == 1) & (s[..., D.S_FITS] == 1)
            & (s[..., D.S_NEVER] == 0))


def limit_spec(scene, cand, opt):
    """Return the LimitSpec of a candidate: its limit set's bands and flips, its sensor."""
    # The bands need no arrival (and a design outside the arrival's domain still has them).
    res = D.evaluate_grid(scene, [cand.h], [cand.w], goals=[cand.goal],
                          fractions=[cand.fraction], options=opt._replace(arrival_edge=-1),
                          workers=1)
    f = cand.figures
    if f['status'] not in (D.ST_OK, D.ST_ARRIVAL_OUTSIDE):
        raise ThrowmapError(f'the design has no limit set: {D.STATUS_TEXT[int(f["status"])]}')
    model = scene.model.at(cand.h, cand.w).nominal()    # as the design kernel: no noise
    e, _, rot = model.orbit_arrays(int(f['ref_edge']), f['ref_R'], opt.ref_throws)
    if e[-1] < 0:
        raise ThrowmapError(f'the part was lost at throw {len(e) - 1} of the reference orbit')
    half = opt.ref_throws // 2
    flips = frozenset((int(e[k - 1]), int(e[k])) for k in range(half + 1, len(e))
                      if not is_jog(e[k - 1], e[k], rot[k]))
    return LimitSpec(res.bands[0], flips, cand.goal, f['sensor_radius'], opt.footprint,
                     f['r_hi'], 1.1 * f['r_hi'])


def assess(scene, cand, opt, cells=120):
    """Fill ``cand.robustness`` (throwmap.robustness) and return the candidate."""
    try:
        spec = limit_spec(scene, cand, opt)
    except ThrowmapError as exc:
        # No limit set to be robust about (e.g. a scene's own design whose orbit leaves the
        # domain of f): not robust to any error, reported with the reason, not a crash.
        cand.robustness = {'speed_error': 0.0, 'offset_error': 0.0, 'joint_fraction': 0.0,
                           'transient_bound': None, 'nominal_ok': False,
                           'nominal_reason': f'no limit set: {exc}', 'cells': cells,
                           'samples': 0}
        return cand
    rb = robustness(scene.model, cand.h, cand.w, spec, cells=cells)
    cand.robustness = rb.as_dict()
    return cand


def _best(res, mask, top, objective='part_time'):
    """Return the indices (k, gi, fi) of the ``top`` eligible entries by objective, best first."""
    if objective == 'part_time':
        mean = np.where(mask, res.sensor[..., D.S_PART_MEAN], np.inf)
        p95 = np.where(mask, res.sensor[..., D.S_PART_P95], np.inf)
        mean = np.where(np.isnan(mean), np.inf, mean)
        # Smallest mean first, then smallest p95 (lexsort is stable: then the grid's order).
        order = np.lexsort((p95.ravel(), mean.ravel()))[:top]
        return [np.unravel_index(i, mean.shape) for i in order if np.isfinite(mean.flat[i])]
    feed = np.where(mask, res.sensor[..., D.S_PER_SECOND], -np.inf)
    order = np.argsort(-feed, axis=None, kind='stable')[:top]
    return [np.unravel_index(i, feed.shape) for i in order if np.isfinite(feed.flat[i])]


def pareto_front(cands, objective='part_time'):
    """Candidates not beaten on both the objective and robustness (best by objective first)."""
    front = []
    for c in sorted(cands, key=lambda c: tuple(-x for x in c.merit(objective))
                    + (-c.robust(),)):
        if all(c.robust() > f.robust() for f in front):
            front.append(c)
    return front


def search(scene, h_range, w_range, n_h=40, n_w=40, goals=None, fractions=(0.25,), floor=0.0,
           top=8, refine=5, options=None, workers=None, progress=None, cells=120, spread=12,
           objective='part_time'):
    """
    Grid over h in h_range x speed in w_range, then refinement (module docstring).

    ``floor``: the smallest joint robustness s (every throw within +-s of the speed and +-s
    d_min of the offset) a design must have to be chosen. Robustness is computed for the
    ``top`` eligible designs by ``objective`` (:data:`OBJECTIVES`) and ``spread`` more spread
    evenly over the rest of the eligible ones (so the Pareto front has points beyond the best
    designs). ``options.arrival_edge`` >= 0 (eval_options' ``arrival``): first readies from
    the chute's starts, not the grid's.
    """
    check_objective(objective)
    opt = options or D.eval_options(scene)
    hs = np.linspace(h_range[0], h_range[1], n_h)
    ws = np.linspace(w_range[0], w_range[1], n_w)
    H, W = np.meshgrid(hs, ws, indexing='ij')
    res = D.evaluate_grid(scene, H.ravel(), W.ravel(), goals, fractions, opt, workers,
                          progress=progress)
    mask = eligible(res)
    cands = []
    ranked = _best(res, mask, mask.size, objective)
    picks = ranked[:top]
    rest = ranked[top:]
    if rest and spread > 0:
        spots = np.unique(np.linspace(0, len(rest) - 1, spread).round().astype(int))
        picks += [rest[int(i)] for i in spots]
    for k, gi, fi in picks:
        cands.append(Candidate(float(res.h[k]), float(res.w[k]), int(res.goals[gi]),
                               float(res.fractions[fi]), _figures(res, k, gi, fi)))
    # The scene's own design (the paper's, for the triangle); below an arrival's domain it is
    # not eligible, as a grid design there is, rather than an error.
    own = D.evaluate_grid(scene, [scene.h], [scene.release_speed], res.goals[:1].tolist(),
                          [fractions[0]], opt, 1, refuse_arrival_outside=False)
    reference = Candidate(float(scene.h), float(scene.release_speed), int(res.goals[0]),
                          float(fractions[0]), _figures(own, 0, 0, 0), stage='scene')
    for c in cands + [reference]:
        assess(scene, c, opt, cells)
    notes = []
    refined = None
    ok = [c for c in cands if c.robust() >= floor]
    if ok and refine > 1 and n_h > 1 and n_w > 1:
        best = max(ok, key=lambda c: c.merit(objective))
        dh, dw = hs[1] - hs[0], ws[1] - ws[0]
        rh = np.linspace(best.h - dh, best.h + dh, refine)
        rw = np.linspace(best.w - dw, best.w + dw, refine)
        RH, RW = np.meshgrid(rh, rw, indexing='ij')
        refined = D.evaluate_grid(scene, RH.ravel(), RW.ravel(), [best.goal], [best.fraction],
                                  opt, workers)
        rmask = eligible(refined)
        for k, gi, fi in _best(refined, rmask, max(2, top // 2), objective):
            c = Candidate(float(refined.h[k]), float(refined.w[k]), best.goal, best.fraction,
                          _figures(refined, k, gi, fi), stage='refined')
            cands.append(assess(scene, c, opt, cells))
    allc = cands + [reference]
    ok = [c for c in allc if c.robust() >= floor and c.feed() > 0
          and c.figures.get('never_ready', 1) == 0]
    chosen = max(ok, key=lambda c: c.merit(objective)) if ok else None
    if chosen is not None:
        chosen.figures['library_guarantee_radius'] = library_guarantee(scene, chosen)
        if chosen.figures['library_guarantee_radius'] >= chosen.figures['sensor_radius']:
            notes.append('the chosen sensor position is not beyond the guarantee radius of a '
                         '10,000-throw limit set (throwmap.analysis): move it out before use')
    if chosen is None:
        notes.append(f'no design meets the robustness floor {floor}: lower --robust, or widen '
                     'the ranges')
    if scene.arm_length is None or 'finite_arm' not in scene.effects:
        notes.append(endless_arm_note(scene, chosen))
    outside = res.design[:, D.D_STATUS] == D.ST_ARRIVAL_OUTSIDE
    if outside.any():
        notes.append(f'{int(outside.sum())} of {outside.size} designs not eligible: '
                     f'{D.STATUS_TEXT[D.ST_ARRIVAL_OUTSIDE]} (h {res.h[outside].min() * 100:.3f}'
                     f'..{res.h[outside].max() * 100:.3f} cm)')
    return SearchResult(res, (n_h, n_w), cands, chosen, reference,
                        pareto_front(allc, objective), floor, refined, notes, objective)


def library_guarantee(scene, cand, throws=10_000):
    """Return the guarantee radius of the library's own (10,000-throw) limit set for cand."""
    model = scene.model.at(cand.h, cand.w).nominal()    # as the design kernel: no noise
    f = cand.figures
    ls = limit_set(model, int(f['ref_edge']), f['ref_R'], throws)
    return sensor_design(model, ls, cand.goal, scene.sensor_footprint,
                         f['sensor_radius']).guarantee_radius


def vertex_tolerance(scene, cand, opt=None, random_samples=36, eps_max=0.005, steps=8,
                     seed=0, progress=None):
    """
    Largest vertex tolerance eps (m) under which the design keeps its limit set and proof.

    Sampled, not proven: at each eps the part is rebuilt with its vertices moved (each vertex
    alone in 8 directions by eps, then ``random_samples`` parts with every vertex moved
    uniformly within a disc of radius eps; the centre of mass follows the outline), and each
    must still have every start reach one limit set with the nominal flip edges, and no other
    edge reach the sensor. Returns (eps, samples per level, the 95 % bound on the failing
    fraction of random shapes when all pass: 1 - 0.05^(1/random_samples)).
    """
    # 300 throws per start: at the search's 120 a slow start near R_min (transient ~90) may
    # not have settled, which would read as a second attractor.
    opt = (opt or D.eval_options(scene))._replace(throws=max(300, (opt or D.eval_options(
        scene)).throws))
    verts = np.array(scene.part.vertices, dtype=float)
    n = len(verts)
    rng = np.random.default_rng(seed)
    dirs = [(math.cos(a), math.sin(a)) for a in np.linspace(0, 2 * math.pi, 8, endpoint=False)]
    unit = [np.zeros((n, 2)) for _ in range(n * 8)]
    for k in range(n):
        for q, dvec in enumerate(dirs):
            unit[k * 8 + q][k] = dvec
    for _ in range(random_samples):
        r = np.sqrt(rng.random(n))
        a = rng.random(n) * 2 * math.pi
        unit.append(np.stack([r * np.cos(a), r * np.sin(a)], axis=1))
    f = cand.figures
    mask = int(f['flip_mask'])

    def holds(eps):
        for u in unit:
            data = copy.deepcopy(scene.data)
            data['part'] = {k: v for k, v in data['part'].items()
                            if k not in ('vertices', 'vertices_cm', 'cm', 'cm_cm')}
            data['part']['vertices'] = (verts + eps * u).tolist()
            data.pop('start', None)
            try:
                sc = Scene(data, source='<vertex tolerance>')
            except InputError:
                return False
            if sc.part.n != n:
                return False
            res = D.evaluate_grid(sc, [cand.h], [cand.w], [cand.goal], [cand.fraction], opt, 1)
            d = res.design[0]
            if progress:
                progress(eps)
            other = [e for e in range(n) if e != cand.goal and not np.isnan(res.bands[0, e, 0])]
            u_max = sc.part.U.max(axis=1)
            top = max((res.bands[0, e, 1] + u_max[e] for e in other), default=-math.inf)
            if not (d[D.D_STATUS] == D.ST_OK and d[D.D_SHARE] == 1.0
                    and int(d[D.D_FLIP_MASK]) == mask
                    and top + opt.footprint < f['sensor_radius']):
                return False
        return True

    if not holds(0.0):
        return 0.0, len(unit), None
    lo, hi = 0.0, eps_max
    if holds(hi):
        lo = hi
    else:
        for _ in range(steps):
            mid = 0.5 * (lo + hi)
            if holds(mid):
                lo = mid
            else:
                hi = mid
    return lo, len(unit), 1.0 - 0.05 ** (1.0 / random_samples)


def design_scene(scene, cand, name=None):
    """Return the scene data (a dict) of ``scene`` with the candidate's design written in."""
    data = copy.deepcopy(scene.data)
    data['name'] = name or f'{scene.name}_design'
    data['description'] = (f'{scene.name} with the design chosen by throwmap design-search: '
                           f'h = {cand.h * 100:.4f} cm, {math.degrees(cand.w):.3f} deg/s, goal '
                           f'edge {cand.goal}, sensor at {cand.figures["sensor_radius"] * 100:.3f}'
                           ' cm')
    data['arm'] = {k: v for k, v in data['arm'].items() if k not in ('offset', 'offset_cm')}
    data['arm']['offset'] = float(cand.h)
    data['throw'] = {k: v for k, v in data['throw'].items()
                     if k not in ('release_speed', 'release_speed_deg')}
    data['throw']['release_speed'] = float(cand.w)
    sensor = {k: v for k, v in data.get('sensor', {}).items() if k not in ('radius', 'radius_cm',
                                                                           'goal_edge')}
    sensor['goal_edge'] = int(cand.goal)
    sensor['radius'] = float(cand.figures['sensor_radius'])
    data['sensor'] = sensor
    start = data.get('start', {})
    if start:
        # The old start may lie outside the new design's grasp domain: start on the goal edge.
        data['start'] = {'edge': int(cand.goal)}
    return data


def noisy_design_scene(scene, s, distribution='uniform', seed=0, relative=False):
    """
    Return the scene data of ``scene`` (a design) with its release errors bounded at joint s.

    Every throw's release speed and offset within +-s w and +-s d_min (docs/design.md section
    3, the robustness floor's box) by effect release_noise with a bounded ``distribution``
    (uniform or corner), seeded: the design run as a real feeder would throw it. ``relative``:
    the speed's bound is s times each throw's own speed (``release_speed_bound_rel``), for a
    speed policy that changes the speed per throw; else s times the scene's. Effects the scene
    has (its arm's end) stay; one that already draws release errors is refused.
    """
    if not (isinstance(s, (int, float)) and math.isfinite(s) and s >= 0):
        raise InputError('robustness floor', f'must be a number >= 0, got {s!r}',
                         'give the joint s of --robust, e.g. 0.005')
    names = list(scene.effects.names) if scene.effects else []
    if 'release_noise' in names:
        raise InputError('effects', 'the design scene already has effect release_noise',
                         'give the design without it')
    data = copy.deepcopy(scene.data)
    data['effects'] = names + ['release_noise']
    speed = ({'release_speed_bound_rel': float(s)} if relative else
             {'release_speed_bound': float(s * scene.release_speed)})
    data['noise'] = {'seed': int(seed), 'distribution': distribution, **speed,
                     'offset_bound': float(s * scene.part.d_min)}
    return data


def write_scene(data, path):
    """Write scene data as YAML (plain floats, keys in the usual order)."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, 'w', encoding='utf-8') as fh:
        fh.write('# Written by `throwmap design-search`; load it like any scene.\n')
        yaml.safe_dump(data, fh, sort_keys=False, default_flow_style=None)
    return path


# --------------------------------------------------------------------------------- catalogue
def catalogue_task(path, h_range, w_range, n_h, n_w, fractions=(0.25,), floor=0.0, top=4,
                   refine=3, throws=120, objective='part_time'):
    """Search one scene file (one Dask task; also the serial path): a JSON-ready summary."""
    scene = load_scene(path)
    res = search(scene, h_range, w_range, n_h, n_w, fractions=fractions, floor=floor, top=top,
                 refine=refine, options=D.eval_options(scene, throws=throws), workers=1,
                 objective=objective)
    return summary(scene, res, path)


def endless_arm_note(scene, chosen):
    """
    Say that the search took the arm as endless, and how far out the chosen design reaches.

    A scene without arm.length and effect finite_arm has an arm without an end (the search runs
    the scene's own throws); it then cannot refuse designs that put the part or the sensor past
    the real arm's end.
    """
    missing = ('no arm.length' if scene.arm_length is None else
               f'arm.length {scene.arm_length * 100:g} cm but not effect finite_arm')
    text = (f'the arm is taken as endless: the scene gives {missing} (give arm.length_cm and '
            'effects: [finite_arm] to search for your arm)')
    if chosen is None:
        return text
    f = chosen.figures
    return (f'{text}; the chosen design rests the part up to R = {f["r_hi"] * 100:.1f} cm out '
            f'(R_max of Z) and puts the sensor at {f["sensor_radius"] * 100:.1f} cm')


def summary(scene, res, path=None):
    """Return a search's result as plain data (what --json prints and the catalogue compares)."""
    def plain(c):
        return None if c is None else c.as_dict()
    arrival = res.grid.arrival
    return {'scene': scene.name, 'path': path, 'grid': list(res.shape), 'floor': res.floor,
            'objective': res.objective, 'objective_text': OBJECTIVES[res.objective],
            'first_ready_from': 'grid of starts' if arrival is None else {
                'arrival_edge': arrival[0], 'R_low': arrival[1], 'R_high': arrival[2],
                'starts': arrival[3]},
            'designs': int(res.grid.h.size), 'throws': res.grid.throws,
            'seconds': res.grid.seconds, 'chosen': plain(res.chosen),
            'scene_design': plain(res.reference),
            'pareto': [plain(c) for c in res.pareto], 'notes': res.notes}


def run_catalogue(paths, ranges, n_h, n_w, fractions=(0.25,), floor=0.0, top=4, refine=3,
                  scheduler=None, workers=2, client=None, throws=120, objective='part_time'):
    """
    Search every scene of ``paths`` on Dask: ``scheduler`` an address, else a LocalCluster.

    ``ranges``: per scene (h_range, w_range). Each scene is one task running
    :func:`catalogue_task`, the serial path's own function, on one thread.
    The local cluster listens on 127.0.0.1 only (nothing leaves loopback) and has ``workers``
    single-threaded worker processes. Results come back in the order of ``paths``.
    """
    # dask is only needed here: imported on use, like matplotlib for the plots.
    from distributed import Client
    own = None
    if client is None:
        if scheduler:
            client = Client(scheduler)
        else:
            own = local_cluster(workers)
            client = Client(own)
    try:
        futures = [client.submit(catalogue_task, p, tuple(hr), tuple(wr), n_h, n_w,
                                 tuple(fractions), floor, top, refine, throws, objective,
                                 pure=False)
                   for p, (hr, wr) in zip(paths, ranges)]
        return client.gather(futures)
    finally:
        if own is not None:
            client.close()
            own.close()


def local_cluster(workers=2):
    """Return a Dask LocalCluster on 127.0.0.1 only, no dashboard, ``workers`` processes."""
    from distributed import LocalCluster
    return LocalCluster(n_workers=workers, threads_per_worker=1, host='127.0.0.1',
                        dashboard_address=None, processes=True)


def scene_paths(folder):
    """Return the scene files of a catalogue folder, sorted; InputError if there are none."""
    if not os.path.isdir(folder):
        raise InputError('catalogue', f'{folder} is not a directory',
                         'give a folder of scene YAML files')
    paths = sorted(os.path.join(folder, f) for f in os.listdir(folder)
                   if f.endswith(('.yaml', '.yml')))
    if not paths:
        raise InputError('catalogue', f'{folder} holds no .yaml scene files',
                         'put one scene file per part in it')
    return paths


def robustness_map(scene, res, shape, stride, floor_goal=0, opt=None, cells=120):
    """
    Joint robustness over a sub-grid (every ``stride``-th offset and speed) of a search grid.

    Returns (h values, speed values, s array with NaN where the design is not eligible).
    """
    opt = opt or D.eval_options(scene)
    n_h, n_w = shape
    mask = eligible(res)
    ih = np.arange(0, n_h, stride)
    iw = np.arange(0, n_w, stride)
    out = np.full((ih.size, iw.size), np.nan)
    for a, i in enumerate(ih):
        for b, j in enumerate(iw):
            k = i * n_w + j
            if not mask[k, floor_goal, 0]:
                continue
            c = Candidate(float(res.h[k]), float(res.w[k]), int(res.goals[floor_goal]),
                          float(res.fractions[0]), _figures(res, k, floor_goal, 0))
            out[a, b] = assess(scene, c, opt, cells).robust()
    return res.h.reshape(shape)[ih, 0], res.w.reshape(shape)[0, iw], out


def heat_maps(result, path, robust_map=None):
    """Write the objective (and robustness) over (h, speed) with the chosen and scene designs."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    res = result.grid
    n_h, n_w = result.shape
    col = D.S_PART_MEAN if result.objective == 'part_time' else D.S_PER_SECOND
    feed = np.where(eligible(res)[:, 0, 0], res.sensor[:, 0, 0, col], np.nan)
    H = res.h.reshape(n_h, n_w) * 100
    W = np.degrees(res.w.reshape(n_h, n_w))
    panels = [(f'{OBJECTIVES[result.objective]} (eligible designs)', H, W,
               feed.reshape(n_h, n_w))]
    if robust_map is not None:
        rh, rw, rs = robust_map
        RH, RW = np.meshgrid(rh * 100, np.degrees(rw), indexing='ij')
        panels.append(('joint robustness s (+-s speed, +-s d_min offset)', RH, RW, rs))
    fig, axes = plt.subplots(1, len(panels), figsize=(6.5 * len(panels), 5), squeeze=False)
    for ax, (title, X, Y, Z) in zip(axes[0], panels):
        mesh = ax.pcolormesh(X, Y, np.ma.masked_invalid(Z), shading='nearest', cmap='viridis')
        fig.colorbar(mesh, ax=ax)
        for cand, mark, label in ((result.chosen, '*', 'chosen'),
                                  (result.reference, 'o', 'scene design')):
            if cand is not None:
                ax.plot(cand.h * 100, math.degrees(cand.w), mark, color='red', ms=12,
                        mfc='none' if mark == 'o' else 'red', label=label)
        ax.set_xlabel('arm offset h (cm)')
        ax.set_ylabel('release speed (deg/s)')
        ax.set_title(title, fontsize=10)
        ax.legend(loc='upper right', fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def pareto_plot(result, path):
    """Write the objective against robustness of every assessed design, the front joined."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    obj = result.objective
    fig, ax = plt.subplots(figsize=(6, 4.5))
    pts = [c for c in result.candidates if c.robustness is not None]
    ax.plot([c.robust() for c in pts], [c.score(obj) for c in pts], '.', color='grey',
            label='assessed designs')
    front = sorted(result.pareto, key=Candidate.robust)
    ax.plot([c.robust() for c in front], [c.score(obj) for c in front], '-o',
            label='Pareto front')
    ref = result.reference
    ax.plot([ref.robust()], [ref.score(obj)], 's', color='red', mfc='none', ms=10,
            label=f'scene design (h {ref.h * 100:.2f} cm, {math.degrees(ref.w):.0f} deg/s)')
    if result.chosen is not None:
        ax.plot([result.chosen.robust()], [result.chosen.score(obj)], '*', color='red', ms=14,
                label='chosen')
    ax.axvline(result.floor, color='k', lw=0.8, ls='--', label='robustness floor')
    ax.set_xlabel('joint robustness s')
    ax.set_ylabel(OBJECTIVES[obj])
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
