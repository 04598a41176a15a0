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


"""feeder_common.realtime: SCHED_FIFO for every thread, refused with the fix when not allowed."""

import os
import subprocess
import sys
import textwrap

from feeder_common import realtime
import pytest

linux = pytest.mark.skipif(not sys.platform.startswith('linux'), reason='SCHED_FIFO is Linux')


def test_zero_leaves_the_scheduler_alone():
    before = os.sched_getscheduler(0)
    assert realtime.set_realtime_priority(0) == 0
    assert os.sched_getscheduler(0) == before


@pytest.mark.parametrize('priority', [-1, 100])
def test_a_priority_outside_the_range_is_an_error(priority):
    with pytest.raises(realtime.RealtimeError, match=r'outside \[0, 99\]'):
        realtime.set_realtime_priority(priority)


@linux
def test_a_refusal_names_the_limit_and_the_fix(monkeypatch):
    def refuse(tid, policy, param):
        raise PermissionError(1, 'Operation not permitted')
    monkeypatch.setattr(os, 'sched_setscheduler', refuse)
    with pytest.raises(realtime.RealtimeError) as err:
        realtime.set_realtime_priority(20)
    text = str(err.value)
    assert text.startswith('realtime_priority = 20: this process may not use SCHED_FIFO')
    assert 'RLIMIT_RTPRIO' in text and 'CAP_SYS_NICE' in text
    assert 'realtime_priority:=0' in text


CHILD = textwrap.dedent("""
    import os, sys, threading
    from feeder_common.realtime import set_realtime_priority, thread_ids
    inherit = sys.argv[1] == 'inherit'
    started = threading.Event()
    hold = threading.Event()
    before = threading.Thread(target=lambda: (started.set(), hold.wait()))
    before.start()
    started.wait()
    changed = set_realtime_priority(9, inherit=inherit)
    policies = {}
    after = threading.Thread(target=lambda: policies.setdefault(
        'after', os.sched_getscheduler(0) & ~os.SCHED_RESET_ON_FORK))
    after.start()
    after.join()
    hold.set()
    before.join()
    pid = os.fork()
    if pid == 0:
        os._exit(os.sched_getscheduler(0) & ~os.SCHED_RESET_ON_FORK)
    child = os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])
    print(changed, policies['after'], child)
""")


def may_use_fifo():
    code = 'import os; os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))'
    return subprocess.run([sys.executable, '-c', code], capture_output=True).returncode == 0


@linux
@pytest.mark.parametrize('inherit', ['inherit', 'reset'])
def test_every_thread_changes_and_later_ones_inherit_unless_reset(inherit):
    if not may_use_fifo():
        pytest.skip('this user may not use SCHED_FIFO here (no rtprio limit, no CAP_SYS_NICE)')
    out = subprocess.run([sys.executable, '-c', CHILD, inherit], capture_output=True,
                         text=True, timeout=60, check=True).stdout.split()
    changed, after, child = map(int, out)
    assert changed >= 2                 # the main thread and the one started before
    want = os.SCHED_FIFO if inherit == 'inherit' else os.SCHED_OTHER
    assert (after, child) == (want, want)
