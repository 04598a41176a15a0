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
Forger: the attacks of issue 20 against a feeder namespace, without the key, counted.

A process on the feeder's DDS domain that does not hold the key file. Every ``--every`` s it
makes the next attack of this round, in turn:

* ``hit_unsigned`` / ``hit_bad_mac``: hit and run. A new node in a new context (its own DDS
  participant) publishes one ``cycle_status`` with seq = the last seen + 1, sensor 1, a fresh
  stamp, unsigned or signed with a wrong key (as the driver, in its current session), waits
  until the readers have it, and leaves the graph at once;
* ``replay_fresh``: re-publishes the newest genuine signed ``cycle_status`` it recorded (within
  the monitor's ``max_report_age``); ``replay_stale``: one recorded 2-5 s ago;
  ``replay_old_run``: the report of an ended driver run whose seq is the current run's next,
  if it saw an ended run (else counted as skipped);
* ``fired_unsigned`` / ``fired_bad_mac``: a forged ``cycle_fired`` notice for the next seq;
* ``rogue_ready``: a rogue writer on ``edge1_ready`` publishes an unsigned
  ``Verdict(ready=True)`` for the last seen seq;
* ``malformed``: a ``cycle_status`` (feeder_interfaces/CycleStatus) for the next seq, signed
  with a wrong key, with one field set to a value the type holds and no driver writes (a seq
  of 2**64 - 1 or 2**63, an unknown outcome or sensor code, a stamp before 1970 or with
  nanosec past 1e9, texts of 5000 and 100000 characters, a session that is not hex, a MAC of
  31 bytes), the next of :data:`MALFORMED` each time.

Each attack sent is one JSON line in ``--log`` (time, kind, seq, stamp; for a hit and run,
whether every reader acknowledged it before it left: it waits at most 1 s); on SIGINT or
SIGTERM it prints the counts and writes them to ``--counts``. Run it with the workspace's
environment (``. scripts/setup.sh``)::

    python bench/forger.py [--ns /feeder] [--every 2.0] [--log F] [--counts F]
"""

import argparse
import collections
import json
import os
import secrets
import signal
import sys
import time

ATTACKS = ('hit_unsigned', 'replay_fresh', 'fired_unsigned', 'hit_bad_mac', 'replay_stale',
           'rogue_ready', 'fired_bad_mac', 'replay_old_run', 'malformed')
# The hostile field values of the ``malformed`` attack, in turn: (field, value).
MALFORMED = (
    ('seq', 2**64 - 1), ('outcome', 'Completed'), ('sensor', 7), ('stamp', (-1, 0)),
    ('reason', 'x' * 5000), ('session', 'NOT-HEX'), ('mac', b'\xff' * 31), ('seq', 2**63),
    ('outcome', '1' + '0' * 400), ('sensor', -128), ('stamp', (1, 2**32 - 1)),
    ('hardware_id', 'x' * 100_000),
)
STALE_MIN_S, STALE_MAX_S = 2.0, 5.0     # a stale replay: recorded this long ago
HISTORY = 2000                          # genuine reports kept
HIT_ACK_WAIT_S = 1.0    # a hit and run leaves once every reader acknowledged, or after this


class Forger:
    """The forger's long-lived node (its own context) and the attacks."""

    def __init__(self, rclpy, ns, log):
        """Join the graph in a context of its own; ``log``: the JSON lines file or None."""
        from feeder_common import qos
        from feeder_interfaces.msg import CycleStatus, Verdict
        self.rclpy = rclpy
        self.ns = ns.rstrip('/')
        self.driver = f'{self.ns}/feeder_driver'
        self.ctx = rclpy.Context()
        rclpy.init(context=self.ctx)
        self.node = rclpy.create_node('feeder_forger', context=self.ctx)
        self.qos = qos
        self.Status = CycleStatus
        self.Verdict = Verdict
        self.wrong_key = secrets.token_bytes(32)
        self._ack_wait = rclpy.duration.Duration(seconds=HIT_ACK_WAIT_S)
        self.hardware_id = ''           # the driver's port, copied into the forgeries
        self.own_stamps = collections.deque(maxlen=100)     # stamps of our forged reports
        self.last_seq = 0
        self.session = None
        self.sessions = []              # driver sessions seen, in order
        self.genuine = collections.deque(maxlen=HISTORY)   # (received monotonic, msg, seq)
        self.old_runs = {}              # ended session -> {seq: msg}
        self.counts = collections.Counter()
        self.acked = collections.Counter()
        self.log = open(log, 'a', encoding='utf-8') if log else None
        self.node.create_subscription(CycleStatus, f'{self.ns}/cycle_status',
                                      self._on_status, qos.CYCLE_STATUS)
        self.replay_pub = self.node.create_publisher(CycleStatus, f'{self.ns}/cycle_status',
                                                     qos.CYCLE_STATUS)
        self.fired_pub = self.node.create_publisher(CycleStatus, f'{self.ns}/cycle_fired',
                                                    qos.CYCLE_FIRED)
        self.ready_pub = self.node.create_publisher(Verdict, f'{self.ns}/edge1_ready',
                                                    qos.edge1_ready(1.0))
        self.executor = rclpy.executors.SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)

    # ---- what the genuine driver says -------------------------------------------------------
    def _on_status(self, msg):
        from feeder_common.messages import parse_cycle_status
        try:
            st = parse_cycle_status(msg)
        except ValueError:
            return
        if not st.mac or not st.session or st.stamp_ns in self.own_stamps:
            return                      # our own forgeries (or someone else's unsigned ones)
        self.hardware_id = st.hardware_id
        if st.session != self.session:
            if self.session is not None:
                self.old_runs[self.session] = {m_seq: m for _, m, m_seq in self.genuine}
            self.session = st.session
            self.sessions.append(st.session)
            self.last_seq = 0
        # A replay of ours comes back too: keep the first copy of each seq only.
        if st.seq > self.last_seq:
            self.last_seq = st.seq
            self.genuine.append((time.monotonic(), msg, st.seq))

    # ---- attacks ----------------------------------------------------------------------------
    def _now_ns(self):
        return self.node.get_clock().now().nanoseconds

    def _record(self, kind, seq=None, stamp_ns=None, acked=None, note=''):
        self.counts[kind] += 1
        if acked:
            self.acked[kind] += 1
        if self.log:
            self.log.write(json.dumps({'t': time.time(), 'kind': kind, 'seq': seq,
                                       'stamp_ns': stamp_ns, 'acked': acked,
                                       'note': note}) + '\n')
            self.log.flush()

    def spin(self, timeout):
        """Handle at most one pending message (the long-lived node's), waiting ``timeout`` s."""
        self.executor.spin_once(timeout_sec=timeout)

    def drain(self, most=1000):
        """Handle the messages already waiting, so that ``last_seq`` is the newest seen."""
        for _ in range(most):
            before = (self.last_seq, len(self.genuine))
            self.executor.spin_once(timeout_sec=0.0)
            if (self.last_seq, len(self.genuine)) == before:
                break

    def _forged_status(self, seq, stamp_ns, signed):
        """Build a report of cycle ``seq``, sensor 1: unsigned, or signed with a wrong key."""
        from feeder_common.messages import cycle_status, CycleSigner
        self.own_stamps.append(stamp_ns)
        if signed:
            return CycleSigner(self.wrong_key, self.driver, self.session).cycle_status(
                seq, True, '', True, stamp_ns, self.hardware_id)
        return cycle_status(seq, True, '', True, stamp_ns, self.hardware_id)

    def hit_and_run(self, signed):
        """Publish one forged report from a new participant, wait for the acks, and leave."""
        rclpy = self.rclpy
        expected = self.node.count_subscribers(f'{self.ns}/cycle_status')
        ctx = rclpy.Context()
        rclpy.init(context=ctx)
        try:
            node = rclpy.create_node(f'hit_{secrets.token_hex(3)}', context=ctx)
            pub = node.create_publisher(self.Status, f'{self.ns}/cycle_status',
                                        self.qos.CYCLE_STATUS)
            end = time.monotonic() + 2.0
            while pub.get_subscription_count() < expected and time.monotonic() < end:
                self.spin(0.005)        # keep up with the driver meanwhile
            self.drain()
            seq = self.last_seq + 1
            stamp = node.get_clock().now().nanoseconds
            pub.publish(self._forged_status(seq, stamp, signed))
            acked = pub.wait_for_all_acked(self._ack_wait)
            node.destroy_node()
        finally:
            rclpy.shutdown(context=ctx)
        self._record('hit_bad_mac' if signed else 'hit_unsigned', seq, stamp, acked)

    def _replay(self, kind, msg, seq, note=''):
        self.replay_pub.publish(msg)
        self._record(kind, seq, None, None, note)

    def replay_fresh(self):
        """Replay the newest genuine report (within the monitor's max_report_age)."""
        if not self.genuine:
            return self._record('skipped_replay_fresh')
        t, msg, seq = self.genuine[-1]
        self._replay('replay_fresh', msg, seq, f'recorded {time.monotonic() - t:.3f} s ago')

    def replay_stale(self):
        """Replay a genuine report recorded 2-5 s ago."""
        now = time.monotonic()
        old = [g for g in self.genuine if STALE_MIN_S <= now - g[0] <= STALE_MAX_S]
        if not old:
            old = [g for g in self.genuine if now - g[0] >= STALE_MIN_S]
        if not old:
            return self._record('skipped_replay_stale')
        t, msg, seq = old[-1]
        self._replay('replay_stale', msg, seq, f'recorded {now - t:.3f} s ago')

    def replay_old_run(self):
        """Replay an ended run's report whose seq is the current run's next, if any."""
        for session, by_seq in self.old_runs.items():
            msg = by_seq.get(self.last_seq + 1)
            if msg is not None:
                return self._replay('replay_old_run', msg, self.last_seq + 1, session)
        self._record('skipped_replay_old_run')

    def fired(self, signed):
        """Publish a forged fired notice for the next seq (unsigned or with a wrong key)."""
        from feeder_common.messages import CycleSigner, time_msg
        seq, stamp = self.last_seq + 1, self._now_ns()
        if signed:
            msg = CycleSigner(self.wrong_key, self.driver, self.session).cycle_fired(
                seq, stamp, self.hardware_id)
        else:
            msg = self.Status(seq=seq, stamp=time_msg(stamp), outcome=self.Status.OUTCOME_FIRED,
                              sensor=self.Status.SENSOR_NONE, hardware_id=self.hardware_id)
        self.fired_pub.publish(msg)
        self._record('fired_bad_mac' if signed else 'fired_unsigned', seq, stamp)

    def malformed(self):
        """Publish a report for the next seq with one hostile field (the next of MALFORMED)."""
        from builtin_interfaces.msg import Time
        name, value = MALFORMED[self.counts['malformed'] % len(MALFORMED)]
        seq, stamp = self.last_seq + 1, self._now_ns()
        msg = self._forged_status(seq, stamp, True)
        if name == 'stamp':
            msg.stamp = Time(sec=value[0], nanosec=value[1])
        elif name == 'mac':
            msg.mac = list(value)
        else:
            setattr(msg, name, value)
        self.replay_pub.publish(msg)
        self._record('malformed', seq, stamp, note=f'{name} {str(value)[:24]}')

    def rogue_ready(self):
        """Publish an unsigned Verdict(ready=True) on edge1_ready."""
        from feeder_common.messages import time_msg
        now = self._now_ns()
        msg = self.Verdict(seq=self.last_seq, ready=True, state=self.Verdict.STATE_READY,
                           session='forged', stamp=time_msg(now), sent=time_msg(now))
        self.ready_pub.publish(msg)
        self._record('rogue_ready', self.last_seq, now)

    def attack(self, kind):
        """Make one attack of ``kind`` (one of ATTACKS), on the newest report seen."""
        self.drain()
        {'hit_unsigned': lambda: self.hit_and_run(False),
         'hit_bad_mac': lambda: self.hit_and_run(True),
         'replay_fresh': self.replay_fresh, 'replay_stale': self.replay_stale,
         'replay_old_run': self.replay_old_run,
         'fired_unsigned': lambda: self.fired(False), 'fired_bad_mac': lambda: self.fired(True),
         'rogue_ready': self.rogue_ready, 'malformed': self.malformed}[kind]()

    def summary(self):
        """Return the counts: {kind: sent}, and the hit and runs every reader acknowledged."""
        return {'sent': dict(sorted(self.counts.items())),
                'acked': dict(sorted(self.acked.items())),
                'driver_sessions_seen': len(self.sessions), 'last_seq_seen': self.last_seq}

    def close(self):
        """Leave the graph."""
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.shutdown(context=self.ctx)
        if self.log:
            self.log.close()


