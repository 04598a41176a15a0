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
The fast throw map (throwmap) against the slow, independent reference (reference_sim.py).

Random convex parts, offsets, release speeds, gravities and start states are thrown by both;
they must agree on the new edge, jog/flip and R. THROWMAP_LONG=1 runs a much larger sample
(docs/reference-check.md records what it measured).

Tolerances. R' is a sum of arm coordinates of contact vertices (flight contact, then edge
lengths) and one CM offset; in both solvers these come from root-finding to machine precision,
so away from discontinuities the two agree to rounding (measured: < 1e-12 of the part radius
r). R_TOL_REL = 1e-9 r keeps three orders of margin and is still far below any physical scale.
A disagreement is accepted only at a discontinuity of f, shown by the reference itself: between
R -/+ DISC_DELTA_REL r (1e-9 r) the reference must jump, and on one side give the fast solver's
answer (near_discontinuity). Such cases are counted and must stay rare.
"""

import ast
import dataclasses
import functools
import math
import os
import warnings

import numpy as np
import pytest
import reference_sim
from reference_sim import (polygon_mass_properties, ReferencePart, ReferenceSimulator,
                           sticking_impact)
from scipy.spatial import ConvexHull
from throwmap import Part, ThrowModel

LONG = os.environ.get('THROWMAP_LONG', '') not in ('', '0')
N_RANDOM = 20000 if LONG else 1000
SEED = 20260101
R_TOL_REL = 1e-9            # |R'_fast - R'_ref| <= R_TOL_REL * r
T_TOL_REL = 1e-9            # flight time, relative
ROT_TOL = 1e-9              # net rotation, rad
OMEGA_TOL_REL = 1e-8        # impact angular velocities, relative to sqrt(E_release) / r
ENERGY_TOL_REL = 1e-8       # impact energies and energy drift while rolling, of E_release
DISC_DELTA_REL = 1e-9       # perturbation of R (times r) that must reach the other side
SLOPE_MAX = 100.0           # bound of |dR'/dR| where f is continuous (measured max: 32)
MAX_DISC_FRACTION = 0.01    # at most this share of random cases may sit at a discontinuity
MAX_GRASP_PARTS = 25        # R_grasp of a drawn state at most this many part radii
GRAZE_OFFSET_REL = 1e-10    # distance (times R) of the graze test states from the graze
GRAZE_MIN_SPEED = 1e-6      # m/s: slower approaches leave the contact time ill-conditioned

TRIANGLE = [[0.06, 0.0], [0.06, 0.08], [0.0, 0.0]]
BRACKET_OUTLINE = [[0.048, 0.0], [0.048, 0.021], [0.008, 0.021], [0.008, 0.044],
                   [0.0, 0.044], [0.0, 0.0]]


# ---------------------------------------------------------------------------- random cases
def random_polygon(rng):
    """Draw a random convex polygon (3-8 corners, CCW): irregular, near-regular or elongated."""
    while True:
        n = int(rng.integers(3, 9))
        style = rng.uniform()
        if style < 0.3:      # near-regular: rolls like a wheel, many impacts per catch
            ang = np.linspace(0.0, 2 * math.pi, n, endpoint=False) + rng.uniform(0, 0.2, n)
            rad = 1.0 + rng.uniform(0.0, 0.05, n)
            squash = rng.uniform(0.7, 1.0)
        else:
            ang = np.sort(rng.uniform(0.0, 2 * math.pi, n))
            rad = rng.uniform(0.4, 1.0, n)
            # elongated parts have unstable edges
            squash = rng.uniform(0.1, 0.4) if style > 0.7 else rng.uniform(0.3, 1.0)
        pts = np.stack([rad * np.cos(ang), squash * rad * np.sin(ang)], axis=1)
        c, s = math.cos(rng.uniform(0, 2 * math.pi)), math.sin(rng.uniform(0, 2 * math.pi))
        pts = pts @ np.array([[c, s], [-s, c]]) * rng.uniform(0.01, 0.15)
        hull = ConvexHull(pts)
        v = pts[hull.vertices]                       # counterclockwise in 2-D
        v = np.roll(v, -int(rng.integers(len(v))), axis=0)
        e = np.roll(v, -1, axis=0) - v
        en = np.roll(e, -1, axis=0)
        length = np.hypot(e[:, 0], e[:, 1])
        turn = np.abs(np.arctan2(e[:, 0] * en[:, 1] - e[:, 1] * en[:, 0], (e * en).sum(1)))
        size = float(np.ptp(v, axis=0).max())
        if length.min() >= 0.02 * size and turn.min() >= 0.02:
            return v


def random_case(rng):
    """(vertices, cm, rho2, h, w, g, edge, R) with (edge, R) inside the domain of f."""
    v = random_polygon(rng)
    _, cm, rho2 = polygon_mass_properties(v)
    if rng.uniform() < 0.2:     # not a uniform lamina: CM anywhere inside, any rho
        cm = rng.dirichlet(np.full(len(v), 0.7)) @ v
        rho2 *= rng.uniform(0.3, 1.5) ** 2
    part = ReferencePart(v, cm, rho2)
    d_min = float(part.d[part.stable].min())
    u = rng.uniform()
    if u < 0.75:
        h = -rng.uniform(0.02, 0.98) * d_min     # Proposition IV.4's range
    elif u < 0.875:
        h = -rng.uniform(1.02, 2.0) * d_min
    else:
        h = rng.uniform(0.02, 0.5) * d_min
    w = rng.uniform(2.0, 16.0)
    g = -rng.uniform(2.0, 20.0)
    model = fast_model(v, cm, rho2, h, w, g)
    edge = int(rng.choice(model.part.stable_edges))
    lo = model.r_min(edge)
    if lo > MAX_GRASP_PARTS * model.part.r:
        return random_case(rng)     # a barely stable edge: R_grasp of metres, flights of hours
    R = float(lo + rng.uniform(1e-6, 1.0) * max(4 * model.part.r, lo))
    assert model.domain_error(edge, R) is None
    return v, cm, rho2, h, w, g, edge, R


def fast_model(v, cm, rho2, h, w, g):
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')     # h outside (-d_min, 0) is allowed here
        return ThrowModel(Part(v, cm=cm, radius_of_gyration=math.sqrt(rho2)), h, w, g)


def near_discontinuity(sim, edge, R, fast, r):
    """
    Tell whether R is within delta of a jump of the reference, to the fast answer's side.

    The reference must jump between R - delta and R + delta (other edge or kind, or R' apart
    by more than a continuous f can move: SLOPE_MAX * 2 delta), and the fast answer must be
    the reference's on one side (R' within R_TOL + SLOPE_MAX * delta).
    """
    delta = DISC_DELTA_REL * r
    sides = [sim.throw(edge, R - delta), sim.throw(edge, R + delta)]
    jumps = ((sides[0].edge, sides[0].kind) != (sides[1].edge, sides[1].kind)
             or abs(sides[0].R - sides[1].R) > SLOPE_MAX * 2 * delta)
    matches = any(side.edge == fast.edge and side.kind == fast.kind
                  and abs(side.R - fast.R) <= R_TOL_REL * r + SLOPE_MAX * delta
                  for side in sides)
    return jumps and matches


@pytest.fixture(scope='module')
def random_runs():
    rng = np.random.default_rng(SEED)
    runs = []
    for _ in range(N_RANDOM):
        v, cm, rho2, h, w, g, edge, R = random_case(rng)
        model = fast_model(v, cm, rho2, h, w, g)
        sim = ReferenceSimulator(v, cm, rho2, h, w, g)
        fast = model.throw(edge, R)
        ref = sim.throw(edge, R)
        r = model.part.r
        agree = (fast.edge == ref.edge and fast.kind == ref.kind
                 and abs(fast.R - ref.R) <= R_TOL_REL * r)
        disc = False if agree else near_discontinuity(sim, edge, R, fast, r)
        runs.append({'case': (v.tolist(), cm.tolist(), rho2, h, w, g, edge, R), 'model': model,
                     'fast': fast, 'ref': ref, 'r': r, 'agree': agree, 'disc': disc})
    return runs


# ---------------------------------------------------------------------------- comparisons
def test_random_throws_agree_on_edge_kind_and_radius(random_runs):
    bad = [run for run in random_runs if not run['agree'] and not run['disc']]
    disc = [run for run in random_runs if run['disc']]
    agree = [run for run in random_runs if run['agree']]
    assert not bad, 'fast solver and reference disagree away from any discontinuity:\n' + \
        '\n'.join(f"{run['case']}: fast {(run['fast'].edge, run['fast'].R, run['fast'].kind)} "
                  f"ref {(run['ref'].edge, run['ref'].R, run['ref'].kind)}" for run in bad)
    assert len(disc) <= MAX_DISC_FRACTION * len(random_runs), [run['case'] for run in disc]
    worst = max(abs(run['fast'].R - run['ref'].R) / run['r'] for run in agree)
    print(f'\nreference check: {len(agree)}/{len(random_runs)} agree, {len(disc)} at a '
          f'discontinuity; max |dR|/r = {worst:.3g}')
    assert worst <= R_TOL_REL


def test_random_throws_agree_on_flight_rolling_and_impacts(random_runs):
    """Beyond f itself: flight time, first contact, net rotation and every impact."""
    for run in random_runs:
        if not run['agree']:
            continue
        fast, ref = run['fast'], run['ref']
        assert ref.flight_time == pytest.approx(fast.flight_time, rel=T_TOL_REL), run['case']
        assert ref.first_contact_vertex == fast.first_contact_vertex, run['case']
        assert abs(ref.net_rotation - fast.net_rotation) <= ROT_TOL, run['case']
        seq_fast = [(i.kind, i.vertex, i.edge) for i in fast.impacts]
        seq_ref = [(i.kind, i.vertex, i.edge) for i in ref.impacts]
        assert seq_ref == seq_fast, run['case']
        omega_scale = math.sqrt(ref.release_energy) / run['r']
        for a, b in zip(fast.impacts, ref.impacts):
            assert abs(a.omega_before - b.omega_before) <= OMEGA_TOL_REL * omega_scale
            assert abs(a.omega_after - b.omega_after) <= OMEGA_TOL_REL * omega_scale
            assert abs(a.energy_before - b.energy_before) <= ENERGY_TOL_REL * ref.release_energy
            assert abs(a.energy_after - b.energy_after) <= ENERGY_TOL_REL * ref.release_energy
            assert abs(a.x - b.x) <= R_TOL_REL * run['r']


def test_random_cases_cover_the_model(random_runs):
    """The sample must exercise jogs, flips, long rolls, rocking and stops on landing."""
    n = len(random_runs)
    refs = [run['ref'] for run in random_runs]
    jogs = sum(ref.kind == 'jog' for ref in refs)
    long_rolls = sum(len(ref.impacts) >= 4 for ref in refs)
    stop_on_landing = sum(any(i.kind == 'landing' and i.omega_after == 0.0 for i in ref.impacts)
                          for ref in refs)
    rocking = sum(any(a.edge == b.edge for a, b in zip(ref.impacts, ref.impacts[1:]))
                  for ref in refs)
    outside_h = sum(not -run['model'].part.d_min < run['case'][3] < 0 for run in random_runs)
    unstable = sum(not run['model'].part.stable.all() for run in random_runs)
    assert 0.2 * n <= jogs <= 0.8 * n
    assert long_rolls >= 0.05 * n
    assert stop_on_landing >= 0.1 * n
    assert rocking >= 0.05 * n
    assert outside_h >= 0.1 * n
    assert unstable >= 0.2 * n


# ---------------------------------------------------------------------------- reference physics
def test_reference_conserves_energy_in_flight_and_rolling(random_runs):
    for run in random_runs:
        ref = run['ref']
        assert ref.flight_energy_drift <= 1e-12, run['case']
        assert ref.roll_energy_drift <= ENERGY_TOL_REL, run['case']
        # Between two impacts the part rolls: the energy after one is the energy before the next.
        for a, b in zip(ref.impacts, ref.impacts[1:]):
            assert b.energy_before == pytest.approx(a.energy_after, rel=ENERGY_TOL_REL,
                                                    abs=1e-15)
        assert ref.impacts[0].energy_before == pytest.approx(ref.release_energy, rel=1e-12)


def test_reference_impacts_never_add_energy(random_runs):
    for run in random_runs:
        for imp in run['ref'].impacts:
            assert imp.energy_after <= imp.energy_before * (1 + 1e-12) + 1e-15, run['case']


def test_reference_settles_below_both_tip_over_barriers(random_runs):
    for run in random_runs:
        ref = run['ref']
        part = ReferencePart(*run['case'][:3])
        j = ref.edge
        assert part.stable[j]
        ke = ref.impacts[-1].energy_after - (-run['case'][5]) * part.d[j]
        barrier = -run['case'][5] * (min(part.dist[j], part.dist[(j + 1) % part.n]) - part.d[j])
        assert -1e-12 * ref.release_energy <= ke <= barrier * (1 + 1e-12)


def test_sticking_impact_stops_the_vertex_and_keeps_its_angular_momentum():
    rng = np.random.default_rng(7)
    for _ in range(200):
        r = rng.normal(size=2) * 0.05
        vel = rng.normal(size=2)
        omega = rng.normal() * 10
        rho2 = rng.uniform(1e-4, 1e-2)
        xd, yd, wd = sticking_impact(r, vel, omega, rho2)
        # eqs 7-8: the contact vertex is at rest afterwards
        assert abs(xd - r[1] * wd) <= 1e-12 and abs(yd + r[0] * wd) <= 1e-12
        # angular momentum about the contact point: rho^2 w + (CM - P) x v
        before = rho2 * omega - (r[0] * vel[1] - r[1] * vel[0])
        after = rho2 * wd - (r[0] * yd - r[1] * xd)
        assert after == pytest.approx(before, rel=1e-12, abs=1e-15)
        e0 = 0.5 * (vel @ vel + rho2 * omega ** 2)
        e1 = 0.5 * (xd ** 2 + yd ** 2 + rho2 * wd ** 2)
        assert e1 <= e0 * (1 + 1e-12)


def test_reference_part_frames_match_the_library():
    rng = np.random.default_rng(11)
    for _ in range(100):
        v = random_polygon(rng)
        area, cm, rho2 = polygon_mass_properties(v)
        part = Part(v)
        ref = ReferencePart(v, cm, rho2)
        assert area == pytest.approx(part.area, rel=1e-12)
        assert cm == pytest.approx(part.cm, abs=1e-15 + 1e-12 * part.r)
        assert rho2 == pytest.approx(part.rho2, rel=1e-10)
        assert ref.d == pytest.approx(part.d, rel=1e-10)
        assert ref.u_l == pytest.approx(part.u_l, abs=1e-12 * part.r)
        assert ref.u_r == pytest.approx(part.u_r, abs=1e-12 * part.r)
        assert (ref.stable == part.stable).all()


def _graze_states(count):
    """
    States beside a graze, where one vertex dips ~1e-11 m below the arm for ~1e-6 s.

    The flight time T(R) is continuous except at R* where a vertex's lowest point before the
    contact just touches the arm. Bisection on the fast solver's T isolates R*; the states
    returned sit GRAZE_OFFSET_REL R on either side of it: on the early side the dip is about
    as short as the reference's sampling step, yet deep enough that its contact time is
    usually well conditioned (at R* itself the root is a double root, ill-conditioned in
    both solvers).
    """
    rng = np.random.default_rng(9)
    found = []
    while len(found) < count:
        v, cm, rho2, h, w, g, edge, _ = random_case(rng)
        model = fast_model(v, cm, rho2, h, w, g)
        part = model.part
        lo = model.r_min(edge) * (1 + 1e-9) + 1e-12
        radii = np.linspace(lo, lo + 4 * part.r, 80)
        times = np.array([model.throw(edge, r).flight_time for r in radii])
        steps = np.abs(np.diff(times))
        for m in np.flatnonzero(steps > 5 * np.median(steps)):
            a, b, ta, tb = radii[m], radii[m + 1], times[m], times[m + 1]
            while True:
                mid = 0.5 * (a + b)
                if mid in (a, b):
                    break
                tm = model.throw(edge, mid).flight_time
                if abs(tm - ta) < abs(tm - tb):
                    a, ta = mid, tm
                else:
                    b, tb = mid, tm
            if abs(ta - tb) > 1e-6 * max(ta, tb):      # a jump, not a steep slope
                off = GRAZE_OFFSET_REL * b
                early, late = (a - off, b + off) if ta < tb else (b + off, a - off)
                found.append(((v, cm, rho2, h, w, g), edge, early, late))
                break
    return found


def test_grazing_contacts_between_samples_are_found():
    """
    Grazing contacts are found and agree with the fast solver on both sides of a graze.

    Between two samples a graze is found by the sampled-minimum refinement; the fast solver
    uses conservative advancement. A root where the vertex approaches the arm at v m/s moves
    by ~1e-17 m / v when the height is rounded, so grazes approached slower than
    GRAZE_MIN_SPEED are skipped.
    """
    compared = refined = 0
    for params, edge, early, late in _graze_states(12):
        model = fast_model(*params)
        sim = ReferenceSimulator(*params)
        for R in (early, late):
            fast = model.throw(edge, R)
            ref = sim.throw(edge, R)
            if ref.contact_speed < GRAZE_MIN_SPEED:
                continue
            compared += 1
            refined += sim.last_contact_from_graze
            assert ref.first_contact_vertex == fast.first_contact_vertex
            assert ref.flight_time == pytest.approx(fast.flight_time, rel=T_TOL_REL)
            assert (ref.edge, ref.kind) == (fast.edge, fast.kind)
            assert abs(ref.R - fast.R) <= R_TOL_REL * model.part.r
    assert compared >= 22
    assert refined >= 2


# ---------------------------------------------------------------------------- model conventions
@functools.lru_cache(maxsize=None)
def _flat_landing_states(count):
    """States whose flight ends with an edge flat on the arm (found by bisection on R)."""
    rng = np.random.default_rng(5)
    found = []
    while len(found) < count:
        v, cm, rho2, h, w, g, edge, _ = random_case(rng)
        model = fast_model(v, cm, rho2, h, w, g)
        part = model.part
        lo = model.r_min(edge) * (1 + 1e-9) + 1e-12
        radii = np.linspace(lo, lo + 4 * part.r, 40)
        first = [model.throw(edge, r).first_contact_vertex for r in radii]
        for m in range(len(radii) - 1):
            if (first[m] - first[m + 1]) % part.n not in (1, part.n - 1):
                continue
            a, b = radii[m], radii[m + 1]
            while True:       # the contact vertex switches where the edge between lands flat
                mid = 0.5 * (a + b)
                if mid in (a, b):
                    break
                if model.throw(edge, mid).first_contact_vertex == first[m]:
                    a = mid
                else:
                    b = mid
            # A switch can also come from a graze (no flat edge): then neither end is flat.
            found.append(((v, cm, rho2, h, w, g), edge, (a, b)))
            break
    return found


def test_flat_landing_and_tip_from_rest_conventions_agree():
    """
    Check convention (a) and tipping over from rest.

    An edge within 1e-9 rad of flat at the end of flight stops flat on it; on an unstable edge
    the part then tips over from rest.
    """
    stable = unstable = 0
    for params, edge, ends in _flat_landing_states(40):
        model = fast_model(*params)
        sim = ReferenceSimulator(*params)
        for R in ends:
            fast = model.throw(edge, R)
            ref = sim.throw(edge, R)
            flat_fast = fast.impacts[0].kind == 'flat_landing'
            assert (ref.impacts[0].kind == 'flat_landing') == flat_fast
            if not flat_fast:
                continue
            assert ref.impacts[0].edge == fast.impacts[0].edge
            assert (ref.edge, ref.kind) == (fast.edge, fast.kind)
            assert abs(ref.R - fast.R) <= R_TOL_REL * model.part.r
            if model.part.stable[ref.impacts[0].edge]:
                stable += 1
            else:
                unstable += 1
                assert ref.impacts[1].kind == 'tip_from_rest'
    assert stable >= 5 and unstable >= 5


def test_nearly_flat_landings_beyond_the_tolerance_hit_corner_first():
    """
    Just outside the 1e-9 rad window (1e-6 r from a flat landing) the flight ends on a corner.

    The edge then lands an instant later; both solvers must record the same impacts.
    """
    corner = 0
    for params, edge, (a, b) in _flat_landing_states(40):
        model = fast_model(*params)
        sim = ReferenceSimulator(*params)
        off = 1e-6 * model.part.r
        for R in (a - off, b + off):
            fast = model.throw(edge, R)
            ref = sim.throw(edge, R)
            assert ([(i.kind, i.vertex, i.edge) for i in ref.impacts]
                    == [(i.kind, i.vertex, i.edge) for i in fast.impacts])
            assert (ref.edge, ref.kind) == (fast.edge, fast.kind)
            assert abs(ref.R - fast.R) <= R_TOL_REL * model.part.r
            corner += fast.impacts[0].kind == 'flight'
    assert corner >= 20


def test_tiny_hops_from_next_to_the_pivot_agree():
    """Thrown from just right of the pivot (R + u_l -> 0), the left vertex hops for ~1e-7 s."""
    rng = np.random.default_rng(17)
    compared = 0
    while compared < 60:
        v, cm, rho2, h, w, g, edge, _ = random_case(rng)
        model = fast_model(v, cm, rho2, h, w, g)
        part = model.part
        if model.r_grasp[edge] >= -part.u_l[edge]:
            continue        # the grasp bound binds: R cannot come that close to the pivot
        sim = ReferenceSimulator(v, cm, rho2, h, w, g)
        for gap in (1e-9, 1e-7, 1e-5, 1e-3):
            R = -part.u_l[edge] + gap * part.r
            fast = model.throw(edge, R)
            ref = sim.throw(edge, R)
            assert ref.flight_time == pytest.approx(fast.flight_time, rel=T_TOL_REL)
            assert ([(i.kind, i.vertex, i.edge) for i in ref.impacts]
                    == [(i.kind, i.vertex, i.edge) for i in fast.impacts])
            assert (ref.edge, ref.kind) == (fast.edge, fast.kind)
            assert abs(ref.R - fast.R) <= R_TOL_REL * part.r
            compared += 1


def test_jog_flip_boundaries_of_the_paper_triangle_coincide():
    """R_flip of each edge (bisection on the fast map) is where the reference turns too."""
    model = ThrowModel(Part(TRIANGLE), -0.005, 5.5851, -9.66)
    part = model.part
    sim = ReferenceSimulator(part.vertices, part.cm, part.rho2, -0.005, 5.5851, -9.66)
    delta = DISC_DELTA_REL * part.r
    for edge in part.stable_edges:
        a = model.r_min(edge) + 1e-9
        assert model.f(edge, a)[2] == 'jog'
        b = a + 0.01
        while model.f(edge, b)[2] == 'jog':
            b += 0.01
        while b - a > 1e-14:
            mid = 0.5 * (a + b)
            if model.f(edge, mid)[2] == 'jog':
                a = mid
            else:
                b = mid
        assert sim.throw(edge, a - delta).kind == 'jog'
        assert sim.throw(edge, b + delta).kind == 'flip'
        # The criterion for excusing a disagreement accepts the other side's answer here ...
        assert near_discontinuity(sim, edge, a, model.throw(edge, b), part.r)
        # ... but not an answer 1e-6 r off, nor any answer where f is continuous.
        fast = model.throw(edge, b)
        moved = dataclasses.replace(fast, R=fast.R + 1e-6 * part.r)
        assert not near_discontinuity(sim, edge, a, moved, part.r)
        inside = 0.5 * (model.r_min(edge) + a)
        assert not near_discontinuity(sim, edge, inside, model.throw(edge, inside), part.r)


# ---------------------------------------------------------------------------- paper parts
def _orbits_agree(model, sim, edge, R, throws):
    r = model.part.r
    e_fast, r_fast = edge, R
    e_ref, r_ref = edge, R
    for step in range(throws):
        fast = model.throw(e_fast, r_fast)
        ref = sim.throw(e_ref, r_ref)
        assert (ref.edge, ref.kind) == (fast.edge, fast.kind), step
        assert abs(ref.R - fast.R) <= R_TOL_REL * r, step
        e_fast, r_fast = fast.edge, fast.R
        e_ref, r_ref = ref.edge, ref.R
    return e_fast


def test_paper_triangle_30_throw_orbit_agrees():
    """Section V.A: the 6-8-10 triangle, h = -0.5 cm, 320 deg/s, g = -9.66, from (1, 12 cm)."""
    model = ThrowModel(Part(TRIANGLE), -0.005, 5.5851, -9.66)
    _, cm, rho2 = polygon_mass_properties(TRIANGLE)
    sim = ReferenceSimulator(TRIANGLE, cm, rho2, -0.005, 5.5851, -9.66)
    _orbits_agree(model, sim, 1, 0.12, 30)


def test_bracket_placeholder_30_throw_orbit_agrees():
    """The non-convex bracket: contact on the hull, mass properties of the L outline."""
    part = Part(BRACKET_OUTLINE)
    model = ThrowModel(part, -0.0025, math.radians(120.0), -2.20)
    _, cm, rho2 = polygon_mass_properties(BRACKET_OUTLINE)
    assert cm == pytest.approx(part.cm, abs=1e-15)
    sim = ReferenceSimulator(part.vertices, cm, rho2, -0.0025, math.radians(120.0), -2.20)
    _orbits_agree(model, sim, 4, 0.20, 30)


def test_reference_is_independent_of_the_library():
    """The reference must not import throwmap (it is the check, not a copy)."""
    tree = ast.parse(open(reference_sim.__file__, encoding='utf-8').read())
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            names.add((node.module or '').split('.')[0])
    assert names == {'dataclasses', 'math', 'numpy', 'scipy'}
