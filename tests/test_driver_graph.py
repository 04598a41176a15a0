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
The real driver against the emulated controller, with the monitor, as processes on real DDS.

controller_emulator (pty, throw-map truth, injected faults) <- serial -> driver_node ->
proximity + cycle_status (signed, with the test's key) -> monitor_node -> edge1_ready. Every
cycle the driver fires is accounted for against the emulator's truth log, and the monitor's
signed verdict is checked cycle by cycle: true exactly when the cycle completed, the part lies
on the goal edge and the sensor sees it, once the warm-up and the settling are done (both
restart at every failed cycle: issue 20, no ready while a pattern check is off). With a
failure every few cycles that never happens: the faults run checks that no failure makes a
ready; a fault-free run checks the readies themselves.
"""

import json
import time

from feeder_interfaces.msg import CycleStatus, Verdict
from feeder_nodes import (check_statements, Collector, CycleStatuses, Diagnostics, monitor,
                          monitor_rules, start_emulator, STARTUP_TIMEOUT, Statements, Verdicts,
                          wait_for_monitor, wait_reports_matched)
from sensor_msgs.msg import Range
from std_srvs.srv import SetBool

CYCLES = 240
CLEAN_CYCLES = 200      # after the settling (87 throws on the triangle)
PERIOD = 0.03
# Faults: every kind, and a failed cycle at least every ~40 cycles (so the monitor's pattern
# checks, which need 87 settled throws, never apply: no verdict may be ready).
EMULATOR_FAULTS = ['--drop-ack-every', '9', '--garbage-every', '5', '--drop-sens-every', '23',
                   '--delay', '0.4', '--delay-every', '37', '--reset-after', '100',
                   '--unplug-after', '150', '--unplug-for', '1.0']
DRIVER_PARAMS = [f'cycle_period:={PERIOD}', 'ack_timeout_s:=0.15', 'cycle_timeout_s:=1.0',
                 'watchdog_timeout_s:=1.0', 'reconnect_initial_s:=0.1', 'reconnect_max_s:=0.4']


def read_truth(path):
    header, fires = None, {}
    for line in path.read_text().splitlines():
        rec = json.loads(line)
        if rec['type'] == 'header':
            header = rec
        else:
            fires.setdefault(rec['seq'], []).append(rec)
    return header, fires


def test_every_cycle_accounted_and_never_ready_while_failures_keep_the_checks_off(
        graph, ros, tmp_path):
    n_ready = run_driver_graph(graph, ros, tmp_path, EMULATOR_FAULTS, CYCLES, faults=True)
    assert n_ready == 0


def test_ready_exactly_on_the_goal_edge_once_settled(graph, ros, tmp_path):
    n_ready = run_driver_graph(graph, ros, tmp_path, [], CLEAN_CYCLES, faults=False)
    assert n_ready >= 5, 'too few goal-edge detections to mean anything'


def run_driver_graph(graph, ros, tmp_path, emulator_faults, cycles, faults):
    """
    Run emulator, driver and monitor for ``cycles`` cycles (after the settling unless
    ``faults``); check every cycle and verdict; return the number of ready verdicts.
    """
    link = tmp_path / 'feeder-tty'
    truth_path = tmp_path / 'truth.jsonl'
    emu = start_emulator(graph, link, '--truth-log', truth_path, '--cycle-time', '0.02',
                         '--heartbeat', '0.2', *emulator_faults)
    args = ['--ros-args', '-r', '__ns:=/feeder', '-p', f'port:={link}']
    for p in DRIVER_PARAMS:
        args += ['-p', p]
    drv = graph.start('feeder_driver', 'driver_node', *args, name='driver')
    mon = monitor(graph)

    ready = Statements(ros)
    verdict_stream = Verdicts(ros)
    statuses = CycleStatuses(ros)
    prox = Collector(ros, Range, '/feeder/proximity')
    diags = Diagnostics(ros)
    wait_for_monitor(ros, ready)
    # Every volatile stream matched before the first cycle (the writers' own accounts): the
    # driver's cycle_status and proximity writers with the monitor's readers and ours, the
    # monitor's edge1_verdict writer with ours.
    wait_reports_matched(ros, status_readers=2, proximity_readers=2)
    warmup_cycles, settle = monitor_rules(ros, diags)
    if not faults:
        cycles += max(warmup_cycles, settle + 1)

    # Enabling is refused until the driver's handshake with the controller is done.
    end = time.monotonic() + STARTUP_TIMEOUT
    while True:
        res = ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=True))
        if res.success:
            break
        assert 'refused' in res.message and time.monotonic() < end, res.message
        ros.spin_for(0.1)
    ros.spin_until(lambda: len(statuses) >= cycles, 120 + 2 * cycles * PERIOD,
                   f'{cycles} cycles')
    res = ros.call(SetBool, '/feeder/feeder_driver/enable', SetBool.Request(data=False))
    assert res.success, res.message
    ros.spin_for(1.5)       # the cycle in flight ends; the monitor judges the last ones
    assert drv.poll() is None and emu.poll() is None and mon.poll() is None

    # --- every fired cycle: exactly one cycle_status, in seq order --------------------------
    n = len(statuses)
    vals = statuses.parsed          # each as the contract reads it (parse_cycle_status)
    seqs = [v.seq for v in vals]
    assert seqs == list(range(1, n + 1))
    ok = [v.ok for v in vals]
    assert all(s.outcome in (CycleStatus.OUTCOME_COMPLETED, CycleStatus.OUTCOME_FAILED)
               for s in statuses.msgs)
    assert all(v.hardware_id == str(link) and v.session and len(v.mac) == 32 for v in vals)

    # --- against the emulator's truth ----------------------------------------------------------
    header, fires = read_truth(truth_path)
    goal, warmup = header['goal_edge'], header['warmup_throws']
    assert set(fires) <= set(seqs), 'the emulator saw a FIRE the driver never reported'
    injected = set()
    for seq, v, good in zip(seqs, vals, ok):
        recs = fires.get(seq % 65536, [])
        for r in recs:
            injected.update(r['faults'])
        if good:
            (rec,) = recs
            assert rec['outcome'] == 'completed', (seq, rec)
            assert v.sensor == bool(rec['bit']) and v.reason == '', (seq, v, rec)
        else:
            assert v.sensor is None and v.reason, (seq, v)
            assert all(r['outcome'] != 'completed' or r['faults'] for r in recs), (v.reason,
                                                                                   recs)
    failed = [v.reason for v, good in zip(vals, ok) if not good]
    if faults:
        assert injected == {'drop_ack', 'garbage', 'drop_sens', 'delay', 'reset', 'unplug'}
        reasons = ' | '.join(failed)
        for expected in ('no ACK', 'SENS', 'controller reset during cycle',
                         'serial link lost during cycle'):
            assert expected in reasons, f'{expected!r} not among the failures: {reasons}'
        assert sum(ok) >= CYCLES * 0.8
    else:
        assert not injected and not failed, failed

    # proximity: once per completed cycle, with the cycle's bit and sample stamp.
    assert len(prox) == sum(ok)
    by_stamp = {p.header.stamp.sec * 10 ** 9 + p.header.stamp.nanosec: p for p in prox.msgs}
    for v, good in zip(vals, ok):
        if good:
            p = by_stamp[v.stamp_ns]
            assert (p.range == float('-inf')) == v.sensor

    # --- the monitor: one signed verdict per fired cycle on edge1_verdict, naming its seq -----
    parsed = verdict_stream.parsed
    assert [v.seq for v in parsed] == seqs, f'{len(parsed)} verdicts for {n} cycles'
    assert all(v.authentic for v in parsed), [v.reason for v in parsed if not v.authentic][:3]
    verdicts = [v.ready for v in parsed]
    assert warmup_cycles >= warmup
    since, expected_ready = 0, 0
    for seq, v, good, verdict in zip(seqs, vals, ok, parsed):
        if not good:
            since = 0
            assert verdict.ready is False and verdict.state == Verdict.STATE_ANOMALY, \
                f'edge1_ready on failed cycle {seq}: {verdict}'
            continue
        since += 1
        (rec,) = fires[seq % 65536]
        on_goal_seen = rec['bit'] == 1 and rec['edge'] == goal
        # A failed cycle restarts the warm-up and the settling: the part may be anywhere.
        expect = on_goal_seen and since >= warmup_cycles and since > settle
        assert verdict.ready == expect, (
            f'cycle {seq}: edge1_ready {verdict.ready}, truth: edge {rec["edge"]}, R '
            f'{rec["R"]:.4f}, bit {rec["bit"]}, {since} throws since the last failure '
            f'(warm-up {warmup_cycles}, settling {settle})')
        expected_ready += expect
    check_statements(ready, verdict_stream)

    # The driver's own account in /diagnostics agrees.
    ros.spin_for(1.2)
    cyc = diags.by_name['feeder_driver: cycles'][-1]
    dv = Diagnostics.values(cyc)
    assert int(dv['fired']) == n and int(dv['completed']) == sum(ok)
    assert int(dv['failed']) == n - sum(ok)
    link_status = diags.by_name['feeder_driver: serial link'][-1]
    lv = Diagnostics.values(link_status)
    if faults:
        assert int(lv['link_losses']) >= 1 and int(lv['controller_resets']) >= 1
        assert int(lv['dropped checksum']) > 0 and int(lv['garbage bytes']) > 0
    mv = Diagnostics.values(diags.by_name['feeder_monitor: readiness'][-1])
    assert int(mv['failed']) == n - sum(ok) and int(mv['ready']) == expected_ready
    assert sum(verdicts) == expected_ready
    return expected_ready
