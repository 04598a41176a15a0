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

from feeder_common.params import check_scene
from feeder_sim.params import check_start, PREDICTOR_PARAMS, SHARED_PARAMS, STANDIN_PARAMS
import pytest
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
    # The parameter at fault is named first (issue 10: start_edge:=99 named start_radius).
    assert check_start(triangle.model, 99, 0.12).startswith('start_edge = 99 rejected')
    assert check_start(triangle.model, 1, 0.001).startswith('start_radius = 0.001 m')
    assert 'finite' in check_start(triangle.model, 1, float('nan'))


@pytest.mark.parametrize('table', [STANDIN_PARAMS, PREDICTOR_PARAMS])
def test_specs_are_typed_ranged_and_documented(table):
    names = [s.name for s in table]
    assert len(names) == len(set(names))
    text = DOCS.read_text()
    for s in table:
        assert type(s.default) in (bool, int, float, str)
        assert s.description
        if s.minimum is not None:
            assert s.check(type(s.default)(s.minimum)) is None
            assert s.check(type(s.default)(s.minimum - 1)) is not None
        assert f'`{s.name}`' in text, f'{s.name} missing from docs/nodes.md'


@pytest.mark.parametrize('file, table', [('standin.yaml', STANDIN_PARAMS),
                                         ('predictor.yaml', PREDICTOR_PARAMS)])
def test_config_yaml_matches_the_table(file, table):
    """One '/**' section per node; every run-time parameter without a scene default."""
    import yaml
    path = pathlib.Path(__file__).resolve().parents[1] / 'config' / file
    data = yaml.safe_load(path.read_text())
    specs = {s.name: s for s in table}
    assert list(data) == ['/**']
    params = data['/**']['ros__parameters']
    assert set(params) == {s.name for s in table if not s.read_only} - \
        {'start_edge', 'start_radius'}
    for name, value in params.items():
        assert value == specs[name].default, name
        assert type(value) is type(specs[name].default), name


def test_each_node_declares_only_its_own_parameters():
    """The stand-in takes the driver's cycle parameters, the predictor its markers' period."""
    standin = {s.name for s in STANDIN_PARAMS}
    predictor = {s.name for s in PREDICTOR_PARAMS}
    assert standin & predictor == {s.name for s in SHARED_PARAMS}
    assert 'markers_period' not in standin
    assert {'cycle_period', 'key_file', 'truth_log', 'seed', 'joint_states_rate'} <= standin
    assert not {'cycle_period', 'key_file', 'truth_log', 'seed', 'joint_states_rate',
                'sensor_range_m', 'frame_id', 'ack_timeout_s'} & predictor
    assert 'hardware_mode' not in standin | predictor


def test_a_start_beyond_a_finite_arm_is_rejected(short_arm):
    assert check_start(short_arm.model, 1, 0.32) is None
    reason = check_start(short_arm.model, 1, 0.34)
    assert "beyond the arm's end" in reason and '0.33' in reason
