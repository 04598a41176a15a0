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
Effect rolling_resistance against an independent integration of the roll it slows.

The reference: the paper's release (eqs 5-6) and ballistic flight to the first impact the
simulator reports, then the roll about that corner as a pendulum in its angle theta, the normal
force from the constraint, integrated with scipy's DOP853 to the next corner's landing.
"""

import copy
import math

import numpy as np
import pytest
from throwmap import InputError, Scene
from throwmap_testing import REFERENCE_KNOBS, TRIANGLE_SCENE

scipy_integrate = pytest.importorskip('scipy.integrate')

G = -9.66


def rolling_scene(lever_mm, **accuracy):
    data = copy.deepcopy(TRIANGLE_SCENE)
    data.update({'gravity': G, 'contact': {'rolling_resistance_mm': lever_mm},
                 'effects': ['rolling_resistance']})
    if accuracy:
        data['accuracy'] = accuracy
    return Scene(data)


def reference_roll(model, edge, R, flight_impact, lever):
    """
    Roll about the first impact's corner from the simulator's omega after it.

    Returns omega at the next landing, the vertex that lands, and the energy the resistance took.
    """
    part = model.part.arrays
    bu, bv = part.U[edge], part.V[edge]
    w, h = model.w, model.h
    k = flight_impact.vertex
    # Release (eqs 5-6) and the ballistic flight to the time the simulator's corner k lands.
    x0, y0, vx, vy = R, part.d[edge], -(h + part.d[edge]) * w, R * w

    def height(t):
        phi = w * t
        return y0 + vy * t + 0.5 * G * t * t + math.sin(phi) * bu[k] + math.cos(phi) * bv[k]

    t_hit = next(t for t in np.linspace(1e-4, 2.0, 200001) if height(t) < 0.0)
    lo, hi = t_hit - 1e-5, t_hit
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if height(mid) > 0.0 else (lo, mid)
    phi0 = w * hi
    pivot_x = x0 + vx * hi + math.cos(phi0) * bu[k] - math.sin(phi0) * bv[k]
    assert pivot_x == pytest.approx(flight_impact.x, abs=1e-9)
    # theta: the angle of the CM about the corner; l: their distance; I: inertia about it.
    cx = -(math.cos(phi0) * bu[k] - math.sin(phi0) * bv[k])
    cy = -(math.sin(phi0) * bu[k] + math.cos(phi0) * bv[k])
    theta0, length = math.atan2(cy, cx), math.hypot(cx, cy)
    inertia = part.rho2 + length * length

    def normal(theta, om, acc):
        return length * (math.cos(theta) * acc - math.sin(theta) * om * om) - G

    def rhs(t, y):
        theta, om, _ = y
        # I acc = g l cos(theta) - b |N| sign(om), N linear in acc: solve on N's side.
        for side in (1.0, -1.0):
            s = lever * side * math.copysign(1.0, om) if om != 0.0 else 0.0
            acc = ((G * length * math.cos(theta) + s * (length * math.sin(theta) * om * om + G))
                   / (inertia + s * length * math.cos(theta)))
            n = normal(theta, om, acc)
            if n * side >= 0.0:
                return [om, acc, lever * abs(n) * abs(om)]
        raise AssertionError('no consistent normal force')

    def landing(q):
        def event(t, y):
            phi = phi0 + y[0] - theta0
            return math.sin(phi) * bu[q] + math.cos(phi) * bv[q] + length * math.sin(y[0])
        event.terminal = True
        event.direction = -1
        return event

    others = [q for q in range(part.n) if q != k]
    sol = scipy_integrate.solve_ivp(rhs, (0.0, 5.0), [theta0, flight_impact.omega_after, 0.0],
                                    method='DOP853', rtol=1e-12, atol=1e-14,
                                    events=[landing(q) for q in others])
    hits = [(e[0], q, y[0]) for e, q, y in zip(sol.t_events, others, sol.y_events) if len(e)]
    assert hits, 'the reference roll never lands'
    _, q, y = min(hits)
    return y[1], q, y[2]


def single_roll_throws(lever_mm):
    model = rolling_scene(lever_mm, **REFERENCE_KNOBS).model
    found = []
    for edge in (0, 1):
        for R in np.linspace(0.07, 0.2, 14):
            result = model.throw(edge, float(R))
            kinds = [i.kind for i in result.impacts]
            if kinds[:2] == ['flight', 'landing']:
                found.append((model, edge, float(R), result))
    return found


@pytest.mark.parametrize('lever_mm', [0.5, 2.0])
def test_the_roll_matches_an_independent_integration(lever_mm):
    throws = single_roll_throws(lever_mm)
    assert len(throws) >= 8
    for model, edge, R, result in throws:
        flight, landing = result.impacts[:2]
        om, q, dissipated = reference_roll(model, edge, R, flight, lever_mm * 1e-3)
        assert q == landing.vertex, (edge, R)
        assert landing.omega_before == pytest.approx(om, rel=1e-7), (edge, R)
        # The energy the simulator lost over the roll is the work of the resisting torque.
        lost = flight.energy_after - landing.energy_before
        assert lost == pytest.approx(dissipated, rel=1e-6, abs=1e-12), (edge, R)
        assert lost > 0.0


def test_more_resistance_lands_slower_and_zero_is_the_base_model():
    base = rolling_scene(0.0).model
    assert not base.slots      # b = 0 fills no hook: the base model's own kernel
    plain = copy.deepcopy(TRIANGLE_SCENE)
    plain['gravity'] = G
    reference = Scene(plain).model
    for edge, R in ((1, 0.12), (0, 0.15), (1, 0.2)):
        assert base.f(edge, R) == reference.f(edge, R)
    speeds = []
    for lever_mm in (0.25, 1.0, 4.0):
        result = rolling_scene(lever_mm).model.throw(1, 0.12)
        speeds.append(abs(result.impacts[1].omega_before))
    assert speeds[0] > speeds[1] > speeds[2]


def test_a_missing_or_negative_lever_is_refused_with_the_fix():
    data = copy.deepcopy(TRIANGLE_SCENE)
    data.update({'gravity': G, 'effects': ['rolling_resistance']})
    with pytest.raises(InputError, match='rolling_resistance_mm.*missing.*e.g.'):
        Scene(data)
    data['contact'] = {'rolling_resistance_mm': -1}
    with pytest.raises(InputError, match='rolling_resistance_mm.*>= 0'):
        Scene(data)
    data['contact'] = {'rolling_resistance_mm': 500}
    with pytest.raises(InputError, match='500 mm is not below .* radius of gyration'):
        Scene(data).model
    data['effects'] = []
    with pytest.raises(InputError, match='effect rolling_resistance'):
        Scene(data)


def test_the_foam_holds_more_parts_on_a_corner_as_b_grows():
    # Held where the CM is within b of the corner's vertical at a turning point: a zone that
    # widens with b.
    held = []
    for lever_mm in (0.0, 2.0, 5.0):
        model = rolling_scene(lever_mm).model
        count = 0
        for edge in (0, 1, 2):
            for R in np.linspace(0.06, 0.3, 60):
                kinds = [i.kind for i in model.throw(edge, float(R)).impacts]
                count += kinds.count('held_on_corner')
        held.append(count)
    assert held[0] == 0 < held[1] <= held[2]
