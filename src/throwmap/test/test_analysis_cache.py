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
The analysis cache (throwmap.analysis_cache, issue 21 item 4).

A hit is the computation bit for bit (shipped scenes, a noisy one included); anything that
changes the result changes the key; a corrupt, truncated, mistyped, inconsistent, foreign or
others-writable entry is ignored and recomputed, never an exception; concurrent processes leave
one valid entry and compute it once; THROWMAP_CACHE=off turns it off. Every test has a cache
directory of its own (tmp_path), never the user's.
"""

import base64
import dataclasses
import hashlib
import json
import logging
import math
import multiprocessing
import os
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import pytest
from throwmap import analyse, analysis_cache, load_scene
import throwmap.analysis as analysis_module
from throwmap_testing import SCENES

# Small analyses where the test is about the cache, not the scene (a second each).
SMALL = {'throws': 2000, 'grid_radii': 8, 'grid_throws': 60}


@pytest.fixture
def cache(monkeypatch, tmp_path):
    """Give this test a cache directory of its own (not yet made: the cache makes it, 0700)."""
    path = tmp_path / 'cache'
    monkeypatch.setenv('THROWMAP_CACHE_DIR', str(path))
    monkeypatch.delenv('THROWMAP_CACHE', raising=False)
    return path


@pytest.fixture
def computed(monkeypatch):
    """Count the computations behind analyse (a hit computes nothing)."""
    calls = []
    real = analysis_module._analyse

    def counting(*args):
        calls.append(args[0].source)
        return real(*args)

    monkeypatch.setattr(analysis_module, '_analyse', counting)
    return calls


def same(a, b, path='analysis'):
    """Assert a == b bit for bit: types, dataclass fields, arrays' dtype/shape/bytes, floats."""
    assert type(a) is type(b), f'{path}: {type(a).__name__} != {type(b).__name__}'
    if dataclasses.is_dataclass(a):
        for f in dataclasses.fields(a):
            same(getattr(a, f.name), getattr(b, f.name), f'{path}.{f.name}')
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, path
        assert a.tobytes() == b.tobytes(), f'{path}: arrays differ'
    elif isinstance(a, dict):
        assert list(a) == list(b), f'{path}: keys {list(a)} != {list(b)}'
        for k in a:
            same(a[k], b[k], f'{path}[{k!r}]')
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), path
        for k, (x, y) in enumerate(zip(a, b)):
            same(x, y, f'{path}[{k}]')
    elif isinstance(a, float):
        assert a.hex() == b.hex(), f'{path}: {a!r} != {b!r}'
    else:
        assert a == b, f'{path}: {a!r} != {b!r}'


def entries(folder):
    return sorted(pathlib.Path(folder).glob('analysis-*.json'))


def rewrite(path, change):
    """Change an entry's analysis body with ``change(body)``; keep its checksum valid."""
    doc = json.loads(path.read_text())
    change(doc['analysis'])
    doc['sha256'] = hashlib.sha256(json.dumps(doc['analysis'], sort_keys=True)
                                   .encode()).hexdigest()
    path.write_text(json.dumps(doc))


def field(body, name):
    """Return the typed form of one Analysis field in an entry's body."""
    return dict(body['d'])[name]


def set_field(body, name, value):
    for pair in body['d']:
        if pair[0] == name:
            pair[1] = value


# --------------------------------------------------------------------------- hit == miss
@pytest.mark.parametrize('name, arguments', [
    ('triangle', {}),                    # the base model, analyse's defaults
    ('bracket', {}),
    ('house', SMALL),                    # release_noise, sensor_noise, finite_carry: seeded
    ('experiment', SMALL),               # backplate_friction, finite_arm: the event simulator
])
def test_a_hit_is_the_computation_bit_for_bit(cache, computed, name, arguments):
    scene = load_scene(str(SCENES / f'{name}.yaml'))
    miss = analyse(scene, **arguments)
    draws_after_miss = scene.model.rng.standard_normal(4) if scene.model.stochastic else None
    assert len(computed) == 1 and len(entries(cache)) == 1
    again = load_scene(str(SCENES / f'{name}.yaml'))
    hit = analyse(again, **arguments)
    assert len(computed) == 1, 'the second analysis was computed, not read'
    same(miss, hit)
    assert hit.as_dict() == miss.as_dict()
    if draws_after_miss is not None:
        # The noisy model's generator is left where the computation leaves it.
        assert again.model.rng.standard_normal(4).tobytes() == draws_after_miss.tobytes()
    fresh = analysis_module._analyse(load_scene(str(SCENES / f'{name}.yaml')),
                                     arguments.get('throws', 10_000),
                                     arguments.get('grid_radii', 50),
                                     arguments.get('grid_throws', 200), None)
    same(analysis_module.Analysis(**fresh), hit)


