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
The pivot's normal force (issue 12) and effect liftoff.

The closed form of throwmap.catch against a hand computation and a Newton-Euler integration of
the rolling part (scipy); effect liftoff: bit-identical to the base model where every roll stays
in the friction cone, energy never gained through a slip or a hop, and its parameters and
conflicts.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from throwmap import InputError, Scene, ThrowmapError
from throwmap.catch import (pivot_normal, records_min_normal, roll_cone_forces, roll_liftoff,
                            roll_min_normal)
from throwmap.effects.liftoff import roll_cone_exit
from throwmap.status import REC_COLS
from throwmap_testing import PAPER_W, TRIANGLE_VERTICES

G = 9.66


def scene(effects=(), **sections):
    data = {'name': 't', 'part': {'vertices': TRIANGLE_VERTICES}, 'arm': {'offset': -0.005},
            'throw': {'release_speed': PAPER_W}, 'gravity': -G, 'effects': list(effects)}
    data.update(sections)
    return Scene(data)


def test_hand_computed_case_centripetal_demand_beyond_gravity():
    # CM straight above the pivot (alpha = 90 deg): gravity has no torque, so the only vertical
    # acceleration of the CM is centripetal, -l omega^2: N = g - l omega^2 (by hand). At
    # omega = 15 rad/s, l = 5 cm: N = 9.66 - 11.25 = -1.59 m/s^2, a pull.
    lp, rho2, omega = 0.05, 0.0011, 15.0
    inertia = rho2 + lp * lp
    k = omega * omega + 2.0 * G * lp * 1.0 / inertia
    assert pivot_normal(1.0, k, lp, inertia, G) == pytest.approx(G - lp * omega ** 2, rel=1e-12)
    assert pivot_normal(1.0, k, lp, inertia, G) == pytest.approx(-1.59, abs=1e-12)
    # CM level with the pivot (alpha = 0): the centripetal force is horizontal; N carries
    # gravity less the CM's fall, g - g l^2 / I (the pendulum's angular acceleration g l / I).
    assert pivot_normal(0.0, k, lp, inertia, G) == pytest.approx(G * rho2 / inertia, rel=1e-12)
    # A roll from alpha = 0.1 rad that passes the top at that speed: by energy it starts at
    # omega0^2 = 15^2 + 2 g l (1 - sin 0.1) / I. N(s) = 2.952 + 20.12 s^2 - 24.67 s falls to
    # zero at s = 0.1344 (the smaller root): there it lifts off, long before the top.
    omega0 = math.sqrt(omega ** 2 + 2.0 * G * lp * (1.0 - math.sin(0.1)) / inertia)
    assert pivot_normal(math.sin(0.1), k, lp, inertia, G) > 0.0
    a_lift, w_lift = roll_liftoff(0.1, omega0, 2.0, lp, rho2, G)
    a2, c1, c0 = 3 * G * lp * lp / inertia, lp * k, G * rho2 / inertia
    # The parabola's vertex s = l K / (2 a2) = 0.613 lies on the roll: N there is the minimum.
    assert c1 / (2 * a2) == pytest.approx(0.613, abs=1e-3)
    assert roll_min_normal(0.1, omega0, 2.0, lp, rho2, G) == pytest.approx(
        c0 - c1 * c1 / (4 * a2), rel=1e-12)
    s_root = (c1 - math.sqrt(c1 * c1 - 4 * a2 * c0)) / (2 * a2)
    assert s_root == pytest.approx(0.1344, abs=1e-4)
    assert a_lift == pytest.approx(math.asin(s_root), rel=1e-12)
    assert w_lift == pytest.approx(math.sqrt(k - 2 * G * lp * s_root / inertia), rel=1e-12)
    # Slowly, the arm pushes throughout.
    assert roll_min_normal(1.2, 2.0, 2.0, lp, rho2, G) > 0.0
    assert math.isnan(roll_liftoff(1.2, 2.0, 2.0, lp, rho2, G)[0])


