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
Demo of the feeder graph on one scene: hardware stand-in, predictor, monitor and bag recorder.

    scripts/demo_graph.py OUT_DIR [--cycles 300] [--period 0.02] [--scene scenes/triangle.yaml]

Starts the nodes as processes (the colcon install in ros2_ws/install) on a fresh ROS domain
with DDS on loopback and a fresh HMAC key of its own (the sim and the monitor sign with it),
cycles the feeder, prints every edge1_ready that a consumer may act on as it happens (the
monitor's signed statement, checked with feeder_common.messages.check_verdict: its seq, the
cycle's sample stamp, ready) and a summary,
stops everything and leaves OUT_DIR/bag (rosbag2 MCAP), OUT_DIR/cycles.csv and
OUT_DIR/ready.png. Exit status 0 when every verdict agreed with the predicted state, 1 if not,
2 on a set-up problem. ROS glue only: the physics is throwmap's, the logic the nodes'. The
processes, the domain and the probe node are the harness's (tests/feeder_testing.py; this
script puts tests/ on sys.path, its one path edit).
"""

import argparse
import csv
import os
import pathlib
import shutil
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'tests'))
from feeder_testing import Probe, Processes, REPO, STARTUP_TIMEOUT, use_domain  # noqa: E402


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    p.add_argument('out', type=pathlib.Path, help='output directory (created; bag replaced)')
    p.add_argument('--cycles', type=int, default=300, help='cycles to run (default 300)')
    p.add_argument('--period', type=float, default=0.02,
                   help='cycle period, s (default 0.02; 0.005 .. 60)')
    p.add_argument('--scene', type=pathlib.Path, default=REPO / 'scenes' / 'triangle.yaml',
                   help='scene YAML (default scenes/triangle.yaml)')
    a = p.parse_args()
    if a.cycles < 1 or not 0.005 <= a.period <= 60.0:
        p.error('need --cycles >= 1 and 0.005 <= --period <= 60')
    if not a.scene.is_file():
        p.error(f'no scene file {a.scene}')
    return a


def main():
    args = parse_args()
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    (out / 'logs').mkdir(exist_ok=True)
    bag = out / 'bag'
    if bag.exists():
        shutil.rmtree(bag)
    # The caller's ROS_DOMAIN_ID, so that its shell sees the graph; else a free one.
    domain, lock = use_domain(keep_given=True)
    procs = Processes(out / 'logs', error=SystemExit, prog='demo_graph')
    # The run's own key (mode 0600, in a private temporary folder): ~/.ros is left alone.
    from feeder_common import auth
    key_dir = tempfile.mkdtemp(prefix='feeder-demo-')
    key_file = os.path.join(key_dir, 'hmac.key')
    auth.ensure_key(key_file)
    t0 = time.monotonic()
    print(f'demo_graph: {args.scene.name}, {args.cycles} cycles every {args.period} s, '
          f'ROS_DOMAIN_ID={domain} (loopback only), output in {out}', flush=True)
    try:
        scene = str(args.scene.resolve())
        key = f'key_file:={key_file}'
        procs.start('feeder_sim', 'standin_node', '--ros-args', '-r', '__ns:=/feeder',
                    '-r', '__node:=feeder_driver',
                    '-p', f'scene:={scene}', '-p', f'cycle_period:={args.period}', '-p', key,
                    name='sim_hw')
        procs.start('feeder_sim', 'predictor_node', '--ros-args', '-r',
                    '__ns:=/feeder', '-p', f'scene:={scene}', name='predictor')
        procs.start('feeder_monitor', 'monitor_node', '--ros-args', '-r',
                    '__ns:=/feeder', '-p', f'scene:={scene}', '-p', key, name='monitor')
        procs.start('feeder_monitor', 'bag_recorder', bag, '--ros-args', '-r',
                    '__ns:=/feeder', name='recorder')
        return run(args, scene, out, procs, t0, auth.load_key(key_file))
    finally:
        procs.stop_all()
        shutil.rmtree(key_dir, ignore_errors=True)
        if lock is not None:
            lock.close()


def run(args, scene_path, out, procs, t0, key):
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from diagnostic_msgs.msg import DiagnosticArray
    from feeder_common.diagnostics import local_name
    from feeder_common.messages import check_verdict, parse_cycle_status, parse_predicted_state
    from feeder_interfaces.msg import CycleStatus, PredictedState, Verdict
    from throwmap import analyse, load_scene, sees

    reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    latched = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    scene = load_scene(scene_path)
    an = analyse(scene)
    goal, radius = an.sensor.goal_edge, an.sensor.radius
    probe = Probe('feeder_demo', procs=procs, watch=True, error=SystemExit)
    node = probe.node
    got = {k: [] for k in ('status', 'predicted', 'ready', 'verdict')}
    diags = {}

    def keep(key):
        return got[key].append

    actuator = []       # the stand-in's actuator statuses, in arrival order

    def on_diag(msg):
        for s in msg.status:
            diags[local_name(s.name)] = s
            if local_name(s.name) == 'feeder_driver: actuator':
                actuator.append(s)

    node.create_subscription(CycleStatus, '/feeder/cycle_status', keep('status'), reliable)
    node.create_subscription(PredictedState, '/feeder/predicted/state', keep('predicted'),
                             reliable)
    monitor = '/feeder/feeder_monitor'

    stale_ready = set()     # cycles of signed ready statements that came too old to act on

    def on_ready(msg):
        # What a consumer does with each statement: check it when it arrives.
        c = check_verdict(msg, key, monitor, node.get_clock().now().nanoseconds)
        got['ready'].append(c)
        if msg.ready and c.authentic and not c.ready_now:
            stale_ready.add(c.seq)

    node.create_subscription(Verdict, '/feeder/edge1_ready', on_ready, latched)
    # One verdict per judged cycle, with its seq (edge1_ready is the current statement, which
    # the monitor also republishes while idle: it cannot be matched to cycles by counting).
    node.create_subscription(Verdict, '/feeder/edge1_verdict', keep('verdict'), reliable)
    node.create_subscription(DiagnosticArray, '/diagnostics', on_diag, reliable)
    spin_until = probe.spin_until

    def recording(topic):
        return any(i.node_name == 'feeder_bag_recorder'
                   for i in node.get_subscriptions_info_by_topic(topic))

    spin_until(lambda: got['ready'], STARTUP_TIMEOUT, 'the monitor')
    spin_until(lambda: 'feeder_monitor: readiness' in diags, STARTUP_TIMEOUT,
               'the monitor diagnostics')
    spin_until(lambda: all(recording(t) for t in ('/feeder/proximity', '/feeder/edge1_ready',
                                                  '/feeder/predicted/state')),
               STARTUP_TIMEOUT, 'the recorder')
    # Every writer matched its readers, by the writers' own accounts (each node's endpoints
    # status): the stand-in's cycle_status the predictor, the monitor, the recorder and us;
    # its proximity and cycle_fired the monitor and the recorder; the predictor's state and
    # the monitor's verdicts the recorder and us.
    probe.wait_remote_matched('/feeder/feeder_driver', readers={
        '/feeder/cycle_status': 4, '/feeder/proximity': 2, '/feeder/cycle_fired': 2})
    probe.wait_remote_matched('/feeder/feeder_sim', readers={'/feeder/predicted/state': 2})
    probe.wait_remote_matched('/feeder/feeder_monitor', readers={'/feeder/edge1_verdict': 2})
    probe.wait_active('/feeder/feeder_driver')
    print(f'demo_graph: graph up after {time.monotonic() - t0:.1f} s; goal edge {goal}, sensor '
          f'at {100 * radius:.2f} cm (guarantee {100 * an.sensor.guarantee_radius:.2f} cm), '
          f'warm-up {an.sensor.warmup_throws} throw(s)', flush=True)

    def enable(on):
        probe.enable('/feeder/feeder_driver', on)

    printed = {'next': 0, 'seqs': set()}

    def status_value(msg, key):
        """Return a value of a /diagnostics status."""
        return {kv.key: kv.value for kv in msg.values}.get(key)

    def seq_of(msg):
        """Return the seq of a cycle_status (feeder_interfaces/CycleStatus)."""
        return parse_cycle_status(msg).seq

    def signed(msg):
        return check_verdict(msg, key, monitor, 0, max_age_s=float('inf')).authentic

    def states():
        """The predicted state of each cycle, by seq (R None: no part on the arm)."""
        return {p.seq: p for p in map(parse_predicted_state, got['predicted'])}

    def report():
        """Print each statement that was ready when it came (once per cycle), with its state."""
        checks = got['ready']
        known = states()
        while printed['next'] < len(checks):
            c = checks[printed['next']]
            if c.ready_now and c.seq not in printed['seqs']:
                if c.seq not in known:
                    break               # its prediction is on its way
                printed['seqs'].add(c.seq)
                edge, R = known[c.seq].edge, known[c.seq].R
                where = 'no part on the arm' if R is None else f'R = {100 * R:6.2f} cm'
                sec, nsec = divmod(c.stamp_ns, 10 ** 9)
                print(f'  cycle {c.seq:4d}: edge1_ready true (signed, sent '
                      f'{1000 * c.sent_age_s:.1f} ms before it came), stamp {sec}.{nsec:09d}; '
                      f'{where}, edge {edge}', flush=True)
            printed['next'] += 1

    t_run = time.monotonic()
    enable(True)
    end = time.monotonic() + 30 + 3 * args.cycles * args.period
    while len(got['status']) < args.cycles:
        procs.check()
        if time.monotonic() > end:
            raise SystemExit('demo_graph: the feeder stopped cycling')
        probe.executor.spin_once(timeout_sec=0.05)
        report()
    enable(False)
    t_cycles = time.monotonic() - t_run
    # Until the last cycle's status, prediction and verdict are in: the stand-in's last seq
    # from an actuator status sent after the disable (the first one after it may have been
    # on its way), and the predictor's account of the cycles it followed.
    seen_before = len(actuator)

    def last_fired():
        later = actuator[seen_before + 1:]
        return int(status_value(later[-1], 'seq')) if later else None

    def all_in():
        last = last_fired()
        agreement = diags.get('feeder_sim: sensor agreement')
        return last is not None and bool(got['status']) and \
            seq_of(got['status'][-1]) >= last and last in states() and \
            any(int(m.seq) == last for m in got['verdict']) and agreement is not None and \
            status_value(agreement, 'followed') == str(len(got['status']))

    settle = time.monotonic() + 30.0
    while not all_in() and time.monotonic() < settle:
        probe.executor.spin_once(timeout_sec=0.05)
        report()
    rc = procs.stop('recorder')
    recorder_line = (out / 'logs' / 'recorder.log').read_text().strip().splitlines()[-1:]

    # Summary: every verdict against the prediction and the sensor geometry. A false ready is
    # one whose part is not seen on the goal edge; a miss, a detection (the bit the sensor
    # sent: a noisy sensor's may differ from the geometry) on the goal edge not reported once
    # the monitor's warm-up and settling are done (no ready before: issue 20).
    n = len(got['status'])
    unsigned = sum(not signed(m) for m in got['verdict']) + \
        sum(not c.authentic for c in got['ready'])
    verdict_of = {int(m.seq): bool(m.ready) for m in got['verdict']}
    mon = diags.get('feeder_monitor: readiness')
    mon_vals = {kv.key: kv.value for kv in mon.values} if mon else {}
    first_ready = max(int(mon_vals.get('warmup_cycles', an.sensor.warmup_throws)),
                      int(mon_vals.get('settle_cycles', 0)) + 1)
    judged = [k for k, m in enumerate(got['status']) if seq_of(m) in verdict_of]
    first = judged[0] if judged else n      # cycles before it are ones the monitor missed
    rows, false_ready, missed, goal_seen, unpredicted = [], 0, 0, 0, 0
    known = states()
    for k, status in enumerate(map(parse_cycle_status, got['status'])):
        predicted = known.get(status.seq)
        if predicted is None:
            unpredicted += 1    # cannot be judged: the predictor must follow every cycle
            continue
        edge, R, kind = predicted.edge, predicted.R, predicted.throw_kind
        seen = edge >= 0 and bool(sees(scene.part, edge, R, radius, an.sensor.footprint))
        bit = status.sensor is True
        j = k - first
        verdict = verdict_of.get(status.seq)
        if verdict and not (seen and edge == goal):
            false_ready += 1
        if bit and edge == goal and j + 1 >= first_ready:
            goal_seen += 1
            missed += verdict is False
        rows.append((status.seq, edge, '' if R is None else R, kind, int(bit),
                     '' if verdict is None else int(verdict), int(seen)))
    with open(out / 'cycles.csv', 'w', newline='') as fh:
        w = csv.writer(fh)
        w.writerow(['seq', 'edge', 'R_m', 'kind', 'sensor', 'edge1_ready', 'in_view'])
        w.writerows(rows)
    # The predictor's sensor bits against the hardware's (the stand-in publishes no state of
    # its own: it offers only the driver's interface). With release_noise the predictor
    # follows the noise-free map: it cannot agree, and its states are not the part's.
    agreement = diags.get('feeder_sim: sensor agreement')
    agree_vals = {kv.key: kv.value for kv in agreement.values} if agreement else {}
    agree = agree_vals.get('disagree') == '0' and agree_vals.get('followed') == str(n)
    must_agree = not scene.stochastic
    plot(rows, an, scene.part, out / 'ready.png', scene.name)
    ready_n = sum(1 for r in rows if r[5] == 1)
    # Ready cycles not printed: their every statement came older than check_verdict's limit
    # (1 s), so a consumer must not act on it, or none came (edge1_ready keeps only its latest
    # statement: the next cycle's replaced it before this process read it). Both happen only
    # when this process is starved (load).
    ready_seqs = {r[0] for r in rows if r[5] == 1}
    late = len((stale_ready - printed['seqs']) & ready_seqs)
    unseen = len(ready_seqs - printed['seqs'] - stale_ready)
    print(f'demo_graph: {n} cycles in {t_cycles:.1f} s ({n / t_cycles:.0f}/s); sensor fired '
          f'{sum(r[4] for r in rows)} times, {goal_seen} on the goal edge after the warm-up; '
          f'edge1_ready {ready_n} times, {false_ready} false, {missed} missed' +
          (f'; {unpredicted} cycles without a prediction' if unpredicted else '') +
          (f'; {unsigned} statements NOT signed by {monitor}' if unsigned else '') +
          (f'; not printed: {late} ready statements that came too late to act on (sent more '
           f'than 1 s before they arrived), {unseen} that never came (replaced by the next '
           "cycle's first): this process was starved" if late or unseen else ''), flush=True)
    print(f'demo_graph: first cycle that could be ready: {first_ready} (warm-up '
          f'{mon_vals.get("warmup_cycles", "?")}, settling {mon_vals.get("settle_cycles", "?")} '
          'throws); every statement checked with the run\'s key', flush=True)
    print(f'demo_graph: monitor: {mon_vals.get("state", "?")}, anomalies '
          f'{mon_vals.get("anomalies", "?")}; predictor followed '
          f'{agree_vals.get("followed", "?")} cycles, sensor bits '
          f'{"as predicted" if agree else "NOT all as predicted"}' + (
              '' if must_agree else ' (a random scene: the predictor follows the noise-free '
              'map, so the verdicts are judged against the expected part, not the real one)'),
          flush=True)
    print(f'demo_graph: recorder exit {rc}: {recorder_line[0] if recorder_line else "?"}')
    print(f'demo_graph: wrote {out / "bag"}, {out / "cycles.csv"}, {out / "ready.png"} '
          f'({time.monotonic() - t0:.1f} s in all)', flush=True)
    probe.close()
    ok = rc == 0 and ready_n > 0 and unpredicted == 0 and unsigned == 0 and (
        (false_ready == 0 and missed == 0 and agree) if must_agree else True)
    return 0 if ok else 1


def plot(rows, an, part, path, name):
    """R per cycle (dots) and the part's extent along the arm (bars), ready moments starred."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 5))
    u_min, u_max = part.U.min(axis=1), part.U.max(axis=1)
    rows = [r for r in rows if r[1] >= 0]       # a lost part has no R
    for e in sorted({r[1] for r in rows}):
        sel = [r for r in rows if r[1] == e]
        seq = [r[0] for r in sel]
        colour = f'C{e % 10}'
        ax.vlines(seq, [100 * (r[2] + u_min[e]) for r in sel],
                  [100 * (r[2] + u_max[e]) for r in sel], colors=colour, alpha=0.3, lw=1.2)
        ax.plot(seq, [100 * r[2] for r in sel], '.', color=colour, ms=4,
                label=f'edge {e}' + (' (goal)' if e == an.sensor.goal_edge else '') + ': R')
    ready = [(r[0], 100 * r[2]) for r in rows if r[5] == 1]
    if ready:
        ax.plot(*zip(*ready), '*', color='tab:red', ms=12, label='edge1_ready')
    ax.axhline(100 * an.sensor.radius, color='tab:red', lw=1, ls='--', label='sensor')
    ax.axhline(100 * an.sensor.guarantee_radius, color='goldenrod', lw=1, ls=':',
               label='guarantee radius')
    ax.set_xlabel('cycle (seq)')
    ax.set_ylabel('arm coordinate x (cm)')
    ax.set_title(f'{name}: {len(ready)} edge1_ready in {len(rows)} cycles\n'
                 "R after each throw (dot), the part's extent along the arm (bar): the sensor "
                 'fires where a bar crosses its line', fontsize=10)
    ax.legend(loc='upper left', bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == '__main__':
    sys.exit(main())
