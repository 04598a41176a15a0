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
Attack soak (issue 20): the hardware path under a forger, a flaky sensor and bit errors at once.

Processes of the installed workspace, in one ROS domain of their own on loopback:
``controller_emulator`` (the triangle; a flaky sensor with ``--spurious-rate`` and
``--miss-rate``; ``--bit-error-rate`` on the bytes it sends and on the bytes it reads),
``driver_node`` on its pty, ``monitor_node``, ``bag_recorder`` and ``bench/forger.py`` (every
attack of issue 20 in turn, every ``--forge-every`` s). Driver and monitor share a key file
made for the run (``feeder_common.auth.ensure_key``, mode 0600, in the run folder); the forger
does not have it. The driver cycles every ``--period`` s until it has fired ``--cycles``.

Then the bag (read with the ``mcap`` reader, not the recorder's code) is reconciled with the
emulator's truth log by seq (the driver's seq is the wire seq unwrapped: wire = seq mod 65536):

* a **false ready** is a verdict with ready true whose cycle's part is not on the goal edge
  in the truth log, or that is not the verdict of a genuine (signed) report, or an authentic
  ``edge1_ready`` statement with ready true that no ready verdict of the same cycle backs;
  readies whose part is on the goal edge but not in the sensor's view (a spurious reading) are
  counted apart;
* verdicts with ready true that are not authentic (MAC) or stale (sent > 1 s after the
  cycle was sampled), and ready statements sent after the next cycle had fired;
