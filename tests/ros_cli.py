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
The real ROS command line (``ros2``: ros2cli, launch, launch_ros) for tests, where it exists.

It has no wheels: it is found in a ROS install (``ros2`` on PATH whose Python imports
``launch_ros``) or in a side venv built from source (scripts/ros-cli-venv.sh), named by
``FEEDER_ROS_CLI_VENV``. The environment adds the colcon workspace (ros2_ws/install) on top;
the node executables keep their own interpreter (the project venv, from their shebang).
"""

import os
import pathlib
import shutil
import signal
import subprocess

from feeder_testing import INSTALL, install_env

SKIP_REASON = ('the real ros2 CLI / ros2 launch is not installed here (no wheels exist): '
               'set FEEDER_ROS_CLI_VENV to a venv built with scripts/ros-cli-venv.sh, or '
               'run on a ROS 2 Kilted install')


def cli_env():
    """Environment in which ``ros2`` (with launch) runs the workspace, or None."""
    venv = os.environ.get('FEEDER_ROS_CLI_VENV')
    base = dict(os.environ)
    if venv:
        bindir = pathlib.Path(venv) / 'bin'
        if not (bindir / 'ros2').exists():
            return None
        base['PATH'] = f'{bindir}{os.pathsep}{base.get("PATH", "")}'
        base['VIRTUAL_ENV'] = str(venv)
        base['AMENT_PREFIX_PATH'] = str(venv)
        prefix = str(venv)
    else:
        exe = shutil.which('ros2')
        if exe is None:
            return None
        prefix = None
    probe = subprocess.run(['ros2', 'pkg', 'prefix', 'launch_ros'], env=base,
                           capture_output=True, text=True, timeout=60)
    if probe.returncode != 0:
        return None
    env = install_env(INSTALL, base)
    if prefix:
        # install_env puts the project venv's prefix on AMENT_PREFIX_PATH; the CLI's own
        # prefix must be there too (its packages: launch_ros, ros2cli ...).
        env['AMENT_PREFIX_PATH'] = os.pathsep.join([env['AMENT_PREFIX_PATH'], prefix])
    return env


def _default_sigint():
    # A test runner started in the background inherits SIGINT ignored; ros2 launch must
    # see it as a terminal's Ctrl-C.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start(argv, env, log_path):
    """Start ``ros2 ...`` in a session of its own; output to ``log_path``."""
    log = open(log_path, 'w')
    try:
        return subprocess.Popen(['ros2', *map(str, argv)], env=env, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True,
                                preexec_fn=_default_sigint)
    finally:
        log.close()


def run(argv, env, timeout=60):
    """Run ``ros2 ...`` to its end; (exit status, output)."""
    proc = subprocess.run(['ros2', *map(str, argv)], env=env, capture_output=True, text=True,
                          timeout=timeout, preexec_fn=_default_sigint)
    return proc.returncode, proc.stdout + proc.stderr
