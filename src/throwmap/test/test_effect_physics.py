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
Effects checked against independent physics (issue 13).

The references are written apart from the library (reference_impact.py: Routh/Stronge in small
impulse steps; reference_plate.py: the plate drag of a lamina in closed form;
reference_carry.py: a dense wrench-cone scan of the finite carry). Nothing here compares the
library with its own earlier output.
"""

import copy
import math

import numpy as np
import pytest
from reference_impact import routh_impact, sticking_impulse
from throwmap import Scene
from throwmap.internal import routh_stronge_impact, sticking_impact
from throwmap_testing import SCENES, shipped_scene
import yaml


def triangle(**sections):
    # The paper's triangle on an endless arm: these tests compare effects with the base model.
    return shipped_scene('triangle', endless=True, **sections)


def routh(args, e, mu, steps):
    """Return the brute-force Routh integration's post-impact (vx, vy, omega)."""
    return np.array(routh_impact(*args, e, mu, steps=steps)[0])


def converges_to(got, args, e, mu, tol):
    """Tell whether brute force approaches ``got`` as the impulse step shrinks, to ``tol``."""
    weights = np.array([1.0, 1.0, math.sqrt(args[5])])     # omega as a speed rho * omega
    scale = abs(args[2]) + abs(args[3]) + math.sqrt(args[5]) * abs(args[4])
    coarse = (np.abs(routh(args, e, mu, 100_000) - got) * weights).max()
    fine = (np.abs(routh(args, e, mu, 4_000_000) - got) * weights).max()
    return fine < tol * scale and fine < 0.5 * coarse + 1e-12 * scale, (coarse, fine, scale)


def random_impact(rng):
    rx, ry = rng.uniform(-0.05, 0.05, 2)
    vx, vy = rng.uniform(-1, 1), rng.uniform(-2, -0.1)
    om, rho2 = rng.uniform(-8, 8), rng.uniform(1e-4, 2e-3)
    return rx, ry, vx, vy, om, rho2


def is_jam(args, mu):
    """Slipping at first with d u_n / dp <= 0: no normal impulse stops the approach."""
    rx, ry, vx, vy, om, rho2 = args
    ut = vx - om * ry
    ktn = -rx * ry / rho2
    knn = 1.0 + rx * rx / rho2
    return vy + om * rx < 0.0 and ut != 0.0 and knn - ktn * mu * math.copysign(1.0, ut) <= 0.0


# ------------------------------------------------------------------ item 1: the jam
def test_the_issues_jam_example_rebounds_as_routh_says():
    args = (-0.0346, 0.1329, 0.2258, -0.3526, -2.8129, 2.44e-4)
    assert is_jam(args, 2.0)
    got = routh_stronge_impact(*args, 0.3, 2.0)
    assert got[1] + got[2] * args[0] == pytest.approx(0.12250, abs=2e-5)   # the lead's figure
    ok, detail = converges_to(np.array(got), args, 0.3, 2.0, 2e-5)
    assert ok, detail


def test_jam_impacts_with_restitution_follow_routh_in_small_impulse_steps():
    rng = np.random.default_rng(13)
    jams = 0
    while jams < 40:
        args = random_impact(rng)
        e, mu = rng.uniform(0.05, 1.0), rng.uniform(0.3, 3.0)
        if not is_jam(args, mu):
            continue
        jams += 1
        got = np.array(routh_stronge_impact(*args, e, mu))
        ok, detail = converges_to(got, args, e, mu, 5e-5)
        assert ok, (args, e, mu, detail)
        # and it rebounds: with e > 0 the jam is not a plastic impact
        assert got[1] + got[2] * args[0] > 0.0


def test_jam_with_zero_restitution_is_the_sticking_impact():
    """A jam's slip dies out and the contact sticks: with e = 0 that is eqs 7-9 exactly."""
    rng = np.random.default_rng(14)
    jams = 0
    while jams < 40:
        args = random_impact(rng)
        mu = rng.uniform(0.3, 3.0)
        if not is_jam(args, mu):
            continue
        jams += 1
        got = routh_stronge_impact(*args, 0.0, mu)
        assert got == pytest.approx(sticking_impact(*args), rel=1e-9, abs=1e-12)


