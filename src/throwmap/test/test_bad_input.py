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
Bad input beyond test_input.py and test_cli.py: exact messages naming the field and the fix.

Every case here used to end in something other than a documented error (a numba TypingError,
a silently truncated edge, a traceback from the CLI) or named the wrong field.
"""

import io
import json
import math
import sys

import numpy as np
import pytest
from throwmap import DomainError, InputError, Part, ThrowModel
from throwmap.cli import main
from throwmap_testing import PAPER_W, SCENES, TRIANGLE_VERTICES

TRIANGLE = str(SCENES / 'triangle.yaml')


@pytest.fixture(scope='module')
def model():
    return ThrowModel(Part(TRIANGLE_VERTICES), -0.005, PAPER_W, -9.66)


# ------------------------------------------------------------------- the map's arguments
@pytest.mark.parametrize('edge, R, condition, message', [
    (1.0, 0.12, 'edge_index', 'edge must be an integer, got 1.0'),
    (True, 0.12, 'edge_index', 'edge must be an integer, got True'),
    ('1', 0.12, 'edge_index', "edge must be an integer, got '1'"),
    (None, 0.12, 'edge_index', 'edge must be an integer, got None'),
    (2 ** 70, 0.12, 'edge_index',
     'edge 1180591620717411303424 does not exist: the part has edges 0..2'),
    (1, '0.12', 'radius', "R must be a finite number of metres, got '0.12'"),
    (1, None, 'radius', 'R must be a finite number of metres, got None'),
    (1, True, 'radius', 'R must be a finite number of metres, got True'),
    (1, math.inf, 'radius', 'R must be a finite number of metres, got inf'),
    (1, -math.inf, 'radius', 'R must be a finite number of metres, got -inf'),
    (1, math.nan, 'radius', 'R must be a finite number of metres, got nan'),
])
def test_f_and_throw_refuse_wrong_types_with_a_domain_error(model, edge, R, condition, message):
    """Used to raise numba's TypingError (or, for R = inf, 'produced a non-finite state')."""
    for call in (model.f, model.throw):
        with pytest.raises(DomainError) as err:
            call(edge, R)
        assert err.value.condition == condition
        assert str(err.value) == message


def test_numpy_scalars_and_integer_radii_are_accepted(model):
    assert model.f(np.int64(1), np.float64(0.12)) == model.f(1, 0.12)
    assert model.f(1, 1) == model.f(1, 1.0)


@pytest.mark.parametrize('edges, radii, message', [
    ([1.5], [0.12], 'states: edges must be integers, got [1.5]; give edge numbers as integers'),
    (['a'], [0.12], "states: edges must be integers, got ['a']; give edge numbers as integers"),
    ([True, False], [0.12, 0.12],
     'states: edges must be integers, got [True, False]; give edge numbers as integers'),
    ([1], ['x'], 'states: edges and radii must be numbers (could not convert string to float: '
     "'x'); give integer edge numbers and radii in metres"),
    ([1, 1], [0.12], 'states: 2 edges but 1 radii; give one edge per radius'),
])
def test_batch_calls_refuse_non_integer_edges(model, edges, radii, message):
    """f_batch used to truncate 1.5 to edge 1 silently and to let numpy's ValueError escape."""
    for call in (model.f_batch, lambda e, r: model.orbits(e, r, 3)):
        with pytest.raises(InputError) as err:
            call(edges, radii)
        assert str(err.value) == message
        assert err.value.field == 'states'


def test_batch_calls_accept_integral_floats(model):
    assert model.f_batch([1.0], [0.12])['R'][0] == model.f(1, 0.12)[1]


def test_infinite_radius_in_a_batch_is_a_domain_status_not_a_numerical_one(model):
    res = model.f_batch([1, 1, 1], [math.inf, -math.inf, math.nan])
    assert list(res['kind']) == ['', '', '']
    for status, R in zip(res['status'], (math.inf, -math.inf, math.nan)):
        assert model.error_message(status, 1, R) == f'R must be a finite number of metres, got {R}'


