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

"""Bad input gets a clear error naming the field and the fix; never a NaN result."""

import math

import pytest
from throwmap import DomainError, InputError, Part, Scene, ThrowModel
from throwmap_testing import TRIANGLE_VERTICES

TRI = {'name': 't', 'part': {'vertices': TRIANGLE_VERTICES}, 'arm': {'offset': -0.005},
       'throw': {'release_speed': 5.5851}, 'gravity': -9.66}


def scene(**changes):
    data = {k: (dict(v) if isinstance(v, dict) else v) for k, v in TRI.items()}
    for path, value in changes.items():
        keys = path.split('__')
        node = data
        for k in keys[:-1]:
            node = node.setdefault(k, {})
        if value is KeyError:
            node.pop(keys[-1])
        else:
            node[keys[-1]] = value
    return Scene(data)


@pytest.mark.parametrize('vertices, field, words', [
    ([[0, 0], [1, 0]], 'part.vertices', 'fewer than 3 distinct points'),
    ([[0, 0], [0, 0], [1, 0]], 'part.vertices', 'fewer than 3 distinct points'),
    ([[0, 0], [1, 0], [1, 1], [1, 0]], 'part.vertices', 'repeats a point'),
    ([[0, 0], [0.01, 0.01], [0.02, 0.02]], 'part.vertices', 'zero area'),
    ([[0.06, 0.0], [0.0, 0.0], [0.06, 0.08]], 'part.vertices', 'clockwise'),
    ([[0, 0], [1, 0], [float('nan'), 1]], 'part.vertices', 'NaN'),
    ('triangle', 'part.vertices', 'not a list'),
])
def test_bad_part_outline(vertices, field, words):
    with pytest.raises(InputError) as err:
        Part(vertices)
    assert err.value.field == field
    assert words in str(err.value)
    assert err.value.fix   # every error says how to fix it


def test_cm_outside_hull_names_the_field_and_the_fix():
    with pytest.raises(InputError) as err:
        Part(TRIANGLE_VERTICES, cm=[0.1, 0.1])
    assert err.value.field == 'part.cm'
    assert 'not strictly inside the convex hull' in str(err.value)
    assert 'move the centre of mass inside' in str(err.value)
    with pytest.raises(InputError, match='part.cm'):
        Part(TRIANGLE_VERTICES, cm=[0.06, 0.04])      # on the boundary: d = 0


@pytest.mark.parametrize('rho', [0.0, -0.01, float('nan'), 'big'])
def test_bad_radius_of_gyration(rho):
    with pytest.raises(InputError) as err:
        Part(TRIANGLE_VERTICES, radius_of_gyration=rho)
    assert err.value.field == 'part.radius_of_gyration'
    assert 'omit it for a uniform lamina' in str(err.value)


@pytest.mark.parametrize('g', [0.0, 9.81, float('inf')])
def test_bad_gravity(g):
    with pytest.raises(InputError) as err:
        ThrowModel(Part(TRIANGLE_VERTICES), -0.005, 5.5, g)
    assert err.value.field == 'gravity'


@pytest.mark.parametrize('w', [0.0, -1.0, float('nan')])
def test_bad_release_speed(w):
    with pytest.raises(InputError) as err:
        ThrowModel(Part(TRIANGLE_VERTICES), -0.005, w, -9.66)
    assert err.value.field == 'throw.release_speed'


@pytest.mark.parametrize('h', [0.0, 0.002, -0.016, -0.05])
def test_offset_outside_prop_iv4_is_warned_not_refused(h):
    with pytest.warns(UserWarning, match=r'outside Proposition IV.4\'s range'):
        model = ThrowModel(Part(TRIANGLE_VERTICES), h, 5.5851, -9.66)
    edge, R, kind = model.f(1, 0.15)
    assert math.isfinite(R) and kind in ('jog', 'flip')


