#!/usr/bin/env python3
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
How many plate-drag evaluations issue 24's bar allows a throw, and how many a flight needs.

Issue 24 asks every effect to throw within 10x the base model's time at the accuracy of the
default before it (backplate_friction: max |dR| 1.5e-9 m on the experiment scene). This
measures, on the experiment scene's flights, the two numbers that decide whether a flight that
samples the drag along its motion can do that:

* the budget: 10x the base model's time per throw over the time of one exact drag evaluation
  (compiled, along real flights), i.e. how many evaluations the bar pays for if the rest of
  the throw cost nothing;
* the need: how many evaluations the present default makes per throw (counted in pure Python
  with numba off), and how many one sweep alone takes, the drag's double integral along the
  ballistic flight to the contact, int_0^T (T - t) (fx, fy, size tq)(t) dt, to a given
  absolute error in metres: by adaptive Gauss-Kronrod (scipy's ``quad_vec``, 21 points a
  panel) and by 5-node Gauss on equal pieces, each of the drag as it is and of the drag less
  its logarithm where the instantaneous centre crosses the outline
  (``crossing_log_coefficient``; subtracted everywhere, or corrected only on the pieces
  that touch a crossing by ``picard.log_tables``).

Prints figures; asserts nothing. About 2 minutes.

    python bench/plate_floor.py [--states 30]
"""

import argparse
import math
import os
import pathlib
import subprocess
import sys
import time

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import accuracy_vs_time as avt  # noqa: E402
from throwmap.effects.backplate_friction import plate_drag_exact  # noqa: E402
from throwmap.internal import carry_release_state  # noqa: E402
from throwmap import picard  # noqa: E402
from throwmap.jit import njit  # noqa: E402

TOLS = (1e-8, 1e-9, 1e-10)      # m: the sweep's double integral's absolute error
# 5-node Gauss on [0, 1]: nodes, weights, and log_tables' end corrections (E1, E2) for a
# logarithm at a piece's start (False) and end (True)
GAUSS5 = (picard.tables(5)[0], 0.5 * np.polynomial.legendre.leggauss(5)[1],
          {False: picard.log_tables(5)[2:], True: picard.log_tables(5, at_end=True)[2:]})


@njit
def drag_along(vx, vy, om, phi, g, ou, ov, cu, cv, size, mom, coef, vreg, T, n):
    """Sum of the drag at n instants of the ballistic flight (a timing loop)."""
    acc = 0.0
    for i in range(n):
        t = T * i / n
        fx, fy, tq = plate_drag_exact(vx, vy + g * t, om, phi + om * t, ou, ov, cu, cv, size,
                                      mom, coef, vreg)
        acc += fx + fy + tq
    return acc


def flights(model, edges, radii):
    """Release state and first-contact time of each state's throw."""
    part = model.part
    out = []
    for e, r in zip(edges, radii):
        x0, y0, phi0, vx, vy, om = carry_release_state(int(e), float(r), model.w, model.h, 0.0,
                                                       part.d)
        out.append((int(e), phi0, vx, vy, om, model.throw(int(e), float(r)).flight_time))
    return out


def drag_args(model, e, phi0, vx, vy, om):
    p = model.prm.backplate_friction
    return (vx, vy, om, phi0, model.g, p.OU[e], p.OV[e], p.CU[e], p.CV[e], p.size, p.MOM[e],
            p.coef, p.vreg)


def evaluation_time(model, fl):
    """ns per drag evaluation, best of 7, along the flights."""
    n = 20000
    drag_along(*drag_args(model, *fl[0][:5]), 0.1, 10)
    best = math.inf
    for _ in range(7):
        t0 = time.perf_counter()
        for e, phi0, vx, vy, om, T in fl:
            drag_along(*drag_args(model, e, phi0, vx, vy, om), T, n)
        best = min(best, time.perf_counter() - t0)
    return best / (n * len(fl)) * 1e9


def crossings(model, e, phi0, vx, vy, om, T, samples=2000):
    """(time, edge) where the ballistic flight's instantaneous centre crosses an outline edge."""
    from scipy.optimize import brentq
    p = model.prm.backplate_friction
    ou, ov = p.OU[e], p.OV[e]

    def side_along(t, k):
        # om times (the side of edge k's line, the position along it) of the centre
        bx, by = picard.body_velocity(vx, vy + model.g * t, phi0 + om * t)
        return picard.centre_edge(bx, by, om, ou, ov, k)

    ts = np.linspace(0.0, T, samples + 1)
    out = []
    for k in range(ou.shape[0]):
        sv = [side_along(t, k)[0] for t in ts]
        for i in range(samples):
            if sv[i] * sv[i + 1] < 0.0:
                tk = brentq(lambda t, k=k: side_along(t, k)[0], ts[i], ts[i + 1], xtol=1e-15)
                if 0.0 < side_along(tk, k)[1] / om < 1.0:
                    out.append((tk, k))
    return out


