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

"""config/driver.yaml and docs/driver.md agree with the parameter table the node declares."""

import pathlib
import re

from feeder_driver import params
import pytest
import yaml

PKG = pathlib.Path(__file__).resolve().parents[1]
DOCS = PKG.parents[1] / 'docs'


def test_yaml_lists_every_run_time_parameter_with_its_default():
    """Keys '/**' only (ros2 param load and --params-file both take it); no read-only ones."""
    data = yaml.safe_load((PKG / 'config' / 'driver.yaml').read_text())
    assert list(data) == ['/**'], 'keys must be /** (a bare name is ignored in a namespace)'
    values = data['/**']['ros__parameters']
    assert set(values) == {s.name for s in params.SPECS if not s.read_only}
    for name, value in values.items():
        assert value == params.BY_NAME[name].default, name
        assert type(value) is type(params.BY_NAME[name].default), name
    assert params.validate(values, params.defaults()) is None


def test_docs_table_names_every_parameter():
    text = (DOCS / 'driver.md').read_text()
    documented = set(re.findall(r'^\| `([a-z_.]+)` \| (?:string|int|bool|double) \|', text,
                                re.M))
    assert documented == set(params.BY_NAME)


@pytest.mark.parametrize('name, value, text', [
    ('cycle_period', 'fast', 'must be a double'),
    ('cycle_period', float('nan'), 'finite'),
    ('sensor_range_m', 20.0, 'outside'),
    ('baud_rate', 1234, 'not one of the allowed values'),
    ('autostart', 'yes', 'must be a bool'),
    ('port', ' ', 'must not be empty'),
])
def test_check_names_the_problem_and_the_fix(name, value, text):
    _, reason = params.BY_NAME[name].validate(value)
    assert text in reason


def test_an_integer_for_a_double_is_that_double():
    assert params.BY_NAME['cycle_period'].validate(2) == (2.0, None)


def test_rules_across_parameters():
    values = params.defaults()
    assert 'must not exceed reconnect_max_s' in params.validate({'reconnect_initial_s': 20.0},
                                                                values)
    assert 'smaller than cycle_timeout_s' in params.validate({'ack_timeout_s': 6.0}, values)
    # during start-up a rule waits until both of its parameters are declared
    assert params.validate({'reconnect_initial_s': 20.0}, {}) is None


def test_descriptors_carry_ranges_and_read_only():
    from feeder_common.parameters import descriptor
    d = {s.name: descriptor(s) for s in params.SPECS}
    assert d['port'].read_only and d['baud_rate'].read_only and d['autostart'].read_only
    rng = d['cycle_period'].floating_point_range[0]
    spec = params.BY_NAME['cycle_period']
    assert (rng.from_value, rng.to_value) == (spec.minimum, spec.maximum)
    assert d['baud_rate'].integer_range[0].to_value == 2000000
    assert '115200' in d['baud_rate'].additional_constraints
