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
Hard cases of the throw map, each constructed precisely, with the property that must hold.

Each test builds its situation exactly (solving for the R that makes a vertex graze, that
puts the rolling energy on the tip-over threshold, ...) and checks the property. The table of
cases, and why the discontinuities some of them show are real, is docs/numerics.md.
"""

import io
import math

import numpy as np
import pytest
from throwmap import Accuracy, DomainError, load_scene, NumericalError, Part, ThrowModel
from throwmap.cli import main
from throwmap.status import LOST
from throwmap_testing import PAPER_W, SCENES, TRIANGLE_VERTICES

HARD_SCENES = sorted((SCENES / 'hard').glob('*.yaml'))
G = -9.66


def vertex_heights(model, edge, R, t):
    """Heights over the arm of every hull vertex at times t, straight from eqs (5)-(6)."""
    part = model.part
    t = np.atleast_1d(np.asarray(t, dtype=float))
    wt = model.w * t
    u = part.U[edge][:, None]
    v = part.V[edge][:, None]
    return (part.d[edge] + R * model.w * t + 0.5 * model.g * t * t + u * np.sin(wt)
            + v * np.cos(wt))


def signature(res):
    """Return the discrete outcome of a throw: first contact, every event, final edge."""
    return (res.first_contact_vertex, tuple((i.kind, i.vertex, i.edge) for i in res.impacts),
            res.edge)


def assert_valid(model, res):
    """
    Check the invariants every throw must satisfy, whatever the case.

    Finite numbers; the part settles on a stable edge; the net rotation takes the resting pose
    on the start edge to the one on the final edge; energy is conserved in flight and while
    rolling, never gained at an impact, and never below the resting potential; at the first
    impact the contact vertex is on the arm and no vertex is below it.
    """
    part = model.part
    assert math.isfinite(res.R) and math.isfinite(res.net_rotation)
    assert math.isfinite(res.flight_time) and res.flight_time > 0
    assert part.stable[res.edge]
    turn = part.rest_angle[res.edge] - part.rest_angle[res.edge0] - res.net_rotation
    assert abs(math.remainder(turn, 2 * math.pi)) <= 1e-9 + 1e-15 * abs(res.net_rotation)
    e0 = res.release_energy
    assert res.impacts[0].energy_before == pytest.approx(e0, rel=1e-9, abs=0)
    for imp in res.impacts:
        assert imp.energy_after <= imp.energy_before + 1e-12 * e0
    for a, b in zip(res.impacts, res.impacts[1:]):
        if b.kind == 'landing':
            assert b.energy_before == pytest.approx(a.energy_after, rel=1e-9, abs=1e-12 * e0)
    rest = -model.g * part.d[res.edge]
    assert res.impacts[-1].energy_after >= rest * (1 - 1e-12)
    assert e0 >= rest * (1 - 1e-12)
    T, R = res.flight_time, res.R0
    heights = vertex_heights(model, res.edge0, R, T)[:, 0]
    k = res.first_contact_vertex
    wt = model.w * T
    rate = abs(R * model.w + model.g * T + model.w * (part.U[res.edge0, k] * math.cos(wt)
                                                      - part.V[res.edge0, k] * math.sin(wt)))
    size = abs(R) + part.r + abs(R * model.w * T) + abs(model.g) * T * T
    tol = 4 * rate * max(model.accuracy.contact_time_tol, 4.5e-16 * T) + 1e-15 * size
    assert abs(heights[k]) <= tol
    assert heights.min() >= -tol


def bisect(pred, a, b):
    """Adjacent doubles (a', b') in [a, b] with pred(a') == pred(a) != pred(b')."""
    pa = pred(a)
    assert pred(b) != pa
    while True:
        m = 0.5 * (a + b)
        if m in (a, b):
            return a, b
        if pred(m) == pa:
            a = m
        else:
            b = m


def paper_triangle(w=PAPER_W, h=-0.005, **kw):
    """Return the paper's triangle (h = -0.5 cm, 320 deg/s unless changed)."""
    return ThrowModel(Part(TRIANGLE_VERTICES), h, w, G, **kw)


def ngon(n, radius=0.05):
    """Return a regular n-gon around the origin with edge 0 flat at the bottom."""
    angles = 2 * np.pi * np.arange(n) / n - np.pi / 2 - np.pi / n
    return radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)


def graze_state(model, edge, k, t, R):
    """
    Return (t*, R*, F''): thrown at R*, vertex k's height has a double root at t*.

    Newton on the 2x2 system from a nearby guess. Since dF/dR = w t > 0, R* is well conditioned
    (an error in F of 1e-17 m moves it by 1e-17 / (w t*)).
    """
    part = model.part
    w, g = model.w, model.g
    d, u, v = part.d[edge], part.U[edge, k], part.V[edge, k]
    for _ in range(40):
        s, c = math.sin(w * t), math.cos(w * t)
        F = d + R * w * t + 0.5 * g * t * t + u * s + v * c
        Fp = R * w + g * t + w * (u * c - v * s)
        Fpp = g - w * w * (u * s + v * c)
        det = Fp * w - w * t * Fpp
        t, R = t + (w * t * Fp - F * w) / det, R + (F * Fpp - Fp * Fp) / det
    return t, R, Fpp


# ------------------------------------------------------------------------------ grazing
@pytest.mark.parametrize('depth', [1e-6, 1e-9, 1e-12, 1e-14])
def test_graze_a_vertex_that_just_touches_and_one_that_just_misses(depth):
    """
    Vertex 1 of the triangle swings under the CM and dips to the arm; at R* it just grazes.

    Thrown at R*(1 -+ depth) it dips below the arm by w t* R* depth (1.9e-15 m at 1e-14) or
    misses by as much. A touch must be found (first contact V1 at t* - sqrt(2 miss / F'')) and a
    miss must be stepped over (the first contact comes later, elsewhere). Touch vs miss is a
    real discontinuity: a sticking contact stops the vertex however gently it arrives.
    """
    model = paper_triangle(w=30.0, h=-0.3 * 0.016)
    t_star, r_star, fpp = graze_state(model, 0, 1, 0.1834, 0.0353)
    heights = vertex_heights(model, 0, r_star, t_star)[:, 0]
    assert abs(heights[1]) < 1e-16 and fpp > 0
    assert np.delete(heights, 1).min() > 0.05          # nothing else is near the arm then
    miss = model.w * t_star * r_star * depth
    touch = model.throw(0, r_star * (1 - depth))
    assert_valid(model, touch)
    assert touch.first_contact_vertex == 1
    early = math.sqrt(2 * miss / fpp)                   # the root before the bottom of the dip
    assert touch.flight_time == pytest.approx(t_star - early, abs=0.01 * early)
    clear = model.throw(0, r_star * (1 + depth))
    assert_valid(model, clear)
    assert clear.first_contact_vertex == 0 and clear.flight_time > t_star + 0.03
    # Each side converges to its own limit; the limits differ (by 1.9 cm in R').
    limit_touch = model.throw(0, r_star * (1 - 1e-15))
    limit_clear = model.throw(0, r_star * (1 + 1e-15))
    assert abs(touch.R - limit_touch.R) <= 3e-4 * math.sqrt(depth / 1e-6)
    assert abs(clear.R - limit_clear.R) <= 0.1 * depth
    assert abs(limit_touch.R - limit_clear.R) > 0.015


