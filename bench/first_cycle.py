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
Time from starting the sim graph to its first cycle, with a cold and a warm analysis cache.

For each scene the stand-in (the sim as hardware), the predictor and the monitor start at once
as processes (a shared key file, a ROS domain of their own, loopback DDS), as a launch starts
them; the bench calls ``/feeder/feeder_driver/enable`` until it answers success and prints the
seconds from the start to that, to the first ``cycle_status`` and to the first
``edge1_verdict`` (with the cycle's seq). Cache modes: ``cold`` (an empty THROWMAP_CACHE_DIR),
``warm`` (the same directory again), ``off`` (THROWMAP_CACHE=off: every process analyses, as
before issue 21).
The numba cache is whatever it is (run once beforehand to have it warm). Asserts nothing.

    python bench/first_cycle.py [scenes/triangle.yaml ...] [--modes cold,warm,off]
        [--period 1.0] [--timeout 240] [--repeat 1] [--design]

``--design`` first runs ``throwmap design --json --quiet SCENE``, as the launch does to write
the URDF, and counts it in the time. Usage after ``. scripts/setup.sh``.
"""

import argparse
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parents[1]
INSTALL = REPO / 'ros2_ws' / 'install'
sys.path.insert(0, str(REPO / 'tests'))

from feeder_testing import (claim_domain_id, dds_env, install_env, Probe,  # noqa: E402
                            Processes)

# The graph's processes: name -> (package, executable, arguments before the common ones).
# Every one also gets: --ros-args -r __ns:=/feeder -p scene:=SCENE, and key_file:=KEY those
# in KEY_NODES.
NODES = {
    'stand-in': ('feeder_sim', 'standin_node', ['-r', '__node:=feeder_driver']),
    'predictor': ('feeder_sim', 'predictor_node', []),
    'monitor': ('feeder_monitor', 'monitor_node', []),
}
PERIOD_NODES = ('stand-in',)       # the ones that take -p cycle_period:=PERIOD
KEY_NODES = ('stand-in', 'monitor')  # the ones that sign or check (key_file)


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('scenes', nargs='*', type=pathlib.Path,
                   default=sorted((REPO / 'scenes').glob('*.yaml')))
    p.add_argument('--modes', default='cold,warm',
                   help='comma-separated: cold, warm, off (default: cold,warm)')
    p.add_argument('--period', type=float, default=1.0, help='cycle_period, s (launch default)')
    p.add_argument('--timeout', type=float, default=240.0, help='s per run')
    p.add_argument('--repeat', type=int, default=1, help='runs of each scene and mode')
    p.add_argument('--design', action='store_true',
                   help='run `throwmap design` first, as the launch does')
    return p.parse_args()


def run(args, scene, env, key, log_dir):
    """
    One start of the graph; return {event: (seconds after the start, seq)} (None: not seen).

    The processes and the bench's node are the test harness's (tests/feeder_testing.py:
    Processes, Probe); enable is called until it answers success (the stand-in refuses it
    until it is active). It waits for the first cycle_status and edge1_verdict: a probe that
    matched the stand-in late misses its first cycle_status (its seq then says so).
    """
    from feeder_interfaces.msg import CycleStatus, Verdict
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from std_srvs.srv import SetBool
    procs = Processes(log_dir / f'{scene.stem}-{time.monotonic_ns()}', env=env, error=SystemExit,
                      prog='first_cycle')
    probe = Probe('feeder_first_cycle_bench', procs=procs, watch=True, error=SystemExit)
    first = {}
    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    for msg_type, topic in ((CycleStatus, 'cycle_status'), (Verdict, 'edge1_verdict')):
        probe.node.create_subscription(
            msg_type, f'/feeder/{topic}',
            lambda m, topic=topic: first.setdefault(topic, (time.monotonic(), int(m.seq))), qos)
    t0 = time.monotonic()
    times = {'enable': None, 'cycle_status': None, 'edge1_verdict': None}
    try:
        if args.design:
            subprocess.run([sys.executable, '-m', 'throwmap.cli', 'design', '--json', '--quiet',
                            str(scene)], env=install_env(INSTALL, env), check=True,
                           stdout=subprocess.DEVNULL)
        for name, (pkg, exe, extra) in NODES.items():
            argv = ['--ros-args', '-r', '__ns:=/feeder', *extra, '-p', f'scene:={scene}']
            if name in KEY_NODES:
                argv += ['-p', f'key_file:={key}']
            if name in PERIOD_NODES:
                argv += ['-p', f'cycle_period:={args.period}']
            procs.start(pkg, exe, *argv, name=name)
        end = t0 + args.timeout
        while not probe.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=True),
                             startup_timeout=max(1.0, end - time.monotonic())).success:
            probe.spin_for(0.1)
        times['enable'] = time.monotonic() - t0
        probe.spin_until(lambda: len(first) == 2, max(1.0, end - time.monotonic()),
                         'the first cycle_status and edge1_verdict')
    except SystemExit as exc:
        print(exc, file=sys.stderr, flush=True)
    finally:
        procs.stop_all()
        probe.close()
    for what, (at, seq) in first.items():
        times[what] = (at - t0, seq)
    return times


def main():
    args = parse_args()
    modes = [m.strip() for m in args.modes.split(',') if m.strip()]
    if any(m not in ('cold', 'warm', 'off') for m in modes):
        raise SystemExit('first_cycle: --modes takes cold, warm, off')
    domain, lock = claim_domain_id()
    os.environ.update(dds_env(domain))
    from feeder_common import auth
    work = pathlib.Path(tempfile.mkdtemp(prefix='feeder-first-cycle-'))
    key = work / 'hmac.key'
    auth.ensure_key(key)
    print(f'first_cycle: ROS_DOMAIN_ID={domain}, cycle_period {args.period} s, logs in {work}',
          flush=True)
    print(f'{"scene":<12} {"cache":<6} {"enable ok":>10} {"cycle_status":>13} '
          f'{"edge1_verdict":>14}  (s from the start of the processes; #: the cycle seq)',
          flush=True)
    try:
        for scene in args.scenes:
            scene = scene.resolve()
            cache = work / f'cache-{scene.stem}'
            for mode in [m for m in modes for _ in range(args.repeat)]:
                env = dds_env(domain)
                env['THROWMAP_CACHE_DIR'] = str(cache)
                if mode == 'cold':
                    shutil.rmtree(cache, ignore_errors=True)
                if mode == 'off':
                    env['THROWMAP_CACHE'] = 'off'
                else:
                    env.pop('THROWMAP_CACHE', None)
                times = run(args, scene, env, key, work)

                def fmt(v):
                    if v is None:
                        return 'none'
                    return f'{v[0]:.1f} (#{v[1]})' if isinstance(v, tuple) else f'{v:.1f}'

                print(f'{scene.stem:<12} {mode:<6} {fmt(times["enable"]):>10} '
                      f'{fmt(times["cycle_status"]):>13} {fmt(times["edge1_verdict"]):>14}',
                      flush=True)
    finally:
        lock.close()


if __name__ == '__main__':
    main()
