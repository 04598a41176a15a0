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

"""feeder_common.node.publish: what the middleware refuses is logged; a bug still raises."""

from feeder_common.node import publish
import pytest
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy


class Writer:
    topic_name = '/feeder/cycle_status'

    def __init__(self, error=None):
        self.error = error
        self.sent = []

    def publish(self, msg):
        if self.error is not None:
            raise self.error
        self.sent.append(msg)


class Logger:
    def __init__(self):
        self.errors = []

    def error(self, text, **kwargs):
        self.errors.append(text)


def test_a_taken_write_is_true_and_logs_nothing():
    writer, logger = Writer(), Logger()
    assert publish(writer, 'msg', logger) is True
    assert writer.sent == ['msg'] and logger.errors == []


@pytest.mark.parametrize('error', [
    _rclpy.RCLError('Failed to publish: cannot publish data'),
    _rclpy.InvalidHandle('cannot use Destroyable because destruction was requested')])
def test_a_refused_write_is_false_and_logged_with_its_topic_and_reason(error):
    logger = Logger()
    assert publish(Writer(error), 'msg', logger) is False
    assert len(logger.errors) == 1
    assert '/feeder/cycle_status' in logger.errors[0] and str(error) in logger.errors[0]


def test_a_bug_is_not_swallowed():
    # rclpy raises TypeError for a message of the wrong type: a bug of the caller.
    with pytest.raises(TypeError):
        publish(Writer(TypeError('wrong message type')), 'msg', Logger())