def test_graze_a_left_vertex_hop_that_just_clears_the_arm():
    """
    A hop whose left vertex comes back down and just grazes the arm, or just clears it.

    A flat 8 x 3 cm plate spun at 16 rad/s: its left vertex (which starts on the arm) comes
    back down and grazes the arm at t* = 76 ms when thrown at R* = 4.574 cm.

    Just below R* the hop ends on that vertex at t*; just above it the plate clears and lands
    on V3 23 ms later. Both sides are valid throws; the flight time jumps at R* (real).
    """
    part = Part([[0, 0], [0.08, 0], [0.08, 0.03], [0, 0.03]])
    model = ThrowModel(part, -0.3 * part.d_min, 16.0, G)
    t_star, r_star, fpp = graze_state(model, 0, 0, 0.076, 0.0457)
    assert r_star == pytest.approx(0.04573833, abs=1e-8) and fpp > 0
    for depth in (1e-8, 1e-12, 1e-14):
        touch = model.throw(0, r_star * (1 - depth))
        clear = model.throw(0, r_star * (1 + depth))
        for res in (touch, clear):
            assert_valid(model, res)
        assert touch.first_contact_vertex == 0
        assert touch.flight_time == pytest.approx(t_star, abs=2e-4)
        assert clear.first_contact_vertex == 3
        assert clear.flight_time == pytest.approx(0.0988161, abs=1e-6)


# ------------------------------------------------------------------------ two-point landings
def test_near_simultaneous_two_vertex_landing():
    """
    An edge that lands almost flat: either corner first, or both at once.

    Thrown from edge 1 near R = 38.84 cm the triangle lands with E0 almost flat: V1 hits first
    below R*, V0 above it, and within flat_landing_tol of flat both stick at once.

    Whichever corner is first, the part ends on E0 with its vertices where they hit, so R' is
    continuous through all three regimes (the two-point stop and the two corner-first rolls).
    """
    model = paper_triangle()
    part = model.part
    a, b = bisect(lambda R: model.throw(1, R).first_contact_vertex, 0.3883, 0.3885)
    results = {}
    for R in np.concatenate([a - np.logspace(-6, -13, 8), [a, b], b + np.logspace(-13, -6, 8)]):
        res = model.throw(1, R)
        assert_valid(model, res)
        assert (res.edge, res.kind) == (0, 'flip')
        heights = vertex_heights(model, 1, R, res.flight_time)[:, 0]
        tilt = (heights[1] - heights[0]) / part.edge_length[0]    # E0's slope at impact
        first = res.impacts[0]
        if abs(tilt) <= 0.9 * model.accuracy.flat_landing_tol:
            assert first.kind == 'flat_landing' and first.edge == 0
            assert first.energy_after == pytest.approx(-G * part.d[0], rel=1e-12)
        elif abs(tilt) >= 1.1 * model.accuracy.flat_landing_tol:
            assert first.kind == 'flight'
            assert first.vertex == (1 if tilt < 0 else 0)
        results[R] = res.R
    radii = sorted(results)
    values = np.array([results[R] for R in radii])
    steps = np.abs(np.diff(values))
    assert steps.max() <= 2e-6       # the grid steps by up to 1e-6 m in R: no jump
    # All three regimes were crossed.
    kinds = {model.throw(1, R).impacts[0].kind for R in radii}
    assert kinds == {'flight', 'flat_landing'}


def test_flat_landing_tolerance_sliver_at_the_toe_stub_limit():
    """
    A tiny hop at the toe-stub limit: flat_landing_tol decides between stop and flip.

    Thrown from edge 0 just beyond the toe-stub limit R = -u_l, the triangle spinning at
    15 rad/s barely hops and comes down on its left vertex with E0 tilted by phi ~ w T.

    For phi > flat_landing_tol the spin rolls it back over V0 (a flip to E2); for phi below it
    the two-point impact stops it (a jog). This sliver, R - R_min < ~2e-11 m here, is the
    documented model limit: a simultaneous two-point impact has no unique answer, and the
    corner-first answer is what the exact model gives for every phi > 0.
    """
    model = paper_triangle(w=15.0, h=-0.008)
    part = model.part
    assert -part.u_l[0] > model.r_grasp[0]                  # the toe-stub bound sets R_min
    slope = model.w * 2 * model.w / abs(G + model.w ** 2 * part.d[0])    # d(phi)/dR there
    tol = model.accuracy.flat_landing_tol
    for ratio, expected in ((0.25, 'jog'), (0.5, 'jog'), (2.0, 'flip'), (8.0, 'flip')):
        R = -part.u_l[0] + ratio * tol / slope
        res = model.throw(0, R)
        assert_valid(model, res)
        assert res.flight_time * model.w == pytest.approx(ratio * tol, rel=0.05)
        assert res.kind == expected
        if expected == 'jog':
            assert res.impacts[0].kind == 'flat_landing' and res.R == pytest.approx(R, rel=1e-9)
        else:
            assert res.edge == 2 and res.impacts[0].vertex == 0
    # Far from the sliver the corner-first answer is smooth in R.
    radii = -part.u_l[0] + np.logspace(-9, -4, 6)
    assert {model.throw(0, R).edge for R in radii} == {2}


