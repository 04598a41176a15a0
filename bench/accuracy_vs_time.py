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

"""What accuracy costs in time: every accuracy knob, every effect set, and pymunk side by side.

For each configuration: the time per throw (f_batch, one core) and the error against a
high-accuracy reference of the same physics:
* throws: share of random states whose resting edge differs, and the median / max |dR| of the
  rest (mm);
* orbit: throws until the first edge that differs from the reference orbit (from the scene's
  start; the map expands, so any error shows up eventually);
* band: largest difference of the limit set's R bands (mm), from a long orbit.
pymunk (a general-purpose 2D engine) simulates the same throw and catch from the same release
state at several time steps; its reference is the base model (pymunk has no plate friction).

Prints markdown tables and writes a Pareto plot (time per throw vs error). Asserts nothing.
Usage: python bench/accuracy_vs_time.py [--quick] [--out docs/accuracy_pareto.png]
       python bench/accuracy_vs_time.py --plate [--before REV] [--quick]
       python bench/accuracy_vs_time.py --contact [--before REV] [--quick]
       python bench/accuracy_vs_time.py --overhead [--quick]
--plate measures only backplate_friction's configurations (the experiment scene and the
triangle with the plate), --contact only the contact effects' (the rectangle scene: bounces,
unilateral pivots; the triangle at e 0.2, mu 0.8: bounces, pinned pivots; the liftoff scene),
each time the best of 3 runs; --before REV measures the same with the code of git revision
REV (git archive, in a child process) in the same run, on the same states against the same
reference.
--overhead measures what the plate's flight methods cost with a drag that costs nothing
(mu_p 0, the same steps and kink searches) beside mu_p 0.1, and air_drag on the experiment
scene's geometry (its in-plane gravity and 40 cm arm, the air instead of the plate).
"""

import argparse
import copy
import math
import os
import pathlib
import platform
import sys
import time

import numpy as np
from throwmap import limit_set_from_orbit
from throwmap.internal import carry_release_state as release_state
from throwmap.scene import read_yaml, Scene

ROOT = pathlib.Path(__file__).resolve().parents[1]
WRONG_EDGE_MM = 10.0      # a throw that ends on the wrong edge counts as a 10 mm error
# Issue 24's methods: the order-8 flight with error control (and the default closed-form roll).
RK8_FLIGHT = {'flight_method': 'rk8', 'flight_step': 0.1, 'flight_tol': 1e-9}
# The series about the ballistic flight (flight_method picard; issue 24, the plate).
PICARD_FLIGHT = {'flight_method': 'picard', 'flight_step': 0.08, 'flight_tol': 1e-6}
FAST_CONFIGS = [
    {'integrator_step': 5e-3},
    {'integrator_step': 2e-3},
    dict(RK8_FLIGHT, flight_tol=1e-6),
    RK8_FLIGHT,
    dict(RK8_FLIGHT, flight_tol=1e-11),
    PICARD_FLIGHT,
    dict(PICARD_FLIGHT, flight_step=0.04, flight_tol=1e-7),
    dict(PICARD_FLIGHT, flight_step=0.02, flight_tol=1e-9),
]
# --plate: the plate's configurations, each measured with this code and (--before REV) with
# the code of git revision REV in a child process, on the same states against one reference.
PLATE_REF_KNOBS = {'integrator_step': 5e-5, 'roll_step': 5e-5, 'plate_quadrature': 0,
                   'contact_root_tol': 1e-13, 'roll_method': 'rk4', 'flight_method': 'rk4'}
PLATE_CONFIGS = [{}, {'integrator_step': 5e-3}, dict(RK8_FLIGHT, flight_tol=1e-6)] + [
    c for c in FAST_CONFIGS if c.get('flight_method') == 'picard'] + [
    # the plate's default flight before session 39 (its defaults since: the graded series)
    {'flight_method': 'rk4'}]
PLATE_SCENES = {  # scene name, changes, (seed, largest R) of the random states, orbit start:
    # the experiment's as in its table below, the triangle with the plate as in the effects table
    'experiment': ('experiment', {}, (1, 0.28), (1, 0.12)),
    'triangle': ('triangle', {'effects': ['backplate_friction'], 'gravity': None,
                              'plate': {'inclination_deg': 80, 'g0': 9.81, 'mu': 0.1}},
                 (0, 0.3), (1, 0.12)),
}
# --contact: impact_restitution's configurations, the same way (issue 24: closed-form flights
# without a body force, closed-form rolls about unilateral pivots, events by regula falsi).
CONTACT_REF_KNOBS = {'integrator_step': 5e-5, 'roll_step': 5e-5, 'contact_root_tol': 1e-13,
                     'settle_energy': 1e-10, 'roll_method': 'rk4', 'flight_method': 'rk4'}
CONTACT_CONFIGS = [{}, {'roll_method': 'rk4'}, {'integrator_step': 5e-3, 'roll_step': 5e-3}]
CONTACT_SCENES = {  # as the impact_restitution table and the effects table below
    'rectangle': ('rectangle', {}, (2, 0.25), (0, 0.15)),
    'triangle': ('triangle', {'effects': ['impact_restitution'],
                              'contact': {'restitution': 0.2, 'mu': 0.8}}, (0, 0.3), (1, 0.12)),
    'liftoff': ('liftoff', {}, (3, 0.3), (1, 0.12)),
}
# family: (scenes, configurations, reference knobs, what the tables call it)
FAMILIES = {'plate': (PLATE_SCENES, PLATE_CONFIGS, PLATE_REF_KNOBS, 'backplate_friction'),
            'contact': (CONTACT_SCENES, CONTACT_CONFIGS, CONTACT_REF_KNOBS,
                        'impact_restitution / liftoff')}


def knob_text(v):
    return v if isinstance(v, str) else format(v, 'g')


def config_label(knobs):
    """Return 'k=v, ...' of a configuration's knobs, 'defaults' for none."""
    return ', '.join(f'{k}={knob_text(v)}' for k, v in knobs.items()) or 'defaults'


def load(name, **changes):
    data = read_yaml(ROOT / 'scenes' / f'{name}.yaml')
    if name == 'triangle':
        # The tables measure the base model and each effect alone on it: the paper's triangle
        # without its arm's end (scenes/triangle.yaml names finite_arm since issue 21; the
        # finite_arm row adds it back).
        data['arm'] = {k: v for k, v in data['arm'].items() if k not in ('length', 'length_cm')}
        data.pop('effects', None)
    for key, value in changes.items():
        if value is None:
            data.pop(key, None)
        elif isinstance(value, dict):
            data.setdefault(key, {}).update(value)
        else:
            data[key] = value
    return Scene(copy.deepcopy(data))


