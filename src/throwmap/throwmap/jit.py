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
numba in one place: the decorator, the on-disk cache's consistency, direct entry points.

With numba absent (or THROWMAP_NO_NUMBA=1, or NUMBA_DISABLE_JIT=1) ``njit`` returns the plain
Python function: the same code runs, only slower.

The cache. numba's cache=True keys a compiled function on its own source file only: when a
function it calls in another module changes (catch.settle, say), the stale machine code would be
loaded as if nothing had happened. At import, :func:`guard` compares a fingerprint of every
throwmap source that holds compiled code with the one stored beside the cache and drops all of
throwmap's cache files (and the composed modules, throwmap.compose) when it differs.

Which functions are cached. Entry points called from Python (a composed module's) and helpers
whose argument types are all defined in throwmap's own modules. A function that takes a
composed module's own types (its EffectParams) or numba dispatchers must not be: its cache
index would name a module that another process may not have imported, and loading that index
fails there (and a dispatcher passed as an argument is a pointer numba cannot cache at all).
The cores built from hooks and from the throw (event_sim.build, pipeline.build,
design.build_kernel, robustness.build_kernel) are closures, compiled into the cached entry
points of the composed module that calls them.
"""

import glob
import hashlib
import os

HERE = os.path.dirname(os.path.abspath(__file__))
COMPOSED_DIR_NAME = 'composed'

try:  # pragma: no cover - exercised by whichever environment runs the tests
    if os.environ.get('THROWMAP_NO_NUMBA'):
        raise ImportError
    import numba as _numba

    HAVE_NUMBA = not _numba.config.DISABLE_JIT
except ImportError:  # pragma: no cover
    _numba = None
    HAVE_NUMBA = False


def njit(fn=None, *, cache=True, nrt=False, inline=False):
    """
    Compile ``fn`` with numba (nogil, cached on disk if ``cache``); without numba return it.

    ``nrt``: numba's runtime (reference-counted allocation). throwmap's compiled code never
    allocates (callers pass every buffer), so it runs without it: then reading an array out of
    a bundle (a named tuple) costs no atomic reference-count update, which otherwise made a
    throw a third slower than with 26 separate arguments (docs/numerics.md). A function that
    allocates fails to compile without it, so nothing can go wrong silently.

    ``inline``: inline the function into its callers at numba's level. A call passes every
    field of every bundle (the part's arrays, the knobs) as a separate argument, so a small
    hook called once per throw (a release, a check) costs more in the call than in its body.
    """
    def wrap(f):
        if _numba is None:
            return f
        if inline:
            return _numba.njit(cache=cache, nogil=True, _nrt=nrt, inline='always')(f)
        return _numba.njit(cache=cache, nogil=True, _nrt=nrt)(f)
    return wrap if fn is None else wrap(fn)


def entry_point(dispatcher, *example_args):
    """
    Return the compiled function of ``dispatcher`` for the types of ``example_args``.

    numba's dispatcher works out the numba type of every argument at every call; for a named
    tuple of arrays that costs several microseconds, more than a throw. A model's arguments
    never change type, so it compiles (or loads from the cache) once and keeps the entry point,
    which takes the arguments as they are. Without numba: the function itself.
    """
    if not HAVE_NUMBA:
        return dispatcher
    signature = tuple(_numba.typeof(a) for a in example_args)
    return dispatcher.compile(signature)


def _compiled_sources():
    paths = sorted(glob.glob(os.path.join(HERE, '*.py'))
                   + glob.glob(os.path.join(HERE, 'effects', '*.py')))
    for path in paths:
        with open(path, 'rb') as fh:
            text = fh.read()
        if b'njit' in text:
            yield os.path.relpath(path, HERE), text


def fingerprint():
    """Return a hash over every throwmap source that holds compiled code (and numba's version)."""
    digest = hashlib.sha256(getattr(_numba, '__version__', 'none').encode())
    for name, text in _compiled_sources():
        digest.update(name.encode())
        digest.update(text)
    return digest.hexdigest()


def guard():
    """Drop throwmap's numba cache files and composed modules if any compiled source changed."""
    cache = os.path.join(HERE, '__pycache__')
    stamp = os.path.join(cache, 'throwmap_compiled.fingerprint')
    current = fingerprint()
    try:
        with open(stamp, encoding='ascii') as fh:
            if fh.read().strip() == current:
                return current
    except OSError:
        pass
    try:
        stale = (glob.glob(os.path.join(cache, '*.nb[ic]'))
                 + glob.glob(os.path.join(HERE, 'effects', '__pycache__', '*.nb[ic]'))
                 + glob.glob(os.path.join(cache, COMPOSED_DIR_NAME, '*.py'))
                 + glob.glob(os.path.join(cache, COMPOSED_DIR_NAME, '__pycache__', '*.nb[ic]')))
        for path in stale:
            os.remove(path)
        os.makedirs(cache, exist_ok=True)
        tmp = f'{stamp}.{os.getpid()}'
        with open(tmp, 'w', encoding='ascii') as fh:
            fh.write(current)
        os.replace(tmp, stamp)
    except OSError:   # a read-only install: numba then caches elsewhere, or not at all
        pass
    return current


SOURCE_FINGERPRINT = guard()