# ----------------------------------------------------------------------- sweet spot, rolling
def test_sweet_spot_catch_is_continuous():
    """
    At the sweet spot the first impact leaves the triangle at rest on V1 (omega+ = 0).

    On either side omega+ changes sign but is tiny, so gravity decides which way it falls; the
    outcome must not jump: same edge, R' within an ulp or two.
    """
    model = paper_triangle()
    a, b = bisect(lambda R: model.throw(1, R).impacts[0].omega_after > 0, 0.11, 0.13)
    lo, hi = model.throw(1, a), model.throw(1, b)
    for res in (lo, hi):
        assert_valid(model, res)
        assert abs(res.impacts[0].omega_after) < 1e-13 * model.w
    assert lo.impacts[0].omega_after * hi.impacts[0].omega_after <= 0
    assert (lo.edge, lo.kind) == (hi.edge, hi.kind) == (1, 'jog')
    assert hi.R - lo.R == pytest.approx(0, abs=4e-17)
    for delta in (1e-9, 1e-6):
        near = [model.throw(1, a * (1 + s * delta)) for s in (-1, 1)]
        assert all(r.edge == 1 for r in near)
        assert abs(near[1].R - near[0].R) < 20 * delta * a


def test_rolling_energy_exactly_at_the_tip_over_threshold():
    """
    Rolling energy exactly at the tip-over threshold: back below it, over above it.

    Thrown from edge 0 near R = 13.88 cm, the triangle's first impact leaves it with just the
    energy to roll up until its CM is over the pivot V0, |g| l_0 (CM height right above V0).

    Below R* it falls back (a jog, E0 lands), above it it tips over (a flip to E2): the
    separatrix of a pendulum, a real discontinuity. At R* the energy after the impact must
    equal |g| l_0 to rounding, and both sides must be clean throws.
    """
    model = paper_triangle()
    part = model.part
    a, b = bisect(lambda R: model.throw(0, R).edge, 0.1385, 0.1392)
    top = -G * part.vertex_radius[0]
    back, over = model.throw(0, a), model.throw(0, b)
    for res in (back, over):
        assert_valid(model, res)
        assert res.first_contact_vertex == 0
        assert res.impacts[0].energy_after == pytest.approx(top, rel=1e-13)
    assert (back.edge, back.kind) == (0, 'jog') and (over.edge, over.kind) == (2, 'flip')
    assert back.impacts[1].vertex == 1 and over.impacts[1].vertex == 2
    # Landing speeds come from energy conservation, finite at the top (w = 0 there).
    assert math.isfinite(back.impacts[1].omega_before) and back.impacts[1].omega_before < 0
    assert math.isfinite(over.impacts[1].omega_before) and over.impacts[1].omega_before > 0
    # Away from the threshold the map is continuous on each side.
    for R, side in ((a * (1 - 1e-9), back), (b * (1 + 1e-9), over)):
        res = model.throw(0, R)
        assert signature(res) == signature(side)
        assert res.R == pytest.approx(side.R, abs=1e-9)


def test_cm_exactly_above_the_pivot_tips_the_part_deterministically():
    """
    A quadrilateral whose CM is exactly above V1 when it lies on E0 (u_r = 0: E0 unstable).

    Thrown from E1 at R = 9.6037 cm with w = 8 rad/s it lands flat on E0 and is balanced on
    V1 with zero energy to spare. The model tips it on over V1 (documented tie-break), onto
    E1, like a part whose CM lies a hair beyond V1; a hair inside, E0 is stable and it stays.
    """
    s = 0.05
    outline = np.array([[0, 0], [1, 0], [1.5, 1], [0, 1]]) * s

    def model_with_cm_x(x):
        return ThrowModel(Part(outline, cm=[x, 0.5 * s]), -0.005, 8.0, G)

    model = model_with_cm_x(s)
    part = model.part
    assert part.u_r[0] == 0.0 and not part.stable[0]
    assert part.alpha_ccw_end[1] == math.pi / 2            # balanced: straight up from V1
    R = 0.09603733737156481
    res = model.throw(1, R)
    assert_valid(model, res)
    events = [(i.kind, i.vertex, i.edge) for i in res.impacts]
    assert events[0][0] == 'flat_landing' and events[0][2] == 0
    assert events[1:] == [('tip_from_rest', 1, 0), ('landing', 2, 1)]
    assert (res.edge, res.kind) == (1, 'jog')
    beyond = model_with_cm_x(s * (1 + 1e-12)).throw(1, R)
    assert (beyond.edge, beyond.kind) == (1, 'jog')
    assert beyond.R == pytest.approx(res.R, abs=1e-12)
    inside = model_with_cm_x(s * (1 - 1e-12))
    assert inside.part.stable[0]
    assert inside.throw(1, R).edge == 0


# --------------------------------------------------------------------- release speed extremes
def test_release_speed_to_zero_flight_time_to_zero():
    """
    Release speed -> 0: the flight time goes to 0 with it, and every throw is a jog.

    As w -> 0 the hop shrinks: T = 2 w (R + u_l) / |g + w^2 d| to first order, and the jog
    moves the part out by -h w T (Proposition IV.4). Down to w = 5e-324 (the smallest double)
    every throw must be a clean jog; T must follow the formula until it drops below
    contact_time_tol, and the shift must follow -h w T while it is above rounding.
    """
    for w in [1.0, 1e-1, 1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-100, 5e-324]:
        model = paper_triangle(w=w)
        part = model.part
        tol_t = model.accuracy.contact_time_tol
        for edge in part.stable_edges:
            R = 1.5 * model.r_min(edge)
            res = model.throw(edge, R)
            assert_valid(model, res)
            assert (res.edge, res.kind) == (edge, 'jog')
            hop = 2 * w * (R + part.u_l[edge]) / abs(G + w * w * part.d[edge])
            if w < 1.0 and hop > 10 * tol_t:      # (below tol_t both corners 'touch' at tol_t)
                assert res.first_contact_vertex == edge      # the left vertex lands first
            shift = -model.h * w * res.flight_time
            if w <= 1e-2 and hop > 10 * tol_t:
                assert res.flight_time == pytest.approx(hop, rel=1e-6, abs=0)
            else:
                assert res.flight_time <= max(hop * 1.5, tol_t * (1 + 1e-9))
            if shift > 1e-6 * R:
                assert res.R - R == pytest.approx(shift, rel=0.05 if w < 1.0 else 0.2)
            else:
                assert abs(res.R - R - shift) <= 4 * np.spacing(R) + 2 * abs(shift)


