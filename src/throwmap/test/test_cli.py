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

"""The throwmap command line: tables, JSON, stdin batches, errors and exit codes."""

import io
import json
import math
import subprocess
import sys

import pytest
from throwmap.cli import main
from throwmap_testing import SCENES

TRIANGLE = str(SCENES / 'triangle.yaml')


def run(*argv):
    out = io.StringIO()
    code = main(list(argv), out=out)
    return code, out.getvalue()


def test_grasp_json_fields():
    code, text = run('grasp', TRIANGLE, '--json')
    assert code == 0
    data = json.loads(text)
    edges = {e['edge']: e for e in data['edges']}
    assert set(edges) == {0, 1, 2}
    for e in edges.values():
        assert {'edge', 'stable', 'R_grasp', 'mu_min'} <= set(e)
    assert edges[2]['R_grasp'] == pytest.approx(0.17 / 3)
    assert round(data['mu_min'], 3) == 0.382


def test_grasp_table_is_readable():
    code, text = run('grasp', TRIANGLE)
    assert code == 0
    assert 'R_grasp (cm)' in text and '5.667' in text and 'mu >= 0.382' in text


def test_orbit_json_states_have_edge_R_kind():
    code, text = run('orbit', TRIANGLE, '--edge', '1', '--R', '0.12', '--throws', '20',
                     '--json')
    assert code == 0
    states = json.loads(text)['states']
    assert len(states) == 21
    assert states[0] == {'throw': 0, 'edge': 1, 'R': 0.12, 'kind': None}
    assert all(s['kind'] in ('jog', 'flip') for s in states[1:])
    assert states[1]['edge'] == 1 and states[1]['R'] > 0.12


def test_throw_batch_from_stdin_keeps_order_and_reports_errors():
    lines = ['{"edge": 1, "R": 0.12}', '{"edge": 2, "R": 0.01}', 'not json',
             '{"edge": 0, "R": 0.15}', '{"edge": 1}', '{"edge": 1, "R": 0.2, "x": 1}']
    proc = subprocess.run([sys.executable, '-m', 'throwmap.cli', 'throw', TRIANGLE, '--json'],
                          input='\n'.join(lines) + '\n', capture_output=True, text=True,
                          timeout=120)
    rows = [json.loads(x) for x in proc.stdout.splitlines()]
    assert len(rows) == 6
    assert rows[0]['edge'] == 1 and rows[0]['kind'] == 'jog' and rows[0]['R'] > 0.12
    assert 'bound (3)' in rows[1]['error']
    assert rows[2]['error'].startswith('line 3: ')
    assert rows[3]['kind'] in ('jog', 'flip')
    assert 'expected an object with "edge" and "R"' in rows[4]['error']
    assert 'unknown keys' in rows[5]['error']
    assert proc.returncode == 1


def test_single_throw_json_carries_impacts():
    code, text = run('throw', TRIANGLE, '--edge', '1', '--R', '0.2', '--json')
    data = json.loads(text)
    assert code == 0 and data['impacts'] and data['flight_time'] > 0


def test_limit_set_and_basin_json():
    code, text = run('limit-set', TRIANGLE, '--throws', '4000', '--json')
    data = json.loads(text)
    assert code == 0 and data['pattern'] == [0, 2, 1]
    assert set(data['bands']) == {'0', '1', '2'}
    code, text = run('basin', TRIANGLE, '--radii', '5', '--throws', '400', '--json', '--quiet')
    data = json.loads(text)
    assert code == 0 and data['summary'] == {'0-2-1': 15}


def test_plot_writes_pngs(tmp_path):
    code, text = run('plot', TRIANGLE, '--out', str(tmp_path), '--throws', '50',
                     '--orbit-throws', '60', '--quiet')
    assert code == 0
    pngs = sorted(p.name for p in tmp_path.iterdir())
    assert pngs == ['triangle_basin.png', 'triangle_cycle.png', 'triangle_orbit.png']
    for p in tmp_path.iterdir():
        assert p.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n' and p.stat().st_size > 10_000


