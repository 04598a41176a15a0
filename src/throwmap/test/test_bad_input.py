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
import os
import socket
import sys
import threading
import time
import types

import numpy as np
import pytest
from throwmap import DomainError, InputError, Part, ThrowModel
from throwmap import status as kernel_status
from throwmap.cli import main
from throwmap_testing import PAPER_W, SCENES, TRIANGLE_VERTICES

TRIANGLE = str(SCENES / 'triangle.yaml')


@pytest.fixture(scope='module')
def model():
    return ThrowModel(Part(TRIANGLE_VERTICES), -0.005, PAPER_W, -9.66)


def test_every_template_status_message_quotes_the_throw_and_its_limit():
    # A template's fields are looked up only when it is formatted: a wrong name would surface
    # as an AttributeError the first time that (rare) status comes back.
    model = types.SimpleNamespace(
        accuracy=types.SimpleNamespace(max_flight_steps=123, max_impacts=45),
        knobs=types.SimpleNamespace(max_sim_steps=678), arm_length=0.5)
    limits = {kernel_status.ERR_FLIGHT_CAP: 'max_flight_steps = 123 steps',
              kernel_status.ERR_SETTLE_CAP: 'max_impacts = 45 impacts',
              kernel_status.ERR_SIM_CAP: 'max_sim_steps = 678 integrator steps',
              kernel_status.LOST: 'the arm [0, 0.5 m]'}
    for code in kernel_status.TEMPLATES:
        text = kernel_status.message(model, code, 2, 0.125)
        assert '(2, 0.125 m)' in text and limits.get(code, '') in text, text


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


# ------------------------------------------------------------------------------ scene files
SCENE = ('name: t\n'
         'part: {vertices: [[0.06, 0.0], [0.06, 0.08], [0.0, 0.0]]}\n'
         'arm: {offset: -0.005}\n'
         'throw: {release_speed: 5.5851}\n'
         'gravity: -9.66\n')


def _scene_file(tmp_path, text, name='scene.yaml'):
    path = tmp_path / name
    path.write_text(text, encoding='utf-8')
    return str(path)


def _load_error(path):
    from throwmap import load_scene
    with pytest.raises(InputError) as err:
        load_scene(path)
    return str(err.value)


def test_scene_path_that_is_a_directory(tmp_path, capsys):
    """Used to escape as IsADirectoryError (a traceback from the CLI)."""
    message = (f'scene: {tmp_path} is a directory, not a regular file; give the path of a '
               'scene YAML file (e.g. scenes/triangle.yaml)')
    assert _load_error(str(tmp_path)) == message
    assert main(['grasp', str(tmp_path)], out=io.StringIO()) == 2
    assert capsys.readouterr().err == f'throwmap: error: {message}\n'


def _special_file(tmp_path, kind):
    """Return a path of the given kind (and the bound socket, to close after the test)."""
    if kind == 'fifo':
        path = tmp_path / 'scene.fifo'
        os.mkfifo(path)
        return str(path), None
    if kind == 'character device':
        return os.devnull, None
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    path = tmp_path / 'scene.sock'
    sock.bind(str(path))
    return str(path), sock


@pytest.mark.parametrize('kind, named', [('fifo', 'a FIFO (named pipe)'),
                                         ('character device', 'a character device'),
                                         ('socket', 'a socket')])
def test_scene_path_that_is_not_a_regular_file_is_refused_at_once(
        tmp_path, capsys, kind, named):
    """
    Issue 20, attack 9: a FIFO as the scene blocked the loader (and the nodes) for good.

    Run in a thread so that a regression shows as a failure, not as a hung test; a writer
    then opens the FIFO to let the blocked loader go.
    """
    path, sock = _special_file(tmp_path, kind)
    message = (f'scene: {path} is {named}, not a regular file; give the path of a scene YAML '
               'file (e.g. scenes/triangle.yaml)')
    outcome = []
    thread = threading.Thread(target=lambda: outcome.append(_load_error(path)), daemon=True)
    started = time.monotonic()
    thread.start()
    thread.join(timeout=5.0)
    blocked = thread.is_alive()
    if blocked and kind == 'fifo':
        with open(path, 'wb'):
            pass
        thread.join(timeout=5.0)
    try:
        assert not blocked, f'load_scene({path!r}) still blocked after 5 s'
        assert time.monotonic() - started < 1.0
        assert outcome == [message]
        assert main(['grasp', path], out=io.StringIO()) == 2
        assert capsys.readouterr().err == f'throwmap: error: {message}\n'
    finally:
        if sock is not None:
            sock.close()


