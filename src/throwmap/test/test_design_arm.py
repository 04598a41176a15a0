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
Design search on the arm the feeder has (issue 21 item 2, the arm's length).

The paper's feeder has "a 40 cm long horizontal arm". A scene says so with ``arm.length_cm``
and effect ``finite_arm``; the design kernel throws through the scene's own throw kernel (the
model's, with that effect's check), so a design whose Z, grid starts or limit set put the part
past the arm's end is not eligible, and its sensor must fit on the arm. Checked: the design
kernel's limit set is the model's orbit bit for bit, and the chosen design keeps every grid
start on the arm for 10,000 throws.
"""

import io
import json
import math

import numpy as np
import pytest
from throwmap import design as D
from throwmap import Scene
from throwmap.basins import default_grid
from throwmap.cli import main
from throwmap.status import LOST, OK
from throwmap_testing import PAPER_W, TRIANGLE_VERTICES

ARM = 0.40
# The design an endless-arm search chose by readies per second (issue 21): sensor at 43.9 cm.
ENDLESS_CHOICE = (-0.009846153846153848, 4.153023076923076)


def triangle(arm=ARM, h=-0.005, w=PAPER_W):
    data = {'name': 'triangle_arm', 'part': {'vertices': TRIANGLE_VERTICES},
            'arm': {'offset': h}, 'throw': {'release_speed': w}, 'gravity': -9.66,
            'sensor': {'goal_edge': 1}, 'start': {'edge': 1, 'R': 0.12}}
    if arm is not None:
        data['arm']['length'] = arm
        data['effects'] = ['finite_arm']
    return Scene(data)


@pytest.fixture(scope='module')
def on_arm():
    return triangle()


def test_the_design_kernel_throws_the_scenes_own_map(on_arm):
    # One throw kernel: the design kernel's reference orbit (from the goal edge at 1.5 R_min,
    # its second half the limit set) is the model's orbit, bit for bit, with finite_arm.
    model = on_arm.model
    opt = D.eval_options(on_arm, ref_throws=400)
    res = D.evaluate_grid(on_arm, [model.h], [model.w], options=opt)
    e0 = int(res.design[0, D.D_REF_EDGE])
    r0 = float(res.design[0, D.D_REF_R])
    assert e0 == 1 and r0 == 1.5 * model.r_min(1)
    e, r, _ = model.orbit_arrays(e0, r0, 400)
    for edge in model.part.stable_edges:
        tail = r[200:][e[200:] == edge]
        band = res.bands[0, edge]
        if tail.size:
            assert (band[0], band[1]) == (tail.min(), tail.max())
        else:
            assert np.all(np.isnan(band))
    # A design far out on the arm loses the part in the kernel as in the model.
    far = triangle(h=ENDLESS_CHOICE[0], w=ENDLESS_CHOICE[1])
    lost = far.model.orbits([1], [0.30], 200)[3]
    assert lost[0] == LOST


def test_a_design_that_throws_the_part_off_the_arm_is_not_eligible():
    h, w = ENDLESS_CHOICE
    endless = triangle(arm=None, h=h, w=w)
    res = D.evaluate_grid(endless, [h], [w], options=D.eval_options(endless))
    assert res.design[0, D.D_STATUS] == D.ST_OK
    assert res.sensor[0, 0, 0, D.S_FITS]          # an endless arm holds any sensor
    arm = triangle(h=h, w=w)
    res = D.evaluate_grid(arm, [h], [w], options=D.eval_options(arm))
    assert res.design[0, D.D_STATUS] == D.ST_OFF_ARM
    assert 'past the arm' in D.STATUS_TEXT[D.ST_OFF_ARM]
    # The paper's design fits its arm.
    paper = triangle()
    res = D.evaluate_grid(paper, [paper.h], [paper.release_speed],
                          options=D.eval_options(paper))
    assert res.design[0, D.D_STATUS] == D.ST_OK and res.design[0, D.D_R_HI] < ARM


def test_the_search_on_a_40_cm_arm_chooses_a_design_that_keeps_the_part(tmp_path):
    path = tmp_path / 'triangle_arm.yaml'
    path.write_text(json.dumps({
        'name': 'triangle_arm', 'part': {'vertices': TRIANGLE_VERTICES},
        'arm': {'offset': -0.005, 'length_cm': 40}, 'throw': {'release_speed': PAPER_W},
        'gravity': -9.66, 'sensor': {'goal_edge': 1}, 'start': {'edge': 1, 'R': 0.12},
        'effects': ['finite_arm']}))
    out = io.StringIO()
    # ready-rate: the ranking whose endless-arm choice put the sensor at 43.9 cm and lost parts
    code = main(['design-search', str(path), '--grid', '20x20', '--objective', 'ready-rate',
                 '--json', '--quiet'], out=out)
    result = json.loads(out.getvalue())
    assert code == 0 and result['chosen'] is not None
    assert not any(n.startswith('the arm is taken as endless') for n in result['notes'])
    f = result['chosen']['figures']
    assert f['sensor_radius'] + triangle().sensor_footprint <= ARM and f['r_hi'] <= ARM
    chosen = triangle(h=result['chosen']['h'], w=result['chosen']['release_speed'])
    model = chosen.model
    edges, radii = default_grid(model)
    status, done = model.orbits(edges, radii, 10_000)[3:]
    assert not np.any(status == LOST), f'{int(np.sum(status == LOST))} grid starts lost'
    assert np.all(status == OK) and np.all(done == 10_000)
    assert math.isfinite(model.arm_length) and model.arm_length == ARM