# ------------------------------------------------------------------ item 6: mu -> inf
def test_unbounded_friction_is_the_limit_of_routh_and_never_pulls():
    """
    Check mu = inf: Routh's method as mu -> inf, not eqs 7-9 where those would pull.

    Brute-force Routh with mu = 1e3, 1e4 converges to the library's mu = inf impact; eqs 7-9
    agree with it exactly where their normal impulse is >= 0, and where they need a pulling
    (negative) normal impulse the library and Routh do not pull.
    """
    rng = np.random.default_rng(6)
    pulling = pushing = 0
    while pulling < 6 or pushing < 6:
        args = random_impact(rng)
        rx, ry, vx, vy, om, rho2 = args
        if vy + om * rx >= 0.0:
            continue
        pn_sticking = sticking_impulse(*args)[1]
        if pn_sticking >= 0.0:
            if pushing >= 6:
                continue
            pushing += 1
        else:
            if pulling >= 6:
                continue
            pulling += 1
        got = np.array(routh_stronge_impact(*args, 0.0, math.inf))
        weights = np.array([1.0, 1.0, math.sqrt(rho2)])
        errs = [(np.abs(got - routh(args, 0.0, mu, int(1e4 * mu))) * weights).max()
                for mu in (1e3, 1e4)]
        scale = abs(vx) + abs(vy) + math.sqrt(rho2) * abs(om)
        assert errs[1] < 1e-3 * scale and errs[1] < max(0.5 * errs[0], 1e-4 * scale), errs
        assert got[1] - vy >= 0.0                                      # never pulls
        stick = np.array(sticking_impact(*args))
        if pn_sticking >= 0.0:
            assert got == pytest.approx(stick, rel=1e-10, abs=1e-12)
        else:
            assert (np.abs(got - stick) * weights).max() > 1e-3 * scale


# ------------------------------------------------------------------ item 2: re-contact
def test_restitution_to_zero_converges_to_the_sticking_model():
    """
    The issue's case: micro-bounces at x = 0.12671 must end in a plastic catch there.

    With bounce_threshold 0 every rebound is a bounce; as e -> 0 f must tend to the base
    (sticking) model's f(2, 0.15227) = (2, 0.16671, jog), for every e from 1e-2 down.
    """
    base = triangle().model
    ref = base.f(2, 0.15227)
    assert ref[0] == 2 and ref[2] == 'jog'
    errors = []
    for e in (1e-2, 1e-3, 1e-4, 1e-5, 1e-6):
        model = triangle(contact={'restitution': e, 'bounce_threshold': 0.0},
                         effects=['impact_restitution']).model
        got = model.f(2, 0.15227)
        assert got[0] == ref[0] and got[2] == ref[2], (e, got)
        errors.append(abs(got[1] - ref[1]))
        res = model.throw(2, 0.15227)
        assert abs(res.impacts[1].x - res.impacts[0].x) < 1e-6    # re-contact where it hit
    assert errors[-1] < 1e-9
    assert all(b <= a * 1.01 + 1e-12 for a, b in zip(errors, errors[1:]))


def test_restitution_to_zero_converges_over_many_states():
    base = triangle().model
    small = triangle(contact={'restitution': 1e-6, 'bounce_threshold': 0.0},
                     effects=['impact_restitution']).model
    rng = np.random.default_rng(2)
    edges = rng.choice(base.part.stable_edges, 200)
    radii = np.array([base.r_min(e) * 1.001 for e in edges]) + rng.uniform(0, 0.25, 200)
    ref = base.f_batch(edges, radii)
    got = small.f_batch(edges, radii)
    ok = got['status'] == 0
    assert ok.all()
    assert (got['edge'] == ref['edge']).mean() > 0.99
    same = got['edge'] == ref['edge']
    assert np.median(np.abs(got['R'] - ref['R'])[same]) < 1e-9