def main(argv=None):
    """Attack until SIGINT/SIGTERM; print and write the counts."""
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    ap.add_argument('--ns', default='/feeder', help='the feeder namespace (default /feeder)')
    ap.add_argument('--every', type=float, default=2.0, metavar='S',
                    help='seconds between two attacks (default 2)')
    ap.add_argument('--attacks', default=','.join(ATTACKS),
                    help='comma-separated attacks to rotate through (default: all)')
    ap.add_argument('--log', default=None, help='JSON line per attack sent (appended)')
    ap.add_argument('--counts', default=None, help='write the counts here (JSON) at exit')
    args = ap.parse_args(argv)
    kinds = [k for k in args.attacks.split(',') if k]
    bad = [k for k in kinds if k not in ATTACKS]
    if bad or not kinds or not args.every > 0:
        print(f'forger: error: unknown attacks {bad} (known: {", ".join(ATTACKS)}) or '
              f'--every <= 0', file=sys.stderr)
        return 2
    import rclpy
    import rclpy.duration
    import rclpy.executors
    forger = Forger(rclpy, args.ns, args.log)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    print(f'forger: {args.ns}, one attack every {args.every} s: {", ".join(kinds)}',
          flush=True)
    k = 0
    next_at = time.monotonic() + args.every
    try:
        while not stop:
            forger.spin(0.05)
            if time.monotonic() >= next_at and forger.last_seq > 0:
                forger.attack(kinds[k % len(kinds)])
                k += 1
                next_at = time.monotonic() + args.every
    finally:
        summary = forger.summary()
        forger.close()
        print('forger: ' + json.dumps(summary), flush=True)
        if args.counts:
            tmp = f'{args.counts}.tmp{os.getpid()}'
            with open(tmp, 'w') as fh:
                json.dump(summary, fh, indent=1)
            os.replace(tmp, args.counts)
    return 0


if __name__ == '__main__':
    sys.exit(main())
