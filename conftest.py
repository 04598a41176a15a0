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
Settings of every test run from the repository root (scripts/test), before any test module.

One throwmap analysis cache per test session, never the user's (docs/physics.md, "The
analysis cache"): the in-process analyses of every package's tests and the node processes of
the graph tests share it, so each scene is analysed once per session. It is removed at exit.
A THROWMAP_CACHE_DIR given by the caller is kept.
"""

import atexit
import os
import shutil
import tempfile

if 'THROWMAP_CACHE_DIR' not in os.environ:
    _cache = tempfile.mkdtemp(prefix='feeder-test-throwmap-cache-')
    atexit.register(shutil.rmtree, _cache, True)
    os.environ['THROWMAP_CACHE_DIR'] = _cache
