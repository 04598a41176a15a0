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
Hostile scene files and parts (issue 10, items 5 and 7): limits checked before the work.

Each case used to hang (billion laughs, a million vertices), end in an uncaught RecursionError
(deep nesting), allocate gigabytes (100,000 vertices: n x n tables), or name the wrong problem
(a bow tie and huge coordinates were "all points on one line"; 1e308 was "not a number").
"""

import io
import math
import subprocess
import sys

import numpy as np
import pytest
from throwmap import InputError, load_scene, Part
from throwmap.cli import main
from throwmap.part import MAX_COORDINATE, MAX_VERTICES
from throwmap.scene import MAX_ALIASES, MAX_DEPTH, MAX_SCENE_BYTES, MAX_VALUES, read_yaml
from throwmap_testing import TRIANGLE_VERTICES

HEAD = 'name: x\narm: {offset: -0.005}\nthrow: {release_speed: 5.5851}\ngravity: -9.66\n'
TRIANGLE = f'part: {{vertices: {TRIANGLE_VERTICES}}}\n'


def write(tmp_path, text, name='scene.yaml'):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def laughs(levels=9):
    """Return a billion-laughs scene: 10 ** (levels + 1) numbers from a 700-byte file."""
    rows = ['  - &a0 [' + ', '.join(['0.1'] * 10) + ']']
    rows += [f'  - &a{k} [' + ', '.join([f'*a{k - 1}'] * 10) + ']' for k in range(1, levels + 1)]
    return HEAD + 'description:\n' + '\n'.join(rows) + f'\npart: {{vertices: *a{levels}}}\n'


def polygon(n, radius=0.05):
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.stack([radius * np.cos(t), radius * np.sin(t)], axis=1)


def test_billion_laughs_stops_at_the_value_limit(tmp_path):
    """Used to hang every loader (RSS 1-2.9 GB after 60 s); run in a child to bound a hang."""
    path = write(tmp_path, laughs())
    child = subprocess.run(
        [sys.executable, '-c', 'import sys; from throwmap import load_scene\n'
         'try:\n    load_scene(sys.argv[1])\nexcept ValueError as e:\n    print(e)',
         path], capture_output=True, text=True, timeout=120)
    assert child.returncode == 0, child.stderr
    assert child.stdout.startswith(f'{path}: holds more than {MAX_VALUES} values (aliases '
                                   'expanded) (line ')
    assert 'do not alias big lists again and again' in child.stdout


def test_a_small_aliased_scene_still_loads(tmp_path):
    path = write(tmp_path, HEAD + f'description: &d text\npart: &p {{vertices: '
                 f'{TRIANGLE_VERTICES}}}\nsensor: {{goal_edge: 1}}\n')
    assert load_scene(path).part.n == 3


@pytest.mark.parametrize('depth', [MAX_DEPTH + 1, 5000])
def test_deep_nesting_is_refused_not_a_recursion_error(tmp_path, depth):
    path = write(tmp_path, HEAD + 'part: {vertices: ' + '[' * depth + ']' * depth + '}\n')
    with pytest.raises(InputError) as err:
        load_scene(path)
    assert str(err.value) == (
        f'{path}: nests lists/mappings more than {MAX_DEPTH} levels deep (line 5); the limit is '
        'there because no scene comes near it; a scene needs 4 or 5 levels; check the brackets')


def test_an_alias_inside_its_own_anchor_is_refused(tmp_path):
    path = write(tmp_path, HEAD + 'part: {vertices: &v [*v, [0, 0]]}\n')
    with pytest.raises(InputError, match=r'alias \*v refers to the node that contains it'):
        load_scene(path)


def test_too_many_aliases(tmp_path):
    rows = ''.join('  - *n\n' for _ in range(MAX_ALIASES + 1))
    path = write(tmp_path, HEAD + TRIANGLE + 'description:\n  - &n 1\n' + rows)
    with pytest.raises(InputError, match=f'uses more than {MAX_ALIASES} aliases'):
        load_scene(path)


def test_file_size_limit_before_parsing(tmp_path):
    path = write(tmp_path, HEAD + TRIANGLE + '#' * MAX_SCENE_BYTES + '\n')
    with pytest.raises(InputError) as err:
        load_scene(path)
    assert str(err.value) == (f'{path}: is larger than {MAX_SCENE_BYTES} bytes, the limit (a '
                              'scene is a few KB); give a scene file; a part outline has at '
                              f'most {MAX_VERTICES} points')


def test_a_scene_file_of_a_million_vertices_is_refused(tmp_path):
    """It ran on (one million vertices: n x n tables of 8 TB)."""
    verts = ','.join('[0.05,0.01]' for _ in range(1_000_000))
    path = write(tmp_path, HEAD + f'part: {{vertices: [{verts}]}}\n')
    with pytest.raises(InputError, match='is larger than'):
        load_scene(path)


@pytest.mark.parametrize('n', [MAX_VERTICES + 1, 100_000])
def test_part_refuses_more_vertices_than_the_limit_before_any_work(n):
    """100,000 vertices failed after 20 s allocating 2 GiB (U, V are n x n)."""
    with pytest.raises(InputError) as err:
        Part(polygon(n).tolist())
    assert str(err.value) == (
        f'part.vertices: has {n} points; the limit is {MAX_VERTICES} (a part for this feeder '
        f'has a handful of corners); simplify the outline to at most {MAX_VERTICES} points '
        '(only its convex hull touches the arm)')


def test_a_part_at_the_vertex_limit_is_a_regular_polygon():
    """At the limit the part is still built, and its mass properties are the polygon's."""
    n = MAX_VERTICES
    part = Part(polygon(n).tolist())
    # Regular n-gon of circumradius r: area n r^2 sin(2 pi / n) / 2, rho^2 = r^2 (2 + cos) / 6.
    r, a = 0.05, 2.0 * math.pi / n
    assert part.area == pytest.approx(n * r * r * math.sin(a) / 2.0, rel=1e-12)
    assert part.rho2 == pytest.approx(r * r * (2.0 + math.cos(a)) / 6.0, rel=1e-9)
    assert part.stable_edges == list(range(n))
    # k_cw from the linear formula equals the all-pairs one it replaced.
    rel = part.vertices - part.cm
    dots = rel @ rel.T
    nxt = (np.arange(n) + 1) % n
    assert np.allclose(part.k_cw, (part.rho2 + dots[np.arange(n), nxt])
                       / (part.rho2 + dots[nxt, nxt]), rtol=1e-14)