# ------------------------------------------------------------------ item 4: flat landing
def test_flat_landing_records_the_spin_it_lands_with():
    """
    Check the spin of a flat landing: in free flight (no body force) omega is constant.

    A flat landing after a bounce lands with the spin the bounce left, not the release speed.
    """
    model = triangle(contact={'restitution': 0.3, 'bounce_threshold': 0.0},
                     effects=['impact_restitution']).model
    rng = np.random.default_rng(0)
    checked = 0
    for _ in range(200):
        edge = int(rng.choice(model.part.stable_edges))
        R = float(model.r_min(edge) * 1.01 + rng.uniform(0, 0.25))
        res = model.throw(edge, R)
        for before, flat in zip(res.impacts, res.impacts[1:]):
            if flat.kind == 'flat_landing' and before.kind == 'bounce':
                checked += 1
                assert flat.omega_before == pytest.approx(before.omega_after, rel=1e-12,
                                                          abs=1e-15)
                assert abs(flat.omega_before) < 0.5 * model.w
    assert checked > 10


# ------------------------------------------------------------------ item 3: interval domain
def carry_scene(**carry):
    return triangle(contact={'mu': 0.5}, effects=['finite_carry'],
                    throw={'release_speed': 5.5851,
                           'carry': dict({'release_angle_deg': 20}, **carry)})


def test_finite_carry_domain_is_the_interval_a_dense_wrench_cone_scan_finds():
    """Triangle, carry 20 deg, mu 0.5: the grasp holds on a bounded interval of R per edge."""
    from reference_carry import carry_grasp_mask, mask_intervals
    model = carry_scene().model
    part = model.part
    radii = np.linspace(0.0005, 1.2, 24_000)
    step = radii[1] - radii[0]
    for i in part.stable_edges:
        mask = carry_grasp_mask(part.u_l[i], part.u_r[i], part.d[i], part.rho2, model.h,
                                model.g, 0.5, model.w, math.radians(20), radii,
                                time_samples=model.knobs.carry_samples)
        ref = mask_intervals(radii, mask)
        got = model.domain_intervals(i)
        assert len(ref) == len(got) == 1
        assert got[0][0] == pytest.approx(ref[0][0], abs=step)
        assert got[0][1] == pytest.approx(ref[0][1], abs=step)
        assert got[0][1] < 1.0                              # bounded above
        assert model.r_min(i) == got[0][0] and model.r_max(i) == got[0][1]
    # the lead's figures (cm): edge 0 [2.667, 78.377]
    assert model.domain_intervals(0)[0] == pytest.approx((0.02667, 0.78377), abs=2e-5)
    # every layer accepts a state f computes, and refuses one past the upper end; this one
    # is thrown back behind the pivot (edge 1, R -5.9 cm), outside the domain: lost there
    # (issue 21 item 3), not a state the next throw would refuse
    assert model.domain_error(0, 0.405) is None
    assert model.f(0, 0.405)[:3:2] == (-1, 'lost')
    assert 'on edge 1 at R = -0.0591' in model.throw(0, 0.405).lost_reason
    edges, radii = model.orbits([0], [0.405], 1)[:2]
    assert edges[0, 1] == -1
    assert model.f(0, 0.2)[0] == 2 and model.domain_error(*model.f(0, 0.2)[:2]) is None
    err = model.domain_error(0, 0.9)
    assert err is not None and err.condition == 'carry_grasp' and '0.783' in str(err)
    with pytest.raises(ValueError, match='carry'):
        model.f(0, 0.9)


def test_grids_and_starts_stay_inside_a_bounded_domain():
    from throwmap import default_grid
    model = carry_scene().model
    edges, radii = default_grid(model, radii_per_edge=20, r_max=5.0)
    assert all(model.domain_error(int(e), float(r)) is None for e, r in zip(edges, radii))
    edge = 1
    R = model.start_radius(edge)
    assert model.r_min(edge) < R < model.r_max(edge)


def test_scenes_without_finite_carry_keep_the_half_line_domain():
    model = triangle().model
    for i in model.part.stable_edges:
        lo = max(model.r_grasp[i], -model.part.u_l[i])
        assert model.domain_intervals(i) == [(lo, math.inf)]
        assert model.r_min(i) == lo and model.r_max(i) == math.inf


