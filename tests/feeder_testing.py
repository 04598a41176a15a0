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
Support for tests, demos and benchmarks of the feeder graph: DDS domains, processes, emulator.

It lives with the tests and no package installs it. One implementation serves the package
tests (their conftest puts this directory on sys.path), tests/conftest.py,
scripts/demo_graph.py and the benchmarks:

* :func:`claim_domain_id` picks a ROS_DOMAIN_ID that no other test or demo process of this
  machine holds (an exclusive ``flock`` on ``<tmp>/feeder-ros-domain-<id>.lock``, released when
  the returned file is closed) and whose Fast DDS discovery ports on loopback are free, so
  parallel runs never share a DDS domain; :func:`reserve_domain_id` holds one for the whole
  process.
* :func:`dds_env` and :func:`install_env`: environments for child processes (DDS on loopback
  in a given domain; the executables of a colcon install).
* :class:`EmulatorThread`: the controller emulator served from a thread.
"""

import errno
import fcntl
import os
import pathlib
import random
import socket
import sys
import tempfile
import threading

REPO = pathlib.Path(__file__).resolve().parents[1]
INSTALL = REPO / 'ros2_ws' / 'install'

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


def claim_domain_id(lo=1, hi=101, exclude=None):
    """
    Claim a free domain id in [lo, hi]: return (id, open lock file); close the file to free it.

    Ids are tried in random order. ``exclude`` (default: this environment's ROS_DOMAIN_ID, the
    interactive shell's own domain) is never returned.
    """
    if exclude is None:
        exclude = {int(os.environ['ROS_DOMAIN_ID'])} \
            if os.environ.get('ROS_DOMAIN_ID', '').isdigit() else set()
    ids = [d for d in range(lo, hi + 1) if d not in exclude]
    random.shuffle(ids)
    for domain in ids:
        path = os.path.join(tempfile.gettempdir(), f'feeder-ros-domain-{domain}.lock')
        fh = open(path, 'w')
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            fh.close()
            continue
        if _ports_free(domain):
            return domain, fh
        fh.close()
    raise RuntimeError(f'no free ROS_DOMAIN_ID in [{lo}, {hi}]: every lock file '
                       f'{tempfile.gettempdir()}/feeder-ros-domain-*.lock is held or its '
                       'ports are in use')


def reserve_domain_id(lo=1, hi=101):
    """Reserve a domain id in [lo, hi] for this process (the same id on repeated calls)."""
    if 'id' not in _HELD:
        _HELD['id'], _HELD['file'] = claim_domain_id(lo, hi)
    return _HELD['id']


def dds_env(domain_id, base=None):
    """Environment for child processes: DDS on loopback, the given domain."""
    env = dict(os.environ if base is None else base)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env['ROS_DOMAIN_ID'] = str(domain_id)
    env.pop('ROS_LOCALHOST_ONLY', None)
    env.pop('ROS_STATIC_PEERS', None)
    return env


def install_env(install=INSTALL, base=None):
    """
    Environment for the executables of the colcon install ``install`` (e.g. ros2_ws/install).

    Its packages' site-packages go first on PYTHONPATH, their prefixes, then this Python's
    (the venv with the ROS wheels), on AMENT_PREFIX_PATH, and the ``lib`` folders of those that
    have shared libraries (feeder_interfaces' typesupports) on LD_LIBRARY_PATH, as colcon's
    setup scripts do; output unbuffered and uncoloured.
    """
    env = dict(os.environ if base is None else base)
    install = pathlib.Path(install)
    site = f'lib/python{sys.version_info.major}.{sys.version_info.minor}/site-packages'
    pkgs = sorted(p for p in install.iterdir() if p.is_dir()) if install.is_dir() else []
    paths = [str(p / site) for p in pkgs if (p / site).is_dir()]
    env['PYTHONPATH'] = os.pathsep.join(paths + [env.get('PYTHONPATH', '')]).strip(os.pathsep)
    prefixes = [str(p) for p in pkgs] + [sys.prefix]
    env['AMENT_PREFIX_PATH'] = os.pathsep.join(
        prefixes + [env.get('AMENT_PREFIX_PATH', '')]).strip(os.pathsep)
    libs = [str(p / 'lib') for p in pkgs if any((p / 'lib').glob('lib*.so'))]
    env['LD_LIBRARY_PATH'] = os.pathsep.join(
        libs + [env.get('LD_LIBRARY_PATH', '')]).strip(os.pathsep)
    env['PYTHONUNBUFFERED'] = '1'
    env['RCUTILS_COLORIZED_OUTPUT'] = '0'
    return env


class EmulatorThread:
    """A :class:`feeder_driver.emulator.Controller` served from a background thread."""

    def __init__(self, scene, link, **kwargs):
        from feeder_driver.emulator import from_scene
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