def newton_euler(alpha, omega, lp, rho2, ends):
    """Integrate the pinned roll to either end; return sampled (alpha, omega, N, Ft)."""
    inertia = rho2 + lp * lp

    def rhs(t, y):
        return [y[1], -G * lp * math.cos(y[0]) / inertia]
    events = [lambda t, y, e=e: y[0] - e for e in ends]
    for ev in events:
        ev.terminal = True
    sol = solve_ivp(rhs, (0.0, 5.0), [alpha, omega], rtol=1e-12, atol=1e-13,
                    dense_output=True, events=events)
    ts = np.linspace(0.0, sol.t[-1], 100_001)
    a, w = sol.sol(ts)
    acc = -G * lp * np.cos(a) / inertia
    # Newton: the CM at P + l (cos a, sin a); the arm's force = m a_cm - m g.
    n = G + lp * (np.cos(a) * acc - np.sin(a) * w * w)
    ft = lp * (-np.sin(a) * acc - np.cos(a) * w * w)
    end = ends[int(np.argmin([abs(sol.y[0, -1] - e) for e in ends]))]
    return a, w, n, ft, end


@pytest.mark.parametrize('seed', range(6))
def test_closed_form_against_newton_euler(seed):
    rng = np.random.default_rng(seed)
    for _ in range(8):
        lp = rng.uniform(0.01, 0.08)
        rho2 = rng.uniform(0.2, 1.5) * lp * lp
        ends = sorted(rng.uniform(0.05, 3.0, 2))
        if ends[1] - ends[0] < 0.3:
            continue
        alpha = rng.uniform(ends[0] + 0.05, ends[1] - 0.05)
        omega = rng.normal(0.0, 2.5) * math.sqrt(G / lp)
        a, w, n, ft, end = newton_euler(alpha, omega, lp, rho2, ends)
        scale = G + lp * omega * omega
        assert roll_min_normal(alpha, omega, end, lp, rho2, G) == pytest.approx(
            n.min(), abs=1e-6 * scale)
        inertia = rho2 + lp * lp
        k = omega * omega + 2 * G * lp * math.sin(alpha) / inertia
        i = len(a) // 3
        n_i, ft_i, _, _ = roll_cone_forces(a[i], k, lp, inertia, G)
        assert (n_i, ft_i) == pytest.approx((n[i], ft[i]), abs=1e-6 * scale)
        a_lift, w_lift = roll_liftoff(alpha, omega, end, lp, rho2, G)
        if n.min() < -1e-6 * scale:
            first = int(np.argmax(n < 0.0))
            assert a_lift == pytest.approx(a[first], abs=2e-4)
            assert w_lift == pytest.approx(w[first], abs=2e-4 * abs(w).max())
            # The cone with mu = inf is N >= 0: the same point.
            assert roll_cone_exit(alpha, omega, end, lp, rho2, G, math.inf)[0] == \
                pytest.approx(a_lift, abs=1e-9)
            # A finite mu leaves the cone earlier (|Ft| > mu N before N reaches zero).
            a_mu = roll_cone_exit(alpha, omega, end, lp, rho2, G, 1.0)[0]
            first_mu = int(np.argmax((n < 0.0) | (np.abs(ft) > n)))
            assert a_mu == pytest.approx(a[first_mu], abs=2e-4)
        elif n.min() > 1e-6 * scale:
            assert math.isnan(a_lift)


def test_throw_result_carries_the_smallest_normal_force():
    model = scene().model
    e, r, _ = model.orbit_arrays(1, 0.12, 60)
    lows = []
    for edge, R in zip(e[:-1], r[:-1]):
        res = model.throw(int(edge), float(R))
        rec = np.empty((256, REC_COLS))
        nrec = model._throw(int(edge), float(R), (0.0, 0.0), rec).records
        part = model.part.arrays
        assert res.min_normal_force == records_min_normal(rec, nrec, part.vrad, part.rho2, G)
        assert res.needs_pull == (res.min_normal_force < 0.0)
        lows.append(res.min_normal_force)
    lows = np.array(lows)
    # The paper's triangle on its own limit set: some throws push throughout, some need a pull.
    assert (lows < 0).any() and (lows > 0).any()
    assert res.as_dict()['min_normal_force'] == res.min_normal_force


def states(model, count, seed=0):
    rng = np.random.default_rng(seed)
    edges = rng.choice(model.part.stable_edges, count)
    radii = np.array([model.r_min(x) * 1.01 for x in edges]) + rng.uniform(0, 0.2, count)
    return edges, radii


def flight_impact_normal_impulse(model, knobs, edge, R):
    """Return the normal impulse of the base model's sticking impact ending the flight."""
    from throwmap.ballistic import first_contact, state_at
    from throwmap.catch import sticking_impact
    from throwmap.pipeline import release_state
    part = model.part.arrays
    x0, y0, phi0, vx, vy, om = release_state(edge, R, model.w, model.h, part.d)
    _, t, k = first_contact(edge, y0, phi0, vy, om, model.g, part, knobs)
    rx, ry, _, xdot, ydot, _, _ = state_at(t, edge, k, x0, y0, phi0, vx, vy, om, model.g, part)
    return sticking_impact(rx, ry, xdot, ydot, om, part.rho2)[1] - ydot


