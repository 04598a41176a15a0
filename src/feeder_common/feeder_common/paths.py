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
Per-user places on this machine (ROS-free): where an emulator's pty link goes by default.

Two users of one machine, or two feeders of one user, never share a default link, and no other
user can put one where this user's driver looks.
"""

import os
import stat
import tempfile


class RuntimeDirError(OSError):
    """The per-user folder cannot be made, or is not this user's private folder."""


def user_runtime_dir(env=None):
    """
    Return this user's private folder for runtime files (made mode 0700 when absent).

    ``$XDG_RUNTIME_DIR/feeder`` where the session has one, else ``<tmp>/feeder-<uid>``. A folder
    that is not a directory of this user with mode 0700 is refused (RuntimeDirError).
    """
    env = os.environ if env is None else env
    xdg = env.get('XDG_RUNTIME_DIR', '')
    if xdg and os.path.isabs(xdg) and os.path.isdir(xdg):
        path = os.path.join(xdg, 'feeder')
    else:
        path = os.path.join(tempfile.gettempdir(), f'feeder-{os.getuid()}')
    try:
        os.makedirs(path, mode=0o700, exist_ok=True)
        info = os.lstat(path)
    except OSError as exc:
        raise RuntimeDirError(f'cannot make {path}: {exc.strerror}') from None
    if not stat.S_ISDIR(info.st_mode) or info.st_uid != os.getuid() or info.st_mode & 0o077:
        raise RuntimeDirError(f'{path} is not a folder of yours with mode 0700 (another user '
                              'made it?)')
    return path


def emulator_link(namespace, env=None):
    """Return the default pty link of a feeder's emulator: ``feeder-<ns>-tty`` in that folder."""
    name = namespace.strip('/').replace('/', '-') or 'feeder'
    return os.path.join(user_runtime_dir(env), f'feeder-{name}-tty')