def random_states(model, count, seed=0, r_hi=0.3):
    rng = np.random.default_rng(seed)
    part = model.part
    edges = rng.choice(part.stable_edges, count)
    lo = np.array([model.r_min(e) * 1.01 for e in edges])
    return edges, lo + rng.uniform(0, 1, count) * (r_hi - lo)


def timed_batch(model, edges, radii):
    model.f_batch(edges[:2], radii[:2])      # compile / load the cache
    t0 = time.perf_counter()
    res = model.f_batch(edges, radii)
    return res, (time.perf_counter() - t0) / len(edges) * 1e6


def orbit_of(model, start, throws):
    e, r, rot, status, done = model.orbits([start[0]], [start[1]], throws)
    return e[0, :done[0] + 1], r[0, :done[0] + 1], rot[0, :done[0] + 1]


def compare(res, ref):
    ok = (res['status'] == 0) & (ref['status'] == 0)
    same = ok & (res['edge'] == ref['edge'])
    d = np.abs(res['R'] - ref['R'])[same] * 1000
    # One number for the plot: mean error per throw, a wrong resting edge counting WRONG_EDGE_MM.
    per = np.where(same, np.abs(res['R'] - ref['R']) * 1000, WRONG_EDGE_MM)[ok]
    return {'edge_diff': 1.0 - same.sum() / max(ok.sum(), 1),
            'dR_med': float(np.median(d)) if d.size else math.nan,
            'dR_max': float(d.max()) if d.size else math.nan,
            'err': float(per.mean()) if per.size else math.nan}


def orbit_agreement(orb, ref):
    n = min(len(orb[0]), len(ref[0]))
    diff = np.flatnonzero(orb[0][:n] != ref[0][:n])
    return int(diff[0]) if diff.size else n - 1


def band_error(orb, ref_ls):
    ls = limit_set_from_orbit(*orb)
    worst = 0.0
    for e in set(ls.bands) | set(ref_ls.bands):
        if e not in ls.bands or e not in ref_ls.bands:
            return math.inf
        a, b = ls.bands[e], ref_ls.bands[e]
        worst = max(worst, abs(a[0] - b[0]), abs(a[1] - b[1]))
    return worst * 1000


def evaluate(label, group, model, ref, states, start, orbit_throws, band_throws):
    res, us = timed_batch(model, *states)
    row = {'group': group, 'config': label, 'us': us}
    row.update(compare(res, ref['throws']))
    orb = orbit_of(model, start, orbit_throws)
    row['orbit'] = orbit_agreement(orb, ref['orbit'])
    long = orbit_of(model, start, band_throws)
    row['band'] = band_error(long, ref['ls'])
    return row


def timed_best(model, edges, radii, repeats=3):
    """timed_batch's result and its shortest time of ``repeats`` runs (a shared machine)."""
    res, us = timed_batch(model, edges, radii)
    for _ in range(repeats - 1):
        us = min(us, timed_batch(model, edges, radii)[1])
    return res, us


def reference(model, states, start, orbit_throws, band_throws):
    res = model.f_batch(*states)
    orb = orbit_of(model, start, orbit_throws)
    long = orbit_of(model, start, 2 * band_throws)
    return {'throws': res, 'orbit': orb, 'ls': limit_set_from_orbit(*long)}


def floor_row(group, model, ref, start, orbit_throws, band_throws):
    """Run the reference physics itself from a start moved by 1 nm.

    Shows how soon orbits part and how much the bands of a finite orbit scatter: the floor
    under every other row.
    """
    moved = (start[0], start[1] + 1e-9)
    orb = orbit_of(model, moved, orbit_throws)
    long = orbit_of(model, moved, band_throws)
    return {'group': group, 'config': 'floor: reference from a start 1 nm away', 'us': math.nan,
            'edge_diff': 0.0, 'dR_med': math.nan, 'dR_max': math.nan, 'err': math.nan,
            'orbit': orbit_agreement(orb, ref['orbit']), 'band': band_error(long, ref['ls'])}


# ----------------------------------------------------------------------------------- pymunk
def pymunk_space(part, edge, R, w, h, g, iterations, arm_friction, part_friction):
    """A pymunk space with the arm (static segment) and the part at eqs 5-6's release state.

    pymunk's friction coefficient of a contact is the product of the two shapes' frictions.
    Returns (space, body, verts): verts are the outline in the body frame.
    """
    import pymunk
    space = pymunk.Space()
    space.gravity = (0.0, g)
    space.iterations = iterations
    space.collision_slop = 1e-5          # m; the default 0.1 is meant for pixels
    arm = pymunk.Segment(space.static_body, (-1.0, h), (2.0, h), 0.0)
    arm.friction = arm_friction
    arm.elasticity = 0.0
    body = pymunk.Body(1.0, part.rho2)
    verts = [(float(u), float(v)) for u, v in zip(part.U[edge], part.V[edge])]
    shape = pymunk.Poly(body, verts, radius=0.0)
    shape.friction = part_friction
    shape.elasticity = 0.0
    x0, y0, phi0, vx, vy, om = release_state(edge, R, w, h, 0.0, part.d)
    body.position = (x0, y0)
    body.angle = phi0
    body.velocity = (vx, vy)
    body.angular_velocity = om
    space.add(arm, body, shape)
    return space, body, verts


def resting_edge(part, edge, angle):
    """The stable edge whose rest pose is nearest to a body angle (thrown from ``edge``)."""
    best, err = -1, math.inf
    for j in part.stable_edges:
        target = part.rest_angle[j] - part.rest_angle[edge]
        dev = abs(math.remainder(angle - target, 2 * math.pi))
        if dev < err:
            best, err = j, dev
    return best


