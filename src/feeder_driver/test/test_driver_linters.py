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
Style checks of this package (ament_flake8, ament_pep257), for colcon users.

They skip where the linters are not installed: the pip ROS install has ament_flake8 only with
``ros-kilted-ament-flake8 ros-kilted-ament-pep257`` and the flake8 plugins
(flake8-builtins, -comprehensions, -docstrings, -import-order, -quotes).
"""

import pathlib

import pytest

PKG = pathlib.Path(__file__).resolve().parents[1]


def test_flake8():
    pytest.importorskip('flake8')
    main = pytest.importorskip('ament_flake8.main')
    rc, errors = main.main_with_errors(argv=[str(PKG)])
    assert rc == 0, f'{len(errors)} code style errors:\n' + '\n'.join(errors)


def test_pep257():
    main = pytest.importorskip('ament_pep257.main')
    assert main.main(argv=[str(PKG)]) == 0, 'docstring style errors (see output)'
