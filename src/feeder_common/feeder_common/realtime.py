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
Real-time scheduling of a node's process (ROS-free, Linux).

On a machine whose cores are busy with other work, the scheduler delays a waking thread by up
to a few milliseconds at every hop of a message (bench/graph_bench.py --load 2: a do-nothing
rclpy echo then has a p99 of 7-8 ms). Robot software that must answer within a cycle runs its
threads under SCHED_FIFO, as ros2_control's controller manager does (``thread_priority``); a
node's ``realtime_priority`` parameter asks for that. It applies to every thread the process has
(the DDS middleware's receive and event threads exist before the node reads its parameters)
and, by inheritance, to every thread started later.
"""

import os
import resource

PRIORITY_MIN = 1
PRIORITY_MAX = 99

# What a user must do when the kernel refuses (EPERM): grant the priority, or do without it.
GRANT_HINT = ('grant it (run as a user with an rtprio limit of at least that, e.g. '
              "'@realtime - rtprio 98' in /etc/security/limits.conf; in a container "
              '--ulimit rtprio=98 or --cap-add=SYS_NICE) or set realtime_priority:=0 for the '
              'normal scheduler')


class RealtimeError(OSError):
    """The process cannot run at the priority asked for; the text says why and the fix."""


def _rtprio_limit():
    return resource.getrlimit(resource.RLIMIT_RTPRIO)[0]


def thread_ids():
    """Kernel ids of the threads of this process."""
    return sorted(int(t) for t in os.listdir('/proc/self/task'))


def set_realtime_priority(priority, inherit=True):
    """
    Run every thread of this process under SCHED_FIFO at ``priority`` (1-99); 0: leave it.

    ``inherit=False`` sets SCHED_RESET_ON_FORK: threads and processes started later run under
    the normal scheduler (e.g. a benchmark that starts the nodes it measures).

    Return the number of threads changed. Raise :class:`RealtimeError` when the system cannot
    (not Linux) or the kernel refuses (no rtprio limit or CAP_SYS_NICE): a node that asked for
    real-time scheduling must not run without it unnoticed.
    """
    if priority == 0:
        return 0
    if not PRIORITY_MIN <= priority <= PRIORITY_MAX:
        raise RealtimeError(f'realtime_priority = {priority} is outside [0, {PRIORITY_MAX}]')
    if not hasattr(os, 'sched_setscheduler') or not os.path.isdir('/proc/self/task'):
        raise RealtimeError('realtime_priority: SCHED_FIFO needs Linux; set realtime_priority:=0')
    param = os.sched_param(priority)
    policy = os.SCHED_FIFO | (0 if inherit else os.SCHED_RESET_ON_FORK)
    done = 0
    for tid in thread_ids():
        try:
            os.sched_setscheduler(tid, policy, param)
        except ProcessLookupError:      # the thread ended meanwhile
            continue
        except PermissionError:
            raise RealtimeError(
                f'realtime_priority = {priority}: this process may not use SCHED_FIFO '
                f'(the kernel refused: RLIMIT_RTPRIO is {_rtprio_limit()} and no CAP_SYS_NICE); '
                f'{GRANT_HINT}') from None
        done += 1
    return done