# ------------------------------------------------------------------ item 7: extreme regimes
def test_a_plate_whose_drag_can_hold_the_part_is_refused_at_load():
    """
    Refuse mu_p cot(inclination) >= 1: Coulomb drag >= in-plane gravity.

    The part would stop in mid-air; the model cannot represent it and says so, naming the field
    and the fix.
    """
    from throwmap import InputError
    with open(SCENES / 'experiment.yaml', encoding='utf-8') as fh:
        data = yaml.safe_load(fh)
    tan80 = math.tan(math.radians(80))
    data['plate']['mu'] = 2.2 * tan80
    with pytest.raises(InputError, match=r'plate\.mu.*2\.2 >= 1.*mid-air.*tan\(inclination\)'):
        Scene(copy.deepcopy(data)).model
    data['plate']['mu'] = 0.99 * tan80
    model = Scene(copy.deepcopy(data)).model
    assert model.f(1, 0.12)[2] in ('jog', 'flip')


def test_loading_a_carry_scene_does_not_simulate_its_domain():
    """
    Find the carry's grasp domain without throwing (the wrench is affine in R).

    Only the returning arm costs throws: at most STRIKE_SCAN per edge plus a bisection.
    """
    from throwmap.effects import finite_carry
    general = triangle(contact={'mu': 0.5, 'restitution': 0.0},
                       effects=['finite_carry', 'impact_restitution'],
                       throw={'release_speed': 5.5851,
                              'carry': {'release_angle_deg': 20, 'return_time': 0.03}}).model
    for model, cap in ((carry_scene(return_time=0.03).model, finite_carry.STRIKE_SCAN),
                       (general, finite_carry.STRIKE_SCAN_GENERAL)):
        calls = []
        original = model.nominal_status

        def counting(edges, radii, original=original, calls=calls):
            calls.append(len(edges))
            return original(edges, radii)
        model.nominal_status = counting
        params = [p for n, _, p in model.effects.modules() if n == 'finite_carry'][0]
        finite_carry.domain(model, params)
        assert sum(calls) / len(model.part.stable_edges) <= cap + 40


# ------------------------------------------------------------------ item 5: the plate drag
@pytest.mark.parametrize('vertices', [
    [[0.06, 0.0], [0.06, 0.08], [0.0, 0.0]],
    [[0.0, 0.0], [0.05, 0.0], [0.05, 0.02], [0.02, 0.02], [0.02, 0.05], [0.0, 0.05]],
])
def test_plate_drag_is_the_exact_drag_of_a_uniform_lamina(vertices):
    """
    Check the default drag (plate_quadrature 0, closed form) against the reference.

    The reference is written apart (and checked against 4M-point sampling); they agree to
    rounding at random states. The quadrature it replaced was off by up to 7 % of mu_p g_n.
    """
    from reference_plate import plate_drag_exact as reference
    from throwmap import Part
    from throwmap.internal import plate_drag_exact, plate_moments
    part = Part(np.array(vertices, dtype=float))
    ou, ov, cu, cv = part.outline_frames()
    size = float(part.vertex_radius.max())
    mom = plate_moments(ou, ov, size)
    rng = np.random.default_rng(5)
    for _ in range(300):
        edge = int(rng.integers(part.n))
        phi = rng.uniform(-3, 3)
        vx, vy = rng.uniform(-1, 1, 2)
        # |omega| >= 1 rad/s: the instantaneous centre within a metre (far out, both closed
        # forms lose digits to cancellation: about 1e-7 at 200 m); 10 % pure translation
        om = math.copysign(rng.uniform(1, 20), rng.uniform(-1, 1)) if rng.uniform() < 0.9 else 0.0
        got = plate_drag_exact(vx, vy, om, phi, ou[edge], ov[edge], cu[edge], cv[edge], size,
                               mom[edge], 1.0, 0.0)
        c, s = math.cos(phi), math.sin(phi)
        outline = np.stack([c * ou[edge] - s * ov[edge], s * ou[edge] + c * ov[edge]], axis=1)
        ref = reference(outline, [0.0, 0.0], vx, vy, om, 1.0)
        assert got == pytest.approx(ref, abs=1e-9)
    # rolling about a vertex (the instantaneous centre on the outline): torque about P is
    # -sign(omega) <|r - P|>, finite although P lies on two edges' lines
    k = 0
    px, py = ou[1][k], ov[1][k]
    om = 3.0
    got = plate_drag_exact(om * py, -om * px, om, 0.0, ou[1], ov[1], cu[1], cv[1], size,
                           mom[1], 1.0, 0.0)
    ref = reference(np.stack([ou[1], ov[1]], axis=1), [0.0, 0.0], om * py, -om * px, om, 1.0)
    assert np.all(np.isfinite(got)) and got == pytest.approx(ref, abs=1e-9)


