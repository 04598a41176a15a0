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
Issue 20, attack 3 on real DDS: one message killed the monitor (and the predictor).

A ``cycle_status`` whose ``stamp`` was ``'1'`` and 400 zeros (the report was key/value text
then) raised OverflowError in the monitor (exit status 1) and AssertionError in the predictor
(a Time of 10**391 s). The report is a feeder_interfaces/CycleStatus now, whose fields hold no
such number; here this test's own process publishes every extreme they do hold (a seq up to
2**64 - 1, stamps before 1970 or with nanosec past 1e9, outcome and sensor codes no driver
writes, MACs of the wrong length, non-hex sessions, every tricky text in every text field) and
garbage on ``proximity`` to the installed monitor_node and predictor_node processes: both stay
up, count the bad input in /diagnostics, never say ready on a forged report, and judge and
predict the next real cycle.
"""

import math

from builtin_interfaces.msg import Time
from feeder_common import qos
from feeder_common.messages import cycle_status, proximity
from feeder_interfaces.msg import CycleStatus, PredictedState
from feeder_nodes import (Diagnostics, monitor, PredictedStates, predictor, RELIABLE,
                          sim_as_hardware, watch_monitor)
from hostile_messages import KILLER_STAMP, TRICKY
from rclpy.duration import Duration
from sensor_msgs.msg import Range
from std_srvs.srv import Trigger

# One hostile value per field of CycleStatus (the texts: every tricky one, below).
HOSTILE_FIELDS = (
    [('seq', v) for v in (2**64 - 1, 2**63, 2**63 - 1, 0)]
    + [('stamp', Time(sec=sec, nanosec=nsec)) for sec, nsec in (
        (-1, 0), (-2**31, 0), (2**31 - 1, 999_999_999), (1, 10**9), (1, 2**32 - 1))]
    + [('sensor', v) for v in (-128, -2, 2, 127, CycleStatus.SENSOR_NONE)]
    + [('outcome', v) for v in (CycleStatus.OUTCOME_FIRED, CycleStatus.OUTCOME_FAILED,
                                'Completed', 'completed ', KILLER_STAMP)]
    + [('mac', list(tag)) for tag in (b'\x00', b'x' * 31, b'x' * 33, b'\xff' * 32,
                                      b'x' * 4096)]
    + [('session', v) for v in ('ABCDEF', '0' * 65, 'g', KILLER_STAMP)])


def garbage_statuses(seq, stamp):
    """
    Return the most extreme report first, then one hostile field at a time.

    The rest of each is a valid unsigned report of cycle ``seq`` (or, with a 32-byte MAC,
    one mis-signed); the texts (outcome, reason, hardware_id, session) get every tricky text.
    """
    def report(**fields):
        msg = cycle_status(seq, True, '', True, stamp, 'forger')
        for name, value in fields.items():
            setattr(msg, name, value)
        return msg

    out = [report(seq=2**64 - 1, stamp=Time(sec=2**31 - 1, nanosec=2**32 - 1), sensor=127,
                  reason=KILLER_STAMP, mac=list(b'\xff' * 32), session='f' * 64)]
    out += [report(**{name: value}) for name, value in HOSTILE_FIELDS]
    out += [report(**{name: text}) for name in ('outcome', 'reason', 'hardware_id', 'session')
            for text in TRICKY]
    return out


def publish_paced(ros, messages, publisher_of, batch=20):
    """
    Publish ``messages``, waiting for every reader's ack after each ``batch`` of them.

    Unpaced, a burst of about 150 reliable messages failed once in CI (session 37): the
    forger's own write raised "cannot publish data". A reliable Fast DDS write may wait up to
    its max_blocking_time (100 ms) for room in its 100-deep history or for the writer's lock,
    and a loaded 2-core machine can run past that. The feed node is under test here, not the
    forger's writer, so no batch exceeds a fifth of the history.
    """
    for start in range(0, len(messages), batch):
        used = set()
        for msg in messages[start:start + batch]:
            publisher = publisher_of(msg)
            publisher.publish(msg)
            used.add(publisher)
        for publisher in used:
            assert publisher.wait_for_all_acked(Duration(seconds=10)), \
                f'the readers of {publisher.topic_name} did not ack a batch in 10 s'
        ros.spin_for(0.01)


def garbage_predictions(seq, stamp):
    """
    Return PredictedStates no predictor writes, one hostile change each.

    NaN or infinite r with an edge, an edge and r with kind lost, edges past int32's ends,
    seqs past 2**63, bad stamps, a lost part that jogs, every tricky text as the kind.
    """
    sec, nsec = divmod(stamp, 10**9)
    out = []
    for fields in (
            {'r': math.nan}, {'r': math.inf}, {'r': -math.inf}, {'r': 1e308},
            {'throw_kind': 'lost'}, {'edge': -1}, {'edge': -2**31}, {'edge': 2**31 - 1},
            {'seq': 2**64 - 1}, {'seq': 2**63}, {'stamp': Time(sec=-1)},
            {'stamp': Time(sec=1, nanosec=2**32 - 1)},
            {'edge': -1, 'r': math.nan, 'throw_kind': 'jog'}):
        msg = PredictedState(seq=seq, stamp=Time(sec=sec, nanosec=nsec), edge=1, r=0.2,
                             throw_kind='jog')
        for name, value in fields.items():
            setattr(msg, name, value)
        out.append(msg)
    for text in TRICKY:
        out.append(PredictedState(seq=seq, stamp=Time(sec=sec, nanosec=nsec), edge=1, r=0.2,
                                  throw_kind=text))
    return out


def garbage_ranges(stamp):
    """Return Ranges no sensor writes: unusable limits, NaN, stamps before 1970 or past 1e9 ns."""
    out = []
    for rng, lo, hi, sec, nanosec in (
            (0.01, math.nan, 0.02, 1, 0), (0.01, -math.inf, math.inf, 1, 0),
            (0.01, 0.03, 0.02, 1, 0), (math.nan, 0.02, 0.02, 1, 0),
            (-math.inf, 0.02, 0.02, -5, 0), (-math.inf, 0.02, 0.02, 1, 4_000_000_000),
            (3.4e38, -3.4e38, 3.4e38, 2**31 - 1, 999_999_999)):
        msg = proximity(stamp, True, 0.02)
        msg.range, msg.min_range, msg.max_range = rng, lo, hi
        msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
        out.append(msg)
    return out


def test_the_killer_status_and_garbage_leave_monitor_and_predictor_judging(graph, ros):
    sim_as_hardware(graph, 'cycle_period:=0.05')
    pred = predictor(graph)
    mon = monitor(graph)
    ready, verdicts, statuses = watch_monitor(ros)
    states = PredictedStates(ros)
    diags = Diagnostics(ros)
    # The driver's QoS (a 1 s liveliness lease): the monitor's reader matches no other writer.
    status_pub = ros.node.create_publisher(CycleStatus, '/feeder/cycle_status',
                                           qos.CYCLE_STATUS)
    prox_pub = ros.node.create_publisher(Range, '/feeder/proximity', RELIABLE)
    # the monitor's, the predictor's and this test's readers; the monitor's proximity reader
    ros.spin_until(lambda: status_pub.get_subscription_count() >= 3 and
                   prox_pub.get_subscription_count() >= 1, 60.0, 'the readers of the forger')
    ros.spin_for(0.5)

    stamp = ros.node.get_clock().now().nanoseconds
    bad = garbage_statuses(5, stamp)
    status_pub.publish(bad[0])          # alone, as the killer was
    ros.spin_for(1.0)
    assert mon.poll() is None, f'monitor exited with {mon.returncode}:\n{graph.log(mon)}'
    assert pred.poll() is None, f'predictor exited with {pred.returncode}:\n{graph.log(pred)}'
    publish_paced(ros, bad[1:], lambda msg: status_pub)
    for msg in garbage_ranges(stamp):
        prox_pub.publish(msg)
    ros.spin_for(1.0)
    assert mon.poll() is None, f'monitor exited with {mon.returncode}:\n{graph.log(mon)}'
    assert pred.poll() is None, f'predictor exited with {pred.returncode}:\n{graph.log(pred)}'

    # The forger leaves; a real cycle is judged and predicted.
    ros.node.destroy_publisher(status_pub)
    ros.node.destroy_publisher(prox_pub)
    ros.spin_until(lambda: ros.node.count_publishers('/feeder/cycle_status') == 1, 20.0,
                   'the forger to leave')
    res = ros.call(Trigger, '/feeder/feeder_driver/trigger_cycle', Trigger.Request())
    assert res.success, res.message
    seq = int(res.message.split()[-1])
    ros.spin_until(lambda: any(v.seq == seq for v in verdicts.parsed), 10.0,
                   f'the verdict of cycle {seq}')
    ros.spin_until(lambda: any(s.seq == seq for s in states.parsed), 10.0,
                   f'the prediction of cycle {seq}')
    # No forged report made anything ready (the real first cycle is in its warm-up).
    assert not any(v.ready for v in verdicts.parsed), [v for v in verdicts.parsed if v.ready]
    assert not any(c.ready_now or c.ready for c in ready.checked), ready.checked

    # Counted in /diagnostics, and said in the log (throttled: a few lines, not hundreds).
    def counted(name, key):
        got = diags.by_name.get(name, [])
        return bool(got) and int(Diagnostics.values(got[-1])[key]) > 0

    ros.spin_until(lambda: counted('feeder_monitor: inputs', 'bad_input'), 5.0,
                   "the monitor's count of bad input")
    ros.spin_until(lambda: counted('feeder_sim: sensor agreement', 'bad_status'), 5.0,
                   "the predictor's count of bad statuses")
    log = graph.log(mon)
    assert 'ignored' in log and log.count('ignored') < 20, log[-3000:]


def test_hostile_reports_and_predictions_leave_the_feed_node_up(graph, ros):
    """
    feed_node reads cycle_status and predicted/state (typed): garbage on both kills nothing.

    Every hostile report of the monitor's test and every hostile prediction (NaN or infinite
    r, edges past int32's ends, seqs past 2**63, bad stamps, tricky kinds) reach it; it stays
    up and logs no traceback.
    """
    feed = graph.start('feeder_monitor', 'feed_node', '--ros-args', '-r', '__ns:=/feeder',
                       name='feed')
    status_pub = ros.node.create_publisher(CycleStatus, '/feeder/cycle_status',
                                           qos.CYCLE_STATUS)
    state_pub = ros.node.create_publisher(PredictedState, '/feeder/predicted/state',
                                          qos.PREDICTED_STATE)
    ros.spin_until(lambda: status_pub.get_subscription_count() >= 1 and
                   state_pub.get_subscription_count() >= 1, 60.0, "the feed node's readers")
    stamp = ros.node.get_clock().now().nanoseconds
    publish_paced(ros, garbage_statuses(5, stamp) + garbage_predictions(5, stamp),
                  lambda msg: status_pub if isinstance(msg, CycleStatus) else state_pub)
    assert status_pub.wait_for_all_acked(Duration(seconds=10))
    assert state_pub.wait_for_all_acked(Duration(seconds=10))
    ros.spin_for(1.0)
    assert feed.poll() is None, f'feed_node exited with {feed.returncode}:\n{graph.log(feed)}'
    assert 'Traceback' not in graph.log(feed), graph.log(feed)[-3000:]