def _lowest_point_during_flight(model, edge, R, T):
    """Minimum over [0, T) of every vertex's height: a fine grid, then each low dip refined."""
    from scipy.optimize import minimize_scalar
    step = 0.02 / max(model.w, 1.0)
    t = np.linspace(0.0, T, max(2000, int(T / step)))
    heights = vertex_heights(model, edge, R, t)
    lowest = heights[:, :-1].min()
    for k in range(model.part.n):
        h = heights[k]
        dips = np.flatnonzero((h[1:-1] <= h[:-2]) & (h[1:-1] <= h[2:])) + 1
        for i in dips:
            if t[i] > 0.999 * T or h[i] > 1e-3:
                continue
            best = minimize_scalar(lambda x: vertex_heights(model, edge, R, x)[k, 0],
                                   bounds=(t[i - 1], t[i + 1]), method='bounded',
                                   options={'xatol': 1e-13})
            lowest = min(lowest, best.fun)
    return lowest


@pytest.mark.parametrize('w', [20.0, 50.0, 100.0])
def test_very_fast_throws_with_several_turns_find_the_first_contact(w):
    """
    Fast throws that turn many times in flight still find the first contact.

    At 20-100 rad/s the triangle turns 1-30 times in flight and each vertex swings down past
    the arm once a turn. Conservative advancement must return the first contact: no vertex may
    dip below the arm earlier (checked on a grid of 1/50 turn, every low dip refined).
    """
    model = paper_triangle(w=w)
    part = model.part
    turns = []
    for edge in part.stable_edges:
        lo = model.r_min(edge)
        for R in np.linspace(lo * 1.01, lo * 4, 5):
            res = model.throw(edge, R)
            assert_valid(model, res)
            assert _lowest_point_during_flight(model, edge, R, res.flight_time) > -1e-12
            turns.append(res.flight_time * w / (2 * math.pi))
    assert max(turns) > (2 if w == 20.0 else 10)


# ------------------------------------------------------------------- the ends of the domain
def test_R_exactly_at_R_grasp():
    """R_grasp itself is inside the domain, one ulp below it is not; f is continuous there."""
    model = paper_triangle()
    r_grasp = model.r_grasp[2]
    assert r_grasp > -model.part.u_l[2]                      # the grasp bound is the binding one
    res = model.throw(2, r_grasp)
    assert_valid(model, res)
    below = np.nextafter(r_grasp, 0.0)
    with pytest.raises(DomainError) as err:
        model.f(2, below)
    assert err.value.condition == 'grasp_bound_3'
    assert err.value.margin == r_grasp - below > 0
    for eps in (1e-15, 1e-12, 1e-9):
        near = model.throw(2, r_grasp * (1 + eps))
        assert signature(near) == signature(res)
        assert near.R == pytest.approx(res.R, abs=10 * eps * r_grasp)


@pytest.mark.parametrize('edge', [0, 1])
def test_R_at_the_toe_stub_limit(edge):
    """
    R at the toe-stub limit: excluded there, a jog of contact_time_tol one ulp beyond.

    At R = -u_l the left vertex starts at the pivot and would move straight up: excluded
    (toe_stub). One ulp beyond it the hop lasts ~1e-17 s, below contact_time_tol: the throw is
    a flat jog of contact_time_tol, and R' moves by at most what the part moves in that time.
    Further out T grows in proportion to R - R_min, continuously.
    """
    model = paper_triangle()
    part = model.part
    r_min = -part.u_l[edge]
    assert r_min > model.r_grasp[edge]                       # the toe-stub bound binds
    with pytest.raises(DomainError) as err:
        model.f(edge, r_min)
    assert err.value.condition == 'toe_stub'
    tol_t = model.accuracy.contact_time_tol
    res = model.throw(edge, np.nextafter(r_min, 1.0))
    assert_valid(model, res)
    assert res.kind == 'jog' and res.impacts[0].kind == 'flat_landing'
    assert res.flight_time <= tol_t * (1 + 1e-9)
    assert 0 < res.R - r_min <= 2 * abs(model.h) * model.w * tol_t
    slope = 2 * model.w / abs(G + model.w ** 2 * part.d[edge])     # dT/dR at R_min
    for eps in (1e-9, 1e-7, 1e-5):
        near = model.throw(edge, r_min + eps)
        assert_valid(model, near)
        assert near.kind == 'jog'
        assert near.flight_time == pytest.approx(slope * eps, rel=1e-3)


# ------------------------------------------------------------------------- awkward geometry
@pytest.mark.parametrize('n', [64, 128, 256])
def test_many_vertices_near_circular(n):
    """
    Regular 64-, 128- and 256-gons roll like wheels for thousands of impacts.

    Regular 64-, 128- and 256-gons (R_grasp grows like n: 1.0, 2.0, 4.1 m) thrown from R_grasp
    and 1.5 R_grasp roll like wheels for thousands of impacts; every impact must lose energy,
    every roll conserve it, and the part must settle on a stable edge.
    """
    part = Part(ngon(n))
    assert part.n == n and part.stable.all()
    model = ThrowModel(part, -0.5 * part.d_min, PAPER_W, G)
    impacts = []
    for factor in (1.0, 1.5):
        res = model.throw(0, model.r_grasp[0] * factor)
        assert_valid(model, res)
        impacts.append(len(res.impacts))
    assert min(impacts) > 100


@pytest.mark.parametrize('n', [64, 256])
def test_many_vertices_semicircle(n):
    """
    A semicircle with 64 or 256 arc vertices (a D-shape) jogs, flips and rocks.

    A D-shape: n vertices on a 5 cm arc and one flat edge (the realistic way to get many
    vertices). Thrown from the flat edge at ordinary radii it jogs and flips; a flip that
    lands on the arc rocks like a rocking chair (68,000 impacts at n = 256, R = 20 cm).
    """
    arc = np.linspace(0.0, np.pi, n + 1)[:-1]
    part = Part(np.vstack([0.05 * np.stack([np.cos(arc), np.sin(arc)], axis=1), [[-0.05, 0]]]))
    flat = int(np.argmax(part.edge_length))
    model = ThrowModel(part, -0.5 * part.d_min, PAPER_W, G)
    lo = model.r_min(flat)
    kinds = set()
    for R in np.linspace(lo * 1.001, 0.4, 8):
        res = model.throw(flat, R)
        assert_valid(model, res)
        kinds.add(res.kind)
    assert kinds == {'jog', 'flip'}