def pymunk_throw(part, edge, R, w, h, g, dt, iterations, t_max=4.0, still=0.15):
    """Throw and catch in pymunk from the impulsive release state of eqs 5-6.

    The part is a convex Poly (mass 1, moment rho^2), the arm a static segment, friction 1e3
    (effectively sticking) and elasticity 0. Returns (edge, R, time simulated) once the part
    has been still (|v| < 1 mm/s, |omega| < 0.02 rad/s) for ``still`` seconds.
    """
    space, body, verts = pymunk_space(part, edge, R, w, h, g, iterations, 1000.0, 1000.0)
    t = 0.0
    quiet = 0.0
    while t < t_max:
        space.step(dt)
        t += dt
        v = body.velocity
        if math.hypot(v.x, v.y) < 1e-3 and abs(body.angular_velocity) < 0.02:
            quiet += dt
            if quiet >= still:
                break
        else:
            quiet = 0.0
    return resting_edge(part, edge, body.angle), float(body.position.x), t


def pymunk_rows(model, states, ref, configs):
    rows = []
    part = model.part
    for dt, iters in configs:
        pymunk_throw(part, int(states[0][0]), float(states[1][0]), model.w, model.h, model.g,
                     dt, iters)
        t0 = time.perf_counter()
        out = [pymunk_throw(part, int(e), float(r), model.w, model.h, model.g, dt, iters)
               for e, r in zip(*states)]
        us = (time.perf_counter() - t0) / len(out) * 1e6
        res = {'edge': np.array([o[0] for o in out]), 'R': np.array([o[1] for o in out]),
               'status': np.zeros(len(out), dtype=int)}
        row = {'group': 'pymunk', 'config': f'dt={dt:g} s, iterations={iters}', 'us': us,
               'orbit': '-', 'band': '-'}
        row.update(compare(res, ref))
        row['sim_s'] = float(np.mean([o[2] for o in out]))
        rows.append(row)
    return rows


# ----------------------------------------------------------------------------------- liftoff
# Parts for the engine comparison: the paper's triangle and two others, base model physics
# (sticking catch, no effect) at the triangle's section V.A parameters.
LIFTOFF_PARTS = {
    'triangle': {'vertices': [[0.06, 0.0], [0.06, 0.08], [0.0, 0.0]], 'offset': -0.005},
    'rectangle 5 x 2 cm': {'vertices': [[0, 0], [0.05, 0], [0.05, 0.02], [0, 0.02]],
                           'offset': -0.003},
    'house 4 x 5 cm': {'vertices': [[0, 0], [0.04, 0], [0.04, 0.03], [0.02, 0.05],
                                    [0, 0.03]], 'offset': -0.012},
}
ENGINE_DT = 1e-5
ENGINE_ITERATIONS = 30


def liftoff_scene(name, effect, mu=None):
    spec = LIFTOFF_PARTS[name]
    data = {'name': name, 'part': {'vertices': spec['vertices']},
            'arm': {'offset': spec['offset']}, 'throw': {'release_speed': 5.5851},
            'gravity': -9.66}
    if effect:
        data['effects'] = ['liftoff']
        if mu is not None:
            data['liftoff'] = {'mu': mu}
    return Scene(data)


def pymunk_catch(part, edge, R, w, h, g, dt=ENGINE_DT, iterations=ENGINE_ITERATIONS, mu=1e6):
    """pymunk_throw that also returns how high the lowest vertex rose after the first contact.

    A rise above the engine's penetration scale (1e-5 m) after the part first touched the arm
    is a hop: a catch that sticks and rolls never lifts its pivot.
    """
    space, body, verts = pymunk_space(part, edge, R, w, h, g, iterations, mu, 1.0)
    t = 0.0
    quiet = 0.0
    airborne = False       # the part starts on the arm: its flight must begin first
    touched = False
    hop = 0.0
    u = [p[0] for p in verts]
    v = [p[1] for p in verts]
    while t < 4.0:
        space.step(dt)
        t += dt
        a = body.angle
        c, s = math.cos(a), math.sin(a)
        low = body.position.y + min(s * ui + c * vi for ui, vi in zip(u, v)) - h
        if touched:
            hop = max(hop, low)
        elif airborne and low < 1e-5:
            touched = True
        elif low > 1e-4:
            airborne = True
        vel = body.velocity
        if math.hypot(vel.x, vel.y) < 1e-3 and abs(body.angular_velocity) < 0.02:
            quiet += dt
            if quiet >= 0.15:
                break
        else:
            quiet = 0.0
    return resting_edge(part, edge, body.angle), float(body.position.x), hop


def liftoff_comparison(n_throws, mu, seed=3):
    """Base model and effect liftoff against pymunk at dt 1e-5 s: |dR| for pushing / pulling."""
    print(f'\n### Lift-off: the base model and effect liftoff (mu {mu:g}) against pymunk '
          f'{__import__("pymunk").version} (dt {ENGINE_DT:g} s, {ENGINE_ITERATIONS} iterations, '
          f'restitution 0, friction {mu:g}; {n_throws} random throws per part)\n')
    print('| part | rolls | throws | edge differs (base / liftoff) | base: median, max abs dR '
          '(mm) | liftoff: median, max abs dR (mm) | engine hops (> 0.01 mm) |')
    print('|---|---|---:|---:|---:|---:|---:|')
    for name in LIFTOFF_PARTS:
        base = liftoff_scene(name, False).model
        lift = liftoff_scene(name, True, mu).model
        edges, radii = random_states(base, n_throws, seed=seed, r_hi=0.25)
        rb = [base.throw(int(e), float(r)) for e, r in zip(edges, radii)]
        rl = lift.f_batch(edges, radii)
        eng = [pymunk_catch(base.part, int(e), float(r), base.w, base.h, base.g, mu=mu)
               for e, r in zip(edges, radii)]
        pull = np.array([x.min_normal_force < 0.0 for x in rb])
        for label, sel in (('push throughout', ~pull), ('need a pull', pull)):
            idx = np.flatnonzero(sel)
            if not idx.size:
                print(f'| {name} | {label} | 0 | - | - | - | - |')
                continue
            e_eng = np.array([eng[i][0] for i in idx])
            r_eng = np.array([eng[i][1] for i in idx])
            hops = sum(eng[i][2] > 1e-5 for i in idx)

            def stats(e_m, r_m):
                same = e_m == e_eng
                d = np.abs(r_m[same] - r_eng[same]) * 1e3
                return int(np.sum(~same)), (f'{np.median(d):.3f}, {d.max():.3f}' if d.size
                                            else '-')
            nb, sb = stats(np.array([rb[i].edge for i in idx]),
                           np.array([rb[i].R for i in idx]))
            nl, sl = stats(rl['edge'][idx], rl['R'][idx])
            print(f'| {name} | {label} | {idx.size} | {nb} / {nl} | {sb} | {sl} | {hops} |')


