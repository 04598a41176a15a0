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
bag_recorder: records the feeder graph's topics to a rosbag2 MCAP directory.

    bag_recorder OUTPUT_DIR [--topics T ... | --all] [--exclude REGEX] [--duration S]
                 [--max-messages N] [--discovery-period S] [--flush-period S]
                 [--ros-args ...]

It records its own feeder: every topic it discovers in its namespace (``__ns``), plus the
absolute ``/diagnostics``, ``/tf`` and ``/tf_static`` where present (:data:`SHARED_TOPICS`),
so two feeders in one domain, each with its recorder, each get a bag of their own; ``--all``
takes every topic of the domain (the only choice in the root namespace), ``--topics`` exactly
those given (resolved in its namespace).

It subscribes with ``raw=True``, so the bytes it stores are the CDR the publishers sent, with the
QoS the publishers offer (a latched topic is subscribed transient local and recorded so) and the
type hash they announce. Each message is stored with its receive time (log time) and its send time
(publish time, the DDS source timestamp), as rosbag2 does. It stops on SIGINT or SIGTERM, after
``--duration`` seconds or ``--max-messages`` messages, always closing the bag (metadata.yaml
written) and printing a summary. Killed (SIGKILL, a crash), it loses at most the messages of the
last ``--flush-period`` (0.5 s) + DRAIN_PERIOD (0.1 s): every flush puts them on disk and rewrites
metadata.yaml, and the bag stays readable as it is (``bag_reindex`` gives its .mcap the summary a
clean stop writes; see feeder_monitor.bag). A write the disk refuses (full, quota, file size limit,
I/O error) ends it with exit status 3 and one line naming the cause, what the bag holds and the
fix; the bag keeps every message flushed before (feeder_monitor.bag).
"""

import argparse
import heapq
import importlib
from operator import itemgetter
import re
import sys

from feeder_common.node import run_node
from rclpy.callback_groups import CallbackGroup
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
import rclpy.utilities

from .bag import BagWriter, qos, write_cause, WRITE_FAULT_CAUSES, WRITE_FAULT_STATUS

NODE_NAME = 'feeder_bag_recorder'
ALWAYS_EXCLUDED = ('/rosout', '/parameter_events')
# Absolute topics a feeder's recorder takes beside its namespace's: they carry every feeder
# (diagnostic status names carry the namespace, feeder_common.diagnostics), or the transforms
# of a robot model published outside the namespace.
SHARED_TOPICS = ('/diagnostics', '/tf', '/tf_static')
# Seconds between takes of the waiting messages. Their log time is the DDS receive time, so
# the period costs no timing; the subscriptions' depth (1000) holds 5 s of a 200 Hz topic, and a
# kill loses at most this plus the flush period. Each take costs an executor round even when
# nothing waits (20 ms: 5 % of a core idle; 0.1 s: under 1 %).
DRAIN_PERIOD = 0.1


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog='bag_recorder', description='Record feeder topics to a rosbag2 MCAP directory '
        '(give --ros-args -r __ns:=/feeder to resolve relative topic names there).')
    p.add_argument('output', help='bag directory to create (must not exist)')
    p.add_argument('--topics', nargs='+', default=None, metavar='TOPIC',
                   help="topics to record (relative names resolve in the node's namespace); "
                   "default: every topic discovered in the recorder's namespace, plus "
                   f'{", ".join(SHARED_TOPICS)}')
    p.add_argument('--all', action='store_true', dest='all_topics',
                   help='record every topic of the domain (every namespace), except /rosout '
                   'and /parameter_events')
    p.add_argument('--exclude', default=None, metavar='REGEX',
                   help='do not record topics whose full name matches this regular expression')
    p.add_argument('--duration', type=float, default=None, metavar='S',
                   help='stop after S seconds')
    p.add_argument('--max-messages', type=int, default=None, metavar='N',
                   help='stop after N messages in total')
    p.add_argument('--discovery-period', type=float, default=0.5, metavar='S',
                   help='seconds between looks for new topics (default 0.5)')
    p.add_argument('--flush-period', type=float, default=0.5, metavar='S',
                   help='seconds between writes to disk, at most 0.9: a kill loses at most '
                   f'this + {DRAIN_PERIOD} s of messages (default 0.5)')
    args = p.parse_args(argv)
    if args.exclude is not None:
        try:
            re.compile(args.exclude)
        except re.error as exc:
            print(f'bag_recorder: --exclude {args.exclude!r} is not a regular expression '
                  f'({exc}); give a Python regex, e.g. --exclude "^/diagnostics$"',
                  file=sys.stderr, flush=True)
            raise SystemExit(2) from None
    if args.all_topics and args.topics is not None:
        p.error('give --topics or --all, not both')
    if args.duration is not None and args.duration <= 0:
        p.error('--duration must be > 0')
    if args.max_messages is not None and args.max_messages <= 0:
        p.error('--max-messages must be > 0')
    if args.discovery_period <= 0:
        p.error('--discovery-period must be > 0')
    if not 0 < args.flush_period <= 1 - DRAIN_PERIOD:
        p.error(f'--flush-period must be in (0, {1 - DRAIN_PERIOD:g}] s (a kill loses at most '
                f'the flush period + {DRAIN_PERIOD} s of messages)')
    return args


def message_class(msgtype):
    """Import the Python class of 'pkg/msg/Type'."""
    pkg, kind, name = msgtype.split('/')
    return getattr(importlib.import_module(f'{pkg}.{kind}'), name)


def offered_qos(endpoint_qos):
    """Convert an rclpy QoSProfile reported by graph discovery to a rosbags Qos."""
    q = endpoint_qos
    return qos(q.history, q.depth, q.reliability, q.durability, q.deadline.nanoseconds,
               q.lifespan.nanoseconds, q.liveliness, q.liveliness_lease_duration.nanoseconds,
               q.avoid_ros_namespace_conventions)


def announced_hash(publishers):
    """Return the RIHS01 type hash the publishers announce (rosbag2 records it), or None."""
    for p in publishers:
        h = getattr(p, 'topic_type_hash', None)
        if h is not None and getattr(h, 'version', 0) >= 1:
            return str(h)
    return None


def subscription_qos(publisher_qos):
    """Pick a QoS that receives from every publisher (reliable, latched only if all are)."""
    reliable = all(q.reliability == ReliabilityPolicy.RELIABLE for q in publisher_qos)
    latched = all(q.durability == DurabilityPolicy.TRANSIENT_LOCAL for q in publisher_qos)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                      reliability=(ReliabilityPolicy.RELIABLE if reliable
                                   else ReliabilityPolicy.BEST_EFFORT),
                      durability=(DurabilityPolicy.TRANSIENT_LOCAL if latched
                                  else DurabilityPolicy.VOLATILE))


def unmatched(publisher_qos, sub_qos):
    """Say why a publisher's QoS cannot reach the subscription's (DDS request/offer), or ''."""
    if (sub_qos.reliability == ReliabilityPolicy.RELIABLE
            and publisher_qos.reliability != ReliabilityPolicy.RELIABLE):
        return 'it publishes best effort, the recorder subscribed reliable'
    if (sub_qos.durability == DurabilityPolicy.TRANSIENT_LOCAL
            and publisher_qos.durability != DurabilityPolicy.TRANSIENT_LOCAL):
        return 'it publishes volatile, the recorder subscribed transient local'
    return ''


# No QoS event handlers on the recorder's subscriptions (see BagRecorder._check_publishers).
NO_EVENT_HANDLERS = SubscriptionEventCallbacks(use_default_callbacks=False)


class TakenByDrain(CallbackGroup):
    """
    The group of the recorder's subscriptions: the executor never waits on them.

    The executor spends a wait-set rebuild and a task per message it hands to a callback (for
    the recorder at 100 Hz cycling, most of its CPU); instead the drain timer takes every
    waiting message of every topic in one round.
    """

    def can_execute(self, entity):
        return False

    def beginning_execution(self, entity):
        return False

    def ending_execution(self, entity):
        pass


def _never_called(msg):
    raise AssertionError('the drain timer takes these messages, not the executor')


class BagRecorder(Node):
    """Subscribes (raw) to the selected topics as they appear and writes them to a bag."""

    # The drain timer takes messages with their MessageInfo (send and receive times); rclpy
    # 9.1's events executor would instead call the subscriptions' callbacks, without it.
    executor_kind = 'single'

    def __init__(self, writer, topics=None, exclude=None, discovery_period=0.5,
                 max_messages=None, duration=None, flush_period=0.5, drain_period=DRAIN_PERIOD,
                 all_topics=False, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        self.writer = writer
        self.wanted = None if topics is None else {self.resolve_topic_name(t) for t in topics}
        ns = self.get_namespace().rstrip('/')
        # None: every namespace (--all, or a recorder in the root namespace).
        self.prefix = None if all_topics or not ns else ns + '/'
        self.exclude = re.compile(exclude) if exclude else None
        self.max_messages = max_messages
        self.done = None            # why recording ended by itself
        self.exit_reason = None     # why the process stopped (the run helper's)
        self._subs = {}             # topic -> (subscription, its QoS)
        self._checked = {}          # topic -> publishers (node names) already looked at
        self._skipped = set()
        self.create_timer(discovery_period, self._discover)
        self._taken_by_drain = TakenByDrain()
        self.create_timer(drain_period, self._drain)
        self.create_timer(flush_period, writer.flush)
        if duration is not None:
            self._duration_timer = self.create_timer(duration, self._duration_over)
            self._duration_text = f'{duration} s'
        self._discover()

    def finished(self):
        """Why recording is over (the run helper stops the process), or None."""
        if self.done is None and self.writer.fault is not None:
            self.done = 'the disk refused a write'
        return self.done

    def _duration_over(self):
        self.destroy_timer(self._duration_timer)
        self.done = self.done or self._duration_text

    def _selected(self, topic):
        if topic in ALWAYS_EXCLUDED and (self.wanted is None or topic not in self.wanted):
            return False
        if self.exclude is not None and self.exclude.search(topic):
            return False
        if self.wanted is not None:
            return topic in self.wanted
        return self.prefix is None or topic.startswith(self.prefix) or topic in SHARED_TOPICS

    def _discover(self):
        self._check_publishers()
        for topic, types in self.get_topic_names_and_types():
            if topic in self._subs or topic in self._skipped or not self._selected(topic):
                continue
            pubs = self.get_publishers_info_by_topic(topic)
            if not pubs:
                continue        # subscribers only so far: no QoS to match yet
            msgtype = types[0]
            if len(types) > 1 or not self.writer.knows(msgtype):
                self._skipped.add(topic)
                self.get_logger().warning(f'not recording {topic}: type {types} ambiguous, or '
                                          'neither in the Kilted type store nor installed '
                                          '(share/<pkg>/msg on AMENT_PREFIX_PATH)')
                continue
            try:
                cls = message_class(msgtype)
            except (ImportError, AttributeError, ValueError) as exc:
                self._skipped.add(topic)
                self.get_logger().warning(f'not recording {topic}: {exc}')
                continue
            profiles = [p.qos_profile for p in pubs]
            self.writer.add_topic(topic, msgtype, [offered_qos(q) for q in profiles],
                                  announced_hash(pubs))
            sub_qos = subscription_qos(profiles)
            self._subs[topic] = (self.create_subscription(
                cls, topic, _never_called, sub_qos, raw=True,
                callback_group=self._taken_by_drain, event_callbacks=NO_EVENT_HANDLERS),
                sub_qos)
            self._checked[topic] = {p.node_name + p.node_namespace for p in pubs}
            self.get_logger().info(f'recording {topic} ({msgtype})')

    def _check_publishers(self):
        """
        Warn once about a publisher that appeared later and that the subscription cannot match.

        This replaces rclpy's per-subscription incompatible-QoS event handlers: each is one
        more entity the single-threaded executor rebuilds its wait set with for every message.
        """
        for topic, (_, sub_qos) in self._subs.items():
            for pub in self.get_publishers_info_by_topic(topic):
                key = pub.node_name + pub.node_namespace
                if key in self._checked[topic]:
                    continue
                self._checked[topic].add(key)
                problem = unmatched(pub.qos_profile, sub_qos)
                if problem:
                    self.get_logger().warning(
                        f'not recording {topic} from {pub.node_namespace.rstrip("/")}/'
                        f'{pub.node_name}: {problem} (the subscription was made for the '
                        'publishers present when the topic appeared)')

    def _drain(self):
        """
        Take every message waiting on every subscription and write them in receive order.

        Each topic keeps its delivery order (a sample resent by DDS arrives later than the next
        one but is delivered before it); the topics are merged by receive time.
        """
        taken = []
        for topic, (sub, _) in self._subs.items():
            handle = sub.handle
            mine = []
            with handle:
                while True:
                    got = handle.take_message(sub.msg_type, True)
                    if got is None:
                        break
                    data, info = got
                    mine.append((info['received_timestamp'], topic, data, info))
            if mine:
                taken.append(mine)
        for received, topic, data, info in heapq.merge(*taken, key=itemgetter(0)):
            if self.done:
                return
            self.writer.write(topic, received, data, info['source_timestamp'],
                              info.get('publication_sequence_number') or 0)
            if self.max_messages is not None and self.writer.total >= self.max_messages:
                self.done = f'{self.max_messages} messages'

    def destroy_node(self):
        """Take what arrived since the last drain, then destroy the node."""
        self._drain()
        return super().destroy_node()


def main(argv=None):
    argv = sys.argv if argv is None else argv
    args = parse_args(rclpy.utilities.remove_ros_args(argv)[1:])
    try:
        writer = BagWriter(args.output)
    except FileExistsError as exc:
        print(f'bag_recorder: {exc}', file=sys.stderr)
        return 2
    except OSError as exc:
        if exc.errno in WRITE_FAULT_CAUSES:
            cause, fix = write_cause(exc)
            print(f'bag_recorder: error: {cause} creating the bag {args.output} (nothing '
                  f'recorded, nothing left there); {fix}, then record again', file=sys.stderr)
            return WRITE_FAULT_STATUS
        print(f'bag_recorder: error: cannot create the bag {args.output}: {exc.strerror}; '
              'give a new directory where you can write', file=sys.stderr)
        return 2
    made = []

    def make_node(**kwargs):
        made.append(BagRecorder(writer, args.topics, args.exclude, args.discovery_period,
                                args.max_messages, args.duration, args.flush_period,
                                all_topics=args.all_topics, **kwargs))
        return made[-1]

    try:
        # A start-up failure ends the process in run_node: the bag is closed first.
        status = run_node(make_node, 'bag_recorder', argv, before_exit=writer.close)
    finally:
        writer.close()
    if writer.fault is not None:
        # One line, instead of the summary: what failed, what the bag holds, the fix.
        print(f'bag_recorder: error: {writer.fault.line()}', file=sys.stderr, flush=True)
        return WRITE_FAULT_STATUS
    reason = (made[0].done or made[0].exit_reason) if made else 'not started'
    counts = ', '.join(f'{t}: {n}' for t, n in sorted(writer.counts.items()))
    print(f'bag_recorder: stopped: {reason}; {writer.total} messages on {len(writer.counts)} '
          f'topics in {writer.path}' + (f' ({counts})' if counts else ''), flush=True)
    return status


if __name__ == '__main__':
    sys.exit(main())