def _square_with_a_bump(eps, s=0.05):
    """Return a 5 cm square whose bottom edge is split at 30 % by a vertex eps s below it."""
    return np.array([[0, 0], [0.3, -eps], [1, 0], [1, 1], [0, 1]]) * s


def test_nearly_collinear_vertices():
    """
    A square with a vertex a hair out of its bottom edge: stable numerics, real jumps.

    A square with a vertex pushed 1e-3 .. 1e-11 of its size out of the bottom edge (exterior
    angle ~1.4 eps): the bottom becomes two edges, one unstable, and a landing on the bottom
    rolls over the bump through an angle ~eps between two sticking impacts.

    Properties: every throw is valid; results are continuous in eps > 0 (eps = 1e-8 and 1e-10
    agree to O(eps) on a grid of 1,200 throws); below the hull's collinearity threshold
    (1e-12 relative) the bump is dropped and the square's results come back exactly. Between
    the two (eps -> 0+ versus the square) about 1 % of throws differ: two one-point impacts
    are not one two-point impact (docs/numerics.md).
    """
    w = PAPER_W
    square = ThrowModel(Part(_square_with_a_bump(0.0)), -0.01, w, G)
    assert square.part.n == 4
    radii = np.linspace(0.035, 0.4, 300)
    batches = {}
    for eps in (1e-3, 1e-8, 1e-10, 1e-13):
        model = ThrowModel(Part(_square_with_a_bump(eps)), -0.01, w, G)
        part = model.part
        if eps >= 1e-11:
            assert part.n == 5 and not part.stable[0] and part.stable[1:].all()
            turn = part.rest_angle[1] - part.rest_angle[0]
            assert abs(turn) == pytest.approx(eps / 0.3 + eps / 0.7, rel=1e-3)
        else:
            assert part.n == 4
        offset = part.n - 4                       # square edge i is edge i + offset here
        for edge in range(1, 4):
            for R in radii[::25]:
                assert_valid(model, model.throw(edge + offset, R))
        batches[eps] = [model.f_batch(np.full(radii.size, edge + offset), radii)
                        for edge in range(1, 4)]
    ref = [square.f_batch(np.full(radii.size, edge), radii) for edge in range(1, 4)]
    for a, b in zip(batches[1e-8], batches[1e-10]):
        assert np.array_equal(a['edge'], b['edge'])
        assert np.abs(a['R'] - b['R']).max() < 1e-8
    for a, b in zip(batches[1e-13], ref):
        assert np.array_equal(a['edge'], b['edge'])
        assert np.abs(a['R'] - b['R']).max() < 1e-12
    differ = sum(int(np.sum(a['edge'] - 1 != b['edge'])) for a, b in zip(batches[1e-10], ref))
    assert 0 < differ < 0.03 * 3 * radii.size


@pytest.mark.parametrize('aspect', [100, 1000])
def test_very_thin_parts(aspect):
    """
    Plates 1:100 and 1:1000 thin: all throws valid, orbits finite.

    A 10 cm plate 1:100 and 1:1000 thin. Its long edges have d = 0.5 (0.05) mm and start at
    the toe-stub limit; its short edges are 1 (0.1) mm wide, stable but with tip-over barriers
    of 2e-5 J/kg, and R_grasp there is metres. Every throw must be valid and an orbit of 300
    throws must stay finite until it leaves the domain with a DomainError, if it does.
    """
    length, thick = 0.1, 0.1 / aspect
    part = Part([[0, 0], [length, 0], [length, thick], [0, thick]])
    assert part.stable.all() and part.d_min == pytest.approx(thick / 2)
    model = ThrowModel(part, -0.25 * thick, PAPER_W, G)
    for edge in range(4):
        lo = model.r_min(edge)
        for R in lo * (1 + np.logspace(-9, 0.5, 12)):
            assert_valid(model, model.throw(edge, R))
    edges, radii, rots, status, done = model.orbits([0, 1], [0.08, 1.2 * model.r_grasp[1]], 300)
    for k in range(2):
        assert np.all(np.isfinite(radii[k, :done[k] + 1]))
        assert status[k] == 0 or model.domain_error(int(edges[k, done[k]]),
                                                    float(radii[k, done[k]])) is not None


def test_cm_near_the_hull_boundary():
    """
    The CM close to the hull boundary (d_min -> 0): f converges as it gets closer.

    The triangle with its CM moved to delta = 1e-4 .. 1e-10 m from the hypotenuse (d_min ->
    0), rho kept, h = -d_min / 2 (so h -> 0 too). The part lying on the hypotenuse is almost
    flat on its CM. Throws must be valid, and f must converge as delta -> 0 (differences of
    order delta on a fixed grid of states).
    """
    tri = np.array(TRIANGLE_VERTICES)
    rho = math.sqrt(Part(tri).rho2)
    foot = 0.5 * (tri[1] + tri[2])
    inward = np.array([0.8, -0.6])                     # unit normal into the part from E1
    states = [(e, R) for e in range(3) for R in np.linspace(0.075, 0.45, 60)]
    previous = None
    for delta in (1e-4, 1e-6, 1e-8, 1e-10):
        part = Part(tri, cm=foot + delta * inward, radius_of_gyration=rho)
        assert part.d_min == pytest.approx(delta, rel=1e-4) and part.d[1] == part.d_min
        model = ThrowModel(part, -0.5 * part.d_min, PAPER_W, G)
        out = []
        for edge, R in states:
            res = model.throw(edge, R)
            assert_valid(model, res)
            out.append((res.edge, res.R))
        if previous is not None:
            assert [e for e, _ in out] == [e for e, _ in previous]
            assert max(abs(a[1] - b[1]) for a, b in zip(out, previous)) < 1000 * delta
        previous = out


