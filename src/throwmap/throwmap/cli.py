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

"""``throwmap`` command line: grasp, throw, orbit, limit-set, basin, design, plot, ..., funnel."""

import argparse
import itertools
import json
import math
import os
import re
import sys
import time
import warnings

import numpy as np

from . import design as design_kernel
from . import funnel
from . import search as design_search
from .analysis import analyse
from .basins import basin, default_grid
from .errors import ThrowmapError
from .orbits import limit_set, loss_reason, orbit, pull_share
from .robustness import S_MAX
from .scene import load_scene
from .status import LOST, OK

# The batch reads stdin in blocks of this many lines: one f_batch, one write, one flush each.
BATCH_BLOCK = 4096


def _json_default(obj):
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.floating,)):
        return float(obj)
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, tuple):
        return list(obj)
    raise TypeError(f'not JSON serialisable: {type(obj).__name__}')


def _clean(value):
    """JSON has no inf/nan: write them as null."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def _dump(obj, out):
    out.write(json.dumps(_clean(json.loads(json.dumps(obj, default=_json_default))),
                         allow_nan=False) + '\n')


def _table(rows, columns, out):
    widths = [max(len(c), *(len(str(r.get(c, ''))) for r in rows)) for c in columns]
    out.write('  '.join(c.rjust(w) for c, w in zip(columns, widths)) + '\n')
    for r in rows:
        out.write('  '.join(str(r.get(c, '')).rjust(w) for c, w in zip(columns, widths)) + '\n')


def _fmt_cm(x):
    return '-' if x is None or not math.isfinite(x) else f'{x * 100:.3f}'


class Progress:
    """Progress on stderr for long runs, at most twice a second."""

    def __init__(self, label, quiet=False):
        self.label = label
        self.quiet = quiet
        self.last = 0.0
        self.start = time.monotonic()

    def __call__(self, done, total):
        now = time.monotonic()
        if self.quiet or (now - self.last < 0.5 and done < total):
            return
        self.last = now
        sys.stderr.write(f'{self.label}: {done}/{total} ({now - self.start:.1f} s)\n')
        sys.stderr.flush()


# --------------------------------------------------------------------------------- commands
def cmd_grasp(scene, args, out):
    rows, r_all, mu_all = scene.model.grasp_table()
    if args.json:
        _dump({'scene': scene.name, 'offset': scene.h, 'mu': scene.model.mu,
               'edges': [{'edge': g.edge, 'stable': g.stable,
                          'R_grasp': g.R_grasp if g.stable else None,
                          'mu_min': g.mu_min if g.stable else None,
                          'binding_bound': g.binding if g.stable else None,
                          'bounds': list(g.bounds) if g.stable else None,
                          'd': float(scene.part.d[g.edge]),
                          'u_l': float(scene.part.u_l[g.edge]),
                          'u_r': float(scene.part.u_r[g.edge])} for g in rows],
               'R_grasp': r_all, 'mu_min': mu_all,
               'domain_R_min': ({str(i): float(scene.model.r_min(i))
                                 for i in scene.part.stable_edges}
                                if scene.model.domain_note() else None),
               # intervals [lo, hi] of R per stable edge; hi null: unbounded
               'domain': {str(i): [[lo, hi if math.isfinite(hi) else None]
                                   for lo, hi in scene.model.domain_intervals(i)]
                          for i in scene.part.stable_edges}}, out)
        return 0
    out.write(f'{scene.name}: dynamic grasp (impulse cone, constraints (1)-(4)), h = '
              f'{scene.h * 100:g} cm\n')
    table = [{'edge': g.edge, 'stable': 'yes' if g.stable else 'no',
              'd (cm)': f'{scene.part.d[g.edge] * 100:.3f}',
              'R_grasp (cm)': _fmt_cm(g.R_grasp) if g.stable else '-',
              'mu_min': f'{g.mu_min:.3f}' if g.stable else '-',
              'binding': f'({g.binding})' if g.stable else '-'} for g in rows]
    _table(table, ['edge', 'stable', 'd (cm)', 'R_grasp (cm)', 'mu_min', 'binding'], out)
    out.write(f'all stable edges: R >= {r_all * 100:.3f} cm with mu >= {mu_all:.3f}\n')
    note = scene.model.domain_note()
    if note:
        # The impulse cone above is the paper's limit; an effect (finite_carry) moves the domain.
        out.write(note + '\n')
    return 0


# One state as JSON, the common spelling: {"edge": <int>, "R": <number>} (JSON's grammar: its
# whitespace, its numbers). Anything else goes through json.loads.
_WS = r'[ \t\n\r]*'
_STATE_TEXT = (_WS + r'\{' + _WS + r'"edge"' + _WS + ':' + _WS + r'(-?(?:0|[1-9][0-9]*))' + _WS
               + ',' + _WS + r'"R"' + _WS + ':' + _WS
               + r'(-?(?:0|[1-9][0-9]*)(?:\.[0-9]+)?(?:[eE][-+]?[0-9]+)?)' + _WS + r'\}' + _WS)
_STATE = re.compile(_STATE_TEXT)
_STATES = re.compile('^' + _STATE_TEXT.replace(r'[ \t\n\r]', r'[ \t\r]') + '$', re.MULTILINE)


def _parse_state(line, lineno):
    """
    Return (edge, R) of one input line; ValueError with the line number if it is not a state.

    The common spelling is matched directly; anything else goes through json.loads, which
    accepts exactly what JSON does and says what is wrong.
    """
    m = _STATE.fullmatch(line)
    if m:
        return int(m.group(1)), float(m.group(2))
    try:
        state = json.loads(line)
        if not isinstance(state, dict) or 'edge' not in state or 'R' not in state:
            raise ValueError('expected an object with "edge" and "R"')
        unknown = set(state) - {'edge', 'R'}
        if unknown:
            raise ValueError(f'unknown keys {sorted(unknown)}; allowed: edge, R')
    except ValueError as exc:
        raise ValueError(f'line {lineno}: {exc}') from None
    return state['edge'], state['R']


# One answer: what model.throw(edge, R) gives, as json.dumps would write it (floats by repr).
_ROW = ('{"edge": %d, "R": %r, "kind": "%s", "flight_time": %r, "net_rotation": %r, '
        '"impacts": %d, "first_contact_vertex": %d}\n')
_ROW_TEXT = _ROW.replace('%r', '%s')


def _number(x):
    """Return a float for JSON: nan and inf (not JSON) as None."""
    return x if math.isfinite(x) else None


def _states(model, lines, first):
    """
    Parse a block of lines (the first is line ``first``); return (answers, todo, edges, R).

    ``answers`` holds the error of each line that is refused before throwing (not a state, or
    what throw() refuses first: types, edge numbers, unstable edges, R), BLANK for a blank
    line; ``todo`` the other lines, in order, with their states. A block of states in the
    common spelling is parsed at once.
    """
    answers = [None] * len(lines)
    part = model.part
    found = _STATES.findall(''.join(lines))
    if len(found) == len(lines):        # every line in the common spelling
        text_e, text_r = zip(*found)
        try:
            edges = np.fromiter(map(int, text_e), np.int64, len(lines))
        except OverflowError:       # an edge beyond 64 bits: line by line
            pass
        else:
            radii = np.fromiter(map(float, text_r), np.float64, len(lines))
            good = (edges >= 0) & (edges < part.n)
            good[good] = part.stable[edges[good]]
            good &= np.isfinite(radii)
            if good.all():
                return answers, range(len(lines)), edges, radii
    stable = part.stable.tolist()
    todo, edges, radii = [], [], []
    for k, line in enumerate(lines):
        if not line.strip():
            answers[k] = BLANK
            continue
        try:
            edge, R = _parse_state(line, first + k)
        except ValueError as exc:
            answers[k] = str(exc)
            continue
        if not (type(edge) is int and type(R) is float and 0 <= edge < part.n
                and stable[edge] and math.isfinite(R)):
            err = model.domain_error(edge, R)
            if err is not None and err.condition in ('edge_index', 'stable_edge', 'radius'):
                answers[k] = str(err)
                continue
        todo.append(k)
        edges.append(int(edge))
        radii.append(float(R))
    return answers, todo, np.array(edges, dtype=np.int64), np.array(radii, dtype=np.float64)


def _batch(model, lines, first):
    """
    Throw the state of every line of a block with one f_batch, in order.

    Returns (answers, columns): one answer per line, (edge, R, kind, flight time, net
    rotation, events, first contact vertex) of the throw or an error message (str), the error
    model.throw(edge, R) would raise for that line; ``columns`` the f_batch result when every
    line is a throw that landed on the arm (the common case), else None.
    """
    answers, todo, edges, radii = _states(model, lines, first)
    if not len(todo):
        return answers, None
    res = model.f_batch(edges, radii)
    codes = res['status']
    if len(todo) == len(lines) and not codes.any():
        return None, res
    rows = zip(res['edge'].tolist(), res['R'].tolist(), res['kind'].tolist(),
               res['flight_time'].tolist(), res['net_rotation'].tolist(),
               res['events'].tolist(), res['first_contact_vertex'].tolist())
    for i, (k, code, row) in enumerate(zip(todo, codes.tolist(), rows)):
        if code == OK or code == LOST:
            answers[k] = row
        else:
            answers[k] = model.error_message(code, int(edges[i]), float(radii[i]))
    return answers, None


_FLOATS = json.JSONEncoder(check_circular=False)


def _texts(column):
    """Return the JSON texts of a column of floats (encoded at once, as json.dumps does)."""
    return _FLOATS.encode(column.tolist())[1:-1].split(', ')


def _json_lines(answers, columns):
    """Return the JSON lines of a block's answers (json.dumps' formatting, floats by repr)."""
    if columns is not None:
        c = columns
        return ''.join(map(_ROW_TEXT.__mod__, zip(
            c['edge'].tolist(), _texts(c['R']), c['kind'].tolist(), _texts(c['flight_time']),
            _texts(c['net_rotation']), c['events'].tolist(),
            c['first_contact_vertex'].tolist())))
    return ''.join([_ROW % a if type(a) is tuple and a[0] >= 0 else _json_special(a)
                    for a in answers if a is not BLANK])


def _json_special(a):
    if type(a) is str:
        return json.dumps({'error': a}) + '\n'
    # lost: no R (nan), no JSON number for it
    return json.dumps(dict(zip(ROW_KEYS, [_number(x) if isinstance(x, float) else x
                                          for x in a]))) + '\n'


ROW_KEYS = ('edge', 'R', 'kind', 'flight_time', 'net_rotation', 'impacts',
            'first_contact_vertex')
BLANK = object()        # the answer to a blank input line: none


def _blocks(stream, size=BATCH_BLOCK):
    """
    Yield (lines, number of the first) of ``size`` input lines at a time, blank ones included.

    A block is answered as soon as its last line has arrived (the iterator returns what the
    pipe holds, it does not wait for a full buffer), so answers stream with the input.
    """
    first = 1
    while True:
        lines = list(itertools.islice(stream, size))
        if not lines:
            return
        yield lines, first
        first += len(lines)


def throw_batch(model, stream, out, as_json=True):
    """
    Answer one state per input line, in order, block by block; return the exit code.

    JSON: one line per state with edge, R, kind, flight_time, net_rotation, impacts (the
    catch's events), first_contact_vertex, or {"error": ...}, written and flushed once per
    block. A table otherwise. Exit code 1 if any line failed.
    """
    failed = False
    table = []
    for lines, first in _blocks(stream):
        answers, columns = _batch(model, lines, first)
        failed = failed or (answers is not None and any(type(a) is str for a in answers))
        if as_json:
            out.write(_json_lines(answers, columns))
            out.flush()
        else:
            if answers is None:
                c = columns
                answers = list(zip(c['edge'].tolist(), c['R'].tolist(), c['kind'].tolist(),
                                   c['flight_time'].tolist(), c['net_rotation'].tolist(),
                                   c['events'].tolist(), c['first_contact_vertex'].tolist()))
            table.extend({'error': a} if type(a) is str else dict(zip(ROW_KEYS, a))
                         for a in answers if a is not BLANK)
    if not as_json:
        _table([{k: (f'{v:.6g}' if isinstance(v, float) else v) for k, v in r.items()}
                for r in table], ['edge', 'R', 'kind', 'flight_time', 'net_rotation', 'error'],
               out)
    return 1 if failed else 0


def cmd_throw(scene, args, out):
    model = scene.model
    if args.edge is not None or args.R is not None:
        if args.edge is None or args.R is None:
            raise ThrowmapError('--edge and --R go together; give both, or neither to read '
                                'states from stdin')
        res = model.throw(args.edge, args.R)
        if args.json:
            _dump(res.as_dict(), out)
        elif res.kind == 'lost':
            out.write(f'({res.edge0}, {res.R0 * 100:.4f} cm) -> lost: '
                      f'{res.lost_reason}\n')
        else:
            out.write(f'({res.edge0}, {res.R0 * 100:.4f} cm) -> ({res.edge}, '
                      f'{res.R * 100:.4f} cm): {res.kind}, flight {res.flight_time * 1000:.2f} '
                      f'ms, net rotation {math.degrees(res.net_rotation):.2f} deg\n')
            out.write(f'  {_normal_note(res.min_normal_force)}\n')
            if not res.in_domain:
                out.write(f'  no next throw: {res.lost_reason}\n')
        if not args.json:
            _table([{'impact': k, 'kind': i.kind, 'vertex': i.vertex,
                     'edge landed': i.edge if i.edge >= 0 else '-',
                     'x (cm)': f'{i.x * 100:.3f}', 'omega- (rad/s)': f'{i.omega_before:.3f}',
                     'omega+ (rad/s)': f'{i.omega_after:.3f}',
                     'E- (J/kg)': f'{i.energy_before:.5f}', 'E+ (J/kg)': f'{i.energy_after:.5f}'}
                    for k, i in enumerate(res.impacts)],
                   ['impact', 'kind', 'vertex', 'edge landed', 'x (cm)', 'omega- (rad/s)',
                    'omega+ (rad/s)', 'E- (J/kg)', 'E+ (J/kg)'], out)
        return 0
    # Batch: one JSON object per line on stdin, one answer per line, in order.
    return throw_batch(model, sys.stdin, out, as_json=args.json)


def _normal_note(low):
    if math.isnan(low):
        return 'pivot normal force: not computed (the event simulator checks it while it rolls)'
    if math.isinf(low):
        return 'pivot normal force: no roll'
    verdict = ("the roll needs the arm to PULL the part: the paper's rolling assumption fails "
               '(effect liftoff simulates it)' if low < 0 else 'the arm pushes throughout')
    return f'smallest pivot normal force {low:.3f} m/s^2 per unit mass: {verdict}'


def _pull_line(pull):
    if pull is None:
        return 'pulling force: not computed (the event simulator checks it while it rolls)'
    return (f'{pull["pulling"]} of {pull["throws"]} limit-set throws ({pull["share"] * 100:.1f} '
            f'%) need the arm to pull the rolling part (worst {pull["worst"]:.3f} m/s^2)')


def _start(scene, args):
    if (args.edge is None) != (args.R is None):
        raise ThrowmapError('--edge and --R go together; give both, or neither to use the '
                            "scene's start")
    if args.edge is None:
        return scene.default_start()
    return args.edge, args.R


def cmd_orbit(scene, args, out):
    edge, R = _start(scene, args)
    orb = orbit(scene.model, edge, R, args.throws)
    if args.json:
        _dump({'scene': scene.name, 'states': orb.rows()}, out)
        return 0
    _table([{'throw': r['throw'], 'edge': r['edge'] if r['edge'] >= 0 else '-',
             'R (cm)': f'{r["R"] * 100:.3f}' if r['edge'] >= 0 else '-',
             'kind': r['kind'] or 'start'} for r in orb.rows()],
           ['throw', 'edge', 'R (cm)', 'kind'], out)
    if orb.kinds[-1] == 'lost':
        why = loss_reason(scene.model, orb.edges[-2], orb.radii[-2]) or 'a noisy throw'
        out.write(f'the part was lost at throw {len(orb.edges) - 1} ({why}); the orbit ends '
                  'there\n')
    return 0


def cmd_limit_set(scene, args, out):
    edge, R = _start(scene, args)
    ls = limit_set(scene.model, edge, R, args.throws)
    pull = pull_share(scene.model, ls)
    d = ls.as_dict()
    d.update({'scene': scene.name, 'start': {'edge': edge, 'R': R}, 'throws': args.throws,
              'pull': pull})
    if args.json:
        _dump(d, out)
        return 0
    out.write(f'{scene.name}: limit set from ({edge}, {R * 100:.2f} cm), {args.throws} throws\n')
    out.write(f'  edge pattern (flips): {" -> ".join(map(str, ls.pattern))} '
              f'({"periodic" if ls.periodic else "not periodic"})\n')
    cl = d['cycle_length']
    out.write(f'  cycle length: {cl["min"]:.0f}..{cl["max"]:.0f} throws, mean {cl["mean"]:.2f}\n')
    out.write(f'  transient: {ls.transient} throws\n')
    out.write(f'  {_pull_line(pull)}\n')
    _table([{'edge': e, 'R min (cm)': f'{lo * 100:.3f}', 'R max (cm)': f'{hi * 100:.3f}',
             'jogs per visit': '{}..{}'.format(*ls.jogs.get(e, ('-', '-')))}
            for e, (lo, hi) in sorted(ls.bands.items())],
           ['edge', 'R min (cm)', 'R max (cm)', 'jogs per visit'], out)
    return 0


def cmd_basin(scene, args, out):
    model = scene.model
    start = scene.default_start()
    ref = limit_set(model, start[0], start[1], 10_000)
    e, r = default_grid(model, args.radii)
    bas = basin(model, e, r, args.throws, reference=ref,
                progress=Progress('basin', args.quiet))
    if args.json:
        _dump({'scene': scene.name, 'throws': args.throws, 'reference': list(ref.pattern),
               'summary': bas.summary(),
               'starts': [{'edge': int(a), 'R': float(b), 'limit': s, 'transient': int(t)}
                          for a, b, s, t in zip(bas.start_edges, bas.start_radii,
                                                bas.signatures, bas.transients)]}, out)
        return 0
    out.write(f'{scene.name}: {len(e)} starts x {args.throws} throws; reference limit set '
              f'{"-".join(map(str, ref.pattern))}\n')
    for sig, n in sorted(bas.summary().items()):
        note = ' (no flip in the last half: still jogging; try more --throws)' \
            if sig == 'no-flip' else ''
        out.write(f'  {n:5d} starts -> {sig}{note}\n')
    t = bas.transients[bas.transients >= 0]
    if t.size:
        out.write(f'  transient: median {np.median(t):.0f}, 90th percentile '
                  f'{np.percentile(t, 90):.0f}, max {t.max()} throws\n')
    return 0


def cmd_design(scene, args, out):
    an = analyse(scene, progress=Progress('design', args.quiet))
    if args.json:
        d = an.as_dict()
        d['scene'] = scene.name
        _dump(d, out)
        return 0
    out.write(f'{scene.name}: design quantities (Proposition IV.4, section V.B)\n')
    _table([{'edge': row['edge'], 'R_grasp (cm)': _fmt_cm(row['R_grasp']),
             'R_min (cm)': _fmt_cm(row['R_min']), 'R_flip (cm)': _fmt_cm(row['R_flip']),
             'R_max (cm)': _fmt_cm(row['R_max'])} for row in an.radii['edges']],
           ['edge', 'R_grasp (cm)', 'R_min (cm)', 'R_flip (cm)', 'R_max (cm)'], out)
    out.write('  (R_min: R_grasp or the toe-stub bound, whichever is larger)\n')
    out.write(f'  invariant set Z found: {"yes" if an.radii["invariant"] else "no"}\n')
    s = an.sensor
    out.write(f'  goal edge {s.goal_edge}: a sensor beyond {s.guarantee_radius * 100:.2f} cm '
              f'sees no other edge of the limit set; the goal edge reaches '
              f'{s.reach_radius * 100:.2f} cm\n')
    out.write(f'  sensor at {s.radius * 100:.2f} cm: fires on {s.detection_rate * 100:.1f} % of '
              f'limit-set throws; trust it after {s.warmup_throws} warm-up throws\n')
    out.write(f'  {_pull_line(an.pull)}\n')
    if an.stochastic is not None:
        st = an.stochastic
        sp = st['sensor']
        out.write(f'  with noise (seed {scene.seed}, {st["seeds"]} Monte Carlo seeds): basin '
                  'outcomes ' + ', '.join(f'{k} {v * 100:.1f} %' for k, v in
                                          sorted(st['basin_outcomes'].items())) + '\n')
        out.write(f'  P(goal edge | detection at {sp["radius"] * 100:.2f} cm) = '
                  f'{sp["p_goal"]:.4f} (95 % interval {sp["p_goal_lo"]:.4f}..'
                  f'{sp["p_goal_hi"]:.4f}, {sp["detections"]} detections in {sp["throws"]} '
                  f'throws; sensor false positive {sp["false_positive"]:g}, false negative '
                  f'{sp["false_negative"]:g}; parts lost in {sp["lost_fraction"] * 100:.0f} % '
                  'of runs)\n')
    return 0


def cmd_plot(scene, args, out):
    from .plots import plot_all
    an = analyse(scene, grid_throws=args.throws + 1, progress=Progress('plot', args.quiet))
    edge, R = an.start
    orb = orbit(scene.model, edge, R, args.orbit_throws)
    paths = plot_all(scene, args.out, orb, an.limit_set, an.basin, an.sensor)
    if args.json:
        _dump({'scene': scene.name, 'plots': paths}, out)
    else:
        for p in paths:
            out.write(f'wrote {p}\n')
    return 0


def _range(text, name):
    try:
        a, b = (float(x) for x in text.split(':'))
    except ValueError:
        raise ThrowmapError(f'--{name}: expected A:B (two numbers), got {text!r}') from None
    if not (math.isfinite(a) and math.isfinite(b)) or a >= b:
        raise ThrowmapError(f'--{name}: need finite A < B, got {text!r}')
    return a, b


# A million designs take about 45 min on two quiet cores; more is a typo, not a search.
MAX_DESIGNS = 1_000_000


def _grid(text):
    try:
        n_h, n_w = (int(x) for x in text.lower().split('x'))
    except ValueError:
        raise ThrowmapError(f'--grid: expected NHxNW (e.g. 40x40), got {text!r}') from None
    if n_h < 2 or n_w < 2:
        raise ThrowmapError(f'--grid: need at least 2x2, got {text!r}')
    if n_h * n_w > MAX_DESIGNS:
        raise ThrowmapError(f'--grid: {n_h * n_w:,} designs is more than {MAX_DESIGNS:,}; '
                            'search a coarse grid first, then a narrower --h/--speed range')
    return n_h, n_w


def _search_options(args):
    """Refuse design-search options that would be swallowed or could never be met."""
    if not 0.0 <= args.robust <= S_MAX:
        raise ThrowmapError(f'--robust: the floor s must lie in [0, {S_MAX}] '
                            f'(errors are searched up to s = {S_MAX}), got '
                            f'{args.robust}')
    if args.top < 1:
        raise ThrowmapError(f'--top: at least 1 design must be assessed, got {args.top}')
    if args.robust_stride < 0:
        raise ThrowmapError(f'--robust-stride: 0 (no map) or a positive stride, got '
                            f'{args.robust_stride}')
    if args.workers is not None and not 1 <= args.workers <= 256:
        raise ThrowmapError(f'--workers: 1 to 256 threads, got {args.workers}')
    if args.objective not in OBJECTIVE_NAMES:
        raise ThrowmapError(f'--objective: expected one of {", ".join(OBJECTIVE_NAMES)}, got '
                            f'{args.objective!r}')
    if args.arrival is not None:
        args.arrival = _arrival(args.arrival)


# --objective's names on the command line and the search's objectives they select.
OBJECTIVE_NAMES = {'part-time': 'part_time', 'ready-rate': 'ready_rate'}


def _arrival(text):
    """Parse --arrival EDGE:RMIN:RMAX (m) into (edge, R lo, R hi); the scene checks the rest."""
    parts = text.split(':')
    try:
        if len(parts) != 3:
            raise ValueError
        edge, r_lo, r_hi = int(parts[0]), float(parts[1]), float(parts[2])
    except ValueError:
        raise ThrowmapError(f'--arrival: expected EDGE:RMIN:RMAX (an edge and R in m, e.g. '
                            f'1:0.10:0.14), got {text!r}') from None
    if not (math.isfinite(r_lo) and math.isfinite(r_hi) and r_lo <= r_hi):
        raise ThrowmapError(f'--arrival: need finite RMIN <= RMAX (m), got {text!r}')
    return edge, r_lo, r_hi


def _search_ranges(scene, args):
    d = scene.part.d_min
    h = _range(args.h, 'h') if args.h else (-0.95 * d, -0.05 * d)
    w0 = scene.release_speed
    w = _range(args.speed, 'speed') if args.speed else (0.5 * w0, 1.5 * w0)
    if w[0] <= 0:
        raise ThrowmapError(f'--speed: release speeds must be > 0 rad/s, got {args.speed!r}')
    return h, w


def _fractions(text):
    try:
        return tuple(float(x) for x in text.split(','))
    except ValueError:
        raise ThrowmapError(f'--sensor-fraction: expected numbers like 0.25,0.5, got '
                            f'{text!r}') from None


def _cand_row(c):
    f = c.figures
    rb = c.robustness or {}
    return {'stage': c.stage, 'h (cm)': f'{c.h * 100:.3f}',
            'speed (deg/s)': f'{math.degrees(c.w):.1f}', 'goal': c.goal,
            'sensor (cm)': _fmt_cm(f['sensor_radius']),
            'readies/throw': f'{f["readies_per_throw"]:.4f}',
            'readies/s': f'{f["readies_per_second"]:.4f}',
            's/part mean/p95': f'{f["part_seconds_mean"]:.1f}/{f["part_seconds_p95"]:.1f}',
            'parts/min': f'{f["parts_per_minute"]:.2f}',
            'first ready mean/p95/max': f'{f["first_ready_mean"]:.1f}/'
                                        f'{f["first_ready_p95"]:.0f}/{f["first_ready_max"]:.0f}',
            'robust s': f'{rb.get("joint_fraction", math.nan):.4f}',
            'dw alone (deg/s)': f'{math.degrees(rb.get("speed_error", math.nan)):.2f}',
            'dh alone (mm)': f'{rb.get("offset_error", math.nan) * 1000:.2f}'}


def cmd_design_search(scene, args, out):
    n_h, n_w = _grid(args.grid)
    h, w = _search_ranges(scene, args)
    goals = [args.goal_edge] if args.goal_edge is not None else None
    fractions = _fractions(args.sensor_fraction)
    objective = OBJECTIVE_NAMES[args.objective]
    res = design_search.search(scene, h, w, n_h, n_w, goals=goals, fractions=fractions,
                               floor=args.robust, top=args.top, workers=args.workers,
                               options=design_kernel.eval_options(scene, throws=args.throws,
                                                                  arrival=args.arrival),
                               progress=Progress('design-search', args.quiet),
                               objective=objective)
    g = res.grid
    if args.vertex_tolerance:
        for cand in (res.chosen, res.reference):
            if cand is not None:
                eps, n, bound = design_search.vertex_tolerance(scene, cand)
                cand.robustness = dict(cand.robustness or {}, vertex_tolerance=eps,
                                       vertex_samples=n, vertex_fail_bound_95=bound)
    rate = (f'{g.h.size} designs in {g.seconds:.2f} s: {g.h.size / g.seconds:.0f} designs/s, '
            f'{g.throws / g.seconds:,.0f} throws/s ({args.workers or 2} threads)')
    written = {}
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        written['heat_map'] = design_search.heat_maps(
            res, os.path.join(args.out, f'{scene.name}_design_map.png'),
            design_search.robustness_map(scene, g, res.shape, args.robust_stride)
            if args.robust_stride else None)
        written['pareto'] = design_search.pareto_plot(
            res, os.path.join(args.out, f'{scene.name}_pareto.png'))
        if res.chosen is not None:
            written['scene'] = design_search.write_scene(
                design_search.design_scene(scene, res.chosen),
                os.path.join(args.out, f'{scene.name}_design.yaml'))
    if args.json:
        d = design_search.summary(scene, res, args.scene)
        d['written'] = written
        d['throughput'] = {'designs_per_s': g.h.size / g.seconds, 'throws_per_s':
                           g.throws / g.seconds}
        _dump(d, out)
        return 0 if res.chosen is not None else 1
    out.write(f'{scene.name}: design search over h {h[0] * 100:.3f}..{h[1] * 100:.3f} cm x '
              f'speed {math.degrees(w[0]):.1f}..{math.degrees(w[1]):.1f} deg/s, grid '
              f'{n_h}x{n_w}\n  {rate}\n')
    elig = int(design_search.eligible(g).any(axis=(1, 2)).sum())
    out.write(f'  {elig} designs: every start reaches one limit set holding the goal edge, '
              'sensor fits\n')
    what = design_search.OBJECTIVES[objective]
    starts = ('the grid of starts' if g.arrival is None else
              f'{g.arrival[3]} arrivals on edge {g.arrival[0]}, R uniform in '
              f'{g.arrival[1] * 100:.2f}..{g.arrival[2] * 100:.2f} cm')
    ties = ', p95 breaking ties' if objective == 'part_time' else ''
    out.write(f'  ranked by {what}{ties} (--objective {args.objective}); first readies (throws, '
              f"s/part = throws x the limit set's mean cycle) from {starts}\n")
    cols = ['stage', 'h (cm)', 'speed (deg/s)', 'goal', 'sensor (cm)', 'readies/throw',
            'readies/s', 'first ready mean/p95/max', 's/part mean/p95', 'parts/min',
            'robust s', 'dw alone (deg/s)', 'dh alone (mm)']
    out.write(f'  Pareto front ({what} against robustness):\n')
    _table([_cand_row(c) for c in res.pareto], cols, out)
    out.write("  the scene's own design:\n")
    _table([_cand_row(res.reference)], cols, out)
    if res.chosen is not None:
        out.write(f'  chosen (best {what} with robustness >= {args.robust}):\n')
        _table([_cand_row(res.chosen)], cols, out)
    for cand, what in ((res.chosen, 'chosen'), (res.reference, 'scene design')):
        rb = (cand.robustness or {}) if cand is not None else {}
        if 'audit_samples' in rb:
            bound = rb['audit_miss_bound_95']
            verdict = (f'missed fraction < {bound:.2g} with 95 % confidence' if rb['audit_misses']
                       == 0 else 'the sampled verdict is not confirmed there')
            out.write(f'  {what}: cell map audited at s {rb["joint_fraction"]:.4f} on '
                      f'{rb["audit_samples"]} random samples of cell x box: '
                      f'{rb["audit_misses"]} misses ({verdict})\n')
        if 'vertex_tolerance' in rb:
            out.write(f'  {what}: vertex tolerance {rb["vertex_tolerance"] * 1000:.2f} mm (every '
                      f'one of {rb["vertex_samples"]} perturbed parts per level keeps the limit '
                      'set and the proof; sampled: 95 % bound on the failing fraction of random '
                      f'shapes {rb["vertex_fail_bound_95"] or 0:.3f})\n')
    for note in res.notes:
        out.write(f'  note: {note}\n')
    for what, path in written.items():
        out.write(f'  wrote {what}: {path}\n')
    return 0 if res.chosen is not None else 1


def cmd_catalogue(args, out):
    paths = design_search.scene_paths(args.scene)
    scenes = [load_scene(p) for p in paths]
    for sc in scenes:
        design_kernel.check_scene(sc)     # refused here, before any worker starts
    n_h, n_w = _grid(args.grid)
    if args.arrival is not None:
        raise ThrowmapError("--arrival: a chute drops parts on one part's edge; a catalogue "
                            'has many parts: search its scenes one by one')
    ranges = [_search_ranges(sc, args) for sc in scenes]
    t0 = time.perf_counter()
    results = design_search.run_catalogue(paths, ranges, n_h, n_w,
                                          _fractions(args.sensor_fraction), args.robust,
                                          args.top, scheduler=args.scheduler,
                                          workers=args.workers or 2, throws=args.throws,
                                          objective=OBJECTIVE_NAMES[args.objective])
    seconds = time.perf_counter() - t0
    if args.json:
        _dump({'catalogue': args.scene, 'seconds': seconds, 'results': results}, out)
        return 0
    out.write(f'catalogue {args.scene}: {len(paths)} scenes in {seconds:.1f} s on Dask '
              f'({args.scheduler or "local cluster on 127.0.0.1"})\n')
    for r in results:
        c = r['chosen']
        text = ('no design meets the floor' if c is None else
                f'h {c["h"] * 100:.3f} cm, {c["release_speed_deg"]:.1f} deg/s, goal '
                f'{c["goal_edge"]}, {c["figures"]["part_seconds_mean"]:.1f} s/part (p95 '
                f'{c["figures"]["part_seconds_p95"]:.1f}), '
                f'{c["figures"]["readies_per_second"]:.4f} readies/s, '
                f'robust s {c["robustness"]["joint_fraction"]:.4f}')
        out.write(f'  {r["scene"]}: {r["designs"]} designs, {r["seconds"]:.2f} s: {text}\n')
    return 0


def _funnel_row(name, f):
    def num(x, fmt):
        return 'never' if x is None or (isinstance(x, float) and math.isinf(x)) else fmt % x
    return {'policy': name, 'mean': num(f['mean'], '%.2f'), 'p95': num(f['p95'], '%.1f'),
            'worst': num(f['worst'], '%.0f'), 'never ready': f.get('never', 0),
            'false readies': f.get('false_readies', ''),
            'knowledge lost': f.get('knowledge_lost', ''), 'part lost': f.get('lost', ''),
            'no safe speed': f.get('no_safe_speed', '')}


def cmd_funnel(scene, args, out):
    speeds = funnel.parse_speeds(args.speeds)
    if not 20 <= args.cells <= funnel.MAX_CELLS:
        raise ThrowmapError(f'--cells: 20 to {funnel.MAX_CELLS} cells per edge, got {args.cells}')
    if args.arm_length is not None and not (math.isfinite(args.arm_length)
                                            and args.arm_length > 0):
        raise ThrowmapError(f'--arm-length: must be a length > 0 cm, got {args.arm_length}; '
                            "give the arm's length in cm, e.g. --arm-length 40")
    arm = None if args.arm_length is None else args.arm_length / 100.0
    on_arm, note = funnel.arm_scene(scene, arm)
    t0 = time.perf_counter()
    res = funnel.plan(on_arm, speeds, robust=args.robust, cells=args.cells,
                      max_throws=args.throws, one_bit=args.one_bit_bound,
                      progress=(Progress('one-bit bound', args.quiet) if args.one_bit_bound
                                else None))
    seconds = time.perf_counter() - t0
    s = res.system
    notes = ([note] if note else []) + res.notes
    figures = res.figures()
    written = {}
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        written['plot'] = funnel.plot_throws(
            res, os.path.join(args.out, f'{scene.name}_funnel.png'),
            f'{scene.name}: throws to the first proven ready, speeds '
            f'{math.degrees(s.speeds[0]):.0f}-{math.degrees(s.speeds[-1]):.0f} deg/s, '
            f'errors s = {s.robust:g}')
        path = os.path.join(args.out, f'{scene.name}_funnel_policy.json')
        with open(path, 'w') as fh:
            json.dump(funnel.policy_dict(res, args.scene), fh)
        written['policy'] = path
    if args.json:
        _dump({'scene': args.scene, 'speeds_deg': np.degrees(s.speeds), 'robust': s.robust,
               'arm_length': s.arm_length, 'cells_per_edge': s.m, 'goal_edge': s.goal_edge,
               'sensor_radius': s.sensor_radius, 'starts': len(res.starts[0]),
               'figures': figures, 'design_search_fixed': res.search_figures,
               'open_loop_speeds_deg': [None if k < 0 else math.degrees(s.speeds[k])
                                        for k in res.sequence[:50]],
               'safe_speeds_deg': [math.degrees(s.speeds[k]) for k in res.safe_speeds],
               # keyed by speed in deg/s, to 10 digits: '%g' would join 120.0001 and 120.0002
               'one_bit_first_use': (None if res.one_bit is None else
                                     {f'{math.degrees(w):.10g}': n for w, n in
                                      zip(s.speeds, res.one_bit.first_use)}),
               'per_start': {'edge': res.starts[0], 'R': res.starts[1],
                             'bound': res.bound, 'safe_speed_bound': res.safe_bound,
                             **({'one_bit_bound': res.one_bit.throws} if res.one_bit else {}),
                             **{n: r.throws for n, r in res.runs.items()}},
               'notes': notes, 'written': written, 'seconds': seconds}, out)
        return 0
    out.write(f'{scene.name}: funnel over {len(s.speeds)} speeds {math.degrees(s.speeds[0]):.1f}'
              f'..{math.degrees(s.speeds[-1]):.1f} deg/s, per-throw errors s = {s.robust:g} '
              f'(+-{s.dh * 1000:.3f} mm offset, +-s w speed), {s.m} cells per edge up to the '
              f"arm's end {s.arm_length * 100:.1f} cm; sensor {s.sensor_radius * 100:.2f} cm, "
              f'goal edge {s.goal_edge}; {len(res.starts[0])} starts (the design search grid); '
              f'{seconds:.1f} s\n')
    out.write('  throws to the first proven ready (a detection with every cell of the '
              'knowledge on the goal edge):\n')
    rows = [_funnel_row('full-knowledge bound', figures['bound'])]
    if res.one_bit is not None:
        rows.append(_funnel_row('one-bit bound', figures['one-bit bound']))
    rows.append(_funnel_row('full knowledge, safe speeds', figures['safe-speed bound']))
    for name in ('fixed', 'open-loop', 'sensor-based'):
        rows.append(_funnel_row(name, figures[name]))
        rows.append(_funnel_row(f'{name} (errors)', figures[f'{name} (errors)']))
    _table(rows, ['policy', 'mean', 'p95', 'worst', 'never ready', 'false readies',
                  'knowledge lost', 'part lost', 'no safe speed'], out)
    if any(f.get('no_safe_speed') for f in figures.values()):
        out.write('  no safe speed: starts whose knowledge reached a set from which every '
                  'allowed speed may lose the part (a throw off the arm, or a failing one); '
                  'they stop there without a ready (a throw that may lose the part is never '
                  'chosen)\n')
    sf = res.search_figures
    out.write(f"  the design search's figure for the fixed design (its warm-up rule, no errors, "
              f'sensor {sf["sensor_radius"] * 100:.2f} cm): mean {sf["mean"]:.2f}, p95 '
              f'{sf["p95"]:.0f}, worst {sf["worst"]:.0f}\n')
    seq = ' '.join('-' if k < 0 else f'{math.degrees(s.speeds[k]):.0f}'
                   for k in res.sequence[:20])
    out.write(f'  open-loop speeds (deg/s), first 20: {seq}\n')
    safe = [math.degrees(s.speeds[k]) for k in res.safe_speeds]
    out.write('  full knowledge, safe speeds: the bound with only the speeds no start cell can '
              f'be lost by ({", ".join(f"{w:.0f}" for w in safe)} deg/s; not a bound on the '
              'policies, which may use others once the knowledge narrows)\n')
    if res.one_bit is not None:
        groups = []     # runs of neighbouring speeds first usable at the same throw
        for w, n in zip(np.degrees(s.speeds), res.one_bit.first_use):
            if groups and groups[-1][2] == n:
                groups[-1][1] = w
            else:
                groups.append([w, w, n])
        late = ', '.join(f'{a:.0f}' + (f'-{b:.0f}' if b != a else '') + f' from throw {n:.0f}'
                         for a, b, n in groups if n > 1)
        out.write('  one-bit bound: no policy that reads only the bit and never risks the part '
                  'has its first ready sooner (nominal throws; below the fixed, open-loop and '
                  'sensor-based rows start by start): until the first detection every start '
                  'gets the same speeds, and a speed is usable only once no state the zeros '
                  f'allow can be lost by it ({late or "every speed from the first throw"})\n')
    out.write('  (errors): each throw at a corner, edge midpoint or centre of the error box, '
              'drawn at random (seeded)\n')
    for n in notes:
        out.write(f'  note: {n}\n')
    for what, path in written.items():
        out.write(f'  wrote {what}: {path}\n')
    return 0


COMMANDS = {'grasp': cmd_grasp, 'throw': cmd_throw, 'orbit': cmd_orbit,
            'limit-set': cmd_limit_set, 'basin': cmd_basin, 'design': cmd_design,
            'plot': cmd_plot, 'design-search': cmd_design_search, 'funnel': cmd_funnel}


def build_parser():
    parser = argparse.ArgumentParser(
        prog='throwmap', description='Throw map of a dynamic parts feeder (Lynch, Northrop, '
        'Pan). Lengths in metres, angles in radians, g < 0 as in the paper.')
    sub = parser.add_subparsers(dest='command', required=True, metavar='COMMAND')

    def add(name, help_text):
        p = sub.add_parser(name, help=help_text, description=help_text)
        p.add_argument('scene', help='scene YAML file (e.g. scenes/triangle.yaml)')
        p.add_argument('--json', action='store_true', help='print JSON instead of a table')
        p.add_argument('--quiet', action='store_true', help='no progress on stderr')
        p.add_argument('--seed', type=int, default=None,
                       help="seed of the scene's random numbers (effects release_noise, "
                       "sensor_noise); default: the scene's noise.seed")
        return p

    add('grasp', 'R_grasp and mu_min per edge (impulse cone)')
    p = add('throw', 'one throw from --edge/--R, or JSON lines {"edge": 1, "R": 0.12} on stdin')
    p.add_argument('--edge', type=int)
    p.add_argument('--R', type=float, help='throwing radius, m')
    for name, text in (('orbit', 'iterate f: the states after each throw'),
                       ('limit-set', 'forward limit set: edge pattern, R bands, cycle lengths')):
        p = add(name, text)
        p.add_argument('--edge', type=int, help="start edge (default: the scene's start)")
        p.add_argument('--R', type=float, help='start radius, m')
        p.add_argument('--throws', type=int, default=100 if name == 'orbit' else 10_000)
    p = add('basin', 'orbits from a grid of starts: which limit set each reaches')
    p.add_argument('--radii', type=int, default=50, help='radii per stable edge (default 50)')
    p.add_argument('--throws', type=int, default=100)
    add('design', 'R_flip, R_max, the sensor radius and the warm-up throws')
    p = add('plot', 'write PNGs like Figures 5, 6 and 7')
    p.add_argument('--out', default='plots', help='output directory (default: plots)')
    p.add_argument('--throws', type=int, default=100, help='throws per basin start')
    p.add_argument('--orbit-throws', type=int, default=300, help='throws in the orbit plot')
    p = add('design-search', 'search h, release speed, goal edge and sensor position: seconds '
            'per part (or readies per second) under a robustness floor (SCENE may be a folder '
            'of scenes: a catalogue on Dask)')
    p.add_argument('--objective', default='part-time', help='rank by part-time (mean seconds '
                   "from a part's arrival to its first proven ready, p95 breaks ties; default) "
                   'or ready-rate (proven readies per second in the limit set)')
    p.add_argument('--arrival', help='EDGE:RMIN:RMAX: parts arrive from a chute on edge EDGE '
                   'with R uniform in [RMIN, RMAX] m; first readies from there instead of the '
                   'grid of starts')
    p.add_argument('--h', help='arm offsets A:B, m (default: -0.95..-0.05 d_min)')
    p.add_argument('--speed', help="release speeds A:B, rad/s (default: 0.5..1.5 x the scene's)")
    p.add_argument('--grid', default='40x40', help='offsets x speeds (default 40x40)')
    p.add_argument('--goal-edge', type=int, help="goal edge (default: the scene's, else every "
                   'stable edge)')
    p.add_argument('--sensor-fraction', default='0.25', help='sensor positions to try, as '
                   'fractions of the window between guarantee and reach (default 0.25)')
    p.add_argument('--robust', type=float, default=0.0, help='robustness floor s: every throw '
                   'within +-s of the speed and +-s d_min of the offset (default 0)')
    p.add_argument('--top', type=int, default=8, help='designs assessed for robustness')
    p.add_argument('--throws', type=int, default=120, help='throws per basin start (default '
                   '120; a part with a long cycle needs more: every start must show a proven '
                   'ready within them)')
    p.add_argument('--robust-stride', type=int, default=0, help='robustness heat map on every '
                   'N-th offset and speed (0: none)')
    p.add_argument('--vertex-tolerance', action='store_true', help='also the largest vertex '
                   'tolerance of the chosen and the scene design (sampled; ~30 s each)')
    p.add_argument('--workers', type=int, default=None, help='threads (default: 2)')
    p.add_argument('--scheduler', help='Dask scheduler address for a catalogue (default: a '
                   'local cluster on 127.0.0.1)')
    p.add_argument('--out', help='write heat maps, the Pareto plot and the chosen scene here')
    p = add('funnel', "choose each throw's release speed from the sensor's bits: throws to "
            'the first proven ready for the fixed design, an open-loop and a sensor-based '
            'policy, the full-knowledge bound and (--one-bit-bound) the one-bit bound '
            '(docs/funnel.md)')
    p.add_argument('--speeds', required=True, help='the speeds the actuator allows, deg/s: '
                   'A:B:STEP (e.g. 120:600:20) or a list A,B,C')
    p.add_argument('--robust', type=float, default=0.005, help='per-throw error bound s: '
                   'every throw within +-s w of its speed and +-s d_min of the offset '
                   '(default 0.005)')
    p.add_argument('--arm-length', type=float, help="the arm's length, cm (default: the "
                   "scene's; a scene without one needs it)")
    p.add_argument('--cells', type=int, default=200, help='cells per stable edge (default 200)')
    p.add_argument('--throws', type=int, default=200, help='throws per start at most '
                   '(default 200)')
    p.add_argument('--one-bit-bound', action='store_true', help='also the one-bit bound: '
                   'what any policy that reads only the bit and never risks the part needs at '
                   'least (about a minute on the triangle, more on effect scenes)')
    p.add_argument('--out', help='write the plot and the policy file (JSON) here')
    return parser


# The counts' upper ends, refused before anything is allocated: an orbit's states are kept
# (16 bytes a throw: 160 MB at 10^7) and a basin's 10^5 radii per edge are finer than its plot.
COUNT_LIMITS = {
    'throws': (10_000_000, 'run a longer orbit in pieces, each from the last state'),
    'radii': (100_000, 'a basin of more radii is not finer to see; give fewer'),
    'orbit_throws': (10_000_000, 'plot fewer throws'),
}


def _positive(args):
    for name, (most, fix) in COUNT_LIMITS.items():
        value = getattr(args, name, None)
        flag = f'--{name.replace("_", "-")}'
        if value is not None and value < 1:
            raise ThrowmapError(f'{flag} must be >= 1, got {value}')
        # design-search keeps its throws in a range of its own (10 to 10,000), said with it
        if value is not None and value > most and args.command != 'design-search':
            raise ThrowmapError(f'{flag} must be at most {most:,}, got {value:,}; {fix}')


def _out_directory(args):
    # Checked before the work (a design search may take an hour), not when the files are written.
    path = getattr(args, 'out', None)
    if path and os.path.exists(path) and not os.path.isdir(path):
        raise ThrowmapError(f'--out {path}: is a file, not a directory; give a directory '
                            '(it is created if missing)')


def main(argv=None, out=None):
    out = out or sys.stdout
    args = build_parser().parse_args(argv)
    try:
        _positive(args)
        _out_directory(args)
        if args.command == 'design-search':
            _search_options(args)
        if args.command == 'design-search' and os.path.isdir(args.scene):
            return cmd_catalogue(args, out)
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')   # the scene's warnings are printed below, once
            scene = load_scene(args.scene, seed=args.seed)
        for msg in scene.warnings:
            sys.stderr.write(f'throwmap: warning: {args.scene}: {msg}\n')
        return COMMANDS[args.command](scene, args, out)
    except ThrowmapError as exc:
        sys.stderr.write(f'throwmap: error: {exc}\n')
        return 2
    except BrokenPipeError:   # e.g. `throwmap orbit ... | head`
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
    except OSError as exc:    # a file or directory the command could not read or write
        sys.stderr.write(f'throwmap: error: {exc.filename}: {exc.strerror}; check the path '
                         'and its permissions\n')
        return 2


if __name__ == '__main__':
    sys.exit(main())
