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
A small stand-in for diagnostic_updater (which has no wheel): periodic ``/diagnostics``.

Same conventions as ros/diagnostics' ``Updater``: absolute topic ``/diagnostics``, reliable
depth 1, status names ``<node name>: <task name>``, ``hardware_id`` on every status, values as
strings; except that the node name carries its namespace (:func:`status_prefix`,
``feeder_1/feeder_driver: cycles``), so that feeders side by side in one domain, which share
``/diagnostics``, are told apart by rqt_robot_monitor and diagnostic_aggregator (the analyzers
for N feeders: feeder_bringup's ``config/diagnostic_analyzers.yaml``).

Every update ends with a status ``<node>: endpoints``: how many remote endpoints each of the
node's writers and readers has MATCHED (``matched readers of /feeder/cycle_status: 3``;
rmw's matched counts, not the graph's: a reader on the graph that a writer has not matched yet
gets none of its volatile messages). Tests, the demo and the benchmarks wait on it before they
start cycling (tests/feeder_testing.py, ``Probe.wait_remote_matched``); an operator can read it
as who hears whom.

``DiagnosticStatus.level`` is a byte field: levels are the message's own constants
(``DiagnosticStatus.OK`` is a one-byte bytes value) or the names ``ok``, ``warn``, ``error``,
``stale``.
"""

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from . import qos
from .node import publish

LEVELS = {'ok': DiagnosticStatus.OK, 'warn': DiagnosticStatus.WARN,
          'error': DiagnosticStatus.ERROR, 'stale': DiagnosticStatus.STALE}
_LEVEL_VALUES = tuple(LEVELS.values())


def level_of(level):
    """Return the DiagnosticStatus level of a name (``'ok'``...) or of a level constant."""
    if isinstance(level, str) and level in LEVELS:
        return LEVELS[level]
    if level in _LEVEL_VALUES:
        return level
    raise ValueError(f'level {level!r}: use ok/warn/error/stale or DiagnosticStatus.OK/WARN/'
                     'ERROR/STALE (bytes, not int)')


def status_prefix(namespace, node_name):
    """
    Return the name part before ``: <task>``: ``<namespace>/<node>`` without the leading ``/``.

    ``('/feeder_1', 'feeder_driver')`` gives ``feeder_1/feeder_driver``; in the root namespace
    the bare node name, as diagnostic_updater's.
    """
    return f'{namespace.strip("/")}/{node_name}'.lstrip('/')


def namespace_of(status_name):
    """Return the namespace (``/feeder_1``, ``/`` for none) a status name was made in."""
    node = status_name.split(': ', 1)[0]
    return '/' + node.rpartition('/')[0]


def local_name(status_name):
    """Return a status name without its namespace: ``feeder_driver: cycles``."""
    node, sep, task = status_name.partition(': ')
    return node.rpartition('/')[2] + sep + task


class Status:
    """What a task fills in: ``summary(level, message)``, ``add(key, value)``, ``update()``."""

    def __init__(self, name, hardware_id):
        self.msg = DiagnosticStatus(name=name, hardware_id=hardware_id,
                                    level=DiagnosticStatus.OK, message='')

    def summary(self, level, message):
        self.msg.level = level_of(level)
        self.msg.message = str(message)

    def add(self, key, value):
        self.msg.values.append(KeyValue(key=str(key), value=str(value)))

    def update(self, values):
        for key, value in values.items():
            self.add(key, value)


# Topics every node has: no endpoint counts for them.
_NOT_COUNTED = ('/rosout', '/parameter_events')


def matched_endpoints(node):
    """
    Return {'matched readers of <topic>': n, 'matched writers of <topic>': n} of ``node``.

    For each of its publishers (subscriptions), the readers (writers) it matched: rclpy's
    ``Publisher.get_subscription_count`` and ``Subscription.get_publisher_count``.
    """
    counts = {}
    for role, endpoints, count in (
            ('readers', node.publishers, lambda e: e.get_subscription_count()),
            ('writers', node.subscriptions, lambda e: e.get_publisher_count())):
        for e in endpoints:
            if e.topic_name in _NOT_COUNTED:
                continue
            key = f'matched {role} of {e.topic_name}'
            counts[key] = counts.get(key, 0) + count(e)
    return dict(sorted(counts.items()))


class Updater:
    """
    Publish the tasks' statuses every ``period`` s (and on :meth:`force_update`).

    The last status of each update is the node's matched endpoints (``<node>: endpoints``).
    """

    def __init__(self, node, period=1.0, hardware_id='none'):
        self.node = node
        self.hardware_id = hardware_id
        self.tasks = []
        self.prefix = status_prefix(node.get_namespace(), node.get_name())
        self.pub = node.create_publisher(DiagnosticArray, '/diagnostics', qos.DIAGNOSTICS)
        self.timer = node.create_timer(period, self.update)

    def add(self, name, task):
        """Register ``task(status)``; it is called once per update."""
        self.tasks.append((name, task))

    def set_period(self, period):
        self.node.destroy_timer(self.timer)
        self.timer = self.node.create_timer(period, self.update)

    def statuses(self):
        out = []
        for name, task in self.tasks:
            stat = Status(f'{self.prefix}: {name}', self.hardware_id)
            try:
                task(stat)
            except Exception as exc:    # noqa: B902 - a broken task must not stop the rest
                stat.summary('error', f'diagnostic task failed: {exc!r}')
            out.append(stat.msg)
        stat = Status(f'{self.prefix}: endpoints', self.hardware_id)
        counts = matched_endpoints(self.node)
        stat.summary('ok', f'{len(counts)} writers and readers, '
                     f'{sum(counts.values())} matched remote endpoints')
        stat.update(counts)
        out.append(stat.msg)
        return out

    def update(self):
        msg = DiagnosticArray()
        msg.header.stamp = self.node.get_clock().now().to_msg()
        msg.status = self.statuses()
        publish(self.pub, msg, self.node.get_logger())

    force_update = update

    def destroy(self):
        self.node.destroy_timer(self.timer)
        self.node.destroy_publisher(self.pub)
