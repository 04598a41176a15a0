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

import pytest
from throwmap import load_scene, Part, ThrowModel
from throwmap_testing import PAPER_W, SCENES, TRIANGLE_VERTICES


@pytest.fixture(scope='session', autouse=True)
def analysis_cache_dir(tmp_path_factory):
    """
    Point throwmap's analysis cache at one directory of this test session, never the user's.

    Shared by the session's tests (each scene is analysed once, as in a launch); the tests of
    the cache itself give each test a directory of its own.
    """
    path = tmp_path_factory.mktemp('throwmap-analysis-cache')
    path.chmod(0o700)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv('THROWMAP_CACHE_DIR', str(path))
        yield path


@pytest.fixture(scope='session')
def triangle_scene():
    return load_scene(str(SCENES / 'triangle.yaml'))


@pytest.fixture(scope='session')
def triangle():
    return ThrowModel(Part(TRIANGLE_VERTICES), -0.005, PAPER_W, -9.66)