def test_nearly_unstable_edge():
    """
    An edge that is barely stable: f is continuous in the CM through the switch.

    A quadrilateral whose CM sits eta * 5 cm inside the right end of E0 (u_r = eta s): E0 is
    stable for eta > 0 with a tip-over barrier of ~|g| (eta s)^2 / (2 d), unstable for eta <= 0.

    f must be continuous in eta through the switch (to O(eta) on ~500 throws, for |eta| <=
    1e-6) except where the part comes to rest on E0 itself, which only a flat landing on E0
    does here: there the stable part stays and the unstable one tips (a real discontinuity).
    """
    s = 0.05
    outline = np.array([[0, 0], [1, 0], [1.5, 1], [0, 1]]) * s
    rho = math.sqrt(Part(outline).rho2)

    def model(eta):
        return ThrowModel(Part(outline, cm=[s * (1 - eta), 0.5 * s], radius_of_gyration=rho),
                          -0.005, 8.0, G)

    base = model(0.0)
    models = {eta: model(eta) for eta in (1e-3, 1e-6, 1e-9, 1e-12, -1e-12, -1e-9)}
    states = [(e, R) for e in (1, 2, 3) for R in np.linspace(0.06, 0.45, 200)
              if all(m.domain_error(e, R) is None for m in [base, *models.values()])]
    assert len(states) > 400
    reference = [base.throw(e, R) for e, R in states]
    for eta, m in models.items():
        assert m.part.stable[0] == (eta > 0)
        for (edge, R), ref in zip(states, reference):
            res = m.throw(edge, R)
            assert_valid(m, res)
            if abs(eta) <= 1e-6:      # (a CM moved by 50 um can cross a tip-over threshold)
                assert res.edge == ref.edge
                assert abs(res.R - ref.R) <= 1e3 * abs(eta) * s
    flat = 0.09603733737156481                         # lands flat on E0 (see the CM test)
    assert model(1e-9).throw(1, flat).edge == 0
    assert model(-1e-9).throw(1, flat).edge == 1


def test_offset_h_to_zero_and_to_minus_d_min():
    """
    The arm offset h -> 0 and h -> -d_min: f is continuous at both ends.

    h -> 0- and h -> -d_min+ (the ends of Proposition IV.4's range; at the ends themselves the
    model warns and still computes). h only enters through the CM's sideways speed -(h + d) w,
    so f must be continuous in h at both ends: |R'(h) - R'(end)| = O(h - end).
    """
    import warnings
    part = Part(TRIANGLE_VERTICES)
    states = [(e, R) for e in range(3) for R in np.linspace(0.06, 0.4, 40)]
    for end, side in ((0.0, -1.0), (-part.d_min, 1.0)):
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')
            at_end = ThrowModel(part, end, PAPER_W, G)
        limit = [at_end.throw(e, R) if at_end.domain_error(e, R) is None else None
                 for e, R in states]
        for gap in (1e-3, 1e-6, 1e-9, 1e-12):
            h = end + side * gap * part.d_min
            model = ThrowModel(part, h, PAPER_W, G)
            for (edge, R), ref in zip(states, limit):
                if ref is None or model.domain_error(edge, R) is not None:
                    continue
                res = model.throw(edge, R)
                assert_valid(model, res)
                if gap <= 1e-9:
                    assert signature(res) == signature(ref)
                if signature(res) == signature(ref):
                    assert abs(res.R - ref.R) <= 50 * gap * part.d_min


# -------------------------------------------------------------------- scales and determinism
def _scaled_model(k, vertices=TRIANGLE_VERTICES, h=-0.005, w=PAPER_W, g=G):
    """Return the paper's triangle with every length and g multiplied by k."""
    return ThrowModel(Part(np.asarray(vertices) * k), h * k, w, g * k)


@pytest.mark.parametrize('k', [2.0 ** -6, 2.0 ** -3, 2.0 ** 3, 2.0 ** 4])
def test_length_scales_by_powers_of_two_are_bit_exact(k):
    """
    Scaling lengths and g by a power of two scales the orbit exactly.

    Lengths x k and g x k leave every time and angle unchanged and scale every length by k.
    With k a power of two (the triangle at 1 mm .. 1.3 m) every floating-point operation scales
    exactly, so a 300-throw orbit must come out with the same edges and R x k bit for bit.
    """
    base = _scaled_model(1.0)
    scaled = _scaled_model(k)
    for edge, R in ((1, 0.12), (0, 0.2), (2, 0.07)):
        e0, r0, _ = base.orbit_arrays(edge, R, 300)
        e1, r1, _ = scaled.orbit_arrays(edge, R * k, 300)
        assert np.array_equal(e0, e1)
        assert np.array_equal(r0 * k, r1)


@pytest.mark.parametrize('k', [1e-3, 1e-2, 10.0])
def test_length_scales_mm_to_m(k):
    """
    Millimetre to metre parts: lengths and g x k give the same edges and R x k.

    With decimal k (a 60 um .. 1 m triangle, g from 9.7 mm/s^2 to 97 m/s^2) rounding differs,
    so single throws must agree to 1e-12 relative and an orbit must keep the same edges while
    the expanding jogs (Proposition IV.1) amplify rounding: its first 40 throws.
    """
    base = _scaled_model(1.0)
    scaled = _scaled_model(k)
    for edge in range(3):
        for R in np.linspace(0.06, 0.4, 25):
            a, b = base.throw(edge, R), scaled.throw(edge, R * k)
            assert signature(a) == signature(b)
            assert b.R / k == pytest.approx(a.R, rel=1e-12, abs=1e-15)
            assert b.flight_time == pytest.approx(a.flight_time, rel=1e-12)
            assert b.release_energy / k ** 2 == pytest.approx(a.release_energy, rel=1e-12)
    e0, r0, _ = base.orbit_arrays(1, 0.12, 40)
    e1, r1, _ = scaled.orbit_arrays(1, 0.12 * k, 40)
    assert np.array_equal(e0, e1)
    assert np.allclose(r1 / k, r0, rtol=1e-9, atol=0)


def test_determinism_across_calls_batches_and_processes():
    """
    The same state gives the same bits everywhere, in this process and a fresh one.

    The same state gives the same bits: twice in a row, through f, throw, f_batch and orbits,
    and in a fresh interpreter (which loads the compiled kernel from numba's cache).
    """
    import json
    import subprocess
    import sys
    model = paper_triangle()
    rng = np.random.default_rng(11)
    states = [(int(e), float(R)) for e, R in zip(rng.choice(3, 200), rng.uniform(0.06, 0.4, 200))]
    edges = np.array([e for e, _ in states])
    radii = np.array([R for _, R in states])
    batch = model.f_batch(edges, radii)
    again = model.f_batch(edges, radii)
    assert np.array_equal(batch['R'], again['R']) and np.array_equal(batch['edge'], again['edge'])
    o_edge, o_r, _, o_status, _ = model.orbits(edges, radii, 1)
    assert np.array_equal(o_r[:, 1], batch['R']) and (o_status == 0).all()
    for k, (e, R) in enumerate(states):
        j, r1, kind = model.f(e, R)
        res = model.throw(e, R)
        assert (j, r1, kind) == (batch['edge'][k], batch['R'][k], batch['kind'][k])
        assert (res.edge, res.R, res.kind) == (j, r1, kind)
    code = ('import json, sys\n'
            'from throwmap import Part, ThrowModel\n'
            f'm = ThrowModel(Part({TRIANGLE_VERTICES!r}), -0.005, {PAPER_W!r}, {G!r})\n'
            'states = json.load(sys.stdin)\n'
            'print(json.dumps([m.f(e, R)[1].hex() for e, R in states]))\n')
    out = subprocess.run([sys.executable, '-c', code], input=json.dumps(states),
                         capture_output=True, text=True, timeout=300, check=True)
    assert json.loads(out.stdout) == [float(x).hex() for x in batch['R']]


