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
Soak: the sim as hardware, the predictor, the monitor and the bag recorder, N cycles at the
fastest period, then every cycle reconciled from the bag (issue 10). Not in CI.

The stand-in (standin_node, triangle, ``cycle_period`` 0.005 s, its minimum) cycles until it has
fired N cycles; the recorder records ``cycle_status``, ``proximity``, ``edge1_verdict``,
``edge1_ready`` and the predictor's ``predicted/state``. The bag is
read with the mcap reader (not the recorder's code) and every cycle is checked:

* ``cycle_status``: seq 1..n, contiguous, every cycle completed, one ``proximity`` each;
* the truth of a cycle is the geometry of the predicted state (the scene is deterministic, so
  the predictor's state is the simulated part's): the sensor sees the part, and whether it
  lies on the goal edge; the sim's sensor bit must equal it;
* ``edge1_verdict`` (signed ``feeder_interfaces/Verdict``): one per cycle, every one signed by
  the monitor under the run's key (``hmac.key`` in the output folder); ready exactly when the
  part is seen on the goal edge after the warm-up and the settling (the monitor's rules,
  derived here as the node derives them). It counts false ready, missed ready after the
  warm-up and settling, and anomalies (the triangle's orbit has none: each one is false);
  ``edge1_ready`` statements: signed, and ready only for a cycle whose verdict was ready;
* memory: every node's RSS (/proc/<pid>/status) sampled every few seconds; the growth over
  the second half of the run, per 1000 cycles. The recorder holds the index of every chunk
  it wrote (the bag's summary needs it at the end, as rosbag2's MCAP writer holds its own):
  its growth is judged after that index, measured here (bytes per chunk, tracemalloc on
  feeder_monitor.bag.McapLog) times the bag's chunks.

Prints a table; exit status 0 when every count is zero and memory is flat (growth under
``--flat-kb`` KB per 1000 cycles), else 1. ``--reread DIR`` judges a finished run again from
its bag and rss.csv. Usage (after ``. scripts/setup.sh``):

    python bench/soak.py [--cycles 100000] [--out DIR] | --reread DIR
"""

import argparse
import os
import pathlib
import signal
import sys
import tempfile
import time

# The harness (tests/feeder_testing.py: processes, domain, probe node; through graph_bench)
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'tests'))
from feeder_testing import Processes, REPO, use_domain  # noqa: E402
from graph_bench import BenchNode, watch_diagnostics  # noqa: E402

SCENE = str(REPO / 'scenes' / 'triangle.yaml')
PERIOD = 0.005
TOPICS = ('cycle_status', 'proximity', 'edge1_verdict', 'edge1_ready', 'predicted/state')


def rss_kb(pid):
    with open(f'/proc/{pid}/status') as fh:
        for line in fh:
            if line.startswith('VmRSS:'):
                return int(line.split()[1])
    return 0


def key_path(out):
    """The run's HMAC key file (made, mode 0600, when absent): the sim and the monitor's."""
    from feeder_common import auth
    path = pathlib.Path(out) / 'hmac.key'
    auth.ensure_key(path)
    return path


def start(procs, bag, key):
    ns = ['-r', '__ns:=/feeder']
    k = ['-p', f'key_file:={key}']
    procs.start('feeder_sim', 'standin_node', '--ros-args', *ns, '-r',
                '__node:=feeder_driver', '-p', f'scene:={SCENE}',
                '-p', f'cycle_period:={PERIOD}', *k, name='sim')
    procs.start('feeder_sim', 'predictor_node', '--ros-args', *ns, '-p',
                f'scene:={SCENE}', name='predictor')
    procs.start('feeder_monitor', 'monitor_node', '--ros-args', *ns, '-p',
                f'scene:={SCENE}', *k, name='monitor')
    procs.start('feeder_monitor', 'bag_recorder', bag, '--topics', *TOPICS,
                '--ros-args', *ns, name='recorder')


class Driver(BenchNode):
    """The soak's node: enables cycling, reads the sim's seq from /diagnostics (1 Hz)."""

    prog = 'soak'

    def __init__(self, procs):
        super().__init__('feeder_soak', procs)
        self.diags = watch_diagnostics(self)

    @property
    def seq(self):
        """The stand-in's last cycle, from its actuator diagnostics (1 Hz)."""
        actuator = self.diags.get('feeder_driver: actuator')
        return int({kv.key: kv.value for kv in actuator.values}['seq']) if actuator else 0


def read_bag(bag):
    """Messages of the bag by topic, in log order (the mcap reader; rclpy deserializes)."""
    import importlib
    from mcap.reader import make_reader
    from rclpy.serialization import deserialize_message
    out, classes = {}, {}
    files = sorted(pathlib.Path(bag).glob('*.mcap'))
    if not files:
        raise SystemExit(f'soak: no .mcap file in {bag}')
    for path in files:
        with open(path, 'rb') as fh:
            for schema, channel, message in make_reader(fh).iter_messages(log_time_order=True):
                cls = classes.get(schema.name)
                if cls is None:
                    pkg, kind, name = schema.name.split('/')
                    cls = classes[schema.name] = getattr(
                        importlib.import_module(f'{pkg}.{kind}'), name)
                out.setdefault(channel.topic, []).append(deserialize_message(message.data, cls))
    return out


def first_ready_throw(scene):
    """The first judged throw that can be ready: after the monitor's warm-up and settling."""
    from feeder_monitor.readiness import limit_set_orbit, rules_from_analysis
    from throwmap import analyse, scene_analysis
    base = analyse(scene)
    rules = rules_from_analysis(scene, scene_analysis(scene, 0.0, base),
                                limit_set_orbit(scene, base, 20000))
    return max(rules.warmup_cycles, rules.settle_cycles + 1)


def reconcile(msgs, key):
    """Count, cycle by cycle, what the bag shows against the geometry's truth."""
    import numpy as np
    from feeder_common.messages import (check_verdict, parse_cycle_status,
                                        parse_predicted_state)
    from throwmap import analyse, load_scene, sees
    scene = load_scene(SCENE)
    sensor = analyse(scene).sensor
    monitor = '/feeder/feeder_monitor'

    def signed(v):
        return check_verdict(v, key, monitor, 0, max_age_s=float('inf')).authentic
    statuses = [parse_cycle_status(m) for m in msgs.get('/feeder/cycle_status', [])]
    n = len(statuses)
    seqs = [s.seq for s in statuses]
    problems = {}
    if seqs != list(range(1, n + 1)):
        problems['cycle_status seqs not 1..n'] = sum(
            1 for k, s in enumerate(seqs) if s != k + 1)
    problems['failed cycles'] = sum(not s.ok for s in statuses)
    problems['proximity count - cycles'] = len(msgs.get('/feeder/proximity', [])) - n
    predicted, dup_predictions = {}, 0
    for p in (parse_predicted_state(x) for x in msgs.get('/feeder/predicted/state', [])):
        dup_predictions += p.seq in predicted
        predicted.setdefault(p.seq, p)
    problems['duplicate predictions'] = dup_predictions
    problems['cycles without a prediction'] = sum(1 for s in seqs if s not in predicted)
    problems['predictions of no cycle'] = len(set(predicted) - set(seqs))
    # The cycles 1..m that have their prediction; a missing one is counted above.
    m = next((k for k in range(n) if k + 1 not in predicted or k + 1 != seqs[k]), n)
    edges = np.array([predicted[k + 1].edge for k in range(m)])
    radii = np.array([predicted[k + 1].R for k in range(m)], dtype=float)
    seen = np.asarray(sees(scene.part, edges, radii, sensor.radius, sensor.footprint),
                      dtype=bool).reshape(m)
    bits = np.array([bool(s.sensor) for s in statuses[:m]], dtype=bool)
    problems['sensor bit != geometry'] = int((bits != seen).sum())
    truth = seen & (edges == sensor.goal_edge) & \
        (np.arange(1, m + 1) >= first_ready_throw(scene))
    verdicts = {}
    dup = 0
    for v in msgs.get('/feeder/edge1_verdict', []):
        dup += v.seq in verdicts
        verdicts[v.seq] = v
    problems['cycles without a verdict'] = sum(1 for s in seqs if s not in verdicts)
    problems['duplicate verdicts'] = dup
    problems['verdicts not signed'] = sum(not signed(v) for v in verdicts.values())
    statements = msgs.get('/feeder/edge1_ready', [])
    problems['edge1_ready statements not signed'] = sum(not signed(v) for v in statements)
    problems['edge1_ready true without a ready verdict'] = sum(
        1 for v in statements if v.ready and not (v.seq in verdicts and verdicts[v.seq].ready))
    ready = np.array([verdicts[k + 1].ready if k + 1 in verdicts else False for k in range(m)])
    problems['false ready'] = int((ready & ~truth).sum())
    problems['missed ready after warm-up and settling'] = int((truth & ~ready).sum())
    problems['anomalies (false)'] = sum(1 for v in verdicts.values() if v.anomaly)
    return n, int(truth.sum()), problems


def memory_growth(samples, cycles):
    """
    RSS growth per 1000 cycles over the second half of the run (least squares), per node.

    Beside the slope: how many times RSS rose between samples and by how much at most, to
    tell a steady leak (many small rises) from the allocator growing an arena once (one step
    of a few hundred KB). rss.csv keeps the samples.
    """
    import numpy as np
    out = {}
    for name, pts in samples.items():
        pts = [(s, kb) for s, kb in pts if s >= cycles / 2]
        if len(pts) < 3:
            out[name] = (None, None, None, None)
            continue
        x = np.array([p[0] for p in pts], float)
        y = np.array([p[1] for p in pts], float)
        slope = np.polyfit(x, y, 1)[0] * 1000.0
        rises = np.diff(y)[np.diff(y) > 0]
        out[name] = (slope, int(y[0]), int(y[-1]), (len(rises), float(rises.max(initial=0))))
    return out


def write_samples(samples, path):
    """Every RSS sample as CSV (node, seq, rss_kb), to look at the curve behind the slope."""
    with open(path, 'w') as fh:
        fh.write('node,seq,rss_kb\n')
        for name, pts in samples.items():
            for seq, kb in pts:
                fh.write(f'{name},{seq},{kb}\n')


def read_samples(path):
    """rss.csv back into {node: [(seq, rss_kb), ...]}."""
    samples = {}
    for line in pathlib.Path(path).read_text().splitlines()[1:]:
        name, seq, kb = line.split(',')
        samples.setdefault(name, []).append((int(seq), int(kb)))
    return samples


def bag_chunks(bag):
    """(chunks, channels) in the bag's summary."""
    from mcap.reader import make_reader
    chunks = channels = 0
    for path in sorted(pathlib.Path(bag).glob('*.mcap')):
        with open(path, 'rb') as fh:
            summary = make_reader(fh).get_summary()
        chunks += len(summary.chunk_indexes)
        channels = max(channels, len(summary.channels))
    return chunks, channels


def chunk_index_bytes(channels, chunks=2000):
    """Python memory the recorder keeps per chunk written, with ``channels`` channels."""
    import tracemalloc
    from feeder_monitor.bag import McapLog
    with tempfile.TemporaryDirectory() as tmp:
        log = McapLog.create(pathlib.Path(tmp) / 'index.mcap', 'ros2', 'soak')
        schema = log.add_schema('std_msgs/msg/Bool', 'ros2msg', b'bool data')
        ids = [log.add_channel(f'/c{k}', schema, 'cdr', {}) for k in range(channels)]
        stamp = 0

        def one_chunk():
            nonlocal stamp
            for channel in ids:
                stamp += 1
                log.add_message(channel, stamp, b'\0' * 8, stamp, stamp)
            log.flush()

        for _ in range(10):
            one_chunk()
        tracemalloc.start()
        before = tracemalloc.get_traced_memory()[0]
        for _ in range(chunks):
            one_chunk()
        grown = tracemalloc.get_traced_memory()[0] - before
        tracemalloc.stop()
        log.close()
    return grown / chunks


def auth_key(out):
    from feeder_common import auth
    return auth.load_key(pathlib.Path(out) / 'hmac.key')


def judge(out, samples, args, load0):
    """Reconcile the bag, judge the memory, print the table; the exit status."""
    bag = out / 'bag'
    n, ready_truth, problems = reconcile(read_bag(bag), auth_key(out))
    growth = memory_growth(samples, n)
    chunks, channels = bag_chunks(bag)
    per_chunk = chunk_index_bytes(channels)
    index_kb = chunks / max(n, 1) * 1000 * per_chunk / 1024     # per 1000 cycles
    load1 = ', '.join(f'{x:.1f}' for x in os.getloadavg())
    rows = [('cycles in the bag', str(n), ''),
            ('cycles whose part is seen on the goal edge after the warm-up', str(ready_truth),
             '')]
    rows += [(k, str(v), '0') for k, v in problems.items()]
    flat = True
    for name, (slope, first, last, step) in growth.items():
        if slope is None:
            rows.append((f'RSS of {name}', 'too few samples', ''))
            continue
        index = index_kb if name == 'recorder' else 0.0
        flat &= slope - index < args.flat_kb
        of_which = (f'; of which the chunk index {index:.2f} ({chunks} chunks of '
                    f'{per_chunk:.0f} B), the rest {slope - index:+.2f}') if index else ''
        rows.append((f'RSS of {name}, second half', f'{first} -> {last} KB, '
                     f'{slope:+.2f} KB per 1000 cycles ({step[0]} rises, largest '
                     f'{step[1]:.0f} KB){of_which}',
                     f'< {args.flat_kb:g}' + (' beside the index' if index else '')))
    print(f'\nload average: {load0} at the start, {load1} at the end\n')
    print('| check | result | target |\n|---|---|---|')
    for r in rows:
        print('| ' + ' | '.join(r) + ' |')
    ok = flat and not any(problems.values()) and n >= args.cycles
    print(f'\nsoak: {"PASS" if ok else "FAIL"}')
    return 0 if ok else 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    ap.add_argument('--cycles', type=int, default=100_000)
    ap.add_argument('--out', type=pathlib.Path, default=None,
                    help='directory for the bag and the logs (default: a new temporary one)')
    ap.add_argument('--sample-every', type=float, default=2.0, metavar='S',
                    help='seconds between RSS samples (default 2)')
    ap.add_argument('--flat-kb', type=float, default=5.0,
                    help='memory counts as flat below this growth, KB per 1000 cycles '
                    '(default 5: 0.5 MB per 100,000 cycles)')
    ap.add_argument('--reread', type=pathlib.Path, default=None, metavar='DIR',
                    help="judge a finished run again from DIR's bag and rss.csv (no new run)")
    args = ap.parse_args()
    if args.reread is not None:
        out = args.reread.resolve()
        if not (out / 'bag').is_dir() or not (out / 'rss.csv').is_file():
            raise SystemExit(f'soak: {out} has no bag/ and rss.csv of a finished run')
        samples = read_samples(out / 'rss.csv')
        args.cycles = min(seq for pts in samples.values() for seq, _ in pts[-1:])
        return judge(out, samples, args, 'not recorded (a reread)')
    out = (args.out or pathlib.Path(tempfile.mkdtemp(prefix='feeder-soak-'))).resolve()
    out.mkdir(parents=True, exist_ok=True)
    bag = out / 'bag'
    if bag.exists():
        raise SystemExit(f'soak: {bag} exists; give another --out')
    domain, lock = use_domain()
    load0 = ', '.join(f'{x:.1f}' for x in os.getloadavg())
    print(f'soak: {args.cycles} cycles at cycle_period {PERIOD} s, ROS_DOMAIN_ID={domain} '
          f'(loopback), load average {load0}, bag and logs in {out}', flush=True)
    procs = Processes(out, error=SystemExit, prog='soak')
    drv = Driver(procs)
    samples = {}
    try:
        start(procs, bag, key_path(out))
        # Every writer matched its readers, by its own account (the nodes' endpoints
        # statuses): the stand-in's cycle_status the monitor, the predictor and the recorder;
        # its proximity the monitor and the recorder; the monitor's and the predictor's
        # outputs the recorder.
        drv.wait_remote_matched('/feeder/feeder_driver', readers={
            '/feeder/cycle_status': 3, '/feeder/proximity': 2}, timeout=120)
        drv.wait_remote_matched('/feeder/feeder_monitor', readers={
            '/feeder/edge1_verdict': 1, '/feeder/edge1_ready': 1}, timeout=120)
        drv.wait_remote_matched('/feeder/feeder_sim', readers={'/feeder/predicted/state': 1},
                                timeout=120)
        t0 = time.monotonic()
        drv.enable(True)
        next_sample = 0.0
        while drv.seq < args.cycles:
            procs.check()
            now = time.monotonic()
            if now >= next_sample:
                next_sample = now + args.sample_every
                for name, p in procs.procs.items():
                    samples.setdefault(name, []).append((drv.seq, rss_kb(p.pid)))
            drv.executor.spin_once(timeout_sec=0.2)
        drv.enable(False)
        wall = time.monotonic() - t0
        drv.spin_for(3.0)       # the last cycles reach the monitor and the bag
        procs.procs['recorder'].send_signal(signal.SIGINT)
        procs.procs['recorder'].wait(60)
    finally:
        drv.close()
        procs.stop_all()
        lock.close()
    fired = drv.seq
    print(f'soak: {fired}+ cycles in {wall:.0f} s ({fired / wall:.0f} cycles/s); reading the '
          'bag', flush=True)
    write_samples(samples, out / 'rss.csv')
    return judge(out, samples, args, load0)


if __name__ == '__main__':
    sys.exit(main())
