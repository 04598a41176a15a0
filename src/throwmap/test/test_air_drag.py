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

"""Effect air_drag: its limit (drag 0 is the base model bit for bit), its physics, bad input."""

import copy
import math

import numpy as np
import pytest
from scipy.integrate import dblquad, solve_ivp
from throwmap import InputError, Scene
from throwmap.effects import air_drag
from throwmap_testing import PAPER_W, TRIANGLE_VERTICES

BASE = {'name': 't', 'part': {'vertices': TRIANGLE_VERTICES}, 'arm': {'offset': -0.005},
        'throw': {'release_speed': PAPER_W}, 'gravity': -9.66}
AIR = {'density': 1.2, 'drag_coefficient': 1.2, 'frontal_area_cm2': 4.0, 'mass_g': 2.0}


def scene(drag=None, **sections):
    """Return the triangle scene; with ``drag`` (its air section) naming air_drag."""
    data = copy.deepcopy(BASE)
    if drag is not None:
        data.update({'air': drag, 'effects': ['air_drag']})
    data.update(sections)
    return Scene(data)


def states(model, count, seed):
    rng = np.random.default_rng(seed)
    edges = rng.choice(model.part.stable_edges, count)
    lo = np.array([model.r_min(e) * 1.001 for e in edges])
    return edges, lo + rng.uniform(0, 1, count) * (0.28 - lo)


@pytest.fixture(scope='module')
def base():
    return scene().model


def test_zero_drag_is_the_base_model_bit_for_bit(base):
    model = scene(dict(AIR, drag_coefficient=0.0)).model
    assert model.slots == {}        # nothing of the effect is compiled
    e, r = states(base, 300, 1)
    for key in ('edge', 'R', 'status', 'flight_time', 'net_rotation'):
        assert np.array_equal(model.f_batch(e, r)[key], base.f_batch(e, r)[key],
                              equal_nan=True)
    assert model.throw(1, 0.2).impacts == base.throw(1, 0.2).impacts
    still = scene(dict(AIR, density=0.0)).model
    assert np.array_equal(still.orbits([1], [0.12], 50)[1], base.orbits([1], [0.12], 50)[1])


def test_the_drag_law_in_translation_and_in_spin():
    model = scene(AIR).model
    prm = model.prm.air_drag
    k = 1.2 * 1.2 * 4e-4 / (2 * 2e-3)
    assert model.effects.get('air_drag').k == pytest.approx(k, rel=1e-15)
    assert prm.k == pytest.approx(k, rel=1e-15)
    fx, fy, tq = air_drag.body_force(0.3, -0.4, 0.0, 0.7, 1, prm)
    assert (fx, fy, tq) == pytest.approx((-k * 0.5 * 0.3, k * 0.5 * 0.4, 0.0), rel=1e-14)
    # Spin: -k <r^3> w |w|, with <r^3> the area average over the triangle (CM (4, 8/3) cm),
    # integrated here by scipy.
    cx, cy = 0.04, 0.08 / 3
    r3 = dblquad(lambda y, x: ((x - cx) ** 2 + (y - cy) ** 2) ** 1.5, 0, 0.06, 0,
                 lambda x: 0.08 / 0.06 * x, epsabs=1e-16, epsrel=1e-12)[0] / (0.5 * 0.06 * 0.08)
    for w in (-7.0, 3.0):
        assert air_drag.body_force(0.0, 0.0, w, 0.2, 0, prm)[2] == pytest.approx(
            -k * r3 * w * abs(w), rel=1e-4)


def drag_flight(model, edge, R, k, k_spin):
    """First contact (time, vertex) of the drag flight integrated by scipy (independent)."""
    part, h, w, g = model.part, model.h, model.w, model.g
    d = part.d[edge]
    u, v = part.U[edge], part.V[edge]
    rho2 = part.rho2

    def rhs(t, s):
        x, y, phi, vx, vy, om = s
        speed = math.hypot(vx, vy)
        return [vx, vy, om, -k * speed * vx, g - k * speed * vy, -k_spin * om * abs(om) / rho2]

    events = []
    for j in range(part.n):
        def height(t, s, j=j):
            return s[1] + math.sin(s[2]) * u[j] + math.cos(s[2]) * v[j]
        height.terminal = True
        height.direction = -1
        events.append(height)
    sol = solve_ivp(rhs, (0, 2.0), [R, d, 0.0, -(h + d) * w, R * w, w], method='DOP853',
                    rtol=1e-12, atol=1e-14, events=events)
    times = [(ts[0], j) for j, ts in enumerate(sol.t_events) if len(ts)]
    return min(times)


