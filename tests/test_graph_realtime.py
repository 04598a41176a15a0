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
realtime_priority: the nodes on a cycle's path run every thread under SCHED_FIFO when asked,
and refuse to start (exit 2, one line with the fix) when the kernel will not let them.
"""

import os
import resource
import shutil
import subprocess
import sys

from feeder_nodes import monitor, run_cycles, sim_as_hardware, watch_monitor
import pytest

PRIORITY = 7


def may_use_fifo():
    """Whether a process started from here may switch to SCHED_FIFO (asked of a child)."""
    code = 'import os; os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))'
    return subprocess.run([sys.executable, '-c', code], capture_output=True).returncode == 0


def threads(pid):
    """{thread id: (policy, priority)} of a process."""
    out = {}
    for tid in os.listdir(f'/proc/{pid}/task'):
        try:
            out[int(tid)] = (os.sched_getscheduler(int(tid)),
                             os.sched_getparam(int(tid)).sched_priority)
        except ProcessLookupError:
            pass
    return out


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason='SCHED_FIFO is Linux')
def test_every_thread_of_the_sim_and_the_monitor_runs_fifo_and_the_graph_works(graph, ros):
    if not may_use_fifo():
        pytest.skip('this user may not use SCHED_FIFO here (no rtprio limit, no '
                    'CAP_SYS_NICE): the refusal is tested below')
    sim = sim_as_hardware(graph, 'cycle_period:=0.01', f'realtime_priority:={PRIORITY}')
    mon = monitor(graph, f'realtime_priority:={PRIORITY}')
    ready, verdicts, statuses = watch_monitor(ros)
    for proc in (sim, mon):
        seen = threads(proc.pid)
        # the DDS threads, the executor's and the signal waker: several, every one FIFO
        assert len(seen) >= 3, seen
        assert set(seen.values()) == {(os.SCHED_FIFO, PRIORITY)}, seen
    run_cycles(ros, 30, statuses, 0.01)
    ros.spin_until(lambda: len(verdicts) >= 30, 20, '30 verdicts')
    assert all(v.authentic for v in verdicts.parsed)
    for proc in (sim, mon):
        assert graph.stop(proc) == 0, graph.log(proc)


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason='SCHED_FIFO is Linux')
def test_a_node_without_the_right_refuses_to_start_and_says_how_to_grant_it(graph):
    wrapper = ()
    if os.geteuid() == 0:
        # root may always: take CAP_SYS_NICE from the node's process
        if not shutil.which('setpriv'):
            pytest.skip('running as root and util-linux setpriv is missing: cannot take '
                        'CAP_SYS_NICE away from the node')
        wrapper = ('setpriv', '--bounding-set=-sys_nice')
    elif resource.getrlimit(resource.RLIMIT_RTPRIO)[0] >= PRIORITY:
        pytest.skip(f'this user has RLIMIT_RTPRIO {resource.getrlimit(resource.RLIMIT_RTPRIO)}'
                    ': the kernel would allow it')
    procs = [monitor(graph, f'realtime_priority:={PRIORITY}', wrapper=wrapper),
             sim_as_hardware(graph, f'realtime_priority:={PRIORITY}', wrapper=wrapper)]
    for proc in procs:
        assert proc.wait(timeout=60) == 2, graph.log(proc)
        log = graph.log(proc)
        assert f'error: realtime_priority = {PRIORITY}: this process may not use SCHED_FIFO' \
            in log, log
        assert 'rtprio' in log and 'realtime_priority:=0' in log, log