# -------------------------------------------------------------- what is wrong, said plainly
@pytest.mark.parametrize('vertices, edges', [
    ([[0, 0], [0.01, 0.01], [0.01, 0], [0, 0.01]], (0, 2)),               # bow tie
    ([[0, 0], [0.02, 0], [0.02, 0.02], [0.01, 0.0], [0, 0.02]], (0, 2)),   # touches edge 0
    ([[0, 0], [0.02, 0], [0.01, 0], [0.01, 0.01]], (0, 1)),                 # folds back on itself
])
def test_a_self_intersecting_outline_names_the_edges(vertices, edges):
    with pytest.raises(InputError) as err:
        Part(vertices)
    i, j = edges
    n = len(vertices)
    assert str(err.value) == (
        f'part.vertices: the outline crosses itself: its edge from point {i} to {(i + 1) % n} '
        f'meets its edge from point {j} to {(j + 1) % n}; list the points in order around the '
        'part, counterclockwise, so that no two edges cross or touch')


def test_a_simple_non_convex_outline_is_still_accepted():
    star = polygon(40) * np.where(np.arange(40) % 2, 0.6, 1.0)[:, None]
    assert Part(star.tolist()).n == 20       # the hull: the star's outer points


@pytest.mark.parametrize('scale', [1e200, 1e155, 2 * MAX_COORDINATE])
def test_huge_coordinates_are_out_of_range(scale):
    with pytest.raises(InputError) as err:
        Part([[0, 0], [scale, 0], [0, scale]])
    assert str(err.value) == (
        f'part.vertices: point 1 {[float(scale), 0.0]} is out of range: coordinates are limited '
        f'to +-{MAX_COORDINATE:g} m; give the vertices in metres (a part for this feeder is '
        'centimetres across)')


def test_a_microscopic_part_is_refused_with_its_size():
    with pytest.raises(InputError, match=r'the outline is 1e-200 m across; the smallest part '):
        Part([[0, 0], [1e-200, 0], [0, 1e-200]])


def test_collinear_points_still_say_one_line():
    with pytest.raises(InputError, match=r'zero area \(all points on one line\)'):
        Part([[0, 0], [0.01, 0], [0.03, 0]])


# ------------------------------------------------------------------ YAML 1.1 numbers
def test_exponent_numbers_yaml_1_1_misses_are_numbers(tmp_path):
    path = write(tmp_path, 'a: 1e308\nb: 1E-3\nc: -5e-3\nd: 1.5e+2\ne: .5E1\nf: 2.5e3\n'
                 "g: 1e3x\nh: e5\ni: '1e3'\nj: 1e309\n")
    values = read_yaml(path)
    assert values == {'a': 1e308, 'b': 1e-3, 'c': -5e-3, 'd': 150.0, 'e': 5.0, 'f': 2500.0,
                      'g': '1e3x', 'h': 'e5', 'i': '1e3', 'j': math.inf}


def test_a_scene_in_e_notation_loads_and_strings_are_still_refused(tmp_path):
    path = write(tmp_path, HEAD.replace('-0.005', '-5E-3').replace('-9.66', '-966e-2')
                 + 'part: {vertices: [[6e-2, 0], [6e-2, 8e-2], [0, 0]]}\n')
    scene = load_scene(path)
    assert (scene.h, scene.gravity) == (-0.005, -9.66)
    assert scene.part.vertices.tolist() == [[0.06, 0.0], [0.06, 0.08], [0.0, 0.0]]
    bad = write(tmp_path, HEAD.replace('-0.005', '-5e-3x') + TRIANGLE, 'bad.yaml')
    with pytest.raises(InputError, match=r"arm.offset: must be a number, got '-5e-3x'"):
        load_scene(bad)
    huge = write(tmp_path, HEAD.replace('-0.005', '-1e309') + TRIANGLE, 'huge.yaml')
    with pytest.raises(InputError, match=r'arm.offset: must be finite, got -inf'):
        load_scene(huge)


def test_the_cli_reports_the_limit_as_one_line(tmp_path, monkeypatch):
    """The CLI reads through the same loader: one line, exit 2, no traceback."""
    path = write(tmp_path, HEAD + 'part: {vertices: ' + '[' * 3000 + ']' * 3000 + '}\n')
    err = io.StringIO()
    monkeypatch.setattr(sys, 'stderr', err)
    assert main(['grasp', path]) == 2
    assert err.getvalue().strip().splitlines() == [
        f'throwmap: error: {path}: nests lists/mappings more than {MAX_DEPTH} levels deep '
        '(line 5); the limit is there because no scene comes near it; a scene needs 4 or 5 '
        'levels; check the brackets']