def test_plate_drag_creeps_while_the_fastest_point_is_slower_than_v_reg():
    """
    Check the exact drag's creep near rest, state by state.

    The drag is scaled by (the fastest outline point's speed) / v_reg while that is below 1,
    and only then: the scale checked against the outline's speeds at slow states.
    """
    from throwmap import Part
    from throwmap.internal import plate_drag_exact, plate_moments
    part = Part(np.array([[0.06, 0.0], [0.06, 0.08], [0.0, 0.0]]))
    ou, ov, cu, cv = part.outline_frames()
    size = float(part.vertex_radius.max())
    mom = plate_moments(ou, ov, size)
    v_reg = 1e-4
    rng = np.random.default_rng(11)
    scaled = 0
    for _ in range(400):
        phi = rng.uniform(-3, 3)
        vx, vy = rng.uniform(-1e-4, 1e-4, 2)
        om = rng.uniform(-2e-3, 2e-3) if rng.uniform() < 0.8 else 0.0
        c, s = math.cos(phi), math.sin(phi)
        bx, by = c * vx + s * vy, -s * vx + c * vy
        fastest = np.max(np.hypot(bx - om * ov[0], by + om * ou[0]))
        got = plate_drag_exact(vx, vy, om, phi, ou[0], ov[0], cu[0], cv[0], size, mom[0], 1.0,
                               v_reg)
        whole = plate_drag_exact(vx, vy, om, phi, ou[0], ov[0], cu[0], cv[0], size, mom[0],
                                 1.0, 0.0)
        scale = min(1.0, fastest / v_reg)
        scaled += scale < 1.0
        assert got == pytest.approx(tuple(scale * w for w in whole), rel=1e-9, abs=1e-15)
    assert 50 < scaled < 350
    # at rest, with and without the creep: no drag (not 0 / 0)
    for v_reg in (1e-4, 0.0):
        assert plate_drag_exact(0.0, 0.0, 0.0, 0.3, ou[0], ov[0], cu[0], cv[0], size, mom[0],
                                1.0, v_reg) == (0.0, 0.0, 0.0)


# a triangle and an L (non-convex): the parts on which the drag's bend at an edge is measured
CROSSING_PARTS = [
    [[0.06, 0.0], [0.06, 0.08], [0.0, 0.0]],
    [[0.0, 0.0], [0.05, 0.0], [0.05, 0.02], [0.02, 0.02], [0.02, 0.05], [0.0, 0.05]],
]


def drag_about_centre(vertices, om=5.0):
    """
    Return the outline (edge frame 0), size, 2 ln(10) / A, and the drag and log part at a centre.

    drag(p0): plate_drag_exact (coef 1, no creep) of the part turning at om about the
    instantaneous centre p0; log_part(p0, k): crossing_log_coefficient of edge k there.
    """
    from throwmap import Part
    from throwmap.internal import crossing_log_coefficient, plate_drag_exact, plate_moments
    part = Part(np.array(vertices, dtype=float))
    ou, ov, cu, cv = part.outline_frames()
    size = float(part.vertex_radius.max())
    mom = plate_moments(ou, ov, size)

    def velocity(p0):
        # the centre p0 = z x v / om: v = om (p0y, -p0x)
        return om * p0[1], -om * p0[0], om, 0.0

    def drag(p0):
        return np.array(plate_drag_exact(*velocity(p0), ou[0], ov[0], cu[0], cv[0], size,
                                         mom[0], 1.0, 0.0))

    def log_part(p0, k):
        return np.array(crossing_log_coefficient(*velocity(p0), ou[0], ov[0], 1.0, k))

    return ou[0], ov[0], size, 2.0 * math.log(10.0) / part.area, drag, log_part