# ------------------------------------------------------------------- CLI: stdin batches
@pytest.mark.parametrize('line, error', [
    ('{"edge": "1", "R": 0.12}', "edge must be an integer, got '1'"),
    ('{"edge": 1.5, "R": 0.12}', 'edge must be an integer, got 1.5'),
    ('{"edge": true, "R": 0.12}', 'edge must be an integer, got True'),
    ('{"edge": 1, "R": null}', 'R must be a finite number of metres, got None'),
    ('{"edge": 1, "R": "0.12"}', "R must be a finite number of metres, got '0.12'"),
    ('{"edge": 1, "R": 1e400}', 'R must be a finite number of metres, got inf'),
    ('{"edge": 99999999999999999999999, "R": 0.12}',
     'edge 99999999999999999999999 does not exist: the part has edges 0..2'),
])
def test_cli_stdin_batch_reports_bad_types_per_line(monkeypatch, line, error):
    """Each of these lines used to crash the whole batch with a numba TypingError traceback."""
    monkeypatch.setattr(sys, 'stdin', io.StringIO(line + '\n{"edge": 1, "R": 0.12}\n'))
    out = io.StringIO()
    assert main(['throw', TRIANGLE, '--json'], out=out) == 1
    rows = [json.loads(x) for x in out.getvalue().splitlines()]
    assert rows[0] == {'error': error}
    assert rows[1]['edge'] == 1 and rows[1]['kind'] == 'jog'     # the batch goes on


@pytest.mark.parametrize('argv, message', [
    (['--edge', '1', '--R', 'inf'], 'R must be a finite number of metres, got inf'),
    (['--edge', '1', '--R', 'nan'], 'R must be a finite number of metres, got nan'),
    (['--edge', '-1', '--R', '0.1'], 'edge -1 does not exist: the part has edges 0..2'),
])
def test_cli_throw_arguments_outside_the_domain(capsys, argv, message):
    assert main(['throw', TRIANGLE] + argv, out=io.StringIO()) == 2
    assert capsys.readouterr().err == f'throwmap: error: {message}\n'


@pytest.mark.parametrize('argv, message', [
    (['throw', TRIANGLE, '--edge', '1', '--R', 'abc'], "argument --R: invalid float value: 'abc'"),
    (['throw', TRIANGLE, '--edge', '1.5', '--R', '0.1'],
     "argument --edge: invalid int value: '1.5'"),
    (['orbit', TRIANGLE, '--throws', 'many'], "argument --throws: invalid int value: 'many'"),
    (['frob', TRIANGLE], "argument COMMAND: invalid choice: 'frob'"),
])
def test_cli_malformed_arguments_exit_2_with_usage(capsys, argv, message):
    with pytest.raises(SystemExit) as exit_:
        main(argv, out=io.StringIO())
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith('usage: throwmap') and message in err


def test_cli_plot_into_a_file_is_refused_before_the_analysis(tmp_path, capsys):
    """Used to run the whole analysis and then die with a FileExistsError traceback."""
    target = tmp_path / 'plots.png'
    target.write_bytes(b'')
    assert main(['plot', TRIANGLE, '--out', str(target), '--quiet'], out=io.StringIO()) == 2
    assert capsys.readouterr().err == (f'throwmap: error: --out {target}: is a file, not a '
                                       'directory; give a directory (it is created if missing)\n')


def test_cli_file_system_errors_name_the_path(tmp_path, capsys):
    """An OSError (here: a directory below a file) is a message and exit code 2, not a crash."""
    blocker = tmp_path / 'file'
    blocker.write_bytes(b'')
    out_dir = blocker / 'plots'
    argv = ['plot', TRIANGLE, '--out', str(out_dir), '--quiet', '--throws', '5',
            '--orbit-throws', '5']
    assert main(argv, out=io.StringIO()) == 2
    assert capsys.readouterr().err == (f'throwmap: error: {out_dir}: Not a directory; check the '
                                       'path and its permissions\n')
