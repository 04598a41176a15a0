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
A disk cache of scene analyses: computed once per scene content and code version (issue 21).

``throwmap.analyse(scene)`` asks :func:`cached` first; a launch's 4-5 processes analysing one
scene then pay for it once. docs/physics.md ("The analysis cache") has the decisions.

Key: a SHA-256 over the scene's parsed content (``scene.data``, typed, floats exact), its
seed, the quantities ``analyse`` reads off the scene and its model (start, goal edge, sensor
footprint and radius, h, w, g, mu, the part's vertices and centre of mass: a scene changed after
loading changes the key), ``analyse``'s arguments, and the code version: a hash of every
throwmap source file, numpy's, numba's and Python's versions and the machine.

Where: ``$THROWMAP_CACHE_DIR``, else ``$XDG_CACHE_HOME/throwmap/analysis``, else
``~/.cache/throwmap/analysis``; created mode 0700. A directory owned by another user or open to
group or others, and an entry owned by another user or writable by group or others, are
refused (never read). ``THROWMAP_CACHE=off`` (or 0, no, false) turns the cache off.

Format: one JSON file per key, written to a temporary file and renamed (a reader never sees a
half-written entry). Values are typed (tuples, dicts with int keys, floats as their exact hex,
arrays of a few numeric dtypes as their raw bytes, the three result classes); nothing else
decodes, so an entry can hold no code. On load the entry must name its own key, parse, pass the
schema (types, shapes, the result classes' fields), and agree with the physics: the limit set's
bands are the tail's extent, the sensor design recomputed from the cached limit set and basin
is the cached one, and (deterministic scenes) the model maps the tail's last states onto their
successors bit for bit. Anything else is ignored with a log note and recomputed. One process
computes a missing entry while the others wait on its lock file (flock; released by the kernel
if it dies), so a launch computes a cold analysis once instead of 4-5 times on shared cores.
"""

import base64
import dataclasses
import errno
import fcntl
import glob
import hashlib
import json
import logging
import math
import os
import platform
import stat
import sys
import tempfile
import time

import numpy as np

from .basins import Basin
from .jit import _numba, HERE
from .orbits import LimitSet
from .sensor import SensorDesign

try:    # numba's code generator: its machine code depends on the host CPU
    from llvmlite import binding as _llvm
except ImportError:     # pragma: no cover - without numba
    _llvm = None

LOG = logging.getLogger('throwmap.analysis_cache')

FORMAT = 1                      # the entry format; part of the key
MAX_ENTRY_BYTES = 64 << 20      # larger entries are neither written nor read
LOCK_WAIT_S = 600.0             # longest wait for another process's computation
SPOT_CHECKS = 4                 # tail transitions re-thrown on load (deterministic scenes)
CLASSES = {cls.__name__: cls for cls in (LimitSet, Basin, SensorDesign)}
DTYPES = frozenset(('<f8', '<i8', '<f4', '<i4', '|b1', '|u1', '|i1'))
FIELDS = ('start', 'limit_set', 'radii', 'basin', 'sensor', 'stochastic', 'pull')
OFF = frozenset(('off', '0', 'no', 'false'))
# The typed forms of encode(): their keys -> the form.
FORMS = {frozenset('f'): 'f', frozenset('t'): 't', frozenset('d'): 'd',
         frozenset('asb'): 'a', frozenset('cv'): 'c'}

_code_version = None
_warned = set()


class EntryError(ValueError):
    """A cache entry that cannot be used: unreadable, foreign, malformed or inconsistent."""


class Uncacheable(TypeError):
    """A value the entry format does not hold (the analysis is then not cached)."""


# --------------------------------------------------------------------------- the key
def code_version():
    """Return the hash of every throwmap source file and of what its results depend on."""
    global _code_version
    if _code_version is None:
        digest = hashlib.sha256()
        paths = sorted(glob.glob(os.path.join(HERE, '*.py'))
                       + glob.glob(os.path.join(HERE, 'effects', '*.py')))
        for path in paths:
            with open(path, 'rb') as fh:
                text = fh.read()
            digest.update(os.path.relpath(path, HERE).encode() + b'\0')
            digest.update(hashlib.sha256(text).digest())
        cpu = _llvm.get_host_cpu_name() if _llvm is not None and _numba is not None else ''
        platform_id = [sys.version, np.__version__, getattr(_numba, '__version__', 'none'),
                       platform.machine(), cpu]
        digest.update(json.dumps(platform_id).encode())
        _code_version = digest.hexdigest()
    return _code_version


def key(scene, **arguments):
    """
    Return the cache key of ``analyse(scene, **arguments)`` (hex), or None if not cacheable.

    None: the cache is off, or the scene is not a loaded Scene (no ``data``) or holds values
    the key cannot state exactly.
    """
    if not enabled():
        return None
    data = getattr(scene, 'data', None)
    if not isinstance(data, dict):
        return None
    try:
        model = scene.model
        part = model.part
        material = encode({
            'format': FORMAT,
            'code': code_version(),
            'scene': data,
            'seed': scene.seed,
            'start': tuple(scene.default_start()),
            'goal_edge': scene.goal_edge,
            'footprint': scene.sensor_footprint,
            'sensor_radius': scene.sensor_radius,
            'model': [type(model).__name__, float(model.h), float(model.w), float(model.g),
                      None if model.mu is None else float(model.mu),
                      np.ascontiguousarray(part.vertices, dtype='<f8'),
                      np.ascontiguousarray(part.cm, dtype='<f8'), float(part.rho2),
                      float(getattr(model, 'arm_length', math.inf))],
            'arguments': dict(sorted(arguments.items())),
        })
    except Uncacheable as exc:
        LOG.debug('analysis cache: scene %s not cached: %s', getattr(scene, 'source', '?'), exc)
        return None
    except Exception as exc:    # a scene of an unexpected kind: no cache, never an error
        LOG.debug('analysis cache: no key for %s: %r', getattr(scene, 'source', '?'), exc)
        return None
    text = json.dumps(material, sort_keys=True, separators=(',', ':'), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def enabled():
    """Tell whether the cache is on (``THROWMAP_CACHE`` is not off, 0, no or false)."""
    return os.environ.get('THROWMAP_CACHE', '').strip().lower() not in OFF


def directory():
    """Return the cache directory's path (not created)."""
    given = os.environ.get('THROWMAP_CACHE_DIR')
    if given:
        return os.path.abspath(given)
    base = os.environ.get('XDG_CACHE_HOME') or os.path.join(os.path.expanduser('~'), '.cache')
    return os.path.join(base, 'throwmap', 'analysis')


# --------------------------------------------------------------------------- values <-> JSON
def encode(value):
    """Return a JSON-able typed form of ``value``; Uncacheable for a type it does not hold."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int) and type(value) is int:
        return value
    if type(value) is float:
        return {'f': value.hex()}
    if isinstance(value, list) and type(value) is list:
        return [encode(v) for v in value]
    if type(value) is tuple:
        return {'t': [encode(v) for v in value]}
    if type(value) is dict:
        return {'d': [[encode(k), encode(v)] for k, v in value.items()]}
    if type(value) is np.ndarray:
        dtype = value.dtype.newbyteorder('<') if value.dtype.byteorder == '>' else value.dtype
        if dtype.str not in DTYPES:
            raise Uncacheable(f'array of dtype {value.dtype}')
        raw = np.ascontiguousarray(value, dtype=dtype).tobytes()
        return {'a': dtype.str, 's': list(value.shape), 'b': base64.b64encode(raw).decode()}
    if type(value).__name__ in CLASSES and type(value) is CLASSES[type(value).__name__]:
        return {'c': type(value).__name__,
                'v': {f.name: encode(getattr(value, f.name))
                      for f in dataclasses.fields(value)}}
    raise Uncacheable(f'a value of type {type(value).__name__}')


def decode(obj, depth=0):
    """Return the value of a typed form; EntryError for anything :func:`encode` never writes."""
    if depth > 40:
        raise EntryError('nested too deeply')
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if type(obj) is int:
        return obj
    if type(obj) is list:
        return [decode(v, depth + 1) for v in obj]
    if type(obj) is not dict:
        raise EntryError(f'unexpected {type(obj).__name__}')
    tag = FORMS.get(frozenset(obj))
    if tag == 'f' and type(obj['f']) is str:
        try:
            return float.fromhex(obj['f'])
        except ValueError:
            raise EntryError(f'bad float {obj["f"]!r}') from None
    if tag == 't' and type(obj['t']) is list:
        return tuple(decode(v, depth + 1) for v in obj['t'])
    if tag == 'd' and type(obj['d']) is list:
        out = {}
        for pair in obj['d']:
            if type(pair) is not list or len(pair) != 2:
                raise EntryError('bad dict item')
            k = decode(pair[0], depth + 1)
            if not isinstance(k, (int, str, float, tuple)) or k in out:
                raise EntryError('bad dict key')
            out[k] = decode(pair[1], depth + 1)
        return out
    if tag == 'a':
        return _array(obj)
    if tag == 'c' and obj['c'] in CLASSES and type(obj['v']) is dict:
        cls = CLASSES[obj['c']]
        names = [f.name for f in dataclasses.fields(cls)]
        if sorted(obj['v']) != sorted(names):
            raise EntryError(f'{obj["c"]} with fields {sorted(obj["v"])}')
        return cls(**{n: decode(obj['v'][n], depth + 1) for n in names})
    raise EntryError(f'unknown form {sorted(obj)[:3]}')


def _array(obj):
    dtype, shape, data = obj['a'], obj['s'], obj['b']
    if dtype not in DTYPES or type(shape) is not list or len(shape) > 4 \
            or any(type(n) is not int or n < 0 for n in shape) or type(data) is not str:
        raise EntryError('bad array header')
    try:
        raw = base64.b64decode(data.encode('ascii'), validate=True)
    except (ValueError, UnicodeEncodeError):
        raise EntryError('bad array data') from None
    dt = np.dtype(dtype)
    if len(raw) != math.prod(shape) * dt.itemsize:
        raise EntryError(f'array of {len(raw)} bytes for shape {shape}')
    return np.frombuffer(raw, dtype=dt).reshape(shape).astype(dt.newbyteorder('='))


# --------------------------------------------------------------------------- validation
def _check(cond, what):
    if not cond:
        raise EntryError(what)


def _is_int(v):
    return type(v) is int


def _is_num(v):
    return type(v) in (int, float)


def validate(fields, scene, redesign):
    """
    Check decoded analysis fields against the schema and the physics; EntryError if not.

    ``scene``: the scene it is for (its model re-throws the tail's last states);
    ``redesign(limit_set, basin)``: the sensor design as ``analyse`` makes it.
    """
    _check(type(fields) is dict and sorted(fields) == sorted(FIELDS), 'not the analysis fields')
    start = fields['start']
    _check(type(start) is tuple and len(start) == 2 and _is_int(start[0])
           and type(start[1]) is float, 'start')
    _check(start == tuple(scene.default_start()), "start is not the scene's")
    ls, bas, sensor = fields['limit_set'], fields['basin'], fields['sensor']
    _check(type(ls) is LimitSet and type(bas) is Basin and type(sensor) is SensorDesign,
           'result classes')
    _check(type(fields['radii']) is dict and 'R_max_all' in fields['radii'], 'design radii')
    for name in ('stochastic', 'pull'):
        _check(fields[name] is None or type(fields[name]) is dict, name)
    _check(bool(fields['stochastic']) == bool(scene.model.stochastic), 'stochastic part')
    # The limit set.
    _check(type(ls.pattern) is tuple and all(map(_is_int, ls.pattern)), 'pattern')
    _check(type(ls.cycle_lengths) is tuple and all(map(_is_int, ls.cycle_lengths)), 'cycles')
    _check(_is_int(ls.transient) and type(ls.periodic) is bool and type(ls.band_tol) is float,
           'limit set scalars')
    te, tr = ls.tail_edges, ls.tail_radii
    _check(type(te) is np.ndarray and te.dtype == np.int64 and te.ndim == 1 and te.size > 0
           and type(tr) is np.ndarray and tr.dtype == np.float64 and tr.shape == te.shape,
           'limit set tail')
    _check(type(ls.bands) is dict and type(ls.jogs) is dict, 'bands, jogs')
    for k, v in ls.jogs.items():
        _check(_is_int(k) and type(v) is tuple and len(v) == 2 and all(map(_is_num, v)), 'jogs')
    bands = {}
    for e in np.unique(te):
        sel = tr[te == e]
        bands[int(e)] = (float(sel.min()), float(sel.max()))
    _check(ls.bands == bands and all(type(v) is tuple for v in ls.bands.values()),
           "bands are not the tail's extent")
    # The basin.
    n = bas.start_edges.shape[0] if type(bas.start_edges) is np.ndarray else -1
    for name in ('start_edges', 'start_radii', 'status', 'transients'):
        a = getattr(bas, name)
        _check(type(a) is np.ndarray and a.shape == (n,), f'basin {name}')
    m = bas.edges.shape[1] if type(bas.edges) is np.ndarray and bas.edges.ndim == 2 else -1
    for name in ('edges', 'radii', 'rotations'):
        a = getattr(bas, name)
        _check(type(a) is np.ndarray and a.shape == (n, m), f'basin {name}')
    _check(bas.edges.dtype == np.int64 and bas.radii.dtype == np.float64, 'basin dtypes')
    _check(type(bas.signatures) is tuple and len(bas.signatures) == n
           and all(type(s) is str for s in bas.signatures), 'basin signatures')
    # The sensor: every field of its type, and what the design gives from the cached pieces.
    for f in dataclasses.fields(SensorDesign):
        v = getattr(sensor, f.name)
        want = {'int': int, 'float': float, 'bool': bool}[f.type if isinstance(f.type, str)
                                                          else f.type.__name__]
        _check(type(v) is want, f'sensor {f.name}')
    _check(_same(redesign(ls, bas), sensor),
           'the sensor design of the cached limit set and basin differs')
    # The physics: the model maps the tail's last states onto their successors.
    if not scene.model.stochastic:
        k = min(SPOT_CHECKS, te.size - 1)
        for j in range(te.size - 1 - k, te.size - 1):
            edge, R, _ = scene.model.f(int(te[j]), float(tr[j]))
            _check(edge == te[j + 1] and _same(R, float(tr[j + 1])),
                   f'the model does not map tail state {j} onto the next one')


def _same(a, b):
    """Equality with NaN equal to NaN (fields of a dataclass, or two floats)."""
    if dataclasses.is_dataclass(a):
        return type(a) is type(b) and all(_same(getattr(a, f.name), getattr(b, f.name))
                                          for f in dataclasses.fields(a))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return type(a) is type(b) and a == b


# --------------------------------------------------------------------------- the directory
def _warn_once(message):
    if message not in _warned:
        _warned.add(message)
        LOG.warning('%s', message)


def _open_directory():
    """Return the cache directory, created 0700 if absent; None if it is refused or fails."""
    path = directory()
    try:
        os.makedirs(path, mode=0o700, exist_ok=True)
        st = os.lstat(path)
    except OSError as exc:
        _warn_once(f'throwmap: analysis cache {path} cannot be created ({exc.strerror}); '
                   'analysing without it (set THROWMAP_CACHE_DIR, or THROWMAP_CACHE=off)')
        return None
    if not stat.S_ISDIR(st.st_mode):
        _warn_once(f'throwmap: analysis cache {path} is not a directory (a link?); not used')
        return None
    if st.st_uid != os.geteuid():
        _warn_once(f'throwmap: analysis cache {path} belongs to uid {st.st_uid}, not to this '
                   'user; not used (give THROWMAP_CACHE_DIR a directory of your own)')
        return None
    if st.st_mode & 0o077:
        _warn_once(f'throwmap: analysis cache {path} is open to others (mode '
                   f'{stat.S_IMODE(st.st_mode):04o}); not used: make it private with '
                   f'chmod 700 {path}, or remove it')
        return None
    return path


def _entry_path(folder, digest):
    return os.path.join(folder, f'analysis-{digest}.json')


def read_entry(path, digest):
    """Return the decoded fields of the entry at ``path``; None if absent, EntryError if bad."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise EntryError(f'cannot open it ({exc.strerror})') from None
    with os.fdopen(fd, 'rb') as fh:
        st = os.fstat(fh.fileno())
        _check(stat.S_ISREG(st.st_mode), 'not a regular file')
        _check(st.st_uid == os.geteuid(), f'owned by uid {st.st_uid}, not this user')
        _check(not st.st_mode & 0o022, f'writable by others (mode '
                                       f'{stat.S_IMODE(st.st_mode):04o})')
        _check(st.st_size <= MAX_ENTRY_BYTES, f'{st.st_size} bytes, over the limit')
        raw = fh.read(MAX_ENTRY_BYTES + 1)
    try:
        doc = json.loads(raw.decode('utf-8'))
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise EntryError('not JSON (truncated?)') from None
    _check(type(doc) is dict and doc.get('format') == FORMAT and doc.get('key') == digest
           and doc.get('code') == code_version(), 'another format, key or code version')
    _check(doc.get('sha256') == hashlib.sha256(
        json.dumps(doc.get('analysis'), sort_keys=True).encode()).hexdigest(),
        'checksum differs')
    try:
        return decode(doc['analysis'])
    except (TypeError, ValueError, KeyError, RecursionError) as exc:
        raise EntryError(f'malformed: {exc}') from None


def write_entry(folder, digest, fields):
    """Write the entry of ``fields`` atomically (temporary file, then rename); False if not."""
    try:
        body = encode(dict(fields))
    except Uncacheable as exc:
        LOG.debug('analysis cache: result not cached: %s', exc)
        return False
    doc = {'format': FORMAT, 'key': digest, 'code': code_version(), 'analysis': body,
           'sha256': hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()}
    text = json.dumps(doc, sort_keys=True, separators=(',', ':'), allow_nan=False).encode()
    if len(text) > MAX_ENTRY_BYTES:
        LOG.debug('analysis cache: result of %d bytes not cached', len(text))
        return False
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix='.analysis-', suffix='.tmp', dir=folder)  # mode 0600
        with os.fdopen(fd, 'wb') as fh:
            fh.write(text)
        os.replace(tmp, _entry_path(folder, digest))
        return True
    except OSError as exc:
        LOG.debug('analysis cache: cannot write %s: %s', folder, exc)
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        return False


def _lock(folder, digest):
    """Take the entry's lock file (flock); return its fd, or None (then go on unlocked)."""
    try:
        fd = os.open(os.path.join(folder, f'analysis-{digest}.lock'),
                     os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o600)
    except OSError:
        return None
    deadline = time.monotonic() + LOCK_WAIT_S
    while True:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return fd
        except OSError as exc:
            if exc.errno not in (errno.EAGAIN, errno.EACCES) or time.monotonic() > deadline:
                os.close(fd)
                return None
        time.sleep(0.05)


# --------------------------------------------------------------------------- the cache
def _load(folder, digest, scene, redesign):
    path = _entry_path(folder, digest)
    try:
        fields = read_entry(path, digest)
        if fields is not None:
            validate(fields, scene, redesign)
        return fields
    except EntryError as exc:
        LOG.debug('analysis cache: entry %s ignored: %s', path, exc)
    except Exception as exc:    # never an exception to the caller: recompute instead
        LOG.debug('analysis cache: entry %s ignored: %r', path, exc)
    return None


def cached(digest, scene, compute, redesign):
    """
    Return the analysis fields of ``digest`` from the cache, or ``compute()`` them and store.

    ``compute()`` returns {field: value} (FIELDS); ``redesign``: see :func:`validate`. With
    ``digest`` None it is just called. While one process computes a key, others wanting it
    wait for its entry (a lock file).
    """
    folder = None if digest is None else _open_directory()
    if folder is None:
        return compute()
    fields = _load(folder, digest, scene, redesign)
    if fields is not None:
        return fields
    lock = _lock(folder, digest)
    try:
        if lock is not None:    # another process may have written it while we waited
            fields = _load(folder, digest, scene, redesign)
            if fields is not None:
                return fields
        fields = compute()
        write_entry(folder, digest, fields)
        return fields
    finally:
        if lock is not None:
            os.close(lock)