def gauss_pieces(f, T, bounds_of, tol, ref, most=400, log_part=None, cross=()):
    """
    Evaluations of 5-node Gauss on n pieces (bounds_of(n)) of int_0^T (T - t) f dt within tol
    of ref: the least n from which n + 1 ... n + 4 are within it too (a lucky cancellation does
    not count). inf past ``most`` pieces. ``log_part(t, k)``: B of crossing (t_k, k) in
    ``cross``; a piece that starts or ends at t_k is corrected for B ln|t - t_k| by
    picard.log_tables, as a piece of the series flight would be (B costs no drag evaluation).
    """
    c, w, corrections = GAUSS5
    run = 0
    for n in range(1, most + 1):
        bounds = bounds_of(n)
        total = np.zeros(3)
        for a, b in zip(bounds[:-1], bounds[1:]):
            h = b - a
            ts = a + c * h
            values = np.array([f(t) for t in ts])
            vel = h * (w @ values)
            pos = h * h * ((w * (1.0 - c)) @ values)
            for tk, k in cross:
                if tk in (a, b):
                    e1, e2 = corrections[tk == b]
                    bs = np.array([log_part(t, k) for t in ts])
                    vel = vel + h * (e1 @ bs)
                    pos = pos + h * h * (e2 @ bs)
            total += (T - b) * vel + pos
        run = run + 1 if np.max(np.abs(total - ref)) <= tol else 0
        if run == 5:
            return 5 * (len(bounds_of(n - 4)) - 1)
    return math.inf


def quadrature_counts(model, fl):
    """
    Evaluations one sweep takes along each flight, per tolerance, of the drag and of the drag
    less each crossing's B ln|t - t_k| (crossing_log_coefficient; that part integrated apart,
    as a flight would in closed form): adaptive Gauss-Kronrod (quad_vec), and 5-node Gauss on
    equal pieces (plain: ended at the crossings too, as the series flight's are).
    """
    from scipy.integrate import quad_vec
    from throwmap.internal import crossing_log_coefficient
    p = model.prm.backplate_friction
    size = p.size
    kinds = ('gk', 'gk less', 'gauss', 'gauss less', 'gauss corrected')
    counts = {key: {tol: [] for tol in TOLS} for key in kinds}
    agree = 0.0
    n_cross = []
    for e, phi0, vx, vy, om, T in fl:
        args = drag_args(model, e, phi0, vx, vy, om)
        cross = crossings(model, e, phi0, vx, vy, om, T)
        n_cross.append(len(cross))
        at_cross = sorted(tk for tk, _ in cross)

        def state(t):
            return args[0], args[1] + args[4] * t, args[2], args[3] + args[2] * t

        def drag(t):
            fx, fy, tq = plate_drag_exact(*state(t), *args[5:])
            return np.array([fx, fy, size * tq])

        def coefficient(t, k):
            bx, by, bt = crossing_log_coefficient(*state(t), p.OU[e], p.OV[e], p.coef, k)
            return np.array([bx, by, size * bt])

        def log_part(t):
            out = np.zeros(3)
            for tk, k in cross:
                if t != tk:
                    out += coefficient(t, k) * math.log(abs(t - tk))
            return out

        def smooth(t):
            return drag(t) - log_part(t)

        def ended_at_crossings(n):
            return np.unique(np.r_[np.linspace(0.0, T, n + 1), at_cross])

        ref = quad_vec(lambda t: (T - t) * drag(t), 0.0, T, epsabs=1e-14, epsrel=0.0,
                       norm='max', limit=100000, points=at_cross or None)[0]
        logs = quad_vec(lambda t: (T - t) * log_part(t), 0.0, T, epsabs=1e-15, epsrel=0.0,
                        norm='max', limit=100000, points=at_cross or None)[0]
        for tol in TOLS:
            a = quad_vec(lambda t: (T - t) * drag(t), 0.0, T, epsabs=tol, epsrel=0.0,
                         norm='max', limit=100000, full_output=True)
            b = quad_vec(lambda t: (T - t) * smooth(t), 0.0, T, epsabs=tol, epsrel=0.0,
                         norm='max', limit=100000, full_output=True)
            counts['gk'][tol].append(a[2].neval)
            counts['gk less'][tol].append(b[2].neval)
            if tol == TOLS[-1]:
                agree = max(agree, float(np.max(np.abs(ref - (b[0] + logs)))))
            counts['gauss'][tol].append(gauss_pieces(drag, T, ended_at_crossings, tol, ref))
            counts['gauss less'][tol].append(gauss_pieces(
                smooth, T, lambda n: np.linspace(0.0, T, n + 1), tol, ref - logs))
            counts['gauss corrected'][tol].append(gauss_pieces(
                drag, T, ended_at_crossings, tol, ref, log_part=coefficient, cross=cross))
    return counts, agree, n_cross


