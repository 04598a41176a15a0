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
controller_emulator stops with status 0 however many SIGINT/SIGTERM come (issue 23, item 2).

A Ctrl-C reaches every process of the terminal's group and ``ros2 launch`` forwards one more,
so a second signal may come while the emulator closes its pty or the interpreter exits. The
test keeps signalling until the process is gone.
"""

import signal
import subprocess
import time

from feeder_testing import INSTALL, install_env, REPO
import pytest

EMULATOR = INSTALL / 'feeder_driver' / 'lib' / 'feeder_driver' / 'controller_emulator'


def started(tmp_path):
    proc = subprocess.Popen([str(EMULATOR), '--scene', str(REPO / 'scenes' / 'triangle.yaml'),
                             '--link', str(tmp_path / 'tty'), '--sensor-radius', '0.2'],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=install_env(INSTALL), start_new_session=True)
    line = proc.stdout.readline()
    assert 'ready on' in line, line + proc.stdout.read()
    return proc


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_repeated_signals_end_the_emulator_with_status_0(tmp_path, sig):
    for run in range(3):
        proc = started(tmp_path)
        deadline = time.monotonic() + 20
        while proc.poll() is None and time.monotonic() < deadline:
            try:
                proc.send_signal(sig)
            except ProcessLookupError:
                break
            time.sleep(0.0005)
        try:
            status = proc.wait(timeout=10)
        finally:
            if proc.poll() is None:
                proc.kill()
        out = proc.stdout.read()
        proc.stdout.close()
        assert status == 0, f'run {run}: exit status {status}\n{out}'
        assert 'Traceback' not in out, out
        assert not (tmp_path / 'tty').exists()