# ------------------------------------------------------------------------ scenes/hard/*.yaml
def _first_impact_energy_is_the_climb_to_the_top(scene, res):
    return res.impacts[0].energy_after == pytest.approx(
        -scene.gravity * scene.part.vertex_radius[res.first_contact_vertex], rel=1e-13)


# What each scene's start must show (besides assert_valid): the hard thing it is about.
SCENE_PROPERTIES = {
    'balanced_on_vertex': lambda sc, r: [(i.kind, i.vertex) for i in r.impacts][1:] == [
        ('tip_from_rest', 1), ('landing', 2)] and sc.part.u_r[0] == 0.0,
    'cm_near_edge': lambda sc, r: sc.part.d_min < 2e-9,
    'collinear_bump': lambda sc, r: sc.part.n == 5 and len(r.impacts) == 5,
    'fast_spin': lambda sc, r: r.flight_time * sc.release_speed / (2 * math.pi) > 30,
    'flat_landing': lambda sc, r: r.impacts[0].kind == 'flat_landing' and r.edge == 0,
    'flat_sliver_toe_stub': lambda sc, r: r.impacts[0].kind == 'flat_landing' and r.kind == 'jog',
    'graze_miss': lambda sc, r: r.first_contact_vertex == 0 and r.flight_time > 0.2,
    'graze_touch': lambda sc, r: r.first_contact_vertex == 1 and r.flight_time < 0.1834,
    'long_flight': lambda sc, r: r.flight_time > 16000,
    'metre': lambda sc, r: sc.part.r > 0.5,
    'millimetre': lambda sc, r: sc.part.r < 0.006,
    'nearly_unstable_edge': lambda sc, r: sc.part.stable[0] and r.edge == 0,
    'ngon64': lambda sc, r: sc.part.n == 64 and len(r.impacts) > 100,
    'offset_near_minus_dmin': lambda sc, r: 0 < sc.h + sc.part.d_min < 2e-12,
    'offset_near_zero': lambda sc, r: -2e-12 < sc.h < 0,
    'semicircle256': lambda sc, r: sc.part.n == 257 and len(r.impacts) > 10_000,
    'slow_release': lambda sc, r: r.kind == 'jog' and r.flight_time < 1e-7,
    'sweet_spot': lambda sc, r: abs(r.impacts[0].omega_after) < 1e-13 * sc.release_speed,
    'thin_plate': lambda sc, r: sc.part.d_min == pytest.approx(0.0005),
    'tiny_contact_time_tol': lambda sc, r: sc.model.accuracy.contact_time_tol == 1e-17,
    'tip_threshold': _first_impact_energy_is_the_climb_to_the_top,
    'toe_stub_limit': lambda sc, r: r.flight_time <= sc.model.accuracy.contact_time_tol,
}


def test_every_hard_scene_is_listed_and_says_what_is_hard():
    """Each scenes/hard/*.yaml has a test property and opens with a 'HARD CASE' comment."""
    assert sorted(p.stem for p in HARD_SCENES) == sorted(SCENE_PROPERTIES)
    for path in HARD_SCENES:
        assert path.read_text().startswith('# HARD CASE'), path.name


@pytest.mark.parametrize('path', HARD_SCENES, ids=lambda p: p.stem)
def test_hard_scene_loads_throws_and_orbits(path, capsys):
    """
    Load a hard scene with `throwmap grasp`, throw from its start, run a 50-throw orbit.

    The throw must satisfy the generic invariants and the scene's own property; the orbit must
    give finite states until it ends or leaves the domain (lost to the map, documented).
    """
    assert main(['grasp', str(path)], out=io.StringIO()) == 0
    assert 'warning' not in capsys.readouterr().err
    scene = load_scene(str(path))
    edge, R = scene.default_start()
    res = scene.model.throw(edge, R)
    assert_valid(scene.model, res)
    assert SCENE_PROPERTIES[path.stem](scene, res)
    edges, radii, _, status, done = scene.model.orbits([edge], [R], 50)
    assert np.all(np.isfinite(radii[0, :done[0] + 1]))
    if status[0] != 0:
        # The orbit ends at the throw that leaves the part outside the domain of f (lost to
        # the map: edge -1); that throw's full result says where the part rests, and why.
        assert status[0] == LOST and edges[0, done[0] + 1] == -1
        last = scene.model.throw(int(edges[0, done[0]]), float(radii[0, done[0]]))
        assert not last.in_domain and 'outside the domain of f' in last.lost_reason
        assert scene.model.domain_error(last.edge, last.R) is not None


# ------------------------------------------------------------------------------ regressions
def test_regression_tiny_contact_time_tol_does_not_stall():
    """
    Regression: a contact_time_tol below the time resolution stalled the advancement.

    With contact_time_tol = 1e-17 s, below the spacing of doubles at the contact time (5.6e-17
    s at t = 0.4 s), a + tau == a and the loop ran into max_flight_steps: a NumericalError on
    one throw in five of the paper's triangle. Now the shortest step is two ulps of t.
    """
    part = Part(TRIANGLE_VERTICES)
    fine = ThrowModel(part, -0.005, PAPER_W, -9.66,
                      accuracy=Accuracy(contact_time_tol=1e-17))
    default = ThrowModel(part, -0.005, PAPER_W, -9.66)
    for tol_model in (fine, ThrowModel(part, -0.005, PAPER_W, -9.66,
                                       accuracy=Accuracy(contact_time_tol=5e-324))):
        res = tol_model.throw(2, 0.391388)
        ref = default.throw(2, 0.391388)
        assert (res.edge, res.kind) == (ref.edge, ref.kind) == (1, 'flip')
        assert res.R == pytest.approx(ref.R, abs=1e-12)
        assert res.flight_time == pytest.approx(ref.flight_time, abs=2e-12)
    for edge in part.stable_edges:
        for R in np.linspace(0.06, 0.4, 60):
            if default.domain_error(edge, R) is None:
                assert fine.f(edge, R)[:1] == default.f(edge, R)[:1]


