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
Who publishes a topic: the graph check of a node that trusts one publisher (issue 10).

Without DDS security any peer on the domain can publish any topic. A node that decides on
``cycle_status`` and ``proximity`` (the monitor, the predictor) trusts one publisher: the node
``trusted_node`` (e.g. ``/feeder/feeder_driver``), pinned by its writers' GIDs when first seen.
:class:`PublisherGuard` tells, from the node's own graph cache (no network round trip):

* :meth:`crowded` (about 6 us per topic): a second publisher is on a watched topic;
* :meth:`check` (about 35 us per topic): the publishers are not exactly the pinned ones (none,
  another node, a second one, a new GID).

It defends against a second node publishing on the topics beside the driver, and against a
node that takes the driver's place under another name or GID. It cannot tell a forged message
from a genuine one while the forger's writer is not (yet, or no more) in the graph cache, nor a
forger that names its node like the driver and publishes while the driver is gone: only SROS2
(docs/security.md) can, by letting only the driver's enclave publish these topics.
"""


def _gid(info):
    return bytes(info.endpoint_gid).hex()


def _node_of(info):
    ns = info.node_namespace.rstrip('/')
    return f'{ns}/{info.node_name}'


class PublisherGuard:
    """Watch ``topics`` (fully qualified) for publishers other than ``trusted_node``'s."""

    def __init__(self, node, topics, trusted_node):
        self._node = node
        self.topics = tuple(topics)
        self.trusted_node = trusted_node
        self.pinned = {}            # topic -> GID of the trusted writer, once seen

    def crowded(self):
        """Return why a watched topic has more than one publisher (cheap), else None."""
        for topic in self.topics:
            n = self._node.count_publishers(topic)
            if n > 1:
                return f'{n} publishers on {topic}; only {self.trusted_node} may publish it'
        return None

    def check(self):
        """
        Return why the publishers are not exactly the trusted ones, else None.

        The first time ``trusted_node`` is seen as the one publisher of a topic, its writer's
        GID is pinned; a later writer with another GID (the driver restarted, or a node took
        its name) is reported once and pinned in its place.
        """
        for topic in self.topics:
            infos = self._node.get_publishers_info_by_topic(topic)
            if not infos:
                return f'no publisher on {topic} (is {self.trusted_node} running?)'
            others = sorted({_node_of(i) for i in infos if _node_of(i) != self.trusted_node})
            if others:
                return (f'{topic} is published by {", ".join(others)} besides or instead of '
                        f'{self.trusted_node}; only {self.trusted_node} may publish it')
            if len(infos) > 1:
                return (f'{len(infos)} publishers on {topic}, all named {self.trusted_node}; '
                        'only one may publish it')
            gid = _gid(infos[0])
            pinned = self.pinned.get(topic)
            self.pinned[topic] = gid
            if pinned is not None and gid != pinned:
                return (f'the publisher of {topic} changed (GID {pinned} -> {gid}): '
                        f'{self.trusted_node} restarted, or another node took its name')
        return None
