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


"""A node's teardown that hangs still ends the process, with its status and the stacks."""

import os
import subprocess
import sys
import textwrap
import time


def test_a_hung_teardown_ends_with_the_status_and_the_thread_stacks():
    code = textwrap.dedent("""
        import time
        from feeder_common.node import exit_after
        exit_after(0.5, 2, 'some_node')
        time.sleep(60)              # a teardown that never returns
    """)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    t0 = time.monotonic()
    proc = subprocess.run([sys.executable, '-c', code], env=env, capture_output=True, text=True,
                          timeout=30)
    assert proc.returncode == 2, proc.stderr
    assert time.monotonic() - t0 < 20
    assert 'some_node: teardown took more than 0.5 s; exiting with status 2' in proc.stderr
    assert 'time.sleep(60)' in proc.stderr or 'line 5' in proc.stderr, proc.stderr


def test_a_teardown_that_ends_in_time_is_not_cut_short():
    code = textwrap.dedent("""
        import sys, time
        from feeder_common.node import exit_after
        exit_after(5.0, 2, 'some_node')
        time.sleep(0.2)
        sys.exit(0)
    """)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    proc = subprocess.run([sys.executable, '-c', code], env=env, capture_output=True, text=True,
                          timeout=30)
    assert proc.returncode == 0 and 'teardown' not in proc.stderr, proc.stderr
