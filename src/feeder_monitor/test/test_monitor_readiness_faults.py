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
Issue 20, attacks 2 and 5 and deliverable 3: ready means proven now (ROS-free).

The truth is the throw map (readiness_faults.py): the triangle's part thrown from its start,
the geometric bit at the analysis's sensor, read through a flaky sensor and a driver whose seqs
jump and go back.
"""

from feeder_monitor.readiness import (ANOMALY, build_prediction, detection_pattern,
                                      limit_set_orbit, MAY_MISS, MAY_SEE, OFF_GOAL,
                                      ReadinessMonitor, READY, Rules, rules_from_analysis)
from hypothesis import given, settings, strategies as st
import pytest
from readiness_faults import run_faults, truth_orbit


@pytest.fixture(scope='module')
def rules(triangle, triangle_analysis):
    return rules_from_analysis(triangle, triangle_analysis,
                               limit_set_orbit(triangle, triangle_analysis, 20000))


@pytest.fixture(scope='module')
def truth(triangle):
    return truth_orbit(triangle, triangle.default_start(), 30000)


# ------------------------------------------------------------------ attack 2
def test_attack_2_a_seq_jump_or_back_is_never_ready(triangle, rules, truth):
    edges, radii = truth
    from throwmap import sees
    bits = sees(triangle.part, edges[:100], radii[:100], rules.sensor_radius, 0.0)
    m = ReadinessMonitor(rules)
    for k, b in enumerate(bits):
        m.completed(k + 1, bool(b))
    jump = m.completed(5000, True)
    back = m.completed(7, True)
    assert not jump.ready and jump.state == ANOMALY and 'jumped' in jump.anomaly
    assert not back.ready and back.state == ANOMALY and 'went back' in back.anomaly
    # Nor right after: the part may be anywhere, the checks are off for settle_cycles.
    after = [m.completed(8 + k, True) for k in range(rules.settle_cycles)]
    assert not any(v.ready for v in after)


def test_a_flood_of_jumping_statuses_gives_no_ready(rules):
    """10,000 statuses at random seqs, all detections (the issue: 189 false readies)."""
    import random
    rng = random.Random(20)
    m = ReadinessMonitor(rules)
    verdicts = [m.completed(rng.randrange(1, 65536), True) for _ in range(10_000)]
    assert not any(v.ready for v in verdicts)


# ------------------------------------------------------------------ attack 5
@pytest.mark.parametrize('seed', [1, 2, 3, 4, 5])
@pytest.mark.parametrize('rate', [0.01, 0.05])
def test_attack_5_a_flaky_sensor_makes_no_false_ready(triangle, rules, truth, rate, seed):
    # Seed 5 at 0.05 needed the two-flip rule (a spurious detection taken for the last real
    # one, then a missed one, then a spurious one while the part flips).
    run = run_faults(triangle, rules, 20_000, spurious=rate, missed=rate, seed=seed,
                     truth=truth)
    print(f'rate {rate}: {run.line()}')
    assert run.faults['spurious'] > 100 * rate * 100 and run.faults['missed'] > 0
    assert run.false_readies == 0
    assert run.anomaly_and_ready == 0


@pytest.mark.parametrize('rate', [0.0, 0.01, 0.05])
def test_seq_jumps_and_backs_with_a_flaky_sensor_make_no_false_ready(
        triangle, rules, truth, rate):
    run = run_faults(triangle, rules, 20_000, spurious=rate, missed=rate, jumps=0.002,
                     backs=0.001, seed=2, truth=truth)
    print(f'rate {rate} + seq faults: {run.line()}')
    assert run.faults['jumps'] > 10 and run.faults['backs'] > 5
    assert run.false_readies == 0 and run.anomaly_and_ready == 0


def test_a_clean_feeder_misses_almost_no_ready(triangle, rules, truth):
    run = run_faults(triangle, rules, 20_000, seed=3, truth=truth)
    assert run.anomalies == 0 and run.false_readies == 0
    # The first detection after settling has no history yet: not provably on the goal edge.
    assert run.missed_readies <= 2, run.line()
    assert run.seconds_per_cycle < 1e-4, run.line()


# ------------------------------------------------------------------ the rules
def test_no_ready_while_the_checks_are_off_at_start_up(rules):
    m = ReadinessMonitor(rules)
    verdicts = [m.completed(k + 1, True) for k in range(rules.settle_cycles)]
    assert rules.settle_cycles > rules.warmup_cycles
    assert not any(v.ready for v in verdicts)


def test_no_ready_while_the_checks_are_off_after_a_failed_cycle(triangle, rules, truth):
    from throwmap import sees
    edges, radii = truth
    bits = sees(triangle.part, edges, radii, rules.sensor_radius, 0.0)
    m = ReadinessMonitor(rules)
    for k in range(300):
        m.completed(k + 1, bool(bits[k]))
    m.failed(301, 'no SENS')
    verdicts = [m.completed(302 + k, bool(bits[301 + k])) for k in range(rules.settle_cycles)]
    assert bits[301:301 + rules.settle_cycles].any()
    assert not any(v.ready for v in verdicts)


def test_a_detection_the_prediction_does_not_expect_is_an_anomaly(triangle, rules, truth):
    from throwmap import sees
    edges, radii = truth
    bits = sees(triangle.part, edges, radii, rules.sensor_radius, 0.0)
    m = ReadinessMonitor(rules)
    k = 0
    for k in range(400):
        m.completed(k + 1, bool(bits[k]))
    last = max(i for i in range(400) if bits[i])
    # Three cycles after a detection the part is flipping; the run and gap rules (min gap 9
    # only counts after a run) still let a second detection through at gap 1, not at 3.
    while k < last + 3:
        k += 1
        m.completed(k + 1, bool(bits[k]))
    v = m.completed(k + 2, True)
    assert v.anomaly and not v.ready and v.state == ANOMALY


def test_fired_drops_the_held_ready_until_that_cycle_is_judged():
    m = ReadinessMonitor(make_rules(settle_cycles=0, min_gap=None, max_run=None))
    v = m.completed(1, True)
    assert v.ready and m.ready_seq == 1
    assert m.fired(2) is None and m.ready_seq is None
    v = m.completed(2, False)
    assert not v.ready and m.ready_seq is None
    m.fired(3)
    m.fired(4)                      # a late verdict on 3 would be stale: 4 already fired
    v = m.completed(3, True)
    assert not v.ready and m.counts['superseded'] == 1 and m.ready_seq is None
    v = m.completed(4, True)
    assert v.ready and m.ready_seq == 4
    m.fired(3)                      # an old fire report changes nothing
    assert m.ready_seq == 4


def make_rules(**kw):
    base = {'goal_edge': 1, 'sensor_radius': 0.27, 'guarantee_radius': 0.25, 'provable': True,
            'warmup_cycles': 1, 'proven_warmup': 1, 'settle_cycles': 3,
            'pattern': detection_pattern([1, 0, 0, 0, 1]), 'max_run': 1, 'min_gap': 2,
            'max_silence': 6}
    base.update(kw)
    return Rules(**base)


def test_the_prediction_table_of_a_toy_orbit():
    # A period-4 orbit: edges 1 1 0 1, the sensor fires on the 2nd state of each period.
    bits = [0, 1, 0, 0] * 50
    edges = [1, 1, 0, 1] * 50
    pred = build_prediction(bits, edges, 1)
    assert pred is not None and pred.history >= 2
    assert pred.flags(0, 0) == MAY_MISS | MAY_SEE | OFF_GOAL
    assert pred.flags(1, 1) == MAY_MISS | OFF_GOAL          # after a detection: edge 0
    assert pred.flags(2, 0b10) == MAY_MISS                  # two after: edge 1, no detection
    assert pred.flags(3, 0b100) == MAY_MISS                 # three after: edge 1 again
    assert pred.flags(4, 0b1000) == MAY_SEE                 # four after: the next detection
    assert pred.flags(2, 0b11) is None                      # never two in a row


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(['completed', 'failed', 'untrusted', 'fired',
                                           'interrupt', 'disagree']),
                          st.integers(0, 40), st.booleans()), max_size=120),
       st.booleans())
def test_no_verdict_is_ever_anomaly_and_ready(calls, with_prediction):
    """Any call sequence: state anomaly and ready never together; ready_seq only after one."""
    bits = [0, 1, 0, 0] * 50
    pred = build_prediction(bits, [1, 1, 0, 1] * 50, 1) if with_prediction else None
    m = ReadinessMonitor(make_rules(prediction=pred))
    seq = 0
    for what, step, bit in calls:
        seq = max(seq + step - 3, 0)
        if what == 'completed':
            v = m.completed(seq, bit)
        elif what == 'disagree':
            v = m.completed(seq, bit, note='sensor disagreement')
        elif what == 'failed':
            v = m.failed(seq, 'x')
        elif what == 'untrusted':
            v = m.untrusted(seq, 'x')
        elif what == 'fired':
            m.fired(seq)
            assert m.ready_seq is None or m.ready_seq >= seq
            continue
        else:
            m.interrupt('x')
            assert m.ready_seq is None
            continue
        assert not (v.ready and (v.state == ANOMALY or v.anomaly)), v
        assert v.ready == (v.state == READY)
        assert (m.ready_seq == seq) if v.ready else m.ready_seq is None
        if v.ready:
            assert m.settled and m.since_restart >= m.rules.warmup_cycles


def test_where_bits_seldom_tell_the_edge_the_proof_is_needed_only_while_suspect():
    """A part whose bits never tell its edge (scenes/experiment.yaml's case, in a toy)."""
    from feeder_monitor.readiness import Prediction
    anything = MAY_MISS | MAY_SEE | OFF_GOAL
    vague = Prediction(1, ({0: anything}, {0: anything, 1: anything}), 100, 0.0)
    rules = make_rules(prediction=vague, settle_cycles=0, min_gap=None, max_run=None,
                       max_silence=None)
    m = ReadinessMonitor(rules)
    assert [v.ready for v in (m.completed(1, False), m.completed(2, True))] == [False, True]
    v = m.completed(3, False, note='sensor disagreement')      # a sensor anomaly: suspect
    assert v.anomaly and m.suspect_left == m.suspect_cycles
    verdicts = [m.completed(4 + k, k % 5 == 4) for k in range(m.suspect_cycles)]
    assert not any(v.ready for v in verdicts) and m.counts['not_goal_sure'] > 0
    assert m.completed(4 + m.suspect_cycles, True).ready          # suspicion over
    # Where the bits usually do tell the edge, the proof is needed always.
    strict = Prediction(1, vague.tables, 100, 1.0)
    m = ReadinessMonitor(make_rules(prediction=strict, settle_cycles=0, min_gap=None,
                                    max_run=None, max_silence=None))
    assert not any(m.completed(k + 1, True).ready for k in range(5))
