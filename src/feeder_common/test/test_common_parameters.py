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

"""The parameter gate on a real rclpy node (own context): declare, coerce, validate, apply."""

from feeder_common.parameters import ParameterError, ParameterGate
from feeder_common.params import ParamSpec
import pytest
import rclpy
from rclpy.context import Context
from rclpy.parameter import Parameter

SPECS = (
    ParamSpec('period', 1.0, 'a double', minimum=0.01, maximum=10.0),
    ParamSpec('count', 3, 'an integer', minimum=0, maximum=100),
    ParamSpec('name', 'x', 'a string', read_only=True),
    ParamSpec('low', 1.0, 'must stay below high'),
    ParamSpec('high', 2.0, 'must stay above low'),
)


def below(changes, current):
    merged = {**current, **changes}
    if 'low' in merged and 'high' in merged and merged['low'] >= merged['high']:
        return f'low ({merged["low"]}) must be below high ({merged["high"]})'
    return None


@pytest.fixture
def make(domain_id):
    ctx = Context()
    rclpy.init(context=ctx, domain_id=domain_id)
    nodes = []

    def _make(**given):
        node = rclpy.create_node('gate_test', context=ctx, parameter_overrides=[
            Parameter(k, value=v) for k, v in given.items()])
        applied = []
        gate = ParameterGate(node, SPECS, below, applied.append)
        nodes.append(node)
        return node, gate, applied

    yield _make
    for n in nodes:
        n.destroy_node()
    rclpy.shutdown(context=ctx)


def test_an_integer_given_for_a_double_is_declared_as_that_double(make):
    node, gate, applied = make(period=2)
    gate.declare_all()
    value = node.get_parameter('period')
    assert value.type_ == Parameter.Type.DOUBLE and value.value == 2.0
    assert gate.values['period'] == 2.0
    assert applied == []                    # declaration applies nothing


@pytest.mark.parametrize('given, words', [
    ({'period': 'abc'}, 'period must be a double, got string'),
    ({'count': 1.5}, 'count must be an integer, got double 1.5'),
    ({'name': 5}, 'name must be a string, got integer 5'),
    ({'period': 0.001}, 'period = 0.001 is outside [0.01, 10.0]'),
    ({'low': 5.0}, 'low (5.0) must be below high (2.0)'),
])
def test_a_bad_start_up_value_is_one_line(make, given, words):
    _, gate, _ = make(**given)
    with pytest.raises(ParameterError) as err:
        gate.declare_all()
    assert words in str(err.value) and '\n' not in str(err.value)


def test_run_time_sets_are_coerced_validated_and_applied(make):
    node, gate, applied = make()
    gate.declare_all()
    # ros2 param set node period 3  (an INTEGER on the wire)
    res = node.set_parameters([Parameter('period', Parameter.Type.INTEGER, 3)])[0]
    assert res.successful, res.reason
    assert node.get_parameter('period').value == 3.0 and gate.values['period'] == 3.0
    assert applied[-1] == {'period': 3.0}
    res = node.set_parameters([Parameter('high', value=0.5)])[0]
    assert not res.successful and 'must be below high (0.5)' in res.reason
    assert gate.values['high'] == 2.0
    res = node.set_parameters([Parameter('name', value='y')])[0]
    assert not res.successful and 'read-only' in res.reason
    res = node.set_parameters([Parameter('count', value='many')])[0]
    assert not res.successful


def test_unknown_start_up_names_are_reported(make):
    _, gate, _ = make(perod=1.0)
    gate.declare_all()
    assert gate.unknown_given() == ['perod']
