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
A throw that leaves the part at rest outside the domain of f (issue 21 item 3).

Under ``liftoff`` with finite friction a roll that needs more friction than mu allows slips the
part inwards; started just above R_min on the triangle's hypotenuse it comes to rest below
R_min, where the next release would stub the part's toe: no later throw is defined. Such a throw
is an outcome ('lost', with where the part rests and why), never a silent 'jog' whose next
throw raises, and everything that iterates f (orbits, basins, the design radii, PartOnArm)
treats it as the end of the part's prediction.
"""

import math

import numpy as np
import pytest
from throwmap import basin, limit_set, PartLost, PartOnArm, Scene
from throwmap.basins import design_radii
from throwmap.status import LOST, OFF_DOMAIN, OK
from throwmap_testing import PAPER_W, TRIANGLE_VERTICES

BASE = {'name': 't', 'part': {'vertices': TRIANGLE_VERTICES}, 'arm': {'offset': -0.005},
        'throw': {'release_speed': PAPER_W}, 'gravity': -9.66, 'sensor': {'goal_edge': 1}}


def triangle(mu=None):
    data = dict(BASE)
    if mu is not None:
        data.update(effects=['liftoff'], liftoff={'mu': mu})
    return Scene(data)


@pytest.fixture(scope='module')
def slipping():
    return triangle(1.0)


def near_r_min(model, edge, count=60, span=5e-3):
    return model.r_min(edge) + np.linspace(1e-7, span, count)


def test_a_slip_below_r_min_is_a_lost_throw_with_where_and_why(slipping):
    model = slipping.model
    R = model.r_min(1) + 1e-6
    # The kernel's own outcome: at rest on the hypotenuse, below R_min, by the toe-stub bound.
    st, j, r1 = model._throw(1, R, np.zeros(2), model._rec)[:3]
    assert st == OFF_DOMAIN and j == 1 and r1 < model.r_min(1)
    assert model.domain_error(j, r1).condition == 'toe_stub'
    # f and throw: a defined outcome, not a 'jog' to a state f cannot throw from.
    assert model.f(1, R)[0] == -1 and math.isnan(model.f(1, R)[1])
    assert model.f(1, R)[2] == 'lost'
    res = model.throw(1, R)      # lost to the map; the full result says where the part rests
    assert (res.kind, res.edge, res.R, res.in_domain) == ('jog', 1, r1, False)
    assert f'on edge 1 at R = {r1:.6g} m' in res.lost_reason
    assert 'outside the domain of f' in res.lost_reason
    assert 'stub its toe' in res.lost_reason


def test_the_slip_is_friction_not_the_model_near_its_edge():
    """The sticking model and liftoff with ample friction keep the same start in the domain."""
    R = triangle().model.r_min(1) + 1e-6
    for scene in (triangle(), triangle(3.0), triangle(1000.0)):
        j, r1, kind = scene.model.f(1, R)
        assert kind == 'jog' and j == 1 and r1 >= scene.model.r_min(1), scene.effects
    # Less friction slips further: the rest state moves inwards as mu falls.
    rests = []
    for mu in (1.0, 0.6):
        model = triangle(mu).model
        st, j, r1 = model._throw(1, R, np.zeros(2), model._rec)[:3]
        assert (st, j) == (OFF_DOMAIN, 1)
        rests.append(r1)
    assert rests[1] < rests[0] < R


@pytest.mark.parametrize('mu', [0.6, 1.0])
def test_every_throw_lands_in_the_domain_or_is_lost(mu):
    """The invariant the next throw needs, over every stable edge near and above R_min."""
    model = triangle(mu).model
    lost = 0
    for edge in (0, 1, 2):
        radii = np.concatenate([near_r_min(model, edge), np.linspace(0.06, 0.3, 40)])
        res = model.f_batch(np.full(radii.size, edge), radii)
        assert set(res['status'].tolist()) <= {OK, LOST}
        for j, r1, st, kind in zip(res['edge'], res['R'], res['status'], res['kind']):
            if st == LOST:
                lost += 1
                assert j == -1 and math.isnan(r1) and kind == 'lost'
            else:
                assert model.domain_error(int(j), float(r1)) is None, (edge, j, r1)
        for R in radii[:5]:    # one throw at a time says the same as the batch
            j, r1, kind = model.f(edge, float(R))
            assert kind == 'lost' or model.domain_error(j, r1) is None
    assert lost > 0     # the case is exercised: some starts near R_min slip out


def test_orbits_basins_and_design_radii_end_the_part_there(slipping):
    model = slipping.model
    R = model.r_min(1) + 1e-6
    edges, radii, _ = model.orbit_arrays(1, R, 50)
    assert list(edges) == [1, -1] and math.isnan(radii[-1])
    with pytest.raises(PartLost, match='lost at throw 1 .*outside the domain of f'):
        limit_set(model, 1, R)
    bas = basin(model, [1, 1], [R, 0.12], throws=200)
    assert bas.signatures[0] == 'lost' and bas.signatures[1] != 'lost'
    radii_table = design_radii(model)
    assert not radii_table['invariant']
    assert any(i == 1 and j == -1 for i, j, _ in radii_table['escapes'])


def test_a_part_on_the_arm_reports_the_loss_once_and_throws_on_empty(slipping):
    R = slipping.model.r_min(1) + 1e-6
    part = PartOnArm(slipping, 1, R, sensor_radius=0.2672)
    first = part.throw()
    assert (first.kind, first.edge, part.lost_at) == ('lost', -1, 1)
    assert 'outside the domain of f' in first.lost_reason and not first.detected
    # Before, the next throw raised a DomainError (toe stub) on every cycle; now it is empty.
    second = part.throw()
    assert (second.kind, second.edge0, second.lost_reason, part.lost_at) == ('lost', -1, '', 1)
    part.place(1, 0.12)
    assert part.throw().kind in ('jog', 'flip') and part.lost_at is None