COUNTER = '''
import sys, numpy as np
sys.path.insert(0, {here!r})
import accuracy_vs_time as avt
from throwmap.effects import backplate_friction as bf
calls = [0]
exact = bf.plate_drag_exact
def counted(*a):
    calls[0] += 1
    return exact(*a)
bf.plate_drag_exact = counted
model = avt.load('experiment').model
edges, radii = np.load({states!r})
per = []
for e, r in zip(edges, radii):
    calls[0] = 0
    model.f(int(e), float(r))
    per.append(calls[0])
print(np.median(per), np.mean(per), max(per))
'''


def counted_evaluations(edges, radii, tmp):
    """Drag evaluations per throw at the defaults: (median, mean, max), numba off."""
    states = pathlib.Path(tmp) / 'states.npy'
    np.save(states, np.array([edges, radii]))
    env = dict(os.environ, NUMBA_DISABLE_JIT='1')
    code = COUNTER.format(here=str(HERE), states=str(states))
    out = subprocess.run([sys.executable, '-c', code], env=env, check=True, capture_output=True,
                         text=True).stdout.split()
    return tuple(float(v) for v in out)


def main():
    import tempfile
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--states', type=int, default=30)
    args = parser.parse_args()
    tri = avt.load('triangle').model
    exp = avt.load('experiment').model
    t_edges, t_radii = avt.random_states(tri, 250, seed=0, r_hi=0.3)
    seed, r_hi = avt.PLATE_SCENES['experiment'][2]
    edges, radii = avt.random_states(tri, 250, seed=seed, r_hi=r_hi)
    base = avt.timed_best(tri, t_edges, t_radii, 15)[1]
    plate = avt.timed_best(exp, edges, radii, 5)[1]
    fl = flights(exp, edges[:args.states], radii[:args.states])
    ns = evaluation_time(exp, fl)
    with tempfile.TemporaryDirectory() as tmp:
        med, mean, most = counted_evaluations(edges[:args.states], radii[:args.states], tmp)
    counts, agree, n_cross = quadrature_counts(exp, fl)
    budget = 10.0 * base * 1e3 / ns
    print(f'base model (triangle, 250 states, best of 15): {base:.2f} us per throw; '
          f'10x: {10 * base:.2f} us')
    print(f'the plate (experiment scene, defaults, 250 states, best of 5): {plate:.2f} us per '
          f'throw, {plate / base:.0f}x the base model')
    print(f'one exact drag evaluation along the flights: {ns:.0f} ns')
    print(f'the bar pays for {budget:.0f} evaluations a throw, if nothing else cost time')
    print(f'\n{args.states} flights of the experiment scene (flight time '
          f'{min(f[5] for f in fl):.3f}-{max(f[5] for f in fl):.3f} s):')
    print(f'the default flight and roll: {mean:.0f} evaluations a throw (median {med:.0f}, '
          f'max {most:.0f}), {mean * ns / 1e3:.1f} us of evaluations alone')
    print(f'one sweep (the drag along the ballistic flight, int_0^T (T - t) F dt); the centre '
          f'crosses the outline {np.mean(n_cross):.1f} times a flight; with each crossing\'s '
          f'B ln|t - t_k| subtracted and integrated apart (at {TOLS[-1]:g} m within {agree:.1e} m '
          f'of the plain integral): evaluations, median / max over the flights')
    print('| abs error (m) | adaptive Gauss-Kronrod | subtracted | 5-node Gauss, equal pieces '
          'ended at the crossings | subtracted, equal pieces | equal pieces ended at the '
          'crossings, the two next to each corrected (picard.log_tables) |')
    print('|---:|---:|---:|---:|---:|---:|')
    for tol in TOLS:
        row = ' | '.join(f'{np.median(counts[k][tol]):.0f} / {max(counts[k][tol]):.0f}'
                         for k in counts)
        print(f'| {tol:g} | {row} |')

if __name__ == '__main__':
    main()