def test_the_integrated_flight_agrees_with_an_independent_integration(base):
    model = scene(AIR).model
    prm = model.prm.air_drag
    e, r = states(base, 12, 3)
    for edge, R in zip(e, r):
        res = model.throw(int(edge), float(R))
        t_ref, k_ref = drag_flight(model, int(edge), float(R), prm.k, prm.k_spin)
        assert res.first_contact_vertex == k_ref
        assert res.flight_time == pytest.approx(t_ref, abs=1e-9)


def test_drag_takes_energy_and_its_effect_shrinks_with_it(base):
    e, r = states(base, 60, 4)
    ref = base.f_batch(e, r)
    errs = []
    for mass_g in (2.0, 20.0, 200.0):     # k falls tenfold each time
        model = scene(dict(AIR, mass_g=mass_g)).model
        got = model.f_batch(e, r)
        same = got['edge'] == ref['edge']
        errs.append((same.mean(), np.abs(got['R'] - ref['R'])[same].max()))
        res = model.throw(1, 0.2)
        assert res.impacts[0].energy_before < res.release_energy      # flight lost energy
        for imp in res.impacts:
            assert imp.energy_after <= imp.energy_before + 1e-9
    assert errs[-1][0] == 1.0
    assert errs[0][1] > errs[1][1] > errs[2][1] > 0.0
    assert errs[1][1] / errs[2][1] == pytest.approx(10.0, rel=0.3)     # linear in k


@pytest.mark.parametrize('air, field, words', [
    ({'density': 1.2, 'frontal_area_cm2': 4, 'mass_g': 2}, 'air.drag_coefficient', 'missing'),
    ({'drag_coefficient': 1, 'mass_g': 2}, 'air.frontal_area_cm2', 'thickness x width'),
    ({'drag_coefficient': 1, 'frontal_area_cm2': 4}, 'air.mass_g', 'missing'),
    (dict(AIR, density=-1.0), 'air.density', '>= 0'),
    (dict(AIR, mass_g=0), 'air.mass_g', '> 0'),
    (dict(AIR, speed=3), 'air.speed', 'allowed here'),
])
def test_bad_air_parameters_name_the_field(air, field, words):
    with pytest.raises(InputError) as err:
        scene(air)
    assert err.value.field == field and words in str(err.value)


def test_air_parameters_without_the_effect_are_refused():
    with pytest.raises(InputError, match='add air_drag to effects'):
        scene(None, air=AIR)


def test_the_flight_step_is_the_air_drags_own_unless_the_scene_sets_it(base):
    assert scene(AIR).model.simulator.integrator_step == air_drag.FLIGHT_STEP == 2e-3
    told = scene(AIR, accuracy={'integrator_step': 1e-3}).model.simulator.integrator_step
    assert told == 1e-3
    with_plate = copy.deepcopy(BASE)
    del with_plate['gravity']
    with_plate.update({'air': AIR, 'plate': {'inclination_deg': 80, 'g0': 9.81, 'mu': 0.1},
                       'effects': ['backplate_friction', 'air_drag']})
    assert Scene(with_plate).model.simulator.integrator_step == 1e-3   # the plate's kinks
    # Why 2 ms: the throws are as close to the reference (rk4 at 5e-5 s) as at 1 ms.
    e, r = states(base, 150, 6)
    ref = scene(AIR, accuracy={'integrator_step': 5e-5, 'roll_step': 5e-5,
                               'contact_root_tol': 1e-13}).model.f_batch(e, r)
    for step in (2e-3, 1e-3):
        got = scene(AIR, accuracy={'integrator_step': step}).model.f_batch(e, r)
        assert np.array_equal(got['edge'], ref['edge'])
        assert np.max(np.abs(got['R'] - ref['R'])) < 1e-12, step