def orbit_pull_count(throws=400):
    """On the triangle's orbit from (1, 12 cm): throws that need a pull, and engine hops."""
    m = load('triangle').model
    e, r, _ = m.orbit_arrays(1, 0.12, throws)
    states = list(zip(e[:throws], r[:throws]))
    low = np.array([m.throw(int(a), float(b)).min_normal_force for a, b in states])
    hop = np.array([pymunk_catch(m.part, int(a), float(b), m.w, m.h, m.g)[2]
                    for a, b in states])
    print(f"\n### The triangle's orbit from (1, 12 cm), {throws} throws\n")
    print(f'* need a pull (N < 0 in a roll): {int(np.sum(low < 0))}, worst N = '
          f'{low.min():.3f} m/s^2')
    for thr in (1e-6, 1e-5, 1e-4):
        both = int(np.sum((hop > thr) & (low < 0)))
        print(f'* pymunk: the lowest vertex rose more than {thr * 1e3:g} mm after the first '
              f'contact in {int(np.sum(hop > thr))} throws ({both} of them need a pull)')


# ----------------------------------------------------------------------------------- plate
def family_rows(family, configs, data, orbit_throws, band_throws, label):
    """Rows of a family's configurations on its scenes, against the references in ``data``."""
    scenes = FAMILIES[family][0]
    rows = []
    for name, (scene_name, changes, _, start) in scenes.items():
        states = (data[f'{name}_edges'], data[f'{name}_radii'])
        ref = {'throws': {k: data[f'{name}_ref_{k}'] for k in ('edge', 'R', 'status')},
               'orbit': tuple(data[f'{name}_orbit_{i}'] for i in range(3)),
               'ls': limit_set_from_orbit(*(data[f'{name}_long_{i}'] for i in range(3)))}
        for knobs in configs:
            model = load(scene_name, accuracy=knobs, **copy.deepcopy(changes)).model
            res, us = timed_best(model, *states)
            row = {'scene': name, 'config': config_label(knobs), 'code': label, 'us': us}
            row.update(compare(res, ref['throws']))
            row['orbit'] = orbit_agreement(orbit_of(model, start, orbit_throws), ref['orbit'])
            row['band'] = band_error(orbit_of(model, start, band_throws), ref['ls'])
            rows.append(row)
    return rows


def family_comparison(family, quick, before):
    """A family's configurations with this code, and with REV's (--before), in one run."""
    import json
    import subprocess
    import tempfile
    scenes, configs, ref_knobs, title = FAMILIES[family]
    n_states = 100 if quick else 250
    orbit_throws = 100 if quick else 300
    band_throws = 200 if quick else 1000
    tri = load('triangle')
    data = {}
    for name, (scene_name, changes, (seed, r_hi), start) in scenes.items():
        # the plate's states are the triangle's on both scenes (as its tables were made); the
        # rectangle has its own edges
        own = tri if family == 'plate' else load(scene_name, **copy.deepcopy(changes))
        edges, radii = random_states(own.model, n_states, seed=seed, r_hi=r_hi)
        ref_model = load(scene_name, accuracy=ref_knobs, **copy.deepcopy(changes)).model
        ref = ref_model.f_batch(edges, radii)
        data[f'{name}_edges'], data[f'{name}_radii'] = edges, radii
        for k in ('edge', 'R', 'status'):
            data[f'{name}_ref_{k}'] = np.asarray(ref[k])
        for tag, throws in (('orbit', orbit_throws), ('long', 2 * band_throws)):
            for i, a in enumerate(orbit_of(ref_model, start, throws)):
                data[f'{name}_{tag}_{i}'] = a
    rows = []
    if before:
        with tempfile.TemporaryDirectory() as tmp:
            old = pathlib.Path(tmp)
            subprocess.run(f'git -C {ROOT} archive {before} src/throwmap | tar -x -C {old}',
                           shell=True, check=True)
            np.savez(old / 'data.npz', **data)
            # a revision before the series flight has no flight_method picard
            has_picard = (old / 'src' / 'throwmap' / 'throwmap' / 'picard.py').exists()
            # ... and one before session 39 no flight_grade
            has_grade = 'flight_grade' in (
                old / 'src' / 'throwmap' / 'throwmap' / 'accuracy.py').read_text()
            old_configs = [c for c in configs
                           if (has_picard or c.get('flight_method') != 'picard')
                           and (has_grade or 'flight_grade' not in c)]
            (old / 'configs.json').write_text(json.dumps(old_configs))
            env = dict(os.environ, PYTHONPATH=str(old / 'src' / 'throwmap'))
            subprocess.run([sys.executable, __file__, '--child', family, str(old),
                            '--before', before] + (['--quick'] if quick else []),
                           env=env, check=True)
            rows += json.loads((old / 'rows.json').read_text())
    rows += family_rows(family, configs, data, orbit_throws, band_throws, 'this branch')
    base_us = timed_best(tri.model, data['triangle_edges'], data['triangle_radii'])[1]
    print(f'\nbase model (triangle, the same states): {base_us:.2f} us per throw')
    ref_text = ', '.join(f'{k} {knob_text(v)}' for k, v in ref_knobs.items())
    for name in scenes:
        print(f'\n### {title} ({name} scene, {n_states} states): before ({before}) and after, '
              f'against the reference ({ref_text}); time: best of 3 runs\n')
        print('| code | config | time/throw (us) | edge differs | median abs dR (m) '
              '| max abs dR (m) | orbit agrees (throws) | band error (mm) |')
        print('|---|---|---:|---:|---:|---:|---:|---:|')
        for r in (r for r in rows if r['scene'] == name):
            print(f"| {r['code']} | {r['config']} | {r['us']:.1f} "
                  f"| {r['edge_diff'] * 100:.1f} % | {fmt(r['dR_med'] * 1e-3, '.2e')} "
                  f"| {fmt(r['dR_max'] * 1e-3, '.2e')} | {r['orbit']} | {fmt(r['band'], '.2e')} |")


def family_child(family, folder, quick, before):
    """Run a family's configurations with the code in PYTHONPATH (a revision's)."""
    import json
    import throwmap
    folder = pathlib.Path(folder)
    assert str(folder) in throwmap.__file__, throwmap.__file__
    data = dict(np.load(folder / 'data.npz'))
    configs = json.loads((folder / 'configs.json').read_text())
    rows = family_rows(family, configs, data, 100 if quick else 300, 200 if quick else 1000,
                       before)
    for r in rows:
        r['orbit'] = int(r['orbit'])
    (folder / 'rows.json').write_text(json.dumps(rows))