@pytest.mark.parametrize('argv, words', [
    (['grasp', 'nope.yaml'], 'no such file'),
    (['throw', TRIANGLE, '--edge', '2', '--R', '0.01'], 'no dynamic grasp on edge 2'),
    (['throw', TRIANGLE, '--edge', '1'], '--edge and --R go together'),
    (['orbit', TRIANGLE, '--throws', '0'], '--throws must be >= 1'),
    # 10^12 states would be 7 TiB: refused, not a MemoryError traceback
    (['orbit', TRIANGLE, '--throws', str(10 ** 12)], '--throws must be at most 10,000,000'),
    (['basin', TRIANGLE, '--radii', str(10 ** 9)], '--radii must be at most 100,000'),
    (['plot', TRIANGLE, '--orbit-throws', str(10 ** 8)], '--orbit-throws must be at most'),
    # --out a file: refused before the work, for every command that writes there
    (['plot', TRIANGLE, '--out', TRIANGLE], 'is a file, not a directory'),
    (['design-search', TRIANGLE, '--out', TRIANGLE], 'is a file, not a directory'),
    (['funnel', TRIANGLE, '--speeds', '320', '--out', TRIANGLE], 'is a file, not a directory'),
])
def test_errors_exit_2_with_a_message(argv, words, capsys):
    code, _ = run(*argv)
    assert code == 2
    err = capsys.readouterr().err
    assert err.startswith('throwmap: error: ') and words in err


def _expected_row(model, line, lineno):
    """Return what the batch answered for a line before it was rebuilt (model.throw per line)."""
    from throwmap import ThrowmapError
    try:
        state = json.loads(line)
        if not isinstance(state, dict) or 'edge' not in state or 'R' not in state:
            raise ValueError('expected an object with "edge" and "R"')
        unknown = set(state) - {'edge', 'R'}
        if unknown:
            raise ValueError(f'unknown keys {sorted(unknown)}; allowed: edge, R')
        res = model.throw(state['edge'], state['R'])
    except ThrowmapError as exc:
        return {'error': str(exc)}
    except ValueError as exc:
        return {'error': f'line {lineno}: {exc}'}
    return {'edge': res.edge, 'R': None if math.isnan(res.R) else res.R, 'kind': res.kind,
            'flight_time': res.flight_time, 'net_rotation': res.net_rotation,
            'impacts': len(res.impacts), 'first_contact_vertex': res.first_contact_vertex}


@pytest.mark.parametrize('scene_file', ['triangle.yaml', 'house.yaml', 'experiment.yaml'])
def test_batch_answers_each_line_as_a_throw_would_in_order(scene_file):
    import numpy as np
    from throwmap import load_scene
    from throwmap.cli import BATCH_BLOCK, throw_batch
    rng = np.random.default_rng(5)
    odd = ['not json', '{"edge": 1}', '{"edge": 1, "R": 0.2, "x": 1}', '{"edge": 1.0, "R": 0.2}',
           '{"edge": true, "R": 0.2}', '{"edge": 1, "R": "0.2"}', '{"edge": 9, "R": 0.2}',
           '{"edge": 1, "R": 1e400}', '{"R": 0.2, "edge": 1}', '{"edge": 01, "R": 0.2}',
           '   ', '{ "edge" :2 ,"R":0.2 }', '{"edge": 1, "R": 1}', '{"edge": 1, "R": 0.02}',
           '{"edge": 0, "R": 0.45}', '{"edge": -1, "R": 0.2}', '[1, 2]', '{"edge": 1, "R": -0.2}']
    lines = []
    for k in range(2 * BATCH_BLOCK + 300):
        if k % 97 == 0:
            lines.append(odd[(k // 97) % len(odd)])
        else:
            lines.append(json.dumps({'edge': int(rng.integers(0, 5)),
                                     'R': float(rng.uniform(0.05, 0.42))}))
    text = '\n'.join(lines) + '\n'
    batch = load_scene(str(SCENES / scene_file))
    out = io.StringIO()
    code = throw_batch(batch.model, io.StringIO(text), out)
    got = [json.loads(x) for x in out.getvalue().splitlines()]
    single = load_scene(str(SCENES / scene_file))   # same seed: the same draws, in order
    expected = [_expected_row(single.model, line, k + 1) for k, line in enumerate(lines)
                if line.strip()]
    assert code == 1 and len(got) == len(expected)
    assert got == expected
    assert sum('error' in g for g in got) > len(odd)


def test_batch_streams_its_answers_block_by_block():
    from throwmap.cli import BATCH_BLOCK
    proc = subprocess.Popen([sys.executable, '-m', 'throwmap.cli', 'throw', TRIANGLE, '--json'],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        proc.stdin.write('{"edge": 1, "R": 0.12}\n' * BATCH_BLOCK)
        proc.stdin.flush()
        # The first block is answered while stdin is still open.
        first = [proc.stdout.readline() for _ in range(BATCH_BLOCK)]
        assert all(json.loads(x)['kind'] == 'jog' for x in first)
        proc.stdin.write('{"edge": 2, "R": 0.01}\n')
        proc.stdin.close()
        rest = proc.stdout.read().splitlines()
        assert len(rest) == 1 and 'bound (3)' in json.loads(rest[0])['error']
        assert proc.wait(timeout=60) == 1
    finally:
        proc.kill()
