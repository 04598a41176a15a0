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
Keeps numba's on-disk cache of the effect modules consistent with the code they call.

numba's cache=True keys a compiled function on its own source file only: when a function it
calls in another module changes (kernel.settle, say), the stale machine code is loaded as if
nothing had happened. The effect modules call across files (effect_model -> general, closed ->
kernel), so before they are compiled we compare a fingerprint of all of their sources with the
one stored beside the cache and drop their cache files when it differs.
"""

import glob
import hashlib
import os

HERE = os.path.dirname(os.path.abspath(__file__))
# Every module whose compiled functions end up inside the effect modules' machine code.
SOURCES = ('kernel.py', 'closed.py', 'general.py', 'effect_model.py')
CACHED = ('closed', 'general', 'effect_model')


def _fingerprint():
    digest = hashlib.sha256()
    for name in SOURCES:
        with open(os.path.join(HERE, name), 'rb') as fh:
            digest.update(fh.read())
    return digest.hexdigest()


def guard():
    """Drop the effect modules' numba cache files if any of their sources changed."""
    cache = os.path.join(HERE, '__pycache__')
    stamp = os.path.join(cache, 'throwmap_effects.fingerprint')
    try:
        current = _fingerprint()
        with open(stamp, encoding='ascii') as fh:
            if fh.read().strip() == current:
                return
    except OSError:
        pass
    try:
        for mod in CACHED:
            for path in glob.glob(os.path.join(cache, f'{mod}.*.nb[ic]')):
                os.remove(path)
        os.makedirs(cache, exist_ok=True)
        with open(stamp, 'w', encoding='ascii') as fh:
            fh.write(current)
    except OSError:   # a read-only install: numba then cannot cache either
        pass


guard()