# ----------------------------------------------------------------------------------- overhead
AIR = {'drag_coefficient': 1.2, 'frontal_area_cm2': 4, 'mass_g': 20}
AIR_REF_KNOBS = {'integrator_step': 5e-5, 'roll_step': 5e-5, 'contact_root_tol': 1e-13,
                 'roll_method': 'rk4', 'flight_method': 'rk4'}
# the experiment scene with the air instead of the plate: its in-plane gravity (-9.81 sin 80
# deg) and its arm
AIR_ON_EXPERIMENT = {'effects': ['air_drag', 'finite_arm'], 'air': AIR, 'plate': None,
                     'gravity': -9.81 * math.sin(math.radians(80.0))}


def dr_stats(res, ref):
    """Median and max |dR| (m) of the throws that end on the reference's edge, and their count."""
    same = (res['status'] == 0) & (ref['status'] == 0) & (res['edge'] == ref['edge'])
    d = np.abs(res['R'] - ref['R'])[same]
    return float(np.median(d)), float(d.max()), int(same.sum())


def overhead(quick):
    """Print the plate's flight methods at mu_p 0.1 and 0, and air_drag on the experiment."""
    n = 100 if quick else 250
    tri = load('triangle').model
    _, _, (seed, r_hi), _ = PLATE_SCENES['experiment']
    states = random_states(tri, n, seed, r_hi)
    # the base model timed first and again after a warm-up run of the plate (a cold core
    # measured it 40 % slow); the faster of the two
    _, base_us = timed_best(tri, *states, repeats=7)
    ref = load('experiment', accuracy=PLATE_REF_KNOBS).model.f_batch(*states)
    base_us = min(base_us, timed_best(tri, *states, repeats=7)[1])
    print(f'base model (triangle, the same {n} states): {base_us:.2f} us per throw; time: best '
          'of 7 runs')
    print('\n#### backplate_friction (experiment scene): each flight method with the drag '
          '(mu_p 0.1) and with a drag that costs nothing (mu_p 0, the same steps, kink '
          'searches and contact scans)\n')
    print('| config | mu_p 0.1 (us) | x base | mu_p 0 (us) | x base | median / max abs dR at '
          'mu_p 0.1 (m) |')
    print('|---|---:|---:|---:|---:|---|')
    configs = [{}, dict(PICARD_FLIGHT), dict(PICARD_FLIGHT, flight_step=0.04, flight_tol=1e-7),
               dict(PICARD_FLIGHT, flight_step=0.02, flight_tol=1e-9), RK8_FLIGHT]
    for cfg in configs:
        res, us = timed_best(load('experiment', accuracy=cfg).model, *states, repeats=7)
        _, us0 = timed_best(load('experiment', accuracy=cfg, plate={'mu': 0.0}).model, *states,
                            repeats=7)
        med, mx, _ = dr_stats(res, ref)
        print(f'| {config_label(cfg)} | {us:.1f} | {us / base_us:.0f}x | {us0:.1f} '
              f'| {us0 / base_us:.1f}x | {med:.2e} / {mx:.2e} |')
    ref = load('experiment', accuracy=AIR_REF_KNOBS,
               **copy.deepcopy(AIR_ON_EXPERIMENT)).model.f_batch(*states)
    print('\n#### air_drag on the experiment scene (its gravity and arm, the air instead of the '
          'plate) against the reference (rk4 steps 5e-5 s, roots 1e-13 s)\n')
    print('| config | time/throw (us) | x base | median / max abs dR (m) | same edge |')
    print('|---|---:|---:|---|---:|')
    for cfg in ({}, {'integrator_step': 5e-3}, PICARD_FLIGHT):
        res, us = timed_best(load('experiment', accuracy=cfg,
                                  **copy.deepcopy(AIR_ON_EXPERIMENT)).model, *states, repeats=7)
        med, mx, same = dr_stats(res, ref)
        print(f'| {config_label(cfg)} | {us:.1f} | {us / base_us:.1f}x | {med:.2e} / {mx:.2e} | '
              f'{same}/{n} |')


# ----------------------------------------------------------------------------------- main
def fmt(v, spec):
    if isinstance(v, str):
        return v
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return 'inf' if v == math.inf else '-'
    return format(v, spec)


def table(rows, title):
    print(f'\n### {title}\n')
    print('| config | time/throw (us) | edge differs | median abs dR (mm) | max abs dR (mm) '
          '| mean error (mm) | orbit agrees (throws) | band error (mm) |')
    print('|---|---:|---:|---:|---:|---:|---:|---:|')
    for r in rows:
        print(f"| {r['config']} | {fmt(r['us'], '.1f')} | {fmt(r['edge_diff'] * 100, '.1f')} % "
              f"| {fmt(r['dR_med'], '.2e')} | {fmt(r['dR_max'], '.2e')} | {fmt(r['err'], '.2e')} "
              f"| {fmt(r['orbit'], 'd')} | {fmt(r['band'], '.2e')} |")


