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

import pathlib

from feeder_sim.params import check_scene, check_start, ParamSpec, SIM_PARAMS
from throwmap import load_scene as load


DOCS = pathlib.Path(__file__).resolve().parents[3] / 'docs' / 'nodes.md'


def test_scene_checks_give_throwmaps_reason(tmp_path):
    assert 'not set' in check_scene('', load)
    assert 'no such file' in check_scene(str(tmp_path / 'missing.yaml'), load)
    bad = tmp_path / 'bad.yaml'
    bad.write_text('name: x\npart: {vertices: [[0, 0], [1, 0], [0, 1]]}\narm: {offset: -0.001}\n'
                   'throw: {release_speed: 5.0}\ngravity: -9.8\nbogus: 1\n')
    reason = check_scene(str(bad), load)
    assert 'bogus' in reason and 'unknown key' in reason
    assert check_scene(str(pathlib.Path(__file__).resolve().parents[3] / 'scenes' /
                           'triangle.yaml'), load) is None


def test_start_checks_use_the_domain_of_f(triangle):
    assert check_start(triangle.model, 1, 0.12) is None
    assert 'no dynamic grasp' in check_start(triangle.model, 1, 0.001)
    assert 'does not exist' in check_start(triangle.model, 7, 0.12)
    assert 'finite' in check_start(triangle.model, 1, float('nan'))


def test_specs_are_typed_ranged_and_documented():
    names = [s.name for s in SIM_PARAMS]
    assert len(names) == len(set(names))
    text = DOCS.read_text()
    for s in SIM_PARAMS:
        assert type(s.default) in (bool, int, float, str)
        assert s.description
        if s.minimum is not None:
            assert s.check_range(s.minimum) is None
            assert s.check_range(s.minimum - 1) is not None
        assert f'`{s.name}`' in text, f'{s.name} missing from docs/nodes.md'


def test_check_range():
    spec = ParamSpec('x', 1.0, 'x', minimum=0.0, maximum=2.0)
    assert spec.check_range(1.0) is None
    assert 'below' in spec.check_range(-0.1)
    assert 'above' in spec.check_range(2.5)


def test_config_yaml_matches_the_table():
    import yaml
    path = pathlib.Path(__file__).resolve().parents[1] / 'config' / 'sim.yaml'
    data = yaml.safe_load(path.read_text())
    specs = {s.name: s for s in SIM_PARAMS}
    assert set(data) == {'/**/feeder_sim', '/**/feeder_driver'}
    for node, section in data.items():
        params = section['ros__parameters']
        assert set(params) <= set(specs), set(params) - set(specs)
        for name, value in params.items():
            if name == 'hardware_mode':
                assert value == (node == '/**/feeder_driver')
            else:
                assert value == specs[name].default, (node, name)
            assert type(value) is type(specs[name].default), (node, name)


def test_a_start_beyond_a_finite_arm_is_rejected(short_arm):
    assert check_start(short_arm.model, 1, 0.32) is None
    reason = check_start(short_arm.model, 1, 0.34)
    assert "beyond the arm's end" in reason and '0.33' in reason
