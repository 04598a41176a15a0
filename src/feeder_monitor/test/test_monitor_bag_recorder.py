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

from feeder_interfaces.msg import Verdict
from feeder_monitor.bag_recorder import (message_class, offered_qos, parse_args,
                                         subscription_qos)
import pytest
from rclpy.qos import (DurabilityPolicy, qos_profile_sensor_data, QoSProfile,
                       ReliabilityPolicy)
from rosbags.interfaces import QosDurability, QosReliability
from std_msgs.msg import Bool


LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
DEFAULT = QoSProfile(depth=10)


def test_subscription_qos_matches_every_publisher():
    q = subscription_qos([LATCHED])
    assert q.durability == DurabilityPolicy.TRANSIENT_LOCAL
    assert q.reliability == ReliabilityPolicy.RELIABLE
    q = subscription_qos([LATCHED, DEFAULT])
    assert q.durability == DurabilityPolicy.VOLATILE
    q = subscription_qos([qos_profile_sensor_data, DEFAULT])
    assert q.reliability == ReliabilityPolicy.BEST_EFFORT


def test_offered_qos_keeps_durability_and_reliability():
    q = offered_qos(LATCHED)
    assert q.durability == QosDurability.TRANSIENT_LOCAL and q.depth == 1
    assert q.reliability == QosReliability.RELIABLE
    assert offered_qos(qos_profile_sensor_data).reliability == QosReliability.BEST_EFFORT


def test_message_class():
    assert message_class('std_msgs/msg/Bool') is Bool
    # edge1_ready and edge1_verdict: the project's own interface package
    assert message_class('feeder_interfaces/msg/Verdict') is Verdict
    with pytest.raises(ImportError):
        message_class('no_such_pkg/msg/X')


def test_cli():
    a = parse_args(['out', '--topics', 'proximity', 'edge1_ready', '--duration', '3',
                    '--max-messages', '10'])
    assert (a.output, a.topics) == ('out', ['proximity', 'edge1_ready'])
    assert (a.duration, a.max_messages) == (3.0, 10)
    for bad in (['out', '--duration', '0'], ['out', '--max-messages', '-1'], []):
        with pytest.raises(SystemExit):
            parse_args(bad)


def test_a_bad_exclude_regex_is_one_line_and_exit_2(capsys):
    """It ended in a re.error traceback when the node compiled it."""
    with pytest.raises(SystemExit) as stop:
        parse_args(['out', '--exclude', '('])
    assert stop.value.code == 2
    assert capsys.readouterr().err.splitlines() == [
        "bag_recorder: --exclude '(' is not a regular expression (missing ), unterminated "
        'subpattern at position 0); give a Python regex, e.g. --exclude "^/diagnostics$"']
    assert parse_args(['out', '--exclude', '^/diagnostics$']).exclude == '^/diagnostics$'


def test_flush_period_and_drain_stay_within_a_second():
    assert parse_args(['out']).flush_period == 0.5
    assert parse_args(['out', '--flush-period', '0.9']).flush_period == 0.9
    for bad in ('0', '1', '-1'):
        with pytest.raises(SystemExit):
            parse_args(['out', '--flush-period', bad])


def test_a_publisher_the_subscription_cannot_match_is_named():
    """What rclpy's incompatible-QoS event handler said, from discovery instead."""
    from feeder_monitor.bag_recorder import unmatched
    reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    best_effort = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    assert unmatched(reliable, subscription_qos([reliable])) == ''
    assert unmatched(latched, subscription_qos([reliable])) == ''
    assert unmatched(best_effort, subscription_qos([best_effort])) == ''
    assert unmatched(best_effort, subscription_qos([reliable])) == \
        'it publishes best effort, the recorder subscribed reliable'
    assert unmatched(reliable, subscription_qos([latched])) == \
        'it publishes volatile, the recorder subscribed transient local'
