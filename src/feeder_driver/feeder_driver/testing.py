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
Helpers for tests of the driver (ROS-free): DDS domain reservation, emulator in a thread.

:func:`reserve_domain_id` picks a ROS_DOMAIN_ID that no other test process of this machine
holds (an exclusive ``flock`` on ``<tmp>/feeder-ros-domain-<id>.lock``, the same lock files as
tests/conftest.py, kept until the process exits) and whose Fast DDS discovery ports on loopback
are free, so parallel test runs never share a DDS domain.
"""

import errno
import fcntl
import os
import socket
import tempfile
import threading

from .emulator import from_scene

_HELD = {}
# Fast DDS well-known ports: PB 7400, DG 250, PG 2; unicast discovery at offset 10 (d1) and
# user traffic at offset 11 (d3) per participant.
_PB, _DG, _PG = 7400, 250, 2


def _ports_free(domain, participants=6):
    for part in range(participants):
        for offset in (10, 11):
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
                try:
                    s.bind(('127.0.0.1', _PB + _DG * domain + offset + _PG * part))
                except OSError as exc:
                    if exc.errno == errno.EADDRINUSE:
                        return False
                    raise
    return True


def reserve_domain_id(lo=1, hi=101):
    """Reserve a domain id in [lo, hi] for this process (the same id on repeated calls)."""
    if 'id' in _HELD:
        return _HELD['id']
    span = hi - lo + 1
    for offset in range(span):
        domain = lo + (os.getpid() + offset) % span
        path = os.path.join(tempfile.gettempdir(), f'feeder-ros-domain-{domain}.lock')
        fh = open(path, 'w')
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            fh.close()
            continue
        if not _ports_free(domain):
            fh.close()
            continue
        _HELD['id'], _HELD['file'] = domain, fh
        return domain
    raise RuntimeError(f'no free ROS_DOMAIN_ID in [{lo}, {hi}]: every lock file '
                       f'{tempfile.gettempdir()}/feeder-ros-domain-*.lock is held')


def dds_env(domain_id, base=None):
    """Environment for child processes: DDS on loopback, the given domain."""
    env = dict(os.environ if base is None else base)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env['ROS_DOMAIN_ID'] = str(domain_id)
    env.pop('ROS_LOCALHOST_ONLY', None)
    env.pop('ROS_STATIC_PEERS', None)
    return env


class EmulatorThread:
    """A :class:`feeder_driver.emulator.Controller` served from a background thread."""

    def __init__(self, scene, link, **kwargs):
        self.controller = from_scene(scene, link=link, **kwargs)
        self._thread = threading.Thread(target=self.controller.run, name='feeder-emulator',
                                        daemon=True)

    @property
    def records(self):
        return [r for r in self.controller.records if r.get('type') == 'fire']

    def start(self):
        self.controller.start()
        self._thread.start()
        return self

    def stop(self):
        self.controller.stop()
        self._thread.join(timeout=5)
        self.controller.close()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()
