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

import pathlib

import pytest
from throwmap import analyse, load_scene

HERE = pathlib.Path(__file__).resolve()
REPO = HERE.parents[3]
SCENES = REPO / 'scenes'
# The source trees (also when installed copies are on PYTHONPATH) are on sys.path by
# pytest.ini.


@pytest.fixture(scope='session')
def triangle():
    return load_scene(str(SCENES / 'triangle.yaml'))


@pytest.fixture(scope='session')
def triangle_analysis(triangle):
    return analyse(triangle)


@pytest.fixture(scope='session')
def short_arm():
    """Load the triangle on a 33 cm arm (tests/scenes/short_arm.yaml): parts near its end fall."""
    return load_scene(str(REPO / 'tests' / 'scenes' / 'short_arm.yaml'))


@pytest.fixture(scope='session')
def house_path():
    """Return scenes/house.yaml: release noise, a noisy sensor, a finite carry, a 40 cm arm."""
    return str(SCENES / 'house.yaml')
