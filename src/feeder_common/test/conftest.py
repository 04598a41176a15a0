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

import gc
import os
import pathlib

import pytest

HERE = pathlib.Path(__file__).resolve()
REPO = HERE.parents[3]
# The source tree and tests/ (feeder_testing: a free domain id) are on sys.path by pytest.ini.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'


@pytest.fixture(scope='session')
def domain_id():
    from feeder_testing import reserve_domain_id
    return reserve_domain_id()


@pytest.fixture(autouse=True)
def collect_ros_garbage():
    """Free each test's rclpy nodes (reference cycles) before the next test starts."""
    yield
    gc.collect()