def test_regression_flight_of_hours_does_not_stall():
    """
    Regression: a flight of hours stalled the advancement at the default tolerance.

    Late in a flight of 16,800 s the spacing of doubles at t (3.6e-12 s) exceeds twice the
    default contact_time_tol, so the last safe steps did not move t and the throw ended in a
    NumericalError (max_flight_steps). Found by the fuzzer (R = 124 m, g = -0.26 m/s^2).
    """
    part = Part(TRIANGLE_VERTICES)
    model = ThrowModel(part, -0.005, 20.0, -0.01)
    for edge in part.stable_edges:
        res = model.throw(edge, 4.2)
        T = res.flight_time
        assert T == pytest.approx(2 * 4.2 * 20.0 / 0.01, rel=1e-4)
        heights = vertex_heights(model, edge, 4.2, T)[:, 0]
        # The contact vertex is on the arm and no vertex is below it, to the time resolution
        # of t (4e-12 s, at a descent speed of 84 m/s: 3e-10 m).
        assert abs(heights[res.first_contact_vertex]) < 1e-8
        assert heights.min() > -1e-8
        assert math.isfinite(res.R) and model.part.stable[res.edge]


def test_regression_short_hop_is_not_rounded_to_an_ulp_of_d():
    """
    Regression: a short hop's flight time was set by rounding, not by the physics.

    F(t) was evaluated as d + R w t + ... + v cos(wt): with the hop height below an ulp of d
    (3.5e-18 m for the bracket) the sum was rounding noise, and for the bracket's edge 1 d + v
    itself is +3.5e-18 m, so the left vertex 'started above the arm' and fell 20 times longer
    than it flies (w = 1e-8 rad/s). The resting edge's vertices now start at exactly 0 and F
    is f0 plus terms that vanish at t = 0, so the time stays exact to an ulp.
    """
    scene = load_scene(str(SCENES / 'bracket.yaml'))
    part = scene.part
    assert part.d[1] + part.V[1, 1] > 0      # the rounding that used to bite
    for edge in part.stable_edges:
        R = 1.2 * scene.model.r_min(edge)
        for w in (1e-3, 1e-5, 1e-7, 1e-8, 1e-10):
            model = ThrowModel(part, scene.h, w, scene.gravity)
            res = model.throw(edge, R)
            # The left vertex flies a parabola to first order: 2 w (R + u_l) / |g + w^2 d|.
            hop = 2 * w * (R + part.u_l[edge]) / abs(scene.gravity + w * w * part.d[edge])
            if hop > 10 * model.accuracy.contact_time_tol:
                assert res.flight_time == pytest.approx(hop, rel=1e-9, abs=0), (edge, w)
            else:   # below the documented resolution: exact to contact_time_tol
                assert abs(res.flight_time - hop) <= model.accuracy.contact_time_tol
            assert res.first_contact_vertex == edge


def test_regression_a_1024_gon_settles_within_the_default_impact_cap():
    """
    Regression: a near-circular part hit max_impacts although nothing was wrong.

    A regular n-gon rolls like a wheel: each impact loses only ~(2 pi / n)^2 of its energy and
    the barriers are ~(pi / n)^2, so settling takes ~n^2 impacts (297,080 for the 1024-gon
    thrown from R_grasp at 320 deg/s). The old default cap of 100,000 made that a
    NumericalError; the impacts are cheap (~50 ns each), so the default is now 10^6.
    """
    part = Part(ngon(1024))
    model = ThrowModel(part, -0.5 * part.d_min, PAPER_W, G)
    assert model.accuracy.max_impacts == 1_000_000
    for factor in (1.0, 1.5, 2.0):
        res = model.throw(0, model.r_grasp[0] * factor)
        assert part.stable[res.edge] and math.isfinite(res.R) and res.kind == 'flip'
    capped = ThrowModel(part, -0.5 * part.d_min, PAPER_W, G,
                        accuracy=Accuracy(max_impacts=100_000))
    with pytest.raises(NumericalError) as err:
        capped.f(0, model.r_grasp[0])
    assert str(err.value) == ('catch after (0, 16.2974 m) did not settle within '
                              'accuracy.max_impacts = 100000 impacts; raise it')


def test_regression_rolling_ends_are_exact_with_the_cm_next_to_a_vertex():
    """
    Regression: with the CM 2e-13 m from a vertex the rolling ends were off by 3e-8 rad.

    The two ends of the rolling range about V^p (E^p flat, E^{p-1} flat) must differ by exactly
    the exterior angle at V^p, or the net rotation no longer maps resting poses onto each other.
    alpha_ccw_end used d^{p-1}, which is computed from V^{p-1}: its rounding (1e-16 of a 1 mm
    edge) is a large angle when |CM - V^p| is 1e-13 m. Found by the fuzzer (a pose error of
    1.3e-7 rad); both ends now come from V^p's own offset.
    """
    c, s = math.cos(0.3), math.sin(0.3)
    tri = np.array([[0.0, 0.0], [1e-3, 0.0], [0.2e-3, 0.9e-3]]) @ np.array([[c, s], [-s, c]])
    inward = (tri[1] - tri[0]) / np.linalg.norm(tri[1] - tri[0]) + tri[2] / np.linalg.norm(tri[2])
    part = Part(tri, cm=tri[0] + 2e-13 * inward / np.linalg.norm(inward),
                radius_of_gyration=3e-4)
    for p in range(part.n):
        exterior = part.rest_angle[p - 1] - part.rest_angle[p]
        ends = part.alpha_ccw_end[p] - part.alpha_cw_end[p]
        assert math.remainder(exterior - ends, 2 * math.pi) == pytest.approx(0, abs=1e-14)
    model = ThrowModel(part, -0.5 * part.d_min, 20.0, G)
    for edge in part.stable_edges:
        lo = model.r_min(edge)
        for R in lo * (1 + np.logspace(-6, 1, 15)):
            assert_valid(model, model.throw(edge, R))