def test_scene_file_that_is_not_utf8(tmp_path, capsys):
    """Used to escape as UnicodeDecodeError (a traceback from the CLI)."""
    path = tmp_path / 'latin1.yaml'
    path.write_bytes(SCENE.replace('name: t', 'name: caf\xe9').encode('latin-1'))
    message = (f'{path}: is not UTF-8 text (byte 9: invalid continuation byte); save the '
               'scene as UTF-8 YAML')
    assert _load_error(str(path)) == message
    assert main(['grasp', str(path)], out=io.StringIO()) == 2
    assert capsys.readouterr().err == f'throwmap: error: {message}\n'


@pytest.mark.parametrize('extra, key, lines', [
    ('arm: {offset: -0.004}\n', 'arm', (3, 6)),
    ('name: u\n', 'name', (1, 6)),
    ('sensor: {goal_edge: 1, goal_edge: 2}\n', 'goal_edge', (6, 6)),
])
def test_scene_key_given_twice(tmp_path, extra, key, lines):
    """Refuse a key given twice: PyYAML kept the last one silently, hiding the mistake."""
    path = _scene_file(tmp_path, SCENE + extra)
    assert _load_error(path) == (f'{path}: gives {key!r} twice in one mapping (lines '
                                 f'{lines[0]} and {lines[1]}); YAML would keep the last '
                                 'silently; keep one of them')


@pytest.mark.parametrize('part, message', [
    ('{vertices_cm: [[6, 0], [0, 0], [6, 8]]}',
     'part.vertices_cm: the outline is listed clockwise; list the vertices counterclockwise '
     '(paper numbering), e.g. reversed: [[6, 8], [0, 0], [6, 0]]'),
    ('{vertices_cm: [[0, 0], [1, 0]]}',
     'part.vertices_cm: fewer than 3 distinct points (2); give at least 3 distinct points, '
     'counterclockwise'),
    ('{vertices_cm: abc}',
     "part.vertices_cm: not a list of [x, y] pairs: 'abc'; give vertices as [[x0, y0], "
     '[x1, y1], ...] in centimetres'),
    ('{vertices_cm: [[6, 0], [6, 8], [0, 0]], cm_cm: [1]}',
     'part.cm_cm: must be two finite numbers, got [0.01] (numbers converted to metres); give '
     'the centre of mass as [x, y] in centimetres'),
    ('{vertices_cm: [[6, 0], [6, 8], [0, 0]], cm_cm: [6, 8]}',
     'part.cm_cm: the centre of mass [0.06, 0.08] is not strictly inside the convex hull '
     '(distance -0 m to edge E0) (numbers converted to metres); move the centre of mass '
     'inside the part, or omit it to use the centroid'),
])
def test_scene_part_errors_name_the_key_the_file_used(tmp_path, part, message):
    """A part given in centimetres used to be reported as part.vertices / part.cm, in metres."""
    path = _scene_file(tmp_path, SCENE.replace(
        'part: {vertices: [[0.06, 0.0], [0.06, 0.08], [0.0, 0.0]]}', 'part: ' + part))
    assert _load_error(path) == f'{path}: {message}'


def test_scene_release_speed_in_degrees_is_named_as_written(tmp_path):
    """Used to say 'throw.release_speed: must be > 0 rad/s, got -0.0873' for -5 deg/s."""
    path = _scene_file(tmp_path, SCENE.replace('release_speed: 5.5851',
                                               'release_speed_deg: -5'))
    assert _load_error(path) == (f'{path}: throw.release_speed_deg: must be > 0 deg/s, got -5; '
                                 'give the arm speed at release, e.g. 320')


def test_scene_start_with_an_edge_and_no_radius_is_valid(tmp_path):
    """Used to fail with 'R must be a finite number of metres, got inf' at load time."""
    from throwmap import load_scene
    scene = load_scene(_scene_file(tmp_path, SCENE + 'start: {edge: 1}\n'))
    assert scene.default_start() == (1, pytest.approx(1.5 * 0.0546666666666667))


@pytest.mark.parametrize('start, message', [
    ("{edge: '1', R: 0.1}", "start.edge: edge must be an integer, got '1'; pick a stable edge"),
    ('{edge: 5}', 'start.edge: edge 5 does not exist: the part has edges 0..2; pick a stable '
     'edge'),
    ('{R: 0.01}', 'start: no dynamic grasp on edge 0 at R = 0.01 m: bound (3) (line of force '
     'passes right of the right vertex) needs R >= 0.0160417 m (short by 0.00604 m); throw '
     'from R >= R_grasp; pick a start inside the domain of f'),
])
def test_scene_start_is_checked_as_it_will_be_used(tmp_path, start, message):
    """A start with only R (on the default edge) used not to be checked at all."""
    path = _scene_file(tmp_path, SCENE + f'start: {start}\n')
    assert _load_error(path) == f'{path}: {message}'