def test_domain_errors_say_which_condition_and_by_how_much(triangle):
    with pytest.raises(DomainError) as err:
        triangle.f(2, 0.05)
    assert err.value.condition == 'grasp_bound_3'
    assert err.value.margin == pytest.approx(0.17 / 3 - 0.05)
    assert 'short by' in str(err.value) and 'R >= R_grasp' in str(err.value)
    with pytest.raises(DomainError) as err:
        triangle.f(1, 0.03)
    assert err.value.condition == 'toe_stub'
    assert 'stub its toe' in str(err.value)
    with pytest.raises(DomainError) as err:
        triangle.f(3, 0.1)
    assert err.value.condition == 'edge_index'
    with pytest.raises(DomainError) as err:
        triangle.f(1, float('nan'))
    assert err.value.condition == 'radius'


def test_unstable_edge_is_outside_the_domain():
    from throwmap_testing import SCENES
    from throwmap import load_scene
    bracket = load_scene(str(SCENES / 'bracket.yaml'))
    with pytest.raises(DomainError) as err:
        bracket.model.f(2, 0.3)
    assert err.value.condition == 'stable_edge'
    assert '[0, 1, 3, 4]' in str(err.value)


def test_batch_reports_errors_per_state_without_nan_results(triangle):
    res = triangle.f_batch([1, 2, 7, 1], [0.12, 0.01, 0.1, 0.2])
    assert list(res['status'] == 0) == [True, False, False, True]
    assert list(res['kind']) == ['jog', '', '', res['kind'][3]]
    assert 'bound (3)' in triangle.error_message(res['status'][1], 2, 0.01)


@pytest.mark.parametrize('changes, field, words', [
    ({'colour': 'red'}, 'colour', 'allowed here'),
    ({'arm__offest': 0.1}, 'arm.offest', 'allowed here: length, length_cm, offset, offset_cm'),
    ({'arm__offset': KeyError}, 'arm.offset', 'give exactly one of offset / offset_cm'),
    ({'arm__offset_cm': -0.5}, 'arm.offset', 'given twice'),
    ({'gravity': 'down'}, 'gravity', 'must be a number'),
    ({'gravity': 9.66}, 'gravity', 'must be < 0'),
    ({'throw__release_speed': 0}, 'throw.release_speed', 'must be > 0'),
    ({'part__radius_of_gyration': 0}, 'part.radius_of_gyration', 'must be > 0'),
    ({'name': KeyError}, 'name', 'missing'),
    ({'catch__settle_rule': 'fast'}, 'catch.settle_rule', 'use one of full, first_stable'),
    ({'sensor__goal_edge': 5}, 'sensor.goal_edge', 'not a stable edge'),
    ({'accuracy__contact_time_tol': -1}, 'accuracy.contact_time_tol', 'must be a number > 0'),
    ({'start__edge': 2, 'start__R': 0.01}, 'start', 'no dynamic grasp'),
])
def test_scene_errors(changes, field, words):
    with pytest.raises(InputError) as err:
        scene(**changes)
    assert err.value.field == field
    assert words in str(err.value)


def test_scene_units_in_cm_and_degrees_convert():
    s = Scene({'name': 't', 'part': {'vertices_cm': [[6, 0], [6, 8], [0, 0]]},
               'arm': {'offset_cm': -0.5}, 'throw': {'release_speed_deg': 320},
               'gravity': -9.66})
    assert s.part.vertices.ravel().tolist() == pytest.approx(sum(TRIANGLE_VERTICES, []))
    assert s.h == pytest.approx(-0.005)
    assert s.release_speed == pytest.approx(math.radians(320))


def test_scene_file_errors(tmp_path):
    from throwmap import load_scene
    with pytest.raises(InputError, match='no such file'):
        load_scene(str(tmp_path / 'missing.yaml'))
    bad = tmp_path / 'bad.yaml'
    bad.write_text('name: [unclosed\n')
    with pytest.raises(InputError, match='is not valid YAML'):
        load_scene(str(bad))
    typo = tmp_path / 'typo.yaml'
    typo.write_text('name: t\npart: {vertices: [[0.06, 0], [0.06, 0.08], [0, 0]]}\n'
                    'arm: {offset: -0.005}\nthrow: {release_speed: 5.5}\ngravity: -9.66\n'
                    'efects: []\n')
    with pytest.raises(InputError) as err:
        load_scene(str(typo))
    assert str(typo) in str(err.value) and 'efects' in str(err.value)