def test_liftoff_is_the_base_model_bit_for_bit_where_the_arm_pushes():
    base = scene().model
    lift = scene(['liftoff']).model      # mu 1000: slip starts where N falls to |Ft| / 1000
    edges, radii = states(base, 300)
    rb = base.f_batch(edges, radii)
    rl = lift.f_batch(edges, radii)
    low = np.array([base.throw(int(e), float(r)).min_normal_force for e, r in zip(edges, radii)])
    # |Ft| < 100 m/s^2 on these rolls: inside the cone throughout; and the impact at the end of
    # the flight pushes (a grazing one can need a pulling impulse to stick, 2 of these 300:
    # liftoff's impact does not pull there, issue 24)
    pn = np.array([flight_impact_normal_impulse(base, lift.ctx.knobs, int(e), float(r))
                   for e, r in zip(edges, radii)])
    push = (low > 0.1) & (pn >= 0.0)
    assert push.sum() > 50 and (~push).sum() > 20 and ((low > 0.1) & (pn < 0.0)).sum() <= 5
    assert np.all(rb['R'][(low > 0.1) & (pn < 0.0)] != rl['R'][(low > 0.1) & (pn < 0.0)])
    for key in ('edge', 'R', 'net_rotation', 'status'):
        np.testing.assert_array_equal(rb[key][push], rl[key][push])
    # Where a roll needs a pull the result is the simulated one, not the base model's.
    assert np.all(rb['R'][low < 0.0] != rl['R'][low < 0.0])
    # Orbits that never need a pull are identical too; the triangle's does need one.
    e_b, r_b, _ = base.orbit_arrays(1, 0.12, 8)
    e_l, r_l, _ = lift.orbit_arrays(1, 0.12, 8)
    first_pull = next(k for k in range(8)
                      if base.throw(int(e_b[k]), float(r_b[k])).min_normal_force < 0)
    np.testing.assert_array_equal(r_b[:first_pull + 1], r_l[:first_pull + 1])
    assert r_b[first_pull + 1] != r_l[first_pull + 1]


@pytest.mark.parametrize('mu', [1e3, 0.5])
def test_no_energy_is_gained_through_a_slip_or_a_hop(mu):
    base = scene().model
    lift = scene(['liftoff'], liftoff={'mu': mu}).model
    edges, radii = states(base, 80, seed=1)
    hops = 0
    for e, r in zip(edges, radii):
        res = lift.throw(int(e), float(r))
        energies = [res.release_energy]
        for imp in res.impacts:
            energies += [imp.energy_before, imp.energy_after]
        kinds = [i.kind for i in res.impacts]
        hops += 'liftoff' in kinds
        # Flight conserves, impacts dissipate, the integrated slip only loses to friction: the
        # energy never rises (to the integrator's 1e-9 relative).
        assert all(b <= a + 1e-9 * abs(energies[0]) for a, b in zip(energies, energies[1:])), \
            (e, r, kinds, energies)
        # At rest on a stable edge, or (low mu: a slip inwards) outside the domain of f, which
        # is an outcome of its own (issue 21 item 3).
        assert res.edge in base.part.stable_edges or (
            res.kind == 'lost' and 'outside the domain of f' in res.lost_reason), res
    assert hops > 5


def test_liftoff_parameters_and_conflicts():
    assert scene(['liftoff']).model.prm.liftoff.mu == 1000.0
    assert scene(['liftoff'], contact={'mu': 0.7}).model.prm.liftoff.mu == 0.7
    with pytest.raises(InputError, match='liftoff.mu'):
        scene(['liftoff'], liftoff={'mu': 0.0})
    with pytest.raises(InputError, match='liftoff.mu'):
        scene(['liftoff'], liftoff={'mu': 'high'})
    with pytest.raises(InputError, match='liftoff.grip'):
        scene(['liftoff'], liftoff={'grip': 1.0})
    with pytest.raises(InputError, match='effect liftoff'):
        scene([], liftoff={'mu': 1.0})
    with pytest.raises(ThrowmapError, match='impact_restitution and liftoff'):
        scene(['liftoff', 'impact_restitution'], contact={'restitution': 0.2}).model
