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

docs/numerics.md has the table of cases and the discontinuities that are real.
"""

import math

import numpy as np
import pytest
from throwmap import Accuracy, Part, ThrowModel
from throwmap_testing import PAPER_W, TRIANGLE_VERTICES


def vertex_heights(model, edge, R, t):
    """Heights over the arm of every hull vertex at times t, straight from eqs (5)-(6)."""
    part = model.part
    t = np.atleast_1d(np.asarray(t, dtype=float))
    wt = model.w * t
    u = part.U[edge][:, None]
    v = part.V[edge][:, None]
    return (part.d[edge] + R * model.w * t + 0.5 * model.g * t * t + u * np.sin(wt)
            + v * np.cos(wt))


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