def test_the_directory_and_entries_are_private(cache):
    analyse(load_scene(str(SCENES / 'triangle.yaml')), **SMALL)
    assert oct(cache.stat().st_mode & 0o777) == oct(0o700)
    (entry,) = entries(cache)
    assert entry.stat().st_mode & 0o077 == 0
    assert not list(cache.glob('.analysis-*'))     # no temporary file left


# --------------------------------------------------------------------------- the key
def test_the_same_content_elsewhere_hits(cache, computed, tmp_path):
    copy = tmp_path / 'renamed.yaml'
    shutil.copy(SCENES / 'triangle.yaml', copy)
    analyse(load_scene(str(SCENES / 'triangle.yaml')), **SMALL)
    analyse(load_scene(str(copy)), **SMALL)
    assert len(computed) == 1


def test_a_changed_number_misses(cache, computed, tmp_path):
    text = (SCENES / 'triangle.yaml').read_text()
    assert 'release_speed: 5.5851' in text
    changed = tmp_path / 'triangle.yaml'
    changed.write_text(text.replace('release_speed: 5.5851', 'release_speed: 5.5852'))
    a = analyse(load_scene(str(SCENES / 'triangle.yaml')), **SMALL)
    b = analyse(load_scene(str(changed)), **SMALL)
    assert len(computed) == 2 and len(entries(cache)) == 2
    assert a.limit_set.bands != b.limit_set.bands


def test_arguments_seed_and_a_scene_changed_after_loading_miss(cache, computed):
    house = str(SCENES / 'house.yaml')
    analyse(load_scene(house), **SMALL)
    analyse(load_scene(house, seed=8), **SMALL)             # another seed
    analyse(load_scene(house), **dict(SMALL, grid_throws=61))
    scene = load_scene(house)
    scene.sensor_radius = 0.2                               # changed after loading
    moved = analyse(scene, **SMALL)
    assert len(computed) == 4
    assert moved.sensor.radius == 0.2


def test_another_code_version_misses(cache, computed, monkeypatch):
    scene = load_scene(str(SCENES / 'triangle.yaml'))
    analyse(scene, **SMALL)
    monkeypatch.setattr(analysis_cache, '_code_version', 'another version of throwmap')
    analyse(scene, **SMALL)
    assert len(computed) == 2 and len(entries(cache)) == 2


def test_an_entry_of_another_code_version_under_the_key_is_ignored(cache, computed):
    scene = load_scene(str(SCENES / 'triangle.yaml'))
    analyse(scene, **SMALL)
    (entry,) = entries(cache)
    doc = json.loads(entry.read_text())
    doc['code'] = 'another version'
    entry.write_text(json.dumps(doc))
    analyse(scene, **SMALL)
    assert len(computed) == 2
    assert json.loads(entry.read_text())['code'] == analysis_cache.code_version()


def test_the_code_version_covers_every_source_file():
    here = pathlib.Path(analysis_cache.__file__).parent
    assert analysis_cache.code_version() == analysis_cache.code_version()
    sources = list(here.glob('*.py')) + list(here.glob('effects/*.py'))
    assert len(sources) > 30   # orbits, basins, sensor, analysis: not only the compiled ones