* a **missed ready** is a genuine completed cycle after the warm-up whose part is seen on the
  goal edge with a true bit, whose verdict is not ready. Its cause: the anomaly of that cycle;
  else the newest anomaly before it if it came less than warm-up + settle throws (the
  monitor's rules, from its log) before: a forgery, a failed cycle (bit errors), the sensor
  pattern (the flaky sensor); else the start-up; else *superseded* when the verdict was sent
  after the next cycle fired; else *not proven by the rules* (e.g. the prediction not sure of
  the edge while it suspects the sensor);
* anomalies by kind, failed cycles by reason, the flaky readings and bit errors of the
  truth log, the forgeries sent by kind.

Prints a table (and writes it to ``DIR/summary.md``); exit status 0 when there is no false
ready, else 1; 2 when the run could not be made. Usage (after ``. scripts/setup.sh``)::

    python bench/attack_soak.py [--cycles 100000] [--spurious-rate 0.01] [--miss-rate P]
        [--bit-error-rate 1e-4] [--forge-every 2] [--period 0.01] [--out DIR] | --reread DIR
"""

import argparse
import bisect
import collections
import importlib
import json
import os
import pathlib
import sys
import time

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'tests'))

# The harness (processes, domain, probe node): tests/feeder_testing.py
from feeder_testing import Probe, Processes, use_domain  # noqa: E402

SCENE = str(REPO / 'scenes' / 'triangle.yaml')
NS = '/feeder'
DRIVER = f'{NS}/feeder_driver'
MONITOR = f'{NS}/feeder_monitor'
TOPICS = ('cycle_status', 'cycle_fired', 'edge1_verdict', 'edge1_ready')
SEQ_MODULO = 65536          # feeder_driver.protocol.SEQ_MODULO
MAX_AGE_NS = 1_000_000_000  # the monitor's max_report_age (default 1 s)
NS_PER_S = 1_000_000_000


# ---- the run ----------------------------------------------------------------------------------

def run(args, out):
    """Start the graph, cycle until ``args.cycles`` fired, stop; return the run's facts."""
    from feeder_common import auth
    key_file = out / 'hmac.key'
    auth.ensure_key(key_file)
    domain, lock = use_domain()
    link = out / 'tty'
    load0 = ', '.join(f'{x:.1f}' for x in os.getloadavg())
    print(f'attack_soak: {args.cycles} cycles every {args.period} s (emulator cycle time '
          f'{args.cycle_time} s), flaky sensor spurious {args.spurious_rate} miss '
          f'{args.miss_rate}, bit errors {args.bit_error_rate} per byte, an attack every '
          f'{args.forge_every} s; ROS_DOMAIN_ID={domain} (loopback), load {load0}; in {out}',
          flush=True)
    procs = Processes(out / 'logs', error=SystemExit, prog='attack_soak')
    from diagnostic_msgs.msg import DiagnosticArray
    from feeder_common.diagnostics import local_name
    from std_srvs.srv import SetBool
    probe = Probe('feeder_attack_soak', procs=procs, watch=True, error=SystemExit)
    node = probe.node
    diag = {}

    def on_diag(msg):
        for s in msg.status:
            # by '<node>: <task>' (the status names carry the namespace)
            diag[local_name(s.name)] = {kv.key: kv.value for kv in s.values}

    node.create_subscription(DiagnosticArray, '/diagnostics', on_diag, 50)

    def fired():
        return int(diag.get('feeder_driver: cycles', {}).get('fired', 0))

    def enable(on):
        for _ in range(50):
            res = probe.call(SetBool, f'{DRIVER}/enable', SetBool.Request(data=on))
            if res.success:
                break
            probe.spin_for(0.2)     # the link is not up yet
        else:
            raise SystemExit(f'attack_soak: enable {on} refused: {res.message}')

    t_wall = None
    ros = ['--ros-args', '-r', f'__ns:={NS}']
    try:
        procs.start('feeder_driver', 'controller_emulator', '--scene', SCENE,
                    '--link', link, '--cycle-time', args.cycle_time, '--heartbeat', 0.25,
                    '--spurious-rate', args.spurious_rate, '--miss-rate', args.miss_rate,
                    '--bit-error-rate', args.bit_error_rate, '--host-bit-error-rate',
                    args.bit_error_rate, '--seed', args.seed, '--truth-log',
                    out / 'truth.jsonl', name='emulator')
        end = time.monotonic() + 60
        while not os.path.islink(link):
            procs.check()
            if time.monotonic() > end:
                raise SystemExit('attack_soak: the emulator made no pty in 60 s')
            time.sleep(0.1)
        procs.start('feeder_monitor', 'bag_recorder', out / 'bag', '--topics', *TOPICS, *ros,
                    name='recorder')
        procs.start('feeder_monitor', 'monitor_node', *ros, '-p', f'scene:={SCENE}',
                    '-p', f'key_file:={key_file}', name='monitor')
        procs.start('feeder_driver', 'driver_node', *ros, '-p', f'port:={link}',
                    '-p', f'key_file:={key_file}', '-p', f'cycle_period:={args.period}',
                    '-p', 'ack_timeout_s:=0.1', '-p', 'cycle_timeout_s:=0.5', name='driver')
        # The writers matched their readers, by their own accounts (the nodes' endpoints
        # statuses): the driver's reports the monitor and the recorder, the monitor's
        # statements the recorder.
        probe.wait_remote_matched(DRIVER, readers={f'{NS}/cycle_status': 2,
                                                   f'{NS}/cycle_fired': 2}, timeout=120)
        probe.wait_remote_matched(MONITOR, readers={f'{NS}/edge1_verdict': 1,
                                                    f'{NS}/edge1_ready': 1}, timeout=120)
        procs.command([sys.executable, REPO / 'bench' / 'forger.py', '--ns', NS,
                       '--every', args.forge_every, '--log', out / 'forgeries.jsonl',
                       '--counts', out / 'forger.json'], 'forger')
        probe.wait_remote_matched(DRIVER, readers={f'{NS}/cycle_status': 3}, timeout=120)
        enable(True)
        t0 = time.monotonic()
        last_print = t0
        while fired() < args.cycles:
            procs.check()
            probe.executor.spin_once(timeout_sec=0.2)
            if time.monotonic() - last_print >= 60:
                last_print = time.monotonic()
                rate = fired() / (last_print - t0)
                print(f'attack_soak: {fired()} cycles fired in {last_print - t0:.0f} s '
                      f'({rate:.0f}/s)', flush=True)
        enable(False)
        t_wall = time.monotonic() - t0
        probe.spin_for(3.0)       # the last cycles reach the monitor and the bag
        procs.stop('forger')
        procs.stop('recorder', timeout=60)
    finally:
        probe.close()
        procs.stop_all()
        lock.close()
    facts = {'cycles_fired': fired(), 'wall_s': t_wall, 'load_start': load0,
             'load_end': ', '.join(f'{x:.1f}' for x in os.getloadavg()),
             'args': {k: (str(v) if isinstance(v, pathlib.Path) else v)
                      for k, v in vars(args).items()},
             'diagnostics': diag}
    (out / 'run.json').write_text(json.dumps(facts, indent=1))
    return facts


# ---- reading back -----------------------------------------------------------------------------

def read_bag(bag):
    """Yield (topic, log_time_ns, message) of the bag in log order (mcap reader, rclpy)."""
    from mcap.reader import make_reader
    from rclpy.serialization import deserialize_message
    classes = {}
    files = sorted(pathlib.Path(bag).glob('*.mcap'))
    if not files:
        raise SystemExit(f'attack_soak: no .mcap file in {bag}')
    for path in files:
        with open(path, 'rb') as fh:
            for schema, channel, message in make_reader(fh).iter_messages(log_time_order=True):
                cls = classes.get(schema.name)
                if cls is None:
                    pkg, kind, name = schema.name.split('/')
                    cls = classes[schema.name] = getattr(
                        importlib.import_module(f'{pkg}.{kind}'), name)
                yield (channel.topic, message.log_time,
                       deserialize_message(message.data, cls))


def read_truth(path):
    """Return (header, {driver seq: fire record}, host-side bit error lines) of a truth log."""
    header, by_seq, rx_errors = None, {}, 0
    full = None
    for line in open(path, encoding='utf-8'):
        rec = json.loads(line)
        if rec['type'] == 'header':
            header = rec
            continue
        if rec['type'] == 'rx_bit_errors':
            rx_errors += 1
            continue
        if rec['type'] != 'fire':
            continue
        wire = rec['seq']
        # Unwrap: the driver's seqs only grow, by less than SEQ_MODULO between two FIREs.
        full = wire if full is None else full + (wire - full) % SEQ_MODULO
        if rec.get('cycle') is not None or full not in by_seq:
            by_seq[full] = rec
    return header, by_seq, rx_errors


def anomaly_kind(text):
    """Name the cause of an anomaly from its text (feeder_monitor.readiness and monitor_node)."""
    t = text or ''
    if 'not trusted' in t:
        for key, kind in (('unsigned', 'unsigned report'), ('bad MAC', 'bad MAC'),
                          ('stale', 'stale report'), ('stamped', 'report from the future'),
                          ('replayed', 'replayed report'), ('ended driver run', 'ended run'),
                          ('malformed', 'malformed report'), ('without a sample', 'no stamp')):
            if key in t:
                return f'refused: {kind}'
        return 'refused: other'
    if 'failed:' in t:
        return 'failed cycle'
    if 'detection after only' in t or 'consecutive detections' in t or \
            'no detection for' in t or 'limit set cannot show' in t:
        return 'sensor pattern'
    if 'missing cycles' in t or 'seq went back' in t:
        return 'seq gap'
    if 'proximity' in t:
        return 'proximity cross-check'
    if 'not alive' in t or 'left its active' in t or 'stalled' in t or 'new run' in t:
        return 'driver or monitor liveness'
    return 'other'


def monitor_rules(out):
    """Return (warm-up, settle) throws from the monitor's log line of its rules."""
    import re
    text = (out / 'logs' / 'monitor.log').read_text(errors='replace')
    m = re.search(r'warm-up (\d+), settle (\d+)', text)
    if not m:
        raise SystemExit('attack_soak: the monitor log names no warm-up and settle')
    return int(m.group(1)), int(m.group(2))


def cause_group(kind, genuine_stale):
    """Group an anomaly kind by what in the soak made it."""
    if kind.startswith('refused'):
        return 'genuine report refused (late)' if genuine_stale else 'forgery'
    return {'failed cycle': 'failed cycle (bit errors)',
            'sensor pattern': 'sensor pattern (flaky sensor)'}.get(kind, kind)


def reconcile(out):
    """Reconcile the bag with the truth log; (rows, false_readies)."""
    from feeder_common import auth
    from feeder_common.messages import parse_cycle_status, parse_cycle_fired, time_ns
    key = auth.load_key(out / 'hmac.key')
    header, truth, rx_errors = read_truth(out / 'truth.jsonl')
    goal = header['goal_edge']
    warmup = header.get('warmup_throws') or 1
    msgs = read_bag(out / 'bag')
    count = collections.Counter()
    genuine = {}                # seq -> CycleStatus (signed by the driver)
    fired_stamp = {}            # seq -> stamp of the genuine fired notice
    failures = collections.Counter()
    verdicts = []               # (log index, Verdict fields)
    statements = []
    for i, (topic, _, m) in enumerate(msgs):
        if topic == f'{NS}/cycle_status':
            try:
                st = parse_cycle_status(m)
            except ValueError:
                count['cycle_status unparsable'] += 1
                continue
            fields = auth.cycle_fields(DRIVER, st.session, st.seq, st.stamp_ns,
                                       'completed' if st.ok else 'failed',
                                       {True: '1', False: '0', None: 'none'}[st.sensor],
                                       st.reason)
            if st.mac and auth.mac_ok(key, auth.CYCLE_LABEL, fields, st.mac):
                if st.seq in genuine:
                    count['genuine reports seen again (replays)'] += 1
                    continue
                genuine[st.seq] = st
                if not st.ok:
                    failures[st.reason.split(' (')[0].split(':')[0][:60]] += 1
            else:
                count['forged reports in the bag'] += 1
        elif topic == f'{NS}/cycle_fired':
            try:
                f = parse_cycle_fired(m)
            except ValueError:
                continue
            if f.mac and auth.mac_ok(key, auth.FIRED_LABEL, auth.fired_fields(
                    DRIVER, f.session, f.seq, f.stamp_ns), f.mac):
                fired_stamp.setdefault(f.seq, f.stamp_ns)
            else:
                count['forged fired notices in the bag'] += 1
        elif topic in (f'{NS}/edge1_verdict', f'{NS}/edge1_ready'):
            stamp = time_ns(m.stamp) if (m.stamp.sec or m.stamp.nanosec) else None
            sent = time_ns(m.sent)
            authentic = bool(m.mac) and auth.mac_ok(key, auth.VERDICT_LABEL, auth.verdict_fields(
                MONITOR, m.session, m.seq, stamp, m.ready, m.state, m.anomaly, sent),
                bytes(m.mac))
            v = (i, m.seq, stamp, m.ready, m.state, m.anomaly, sent, authentic)
            (verdicts if topic.endswith('verdict') else statements).append(v)

    # Verdicts of genuine reports: the first verdict of each (seq, stamp) that a genuine
    # report carries; every other verdict judged a forgery or a replay.
    first = {}
    for v in verdicts:
        first.setdefault((v[1], v[2]), v)
    gverdict = {}
    for seq, st in genuine.items():
        v = first.get((seq, st.stamp_ns))
        if v is not None:
            gverdict[seq] = v
    gv_index = {v[0] for v in gverdict.values()}
    ready_verdicts = [v for v in verdicts if v[3]]
    false_edge = false_unseen = ready_not_genuine = 0
    false_list = []
    for v in ready_verdicts:
        if v[0] not in gv_index:
            ready_not_genuine += 1
            false_list.append((v[1], 'not the verdict of a genuine report', None))
            continue
        rec = truth.get(v[1])
        if rec is None or rec.get('edge') != goal:
            false_edge += 1
            false_list.append((v[1], 'part not on the goal edge', rec))
        elif not rec.get('seen'):
            false_unseen += 1
    bad_ready = sum(1 for v in ready_verdicts if not v[7])
    stale_ready = sum(1 for v in ready_verdicts if v[2] is None or v[6] - v[2] > MAX_AGE_NS)
    ready_keys = {(v[1], v[2]) for v in ready_verdicts if v[7]}
    rogue = sum(1 for s in statements if not s[7] and s[3])
    unbacked = sum(1 for s in statements if s[7] and s[3] and (s[1], s[2]) not in ready_keys)
    lags = [s[6] - fired_stamp[s[1] + 1] for s in statements
            if s[7] and s[3] and fired_stamp.get(s[1] + 1) is not None and
            s[6] > fired_stamp[s[1] + 1]]

    # Anomalies in log order, with their cause and the newest genuine seq judged before
    # them; then each missed ready's cause.
    anomalies = []          # (log index, kind, group, newest genuine seq)
    genuine_keys = {(seq, st.stamp_ns) for seq, st in genuine.items()}
    newest = 0
    for v in verdicts:
        if v[0] in gv_index:
            newest = max(newest, v[1])
        if v[5]:
            kind = anomaly_kind(v[5])
            is_first_of_genuine = (v[1], v[2]) in genuine_keys and first[(v[1], v[2])] is v
            anomalies.append((v[0], kind, cause_group(kind, is_first_of_genuine), newest))
    # Interrupts (the driver left or stalled, the monitor stalled) show on edge1_ready only.
    # A statement is republished while idle: count each interrupt once.
    interrupts, prev = [], None
    for s in statements:
        if s[7] and s[5] and (s[1], s[5]) != prev and \
                anomaly_kind(s[5]) == 'driver or monitor liveness':
            interrupts.append((s[0], anomaly_kind(s[5]), s[1]))
        prev = (s[1], s[5]) if s[7] else prev
    events = sorted(anomalies + [(i, k, k, seq) for i, k, seq in interrupts])
    kinds = collections.Counter(a[1] for a in anomalies)
    kinds.update(k for _, k, _ in interrupts)
    idx = [e[0] for e in events]
    warmup_m, settle = monitor_rules(out)
    window = warmup_m + settle + 1      # throws after a restart before a ready can come
    candidates = 0
    missed = collections.Counter()
    for seq, st in genuine.items():
        rec = truth.get(seq)
        if not st.ok or not st.sensor or seq < warmup or rec is None or \
                rec.get('edge') != goal or not rec.get('seen'):
            continue
        candidates += 1
        v = gverdict.get(seq)
        if v is not None and v[3]:
            continue
        if v is None:
            missed['no verdict'] += 1
            continue
        if v[5]:
            missed[f'{cause_group(anomaly_kind(v[5]), False)} (this cycle)'] += 1
            continue
        k = bisect.bisect_left(idx, v[0]) - 1
        nxt = fired_stamp.get(seq + 1)
        if k >= 0 and seq - events[k][3] <= window:
            missed[events[k][2]] += 1
        elif k < 0 and seq <= window:
            missed['start-up warm-up'] += 1
        elif nxt is not None and v[6] > nxt:
            missed['superseded: the next cycle fired before the verdict'] += 1
        else:
            missed['not proven by the rules (e.g. the prediction unsure of the edge)'] += 1

    completed = [st for st in genuine.values() if st.ok]
    flaky = collections.Counter(truth[st.seq].get('flaky') for st in completed
                                if st.seq in truth)
    frames_hit = collections.Counter(f for r in truth.values()
                                     for f in (r.get('bit_errors') or {}))
    forger = {}
    if (out / 'forger.json').is_file():
        forger = json.loads((out / 'forger.json').read_text())
    runf = json.loads((out / 'run.json').read_text()) if (out / 'run.json').is_file() else {}
    n = len(genuine)
    wall = runf.get('wall_s')
    rows = [
        ('cycles fired (driver)', runf.get('cycles_fired', '?')),
        ('genuine cycle reports in the bag', n),
        ('wall time', f'{wall:.0f} s ({n / wall:.1f} cycles/s)' if wall else '?'),
        ('failed cycles', f'{sum(failures.values())}: ' + '; '.join(
            f'{k} {v}' for k, v in failures.most_common())),
        ('cycles in the truth log', len(truth)),
        ('flaky sensor on completed cycles', ', '.join(
            f'{k or "true reading"} {v}' for k, v in flaky.most_common())),
        ('frames sent with a bit error (truth log)', ', '.join(
            f'{k} {v}' for k, v in frames_hit.most_common()) or '0'),
        ('reads from the host with a bit error', rx_errors),
        ('verdicts', len(verdicts)),
        ('ready verdicts', len(ready_verdicts)),
        ('**false readies: part not on the goal edge**', false_edge),
        ('**false readies: ready verdict not of a genuine report**', ready_not_genuine),
        ('**false readies: signed ready statement without a ready verdict**', unbacked),
        ('ready verdicts on the goal edge but not in the sensor view (spurious bit)',
         false_unseen),
        ('ready verdicts not authentic / stale', f'{bad_ready} / {stale_ready}'),
        ('signed ready statements sent after the next cycle fired (its notice in flight)',
         f'{len(lags)}' + (f', at most {max(lags) / 1e6:.1f} ms after' if lags else '')),
        ('unsigned ready statements on edge1_ready (rogue writer)', rogue),
        ('monitor rules: warm-up, settle (throws)', f'{warmup_m}, {settle}'),
        ('cycles seen on the goal edge with bit 1 after the warm-up', candidates),
        ('missed readies', f'{sum(missed.values())} '
                           f'({100 * sum(missed.values()) / max(candidates, 1):.1f} %)'),
    ]
    rows += [(f'  missed: {k}', v) for k, v in missed.most_common()]
    rows += [(f'anomalies: {k}', v) for k, v in kinds.most_common()]
    rows += [(k, v) for k, v in sorted(count.items())]
    for k, v in sorted(forger.get('sent', {}).items()):
        acked = f' (acknowledged by every reader before it left: ' \
            f'{forger.get("acked", {}).get(k, 0)})' if k.startswith('hit') else ''
        rows.append((f'forger sent: {k}', f'{v}{acked}'))
    false = false_edge + ready_not_genuine + unbacked
    return rows, false, false_list


def report(out):
    """Print the table, write summary.md; the exit status."""
    rows, false, false_list = reconcile(out)
    lines = ['| figure | value |', '|---|---|'] + [f'| {k} | {v} |' for k, v in rows]
    for seq, why, rec in false_list[:20]:
        lines.append(f'\nfalse ready: seq {seq}: {why}; truth {json.dumps(rec)}')
    lines.append(f'\nattack_soak: {"PASS" if false == 0 else "FAIL"}: {false} false readies')
    text = '\n'.join(lines)
    print(text, flush=True)
    (out / 'summary.md').write_text(text + '\n')
    return 0 if false == 0 else 1


def main():
    """Run the soak (or reread one) and report; the exit status."""
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    ap.add_argument('--cycles', type=int, default=100_000,
                    help='cycles the driver fires (default 100000)')
    ap.add_argument('--spurious-rate', type=float, default=0.01,
                    help='flaky sensor: a 1 when the part is not seen (default 0.01)')
    ap.add_argument('--miss-rate', type=float, default=None,
                    help='flaky sensor: a 0 when the part is seen (default: the spurious rate)')
    ap.add_argument('--bit-error-rate', type=float, default=1e-4,
                    help='per byte, both directions (default 1e-4)')
    ap.add_argument('--forge-every', type=float, default=2.0, metavar='S',
                    help='seconds between two attacks of the forger (default 2)')
    ap.add_argument('--period', type=float, default=0.01,
                    help="driver cycle_period, s (default 0.01, the driver's minimum)")
    ap.add_argument('--cycle-time', type=float, default=0.004,
                    help="emulator's FIRE-to-SENS time, s (default 0.004)")
    ap.add_argument('--seed', type=int, default=1,
                    help="seed of the emulator's flaky sensor and bit errors (default 1)")
    ap.add_argument('--out', type=pathlib.Path, default=None,
                    help='run folder (default out/attack-soak-<date>-<time>)')
    ap.add_argument('--reread', type=pathlib.Path, default=None, metavar='DIR',
                    help='reconcile a finished run in DIR again (no new run)')
    args = ap.parse_args()
    if args.miss_rate is None:
        args.miss_rate = args.spurious_rate
    if args.reread is not None:
        return report(args.reread.resolve())
    out = (args.out or REPO / 'out' / f'attack-soak-{time.strftime("%Y%m%d-%H%M%S")}')
    out = out.resolve()
    if (out / 'bag').exists():
        raise SystemExit(f'attack_soak: {out}/bag exists; give another --out')
    out.mkdir(parents=True, exist_ok=True)
    run(args, out)
    print('attack_soak: reading the bag', flush=True)
    return report(out)


if __name__ == '__main__':
    sys.exit(main())
