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

import math
import pathlib

import numpy as np
import pytest
from throwmap import (Accuracy, DomainError, load_scene, NumericalError, orbit, Part,
                      ThrowModel)
from throwmap.cli import main
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
    """The discrete outcome of a throw: first contact, every event, and the final edge."""
    return (res.first_contact_vertex, tuple((i.kind, i.vertex, i.edge) for i in res.impacts),
            res.edge)


def assert_valid(model, res):
    """Invariants every throw must satisfy, whatever the case.

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
    return ThrowModel(Part(TRIANGLE_VERTICES), h, w, G, **kw)


def graze_state(model, edge, k, t, R):
    """(t*, R*, F''): vertex k's height has a double root, F = F' = 0 at t*, when thrown at R*.

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
    from throwmap import load_scene
    from throwmap_testing import SCENES
    scene = load_scene(str(SCENES / 'bracket.yaml'))
    part = scene.part
    assert part.d[1] + part.V[1, 1] > 0      # the rounding that used to bite
    for edge in part.stable_edges:
        R = 1.2 * max(scene.model.r_grasp[edge], -part.u_l[edge])
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


def ngon(n, radius=0.05):
    """A regular n-gon around the origin with one edge flat at the bottom (edge 0)."""
    angles = 2 * np.pi * np.arange(n) / n - np.pi / 2 - np.pi / n
    return radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)


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
        edge, R, kind = model.f(0, model.r_grasp[0] * factor)
        assert part.stable[edge] and math.isfinite(R) and kind == 'flip'
    capped = ThrowModel(part, -0.5 * part.d_min, PAPER_W, G,
                        accuracy=Accuracy(max_impacts=100_000))
    with pytest.raises(NumericalError) as err:
        capped.f(0, model.r_grasp[0])
    assert str(err.value) == ('catch after (0, 16.2974 m) did not settle within '
                              'accuracy.max_impacts = 100000 impacts; raise it')
