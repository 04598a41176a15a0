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

"""Fixtures of the feeder_driver tests: DDS on loopback, a domain of their own."""

import gc
import os
import pathlib

import pytest

PKG = pathlib.Path(__file__).resolve().parents[1]
REPO = PKG.parents[1]
# The source trees (not a possibly stale colcon install) and tests/ (feeder_testing, in no
# package) are on sys.path by pytest.ini.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'


@pytest.fixture(scope='session')
def domain_id():
    from feeder_testing import reserve_domain_id
    return reserve_domain_id()


@pytest.fixture(scope='session')
def scene_path():
    return str(REPO / 'scenes' / 'triangle.yaml')


@pytest.fixture(scope='session')
def sensor_radius(scene_path):
    """Return the scene's designed sensor radius (analysed once per session)."""
    from throwmap import analyse, load_scene
    return analyse(load_scene(scene_path)).sensor.radius


@pytest.fixture
def link_path(tmp_path):
    return str(tmp_path / 'feeder-tty')


@pytest.fixture(autouse=True)
def collect_ros_garbage():
    """
    Collect the garbage of each test before the next one starts.

    rclpy nodes are reference cycles, freed only by the garbage collector. Left for a late
    collection, a finished test's nodes stay alive into the next tests and disturb their
    discovery (test_driver_process failed 1 run in 3 without this, 0 in 5 with it); freed in a
    forked child, they would crash it (the linter tests now run flake8 in a child process).
    """
    yield
    gc.collect()
