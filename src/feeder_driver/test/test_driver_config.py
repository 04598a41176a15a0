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


def test_yaml_lists_every_parameter_with_its_default():
    data = yaml.safe_load((PKG / 'config' / 'driver.yaml').read_text())
    assert list(data) == ['/**'], 'keys must be /** or fully qualified (a bare name is ignored)'
    values = data['/**']['ros__parameters']
    assert set(values) == set(params.BY_NAME)
    for name, value in values.items():
        assert value == params.BY_NAME[name].default, name
        assert type(value) is type(params.BY_NAME[name].default), name
    assert params.validate(values, values) is None


def test_docs_table_names_every_parameter():
    text = (DOCS / 'driver.md').read_text()
    documented = set(re.findall(r'^\| `([a-z_.]+)` \| (?:string|int|bool|double) \|', text,
                                re.M))
    assert documented == set(params.BY_NAME)


@pytest.mark.parametrize('name, value, text', [
    ('cycle_period', 1, 'write 1.0'),
    ('cycle_period', float('nan'), 'finite'),
    ('sensor_range_m', 20.0, 'outside'),
    ('baud_rate', 1234, 'standard rate'),
    ('autostart', 'yes', 'must be a bool'),
])
def test_check_names_the_problem_and_the_fix(name, value, text):
    assert text in params.check(name, value)


def test_descriptors_carry_ranges_and_read_only():
    d = params.descriptors()
    assert d['port'].read_only and d['baud_rate'].read_only and d['autostart'].read_only
    rng = d['cycle_period'].floating_point_range[0]
    assert (rng.from_value, rng.to_value) == params.BY_NAME['cycle_period'].bounds
    assert d['baud_rate'].integer_range[0].to_value == 2000000