def pareto_plot(rows, path):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 6))
    markers = {'base: advancement': ('o', 'C0'), 'base: scan': ('s', 'C1'),
               'backplate_friction': ('^', 'C2'),
               'backplate_friction, before issue 24': ('^', 'none'),
               'air_drag': ('D', 'C4'), 'air_drag, before issue 24': ('D', 'none'),
               'impact_restitution': ('v', 'C3'), 'pymunk': ('X', 'C7')}
    for group, (mk, face) in markers.items():
        sel = [r for r in rows if r['group'] == group and math.isfinite(r['us'])]
        if not sel:
            continue
        # mean error per throw (mm), a wrong edge counting 10 mm; floored so exact rows show
        err = [max(r['err'], 1e-12) for r in sel]
        edge = 'C2' if 'backplate' in group else 'C4' if 'air' in group else None
        ax.loglog([r['us'] for r in sel], err, mk, label=group, ms=8, alpha=0.8,
                  mfc=face if face != 'none' else 'none', mec=edge if face == 'none' else None)
        for r, e in zip(sel, err):
            label = r['config'].split(' (')[0].replace('advancement, ', '').replace(
                'scan, ', '').replace(' s, iterations=', ' s x')
            ax.annotate(label, (r['us'], e), fontsize=6, alpha=0.7, xytext=(3, 3),
                        textcoords='offset points')
    ax.set_xlabel('time per throw (us, one core)')
    ax.set_ylabel(f'mean error per throw (mm; wrong edge = {WRONG_EDGE_MM:g} mm; floor 1e-12)')
    ax.set_title('What accuracy costs: throwmap knobs and effects vs pymunk '
                 '(hollow: defaults before issue 24)')
    ax.grid(True, which='both', alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    os.makedirs(os.path.dirname(path) or '.', exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--quick', action='store_true', help='fewer states, knobs and throws')
    parser.add_argument('--out', default=str(ROOT / 'docs' / 'accuracy_pareto.png'))
    parser.add_argument('--liftoff', action='store_true',
                        help='only the lift-off comparison against pymunk at dt 1e-5 s')
    parser.add_argument('--mu', type=float, nargs='+', default=[1e6, 1.0],
                        help='arm friction coefficients of the lift-off comparison')
    parser.add_argument('--plate', action='store_true',
                        help="only the plate's configurations on the experiment and the triangle")
    parser.add_argument('--contact', action='store_true',
                        help="only the contact effects' configurations (the rectangle, the "
                        'triangle with restitution, the liftoff scene)')
    parser.add_argument('--before', metavar='REV',
                        help='with --plate or --contact: also measure the code of git revision '
                        'REV')
    parser.add_argument('--overhead', action='store_true',
                        help="only the plate's flight methods with and without the drag, and "
                        "air_drag on the experiment scene")
    parser.add_argument('--child', nargs=2, metavar=('FAMILY', 'FOLDER'),
                        help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        family_child(args.child[0], args.child[1], args.quick, args.before)
        return
    if args.overhead:
        overhead(args.quick)
        return
    for family in ('plate', 'contact'):
        if getattr(args, family):
            family_comparison(family, args.quick, args.before)
            return
    if args.liftoff:
        for mu in args.mu:
            liftoff_comparison(20 if args.quick else 100, mu)
        orbit_pull_count(40 if args.quick else 400)
        return
    quick = args.quick
    n_states = 100 if quick else 1000
    orbit_throws = 100 if quick else 300
    band_throws = 200 if quick else 1000
    print(f'python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} cores; '
          f'{n_states} random states, orbits of {orbit_throws} throws, bands from '
          f'{band_throws} throws{" (--quick)" if quick else ""}')
    rows = []

    # --- base model: conservative advancement vs fixed-step scan (triangle)
    tri = load('triangle')
    states = random_states(tri.model, n_states)
    start = tri.default_start()
    ref_scene = load('triangle', accuracy={'contact_time_tol': 1e-15})
    ref = reference(ref_scene.model, states, start, orbit_throws, band_throws)
    base_rows = [floor_row('base: advancement', ref_scene.model, ref, start, orbit_throws,
                           band_throws)]
    for tol in ((1e-6, 1e-12) if quick else (1e-4, 1e-6, 1e-9, 1e-12)):
        s = load('triangle', accuracy={'contact_time_tol': tol})
        base_rows.append(evaluate(f'advancement, contact_time_tol={tol:g}', 'base: advancement',
                                  s.model, ref, states, start, orbit_throws, band_throws))
    steps = (1e-2, 1e-3, 1e-4) if quick else (2e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4)
    for step in steps:
        s = load('triangle', accuracy={'contact_method': 'scan', 'contact_scan_step': step,
                                       'contact_root_tol': 1e-12})
        base_rows.append(evaluate(f'scan, step={step:g} s', 'base: scan', s.model, ref, states,
                                  start, orbit_throws, band_throws))
    table(base_rows, 'Base model (triangle): contact finder (reference: advancement, '
          'tol 1e-15 s)')
    rows += base_rows

    # --- effects: what each one costs at the default knobs (triangle; no effect = base), and
    # the same set with the effect at zero strength (its limit case)
    plate = {'inclination_deg': 80, 'g0': 9.81}
    air = AIR
    all_on = {'effects': ['backplate_friction', 'air_drag', 'impact_restitution',
                          'finite_carry', 'finite_arm', 'release_noise', 'sensor_noise'],
              'gravity': None, 'plate': dict(plate, mu=0.1), 'air': air,
              'contact': {'mu': 0.8, 'restitution': 0.2},
              'throw': {'carry': {'release_angle_deg': 3}}, 'arm': {'length_cm': 40},
              'noise': {'release_speed_sd_deg': 2}, 'sensor': {'false_positive': 0.01}}
    all_zero = dict(all_on, plate=dict(plate, mu=0.0), air=dict(air, drag_coefficient=0.0),
                    contact={'mu': 1e9, 'restitution': 0.0},
                    throw={'carry': {'release_angle': 1e-8}}, arm={'length': 1e3},
                    noise={'release_speed_sd': 0.0},
                    sensor={'false_positive': 0.0, 'false_negative': 0.0})
    effect_sets = [
        ('none (base ThrowModel)', {}),
        ('sensor_noise', {'effects': ['sensor_noise'], 'sensor': {'false_positive': 0.01}}),
        ('sensor_noise at 0 (rates 0)', {'effects': ['sensor_noise'],
                                         'sensor': {'false_positive': 0.0}}),
        ('finite_arm', {'effects': ['finite_arm'], 'arm': {'length_cm': 40}}),
        ('finite_arm at 0 (L = 1 km)', {'effects': ['finite_arm'], 'arm': {'length': 1e3}}),
        ('release_noise', {'effects': ['release_noise'],
                           'noise': {'release_speed_sd_deg': 2}}),
        ('release_noise at 0 (sd 0)', {'effects': ['release_noise'],
                                       'noise': {'release_speed_sd': 0.0}}),
        ('finite_carry', {'effects': ['finite_carry'], 'contact': {'mu': 0.8},
                          'throw': {'carry': {'release_angle_deg': 3}}}),
        ('finite_carry at 0 (theta_r 1e-8 rad)', {'effects': ['finite_carry'],
                                                  'contact': {'mu': 0.8},
                                                  'throw': {'carry': {'release_angle': 1e-8}}}),
        ('impact_restitution (e=0.2, mu=0.8)', {'effects': ['impact_restitution'],
                                                'contact': {'restitution': 0.2, 'mu': 0.8}}),
        ('impact_restitution at 0 (e=0, mu=inf)', {'effects': ['impact_restitution'],
                                                   'contact': {'restitution': 0.0}}),
        ('backplate_friction', {'effects': ['backplate_friction'], 'gravity': None,
                                'plate': dict(plate, mu=0.1)}),
        ('backplate_friction, before issue 24 (roll_method rk4, flight_method rk4)',
         {'effects': ['backplate_friction'], 'gravity': None, 'plate': dict(plate, mu=0.1),
          'accuracy': {'roll_method': 'rk4', 'flight_method': 'rk4'}}),
        ('backplate_friction, flight rk8 (flight_tol 1e-9)',
         {'effects': ['backplate_friction'], 'gravity': None, 'plate': dict(plate, mu=0.1),
          'accuracy': RK8_FLIGHT}),
        ('backplate_friction, flight picard (flight_step 0.08, flight_tol 1e-6)',
         {'effects': ['backplate_friction'], 'gravity': None, 'plate': dict(plate, mu=0.1),
          'accuracy': PICARD_FLIGHT}),
        ('backplate_friction at 0 (mu_p 0)', {'effects': ['backplate_friction'],
                                              'gravity': None, 'plate': dict(plate, mu=0.0)}),
        ('air_drag', {'effects': ['air_drag'], 'air': air}),
        ('air_drag, before issue 24 (roll_method rk4, integrator_step 1 ms)',
         {'effects': ['air_drag'], 'air': air,
          'accuracy': {'roll_method': 'rk4', 'integrator_step': 1e-3}}),
        ('air_drag at 0 (C_d 0)', {'effects': ['air_drag'],
                                   'air': dict(air, drag_coefficient=0.0)}),
        ('all seven', all_on),
        ('all seven, before issue 24 (roll_method rk4)',
         dict(all_on, accuracy={'roll_method': 'rk4', 'integrator_step': 1e-3})),
        ('all seven at 0', all_zero),
    ]
    print('\n### Effects: time per throw at the default knobs (triangle)\n')
    print('| effects | model | compiled hooks | time/throw (us) | f(i, R) one call (us) |')
    print('|---|---|---|---:|---:|')
    for label, changes in effect_sets:
        s = load('triangle', **copy.deepcopy(changes))
        m = s.model
        slots = getattr(m, 'slots', None)
        hooks = '-' if slots is None else (', '.join(
            f'{n}: {"+".join(v)}' for n, v in slots.items()) or 'none (pipeline defaults)')
        general = bool(getattr(getattr(m, 'effects', None), 'general', False))
        st = random_states(m, n_states // 2 if general else n_states)
        ok = np.array([m.domain_error(int(e), float(r)) is None for e, r in zip(*st)])
        st = (st[0][ok], st[1][ok])
        _, us = timed_batch(m, *st)
        m.f(int(st[0][0]), float(st[1][0]))
        t0 = time.perf_counter()
        for e, r in zip(st[0][:200], st[1][:200]):
            try:
                m.f(int(e), float(r))
            except ValueError:
                pass
        one = (time.perf_counter() - t0) / min(200, len(st[0])) * 1e6
        print(f'| {label} | {type(m).__name__} | {hooks} | {us:.1f} | {one:.1f} |')

    # --- backplate_friction knobs (experiment scene)
    # The reference drag is the exact one (plate_quadrature 0, closed form): a quadrature
    # reference would share the quadrature error it is meant to measure.
    exp_ref_knobs = {'integrator_step': 5e-5, 'roll_step': 5e-5, 'plate_quadrature': 0,
                     'contact_root_tol': 1e-13, 'roll_method': 'rk4', 'flight_method': 'rk4'}
    exp_states = random_states(tri.model, n_states // 4, seed=1, r_hi=0.28)
    exp_start = (1, 0.12)
    ref_e = reference(load('experiment', accuracy=exp_ref_knobs).model, exp_states, exp_start,
                      orbit_throws, band_throws)
    fr_rows = [floor_row('backplate_friction', load('experiment', accuracy=exp_ref_knobs).model,
                         ref_e, exp_start, orbit_throws, band_throws)]
    s = load('experiment')
    fr_rows.append(evaluate('defaults (' + ', '.join(
        f'{k}={knob_text(getattr(s.model.knobs, k))}'
        for k in list(exp_ref_knobs) + ['flight_step', 'flight_tol', 'flight_grade']) + ')',
        'backplate_friction', s.model, ref_e, exp_states, exp_start, orbit_throws, band_throws))
    # the plate's defaults before issue 24: rk4 rolls and rk4 flights at 1 ms
    s = load('experiment', accuracy={'roll_method': 'rk4', 'flight_method': 'rk4'})
    fr_rows.append(evaluate('defaults before issue 24 (roll_method=rk4, flight_method=rk4)',
                            'backplate_friction, before issue 24', s.model, ref_e, exp_states,
                            exp_start, orbit_throws, band_throws))
    for knobs in FAST_CONFIGS:
        s = load('experiment', accuracy=knobs)
        fr_rows.append(evaluate(config_label(knobs),
                                'backplate_friction', s.model, ref_e, exp_states, exp_start,
                                orbit_throws, band_throws))
    # All knobs together, coarse to fine: the operating points a user would pick (the plot).
    presets = [('coarse', {'integrator_step': 5e-3, 'roll_step': 5e-3, 'plate_quadrature': 0}),
               ('fast', {'integrator_step': 2e-3, 'roll_step': 2e-3, 'plate_quadrature': 0}),
               ('fine', {'integrator_step': 2e-4, 'roll_step': 2e-4, 'plate_quadrature': 0}),
               ('finest', {'integrator_step': 1e-4, 'roll_step': 1e-4, 'plate_quadrature': 0}),
               ('quadrature 4 (the default before issue 13)',
                {'integrator_step': 1e-3, 'roll_step': 1e-3, 'plate_quadrature': 4}),
               ('quadrature 8 (the reference before issue 13)',
                {'integrator_step': 1e-4, 'roll_step': 1e-4, 'plate_quadrature': 8})]
    for label, knobs in (presets[1:3] if quick else presets):
        s = load('experiment', accuracy=knobs)
        fr_rows.append(evaluate(f'{label} (' + ', '.join(f'{k}={v:g}' for k, v in knobs.items())
                                + ')', 'backplate_friction', s.model, ref_e, exp_states,
                                exp_start, orbit_throws, band_throws))
    sweeps = [] if quick else [
              ('integrator_step', (5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4), 's'),
              ('roll_step', (5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4), 's'),
              ('plate_quadrature', (1, 2, 4, 8), ''),
              ('contact_root_tol', (1e-5, 1e-7, 1e-9, 1e-12), 's')]
    for knob, values, unit in sweeps:
        for v in values:
            knobs = dict(exp_ref_knobs)
            knobs[knob] = v
            s = load('experiment', accuracy=knobs)
            fr_rows.append(evaluate(f'{knob}={v:g} {unit}'.strip(), 'isolated knob',
                                    s.model, ref_e, exp_states, exp_start, orbit_throws,
                                    band_throws))
    table(fr_rows, 'backplate_friction (experiment scene): presets (all knobs together), then '
          'each knob alone from the reference (exact drag, steps 5e-5 s, root 1e-13 s)')
    rows += fr_rows

    # --- air_drag knobs (triangle scene), before and after issue 24
    air_ref_knobs = AIR_REF_KNOBS
    air_scene = {'effects': ['air_drag'], 'air': air}
    ref_a = reference(load('triangle', accuracy=air_ref_knobs, **air_scene).model, states,
                      start, orbit_throws, band_throws)
    ad_rows = [floor_row('air_drag', load('triangle', accuracy=air_ref_knobs,
                                          **air_scene).model, ref_a, start, orbit_throws,
                         band_throws)]
    for label, group, knobs in [('defaults', 'air_drag', {}),
                                ('defaults before issue 24 (roll_method=rk4, '
                                 'integrator_step=0.001)', 'air_drag, before issue 24',
                                 {'roll_method': 'rk4', 'integrator_step': 1e-3})] + [
            (config_label(kn), 'air_drag', kn)
            for kn in [{'integrator_step': 1e-3}] + FAST_CONFIGS]:
        s = load('triangle', accuracy=knobs, **air_scene)
        ad_rows.append(evaluate(label, group, s.model, ref_a, states, start, orbit_throws,
                                band_throws))
    table(ad_rows, 'air_drag (triangle scene, C_d 1.2, 4 cm^2, 20 g): configurations against '
          'the reference (rk4 steps 5e-5 s, root 1e-13 s)')
    rows += ad_rows

    # --- impact_restitution knobs (rectangle scene)
    rect = load('rectangle')
    rect_states = random_states(rect.model, n_states // 4, seed=2, r_hi=0.25)
    rect_start = rect.default_start()
    rect_ref_knobs = {'integrator_step': 5e-5, 'roll_step': 5e-5, 'contact_root_tol': 1e-13,
                      'settle_energy': 1e-10, 'roll_method': 'rk4', 'flight_method': 'rk4'}
    ref_r = reference(load('rectangle', accuracy=rect_ref_knobs).model,
                      rect_states, rect_start, orbit_throws, band_throws)
    re_rows = [floor_row('impact_restitution', load('rectangle', accuracy=rect_ref_knobs).model,
                         ref_r, rect_start, orbit_throws, band_throws)]
    s = load('rectangle')
    re_rows.append(evaluate('defaults', 'impact_restitution', s.model, ref_r, rect_states,
                            rect_start, orbit_throws, band_throws))
    for label, knobs in ((('fast', {'integrator_step': 2e-3, 'roll_step': 2e-3}),
                          ('fine', {'integrator_step': 2e-4, 'roll_step': 2e-4}))
                         if quick else
                         (('coarse', {'integrator_step': 5e-3, 'roll_step': 5e-3}),
                          ('fast', {'integrator_step': 2e-3, 'roll_step': 2e-3}),
                          ('fine', {'integrator_step': 2e-4, 'roll_step': 2e-4}),
                          ('finest', {'integrator_step': 1e-4, 'roll_step': 1e-4}))):
        s = load('rectangle', accuracy=knobs)
        re_rows.append(evaluate(f'{label} (' + ', '.join(f'{k}={v:g}' for k, v in knobs.items())
                                + ')', 'impact_restitution', s.model, ref_r, rect_states,
                                rect_start, orbit_throws, band_throws))
    sweeps = [] if quick else [('integrator_step', (5e-3, 2e-3, 1e-3, 5e-4, 2e-4), 's'),
                               ('roll_step', (5e-3, 2e-3, 1e-3, 5e-4, 2e-4), 's'),
                               ('settle_energy', (1e-4, 1e-6, 1e-8), 'J/kg')]
    for knob, values, unit in sweeps:
        for v in values:
            knobs = dict(rect_ref_knobs)
            knobs[knob] = v
            s = load('rectangle', accuracy=knobs)
            re_rows.append(evaluate(f'{knob}={v:g} {unit}', 'isolated knob', s.model,
                                    ref_r, rect_states, rect_start, orbit_throws, band_throws))
    table(re_rows, 'impact_restitution (rectangle scene, e = 0.3, mu = 0.6, unilateral): '
          'presets, then each knob alone from the reference (steps 5e-5 s, root 1e-13 s, '
          'settle_energy 1e-10 J/kg)')
    rows += re_rows

    # --- pymunk against the base model (triangle)
    n_py = 20 if quick else 100
    py_states = (states[0][:n_py], states[1][:n_py])
    ref_py = ref_scene.model.f_batch(*py_states)
    configs = ([(1e-3, 10), (1e-4, 10)] if quick else
               [(2e-3, 10), (1e-3, 10), (5e-4, 10), (2e-4, 10), (1e-4, 10), (1e-4, 30),
                (5e-5, 30)])
    py_rows = pymunk_rows(ref_scene.model, py_states, ref_py, configs)
    print(f'\n### pymunk {__import__("pymunk").version} (triangle, {n_py} throws per config; '
          'reference: the base model)\n')
    print('| config | time/throw (us) | simulated s/throw | edge differs | median abs dR (mm) '
          '| max abs dR (mm) | mean error (mm) |')
    print('|---|---:|---:|---:|---:|---:|---:|')
    for r in py_rows:
        print(f"| {r['config']} | {r['us']:.0f} | {r['sim_s']:.2f} | "
              f"{r['edge_diff'] * 100:.1f} % | {fmt(r['dR_med'], '.2e')} | "
              f"{fmt(r['dR_max'], '.2e')} | {fmt(r['err'], '.2e')} |")
    rows += py_rows
    pareto_plot(rows, args.out)
    print(f'\nwrote {args.out}')


if __name__ == '__main__':
    main()