@pytest.mark.parametrize('vertices', CROSSING_PARTS)
def test_plate_drag_bends_as_d2_log_d_where_the_centre_crosses_an_edge(vertices):
    """
    Check the drag's kink where the instantaneous centre crosses an outline edge.

    The drag is the gradient, turned by 90 degrees, of the potential int |r - c| dA / A (c the
    centre): at distance d from an edge the gradient's normal part bends as d^2 log|d| / A, so
    the force along the edge has the second derivative 2 log|d| / A + smooth (it changes by
    2 ln(10) / A per decade of d) and the force across it is smooth. This is why the series
    flight's error falls as the cube of its pieces' length (docs/accuracy.md).
    """
    ou, ov, size, per_decade, drag, _ = drag_about_centre(vertices)
    for j in range(len(ou)):
        jn = (j + 1) % len(ou)
        t = np.array([ou[jn] - ou[j], ov[jn] - ov[j]])
        t /= np.hypot(*t)
        n = np.array([-t[1], t[0]])
        mid = 0.5 * np.array([ou[j] + ou[jn], ov[j] + ov[jn]])
        for side in (1.0, -1.0):
            bend = []
            for d in (1e-4 * size, 1e-5 * size):
                h = d / 20.0
                f2 = (drag(mid + side * (d + h) * n) - 2.0 * drag(mid + side * d * n)
                      + drag(mid + side * (d - h) * n))[:2] / (h * h)
                bend.append(f2)
            change = bend[1] - bend[0]
            assert abs(change @ t) == pytest.approx(per_decade, rel=0.01), (j, side)
            assert abs(change @ n) < 0.01 * per_decade, (j, side)


@pytest.mark.parametrize('vertices', CROSSING_PARTS)
def test_the_drag_less_its_log_part_is_smooth_where_the_centre_crosses_an_edge(vertices):
    """
    Check crossing_log_coefficient: the drag less B ln|d| does not bend as d^2 ln|d|.

    The test above measures the bend of the force along the edge: 2 ln(10) / A per decade of
    d. With B ln|d| subtracted (B at the same centre) the second derivative of the force and
    of the torque changes by under 1 % of that between d = 1e-4 and 1e-5 of the part's size,
    on both sides of every edge, at its middle and a quarter along; with half of B subtracted
    half the bend is left (so the check can fail).
    """
    ou, ov, size, per_decade, drag, log_part = drag_about_centre(vertices)
    n_edges = len(ou)
    scale = np.array([1.0, 1.0, 1.0 / size])        # the torque per unit length
    for share, bends in ((1.0, False), (0.5, True)):
        for k in range(n_edges):
            kn = (k + 1) % n_edges
            a = np.array([ou[k], ov[k]])
            e = np.array([ou[kn], ov[kn]]) - a
            n = np.array([-e[1], e[0]]) / np.hypot(*e)
            for along in (0.5, 0.25):
                for side in (1.0, -1.0):
                    change = []
                    for d in (1e-4 * size, 1e-5 * size):
                        h = d / 20.0
                        at = []
                        for x in (d + h, d, d - h):
                            p0 = a + along * e + side * x * n
                            at.append(drag(p0) - share * log_part(p0, k) * math.log(x))
                        change.append((at[0] - 2.0 * at[1] + at[2]) / (h * h))
                    step = np.abs(change[1] - change[0])
                    if bends:
                        assert np.hypot(*step[:2]) > 0.4 * per_decade, (k, along, side)
                    else:
                        assert np.all(step * scale < 0.01 * per_decade), (k, along, side, step)


def test_the_experiment_scene_uses_the_exact_drag():
    with open(SCENES / 'experiment.yaml', encoding='utf-8') as fh:
        data = yaml.safe_load(fh)
    model = Scene(data).model
    assert model.knobs.plate_quadrature == 0 and model.prm.backplate_friction.exact