# --------------------------------------------------------------------------- bad entries
def _damage_cases():
    def truncate(path):
        data = path.read_bytes()
        path.write_bytes(data[:len(data) // 2])

    def garbage(path):
        path.write_bytes(b'\x80\x04\x95 not json, a pickle perhaps')

    def flip_a_byte(path):             # the checksum catches it
        data = bytearray(path.read_bytes())
        k = data.index(b'"b":"') + 40
        data[k] = ord('A') if data[k] != ord('A') else ord('B')
        path.write_bytes(bytes(data))

    def empty(path):
        path.write_bytes(b'')

    def wrong_type(path):              # the guarantee radius as a string
        def change(body):
            sensor = field(body, 'sensor')
            sensor['v']['guarantee_radius'] = '0.30'
        rewrite(path, change)

    def moved_guarantee(path):         # a plausible float: the sensor redesign catches it
        def change(body):
            sensor = field(body, 'sensor')
            sensor['v']['guarantee_radius'] = {'f': (0.30).hex()}
        rewrite(path, change)

    def widened_band(path):            # bands no longer the tail's extent
        def change(body):
            bands = field(body, 'limit_set')['v']['bands']['d']
            bands[0][1]['t'][1] = {'f': (1.0).hex()}
        rewrite(path, change)

    def shifted_tail(path):            # consistent bands, but not this model's orbit
        def change(body):
            tail = field(body, 'limit_set')['v']['tail_radii']
            radii = np.frombuffer(base64.b64decode(tail['b']), '<f8').copy()
            radii[-3] = np.nextafter(radii[-3], 1.0)
            tail['b'] = base64.b64encode(radii.tobytes()).decode()
        rewrite(path, change)

    def object_array(path):            # an object dtype is never decoded
        def change(body):
            field(body, 'basin')['v']['radii']['a'] = '|O'
        rewrite(path, change)

    def unknown_class(path):           # only LimitSet, Basin, SensorDesign
        def change(body):
            set_field(body, 'pull', {'c': 'Popen', 'v': {'args': 'touch /tmp/pwned'}})
        rewrite(path, change)

    def missing_field(path):
        def change(body):
            body['d'] = [p for p in body['d'] if p[0] != 'radii']
        rewrite(path, change)

    def short_array(path):
        def change(body):
            arr = field(body, 'basin')['v']['status']
            arr['s'] = [arr['s'][0] + 1]
        rewrite(path, change)

    def others_writable(path):
        path.chmod(0o666)

    def symlink(path):
        target = path.with_name('elsewhere.json')
        path.rename(target)
        path.symlink_to(target)

    def foreign_owner(path):
        if os.geteuid() != 0:
            pytest.skip('needs root to give the entry to another user')
        os.chown(path, 12345, 12345)

    return [truncate, garbage, flip_a_byte, empty, wrong_type, moved_guarantee, widened_band,
            shifted_tail, object_array, unknown_class, missing_field, short_array,
            others_writable, symlink, foreign_owner]


@pytest.mark.parametrize('damage', _damage_cases(), ids=lambda f: f.__name__)
def test_a_bad_entry_is_ignored_and_recomputed(cache, computed, damage, caplog):
    scene = load_scene(str(SCENES / 'triangle.yaml'))
    good = analyse(scene, **SMALL)
    entry = entries(cache)[0]
    damage(entry)
    with caplog.at_level(logging.DEBUG, logger='throwmap.analysis_cache'):
        again = analyse(load_scene(str(SCENES / 'triangle.yaml')), **SMALL)
    assert len(computed) == 2, 'the bad entry was used'
    same(good, again)
    assert any('ignored' in r.getMessage() for r in caplog.records)
    # Rewritten: a valid entry of this user, private, and a hit from now on.
    st = os.lstat(entry)
    assert st.st_uid == os.geteuid() and not st.st_mode & 0o077 and entry.is_file()
    analyse(load_scene(str(SCENES / 'triangle.yaml')), **SMALL)
    assert len(computed) == 2


def test_a_directory_open_to_others_is_not_used(cache, computed, caplog):
    cache.mkdir(mode=0o700)
    cache.chmod(0o777)
    scene = load_scene(str(SCENES / 'triangle.yaml'))
    with caplog.at_level(logging.WARNING, logger='throwmap.analysis_cache'):
        analyse(scene, **SMALL)
        analyse(scene, **SMALL)
    assert len(computed) == 2 and not entries(cache)
    assert any('open to others' in r.getMessage() for r in caplog.records)


def test_a_directory_of_another_user_is_not_used(cache, computed):
    if os.geteuid() != 0:
        pytest.skip('needs root to give the directory to another user')
    cache.mkdir(mode=0o700)
    os.chown(cache, 12345, 12345)
    scene = load_scene(str(SCENES / 'triangle.yaml'))
    analyse(scene, **SMALL)
    analyse(scene, **SMALL)
    assert len(computed) == 2 and not entries(cache)


def test_an_unwritable_place_only_costs_the_cache(monkeypatch, tmp_path, computed):
    blocker = tmp_path / 'a-file'
    blocker.write_text('')
    monkeypatch.setenv('THROWMAP_CACHE_DIR', str(blocker / 'cache'))
    an = analyse(load_scene(str(SCENES / 'triangle.yaml')), **SMALL)
    assert len(computed) == 1 and an.sensor.goal_edge == 1


def test_the_decoder_builds_only_plain_values():
    value = {'a': (1, 2.5, None, True, 'x'), 3: [math.inf, -0.0],
             'arr': np.arange(6, dtype=np.int64).reshape(2, 3)}
    back = analysis_cache.decode(json.loads(json.dumps(analysis_cache.encode(value))))
    same(value, back)
    for bad in ({'c': 'Analysis', 'v': {}}, {'a': '|O', 's': [1], 'b': 'AA=='},
                {'x': 1}, {'f': 'not a float'}, {'d': [[1]]}, 1.5):
        with pytest.raises(analysis_cache.EntryError):
            analysis_cache.decode(bad)
    with pytest.raises(analysis_cache.Uncacheable):
        analysis_cache.encode(object())
    source = pathlib.Path(analysis_cache.__file__).read_text()
    assert 'pickle' not in source.replace("'pickle perhaps'", '')


# --------------------------------------------------------------------------- concurrency
CHILD = """
import sys
import throwmap.analysis as a
from throwmap import analyse, load_scene
real = a._analyse
def counting(*args):
    print('computed', flush=True)
    return real(*args)
a._analyse = counting
an = analyse(load_scene(sys.argv[1]), throws=2000, grid_radii=8, grid_throws=60)
print('sensor', an.sensor.radius.hex(), flush=True)
"""


def test_processes_starting_together_compute_once_and_leave_one_entry(cache):
    env = dict(os.environ)
    procs = [subprocess.Popen([sys.executable, '-c', CHILD, str(SCENES / 'bracket.yaml')],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True) for _ in range(4)]
    outs = [p.communicate(timeout=240) for p in procs]
    assert all(p.returncode == 0 for p in procs), [o[1][-2000:] for o in outs]
    computed = sum(o[0].count('computed') for o in outs)
    assert computed == 1, f'{computed} processes computed the analysis'
    radii = {line for o in outs for line in o[0].splitlines() if line.startswith('sensor')}
    assert len(radii) == 1
    (entry,) = entries(cache)
    assert not list(cache.glob('.analysis-*'))
    digest = entry.name[len('analysis-'):-len('.json')]
    scene = load_scene(str(SCENES / 'bracket.yaml'))
    assert digest == analysis_cache.key(scene, **SMALL)
    fields = analysis_cache.read_entry(str(entry), digest)
    redesign = lambda ls, bas: analysis_module._sensor(scene, ls, bas)  # noqa: E731
    analysis_cache.validate(fields, scene, redesign)


def _writer(folder, digest, fields, barrier, rounds):
    barrier.wait()
    for _ in range(rounds):
        assert analysis_cache.write_entry(folder, digest, fields)


def test_concurrent_writers_never_show_a_reader_half_an_entry(cache):
    scene = load_scene(str(SCENES / 'triangle.yaml'))
    analyse(scene, **SMALL)
    (entry,) = entries(cache)
    digest = entry.name[len('analysis-'):-len('.json')]
    fields = analysis_cache.read_entry(str(entry), digest)
    ctx = multiprocessing.get_context('fork')
    barrier = ctx.Barrier(4)
    writers = [ctx.Process(target=_writer, args=(str(cache), digest, fields, barrier, 15))
               for _ in range(3)]
    for w in writers:
        w.start()
    barrier.wait()
    reads = 0
    while any(w.is_alive() for w in writers) or reads < 20:
        same(fields, analysis_cache.read_entry(str(entry), digest), 'read during writes')
        reads += 1
    for w in writers:
        w.join(timeout=60)
        assert w.exitcode == 0
    assert entries(cache) == [entry] and not list(cache.glob('.analysis-*'))


# --------------------------------------------------------------------------- off, and where
@pytest.mark.parametrize('value', ['off', '0', 'false', 'NO'])
def test_the_cache_can_be_turned_off(cache, computed, monkeypatch, value):
    monkeypatch.setenv('THROWMAP_CACHE', value)
    scene = load_scene(str(SCENES / 'triangle.yaml'))
    analyse(scene, **SMALL)
    analyse(scene, **SMALL)
    assert len(computed) == 2 and not cache.exists()


def test_where_the_cache_lives(monkeypatch, tmp_path):
    monkeypatch.delenv('THROWMAP_CACHE_DIR')
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path / 'xdg'))
    assert analysis_cache.directory() == str(tmp_path / 'xdg' / 'throwmap' / 'analysis')
    monkeypatch.delenv('XDG_CACHE_HOME')
    monkeypatch.setenv('HOME', str(tmp_path / 'home'))
    assert analysis_cache.directory() == str(tmp_path / 'home' / '.cache' / 'throwmap'
                                             / 'analysis')


def test_this_test_session_does_not_use_the_users_cache(analysis_cache_dir):
    # conftest.py points the whole session at a directory of its own.
    assert os.environ['THROWMAP_CACHE_DIR'] == str(analysis_cache_dir)
    user = os.path.join(os.path.expanduser('~'), '.cache')
    assert not str(analysis_cache_dir).startswith(user)
