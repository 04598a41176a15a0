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

"""Physical laws the throw map must obey, over the paper's triangle and random parts."""

import math

import numpy as np
import pytest
from throwmap import in_dynamic_grasp, Part, ThrowModel
from throwmap.internal import sticking_impact
from throwmap_testing import PAPER_W, random_convex_vertices, random_state, TRIANGLE_VERTICES


def _random_models(count, seed):
    rng = np.random.default_rng(seed)
    models = []
    while len(models) < count:
        part = Part(random_convex_vertices(rng))
        h = -rng.uniform(0.05, 0.95) * part.d_min
        w = rng.uniform(1.0, 12.0)
        g = -rng.uniform(2.0, 12.0)
        models.append((ThrowModel(part, h, w, g), rng))
    return models


def _throws(count=400, seed=1):
    for model, rng in _random_models(count // 10, seed):
        for _ in range(10):
            edge, R = random_state(model, rng)
            yield model, model.throw(edge, R)


def test_energy_conserved_in_flight_and_rolling_and_never_gained_at_impacts():
    checked = 0
    for model, res in _throws():
        scale = res.release_energy
        # Flight: the energy just before the first impact equals the energy at release.
        assert res.impacts[0].energy_before == pytest.approx(res.release_energy, rel=1e-9)
        for imp in res.impacts:
            assert imp.energy_after <= imp.energy_before + 1e-12 * scale
        # Rolling between impacts is conservative: what one impact leaves, the next one meets.
        for a, b in zip(res.impacts, res.impacts[1:]):
            if b.kind == 'landing':
                assert b.energy_before == pytest.approx(a.energy_after, rel=1e-9, abs=1e-12)
        checked += len(res.impacts)
    assert checked > 400


def test_settled_edge_is_stable_and_jog_flip_agrees_with_rotation():
    kinds = set()
    for model, res in _throws(seed=2):
        part = model.part
        assert part.stable[res.edge]
        # Net rotation takes the resting pose on edge0 to the resting pose on edge.
        diff = part.rest_angle[res.edge] - part.rest_angle[res.edge0] - res.net_rotation
        assert math.remainder(diff, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
        if res.kind == 'jog':
            assert res.edge == res.edge0 and abs(res.net_rotation) < 1e-9
        else:
            assert res.edge != res.edge0 or abs(res.net_rotation) > math.pi
        kinds.add(res.kind)
    assert kinds == {'jog', 'flip'}


def test_resting_pose_after_a_catch_lies_on_the_arm():
    for model, res in _throws(count=100, seed=3):
        verts = model.part.pose_vertices(res.edge, res.R, model.h)
        assert verts[:, 1].min() == pytest.approx(model.h, abs=1e-15)
        assert np.all(verts[:, 1] >= model.h - 1e-15)
        # The resting edge's two vertices are the ones on the arm.
        on_arm = np.flatnonzero(np.abs(verts[:, 1] - model.h) < 1e-12)
        assert set(on_arm) >= {res.edge, (res.edge + 1) % model.part.n}


@pytest.mark.parametrize('h', [-0.004, -0.002, 0.002, 0.004])
def test_small_release_speed_jog_shift_matches_first_order_estimate(h):
    """
    Check the first-order jog shift -h w T of Prop. IV.4.

    The left vertex starts with x velocity -h w, so a short hop shifts the part by about
    -h w T: outward for h < 0, inward for h > 0.
    """
    part = Part(TRIANGLE_VERTICES)
    errors = []
    for w in (0.4, 0.2, 0.1):
        model = ThrowModel(part, h, w, -9.66) if h < 0 else _quiet_model(part, h, w)
        R = 0.10
        res = model.throw(1, R)
        assert res.kind == 'jog'
        estimate = -h * w * res.flight_time
        shift = res.R - R
        assert math.copysign(1, shift) == math.copysign(1, -h)
        errors.append(abs(shift - estimate) / abs(estimate))
    # First order: the relative error shrinks with w (roughly in proportion).
    assert errors[-1] < 0.05
    assert errors[0] > errors[1] > errors[2]


def _quiet_model(part, h, w, g=-9.66, **kw):
    with pytest.warns(UserWarning, match='outside Proposition IV.4'):
        return ThrowModel(part, h, w, g, **kw)


def test_sticking_impact_law_and_sweet_spot():
    rng = np.random.default_rng(5)
    for _ in range(200):
        rx, ry = rng.uniform(-0.05, 0.05, 2)
        vx, vy, om = rng.uniform(-2, 2, 3)
        rho2 = rng.uniform(1e-4, 3e-3)
        vx1, vy1, om1 = sticking_impact(rx, ry, vx, vy, om, rho2)
        # The contact vertex stops (eqs 7, 8) ...
        assert vx1 - om1 * ry == pytest.approx(0, abs=1e-12)
        assert vy1 + om1 * rx == pytest.approx(0, abs=1e-12)
        # ... the impulse acts through it: angular momentum about it is conserved (eq 9) ...
        lp_before = rho2 * om - (rx * vy - ry * vx)
        lp_after = rho2 * om1 - (rx * vy1 - ry * vx1)
        assert lp_after == pytest.approx(lp_before, abs=1e-12)
        # ... and kinetic energy never grows.
        ke0 = 0.5 * (vx * vx + vy * vy + rho2 * om * om)
        ke1 = 0.5 * (vx1 * vx1 + vy1 * vy1 + rho2 * om1 * om1)
        assert ke1 <= ke0 + 1e-15
        # Sweet spot: with rho^2 omega = r x v the impulse only removes the velocity.
        om_s = (rx * vy - ry * vx) / rho2
        assert sticking_impact(rx, ry, vx, vy, om_s, rho2) == pytest.approx((0, 0, 0),
                                                                            abs=1e-12)


def test_sweet_spot_catch_in_a_throw_leaves_zero_velocity():
    """Find R where the post-impact spin of the first impact changes sign: a sweet-spot catch."""
    model = ThrowModel(Part(TRIANGLE_VERTICES), -0.005, PAPER_W, -9.66)

    def spin(R):
        return model.throw(1, R).impacts[0].omega_after

    rs = np.linspace(0.06, 0.25, 400)
    values = [spin(R) for R in rs]
    crossings = [k for k in range(len(rs) - 1) if values[k] * values[k + 1] < 0
                 and model.throw(1, rs[k]).first_contact_vertex
                 == model.throw(1, rs[k + 1]).first_contact_vertex]
    assert crossings, 'expected a sweet-spot radius on edge 1'
    k = crossings[0]
    a, b = rs[k], rs[k + 1]
    for _ in range(80):
        m = 0.5 * (a + b)
        if spin(a) * spin(m) <= 0:
            b = m
        else:
            a = m
    res = model.throw(1, 0.5 * (a + b))
    first = res.impacts[0]
    assert abs(first.omega_after) < 1e-6 * abs(first.omega_before)
    # Nothing but potential energy is left after a sweet-spot catch.
    part = model.part
    l_k = part.vertex_radius[res.first_contact_vertex]
    ke_after = 0.5 * (part.rho2 + l_k ** 2) * first.omega_after ** 2
    assert ke_after < 1e-10 * first.energy_before


def test_jog_fixed_point_is_unstable_prop_iv1():
    """With h > 0 jogs first move inward, later outward: the fixed point between is unstable."""
    part = Part(TRIANGLE_VERTICES)
    model = _quiet_model(part, 0.003, 2.0, settle_rule='first_stable')
    rs = np.linspace(0.06, 0.5, 600)
    res = model.f_batch(np.full(rs.size, 1), rs)
    jog = res['kind'] == 'jog'
    shift = res['R'] - rs
    sign_changes = [k for k in range(rs.size - 1) if jog[k] and jog[k + 1]
                    and shift[k] * shift[k + 1] < 0]
    assert sign_changes, 'expected a jog fixed point for h > 0'
    for k in sign_changes:
        # Prop IV.1: d(R1 - R)/dR > 0 at the fixed point, i.e. f'(R*) > 1: unstable.
        assert shift[k] < 0 < shift[k + 1]
        a, b = rs[k], rs[k + 1]
        for _ in range(60):
            m = 0.5 * (a + b)
            if model.f(1, m)[1] - m < 0:
                a = m
            else:
                b = m
        r_star = 0.5 * (a + b)
        slope = (model.f(1, r_star + 1e-6)[1] - model.f(1, r_star - 1e-6)[1]) / 2e-6
        assert slope > 1.0
        for eps in (1e-4, -1e-4):
            # Deviations grow at every jog, on either side of R*.
            R, dev = r_star + eps, abs(eps)
            for _ in range(5):
                R = model.f(1, R)[1]
                assert abs(R - r_star) > dev
                dev = abs(R - r_star)


def test_impulse_cone_agrees_with_the_general_wrench_cone():
    """An impulsive throw is the limit of a huge angular acceleration from rest at theta=0."""
    part = Part(TRIANGLE_VERTICES)
    h, mu = -0.005, 0.5
    model = ThrowModel(part, h, PAPER_W, -9.66, mu=mu)
    for edge in part.stable_edges:
        r_grasp = model.grasp[edge].R_grasp
        for R in (0.9 * r_grasp, 0.99 * r_grasp, 1.01 * r_grasp, 2 * r_grasp):
            inside = in_dynamic_grasp(part, edge, R, h, -9.66, mu, 0.0, 0.0, 1e9)
            assert inside == (R >= r_grasp), (edge, R, r_grasp)


def test_gravity_alone_is_held_and_pulling_away_is_not():
    part = Part(TRIANGLE_VERTICES)
    for edge in part.stable_edges:
        assert in_dynamic_grasp(part, edge, 0.1, -0.005, -9.66, 0.5, 0.0, 0.0, 0.0)
        # An arm accelerating down faster than gravity loses the part (Example III.2).
        assert not in_dynamic_grasp(part, edge, 0.1, -0.005, -9.66, 0.5, 0.0, 0.0, -200.0)


def test_determinism_and_batch_equals_single():
    model = ThrowModel(Part(TRIANGLE_VERTICES), -0.005, PAPER_W, -9.66)
    rng = np.random.default_rng(9)
    states = [random_state(model, rng) for _ in range(300)]
    edges = np.array([s[0] for s in states])
    radii = np.array([s[1] for s in states])
    batch = model.f_batch(edges, radii)
    again = model.f_batch(edges, radii)
    assert np.array_equal(batch['R'], again['R'])
    for k, (e, r) in enumerate(states):
        e1, r1, kind = model.f(e, r)
        assert (e1, r1, kind) == (batch['edge'][k], batch['R'][k], batch['kind'][k])
