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
Point the ROS wheels' exported CMake targets at this venv's Python and numpy headers.

The ``ros-*`` message wheels are built in a manylinux container (cibuildwheel): their exported
``<pkg>__rosidl_generator_py`` targets name that container's include folders
(``/opt/python/cp311-cp311/include/python3.11`` and ``.../site-packages/numpy/_core/include``),
which do not exist here, so CMake refuses to generate any package that builds messages on top of
them (``rosidl_generate_interfaces`` with a dependency such as builtin_interfaces). This
rewrites those two folders in the ``share/*/cmake/*.cmake`` files under ``sys.prefix`` (the
venv's copies, nothing else) to the running interpreter's ``include`` folder and numpy's.

Run it with the venv's python (scripts/setup.sh does). Idempotent: a patched file no longer
names ``/opt/python``; it prints what it changed and exits 0, or exits 1 naming the problem
(no Python headers, no numpy, an ``/opt/python`` path it does not know). On a normal ROS
install (apt, rosdep) the files never name ``/opt/python`` and nothing is done.
"""

import pathlib
import re
import sys
import sysconfig

# The manylinux image's interpreters: /opt/python/cp311-cp311, cp313-cp313t, ...
_OPT_PYTHON = r'/opt/python/cp3\d+-cp3\d+t?'
_PYTHON_INCLUDE = re.compile(_OPT_PYTHON + r'/include/python3\.\d+t?(?=[";\s]|$)')
_NUMPY_INCLUDE = re.compile(_OPT_PYTHON + r'/lib/python3\.\d+t?/site-packages/numpy/'
                            r'(?:_core|core)/include(?=[";\s]|$)')
_ANY = re.compile(_OPT_PYTHON + r'[^";\s]*')


def cmake_files(prefix):
    """Return the exported CMake files of the packages installed under ``prefix``."""
    return sorted(pathlib.Path(prefix).glob('share/*/cmake/*.cmake'))


def patch_text(text, python_include, numpy_include):
    """Return ``text`` with the container's include folders replaced, and what is left over."""
    text = _PYTHON_INCLUDE.sub(lambda m: python_include, text)
    text = _NUMPY_INCLUDE.sub(lambda m: numpy_include, text)
    return text, sorted(set(_ANY.findall(text)))


def main(prefix=None):
    prefix = pathlib.Path(sys.prefix if prefix is None else prefix)
    files = [f for f in cmake_files(prefix) if '/opt/python/' in f.read_text(errors='replace')]
    if not files:
        return 0
    python_include = sysconfig.get_paths()['include']
    if not (pathlib.Path(python_include) / 'Python.h').is_file():
        print(f'wheel_cmake_paths: {python_include}/Python.h is missing: this Python has no '
              'development headers, which building messages needs; install them (Debian: '
              'apt-get install python3-dev) or use a Python that has them', file=sys.stderr)
        return 1
    try:
        import numpy
    except ImportError:
        print('wheel_cmake_paths: numpy is not installed in this venv: install the '
              'requirements first (python -m pip install -r requirements.txt)', file=sys.stderr)
        return 1
    numpy_include = numpy.get_include()
    unknown = set()
    for path in files:
        text = path.read_text()
        patched, left = patch_text(text, python_include, numpy_include)
        unknown.update(f'{path}: {p}' for p in left)
        if patched != text:
            path.write_text(patched)
    print(f'wheel_cmake_paths: {len(files)} exported CMake files of the ROS wheels now name '
          f'{python_include} and {numpy_include}')
    if unknown:
        print('wheel_cmake_paths: paths of the wheel builder left that this script does not '
              'know how to replace (a newer wheel?): ' + '; '.join(sorted(unknown)),
              file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main(*sys.argv[1:]))
