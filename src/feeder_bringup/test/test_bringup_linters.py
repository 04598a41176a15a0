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
Run ament_flake8 and ament_pep257 over the package, as `colcon test` would.

They run in a child process: flake8 forks a worker pool, and a fork of a test process that
holds DDS handles (in-process node tests) can crash or hang in the child. They skip where the
linters are not installed (requirements.txt installs them).
"""

import pathlib
import subprocess
import sys

import pytest

PKG = pathlib.Path(__file__).resolve().parents[1]


def _run(module, code):
    pytest.importorskip(module)
    proc = subprocess.run([sys.executable, '-c', code], cwd=PKG, capture_output=True,
                          text=True, timeout=300)
    return proc.returncode, proc.stdout + proc.stderr


@pytest.mark.linter
@pytest.mark.flake8
def test_flake8():
    pytest.importorskip('flake8')
    rc, out = _run('ament_flake8.main', 'import sys; from ament_flake8.main import main; '
                   "sys.exit(main(argv=['.']))")
    assert rc == 0, f'ament_flake8 found problems:\n{out}'


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    rc, out = _run('ament_pep257.main', 'import sys; from ament_pep257.main import main; '
                   "sys.exit(main(argv=['.']))")
    assert rc == 0, f'ament_pep257 found problems:\n{out}'
