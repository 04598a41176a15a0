#!/usr/bin/env python3
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
Latency of the feeder driver against the emulated controller on a pty (prints a table).

One process: the emulator in a thread (its cycle takes --cycle-time s), the driver node and a
probe node in their own rclpy context on a reserved DDS domain (loopback only). Measures, per
cycle: FIRE to SENS as the driver saw it (link + parsing + emulator), trigger service call to
cycle_status arrival at the probe (the whole path a user sees), and the cycle rate reached
with ~/enable at cycle_period 0.01 s. Asserts nothing.

    python bench/driver_latency.py [--cycles 200] [--cycle-time 0.0]
"""

import argparse
import pathlib
import statistics
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parents[1]
# The harness (tests/feeder_testing.py); the packages from the colcon install
sys.path.insert(0, str(REPO / 'tests'))

from feeder_driver.driver_node import DriverNode  # noqa: E402
from feeder_interfaces.msg import CycleStatus  # noqa: E402
from feeder_testing import EmulatorThread, reserve_domain_id  # noqa: E402
import rclpy  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from std_srvs.srv import SetBool, Trigger  # noqa: E402


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(q * (len(xs) - 1))))]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--cycles', type=int, default=200)
    ap.add_argument('--cycle-time', type=float, default=0.0)
    ap.add_argument('--scene', default=str(REPO / 'scenes' / 'triangle.yaml'))
    args = ap.parse_args()
    link = str(pathlib.Path(tempfile.mkdtemp()) / 'feeder-tty')
    emu = EmulatorThread(args.scene, link, cycle_time=args.cycle_time, heartbeat=0.5).start()
    ctx = Context()
    rclpy.init(context=ctx, domain_id=reserve_domain_id())
    ex = SingleThreadedExecutor(context=ctx)
    overrides = [Parameter('port', value=link), Parameter('cycle_period', value=0.01)]
    node = DriverNode(context=ctx, parameter_overrides=overrides)
    probe = rclpy.create_node('bench_probe', context=ctx)
    got = []
    probe.create_subscription(CycleStatus, 'cycle_status',
                              lambda m: got.append(time.perf_counter()),
                              QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    trig = probe.create_client(Trigger, 'feeder_driver/trigger_cycle')
    enable = probe.create_client(SetBool, 'feeder_driver/enable')
    ex.add_node(node)
    ex.add_node(probe)
    node.trigger_configure()
    node.trigger_activate()
    while node.core.link != 'connected':
        ex.spin_once(timeout_sec=0.01)
    trig.wait_for_service(timeout_sec=5)

    def call(client, req):
        fut = client.call_async(req)
        ex.spin_until_future_complete(fut, timeout_sec=5)
        return fut.result()

    user, fire_to_sens = [], []
    for k in range(args.cycles):
        n = len(got)
        t0 = time.perf_counter()
        assert call(trig, Trigger.Request()).success
        while len(got) == n:
            ex.spin_once(timeout_sec=0.01)
        user.append(got[-1] - t0)
        fire_to_sens.append(node.core.last_result.duration_s)
    n0, t0 = len(got), time.perf_counter()
    call(enable, SetBool.Request(data=True))
    while len(got) < n0 + args.cycles:
        ex.spin_once(timeout_sec=0.01)
    rate = args.cycles / (time.perf_counter() - t0)
    call(enable, SetBool.Request(data=False))
    while node.core.pending is not None:
        ex.spin_once(timeout_sec=0.01)
    c = node.core.counters
    print(f'driver latency, {args.cycles} cycles, emulator cycle time {args.cycle_time} s')
    print('| measure | median ms | p95 ms | max ms |')
    print('|---|---|---|---|')
    for name, xs in (('FIRE -> SENS (driver)', fire_to_sens),
                     ('trigger call -> cycle_status at probe', user)):
        print(f'| {name} | {1e3 * statistics.median(xs):.2f} | {1e3 * pct(xs, 0.95):.2f} | '
              f'{1e3 * max(xs):.2f} |')
    print(f'| enable at cycle_period 0.01 s | {rate:.1f} cycles/s | | |')
    print(f'fired {c["fired"]}, completed {c["completed"]}, failed {c["failed"]}')
    node.destroy_node()
    probe.destroy_node()
    ex.shutdown()
    rclpy.shutdown(context=ctx)
    emu.stop()


if __name__ == '__main__':
    main()
