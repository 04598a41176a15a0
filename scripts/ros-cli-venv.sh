#!/usr/bin/env bash
# Builds the real ROS 2 command line (`ros2`: ros2cli) and `ros2 launch` (launch, launch_ros)
# into a venv of their own, beside the project's, to use and test the feeder graph as a ROS
# user would (tests/test_ros_cli.py). They have no wheels on PyPI, so they are installed from
# source trees that you provide; this script downloads no sources.
#
#   usage: scripts/ros-cli-venv.sh SRC VENV
#
# SRC holds one extracted source tree per repository, at these releases (Kilted):
#   SRC/ros2cli            ros2/ros2cli 0.36.1
#   SRC/rosidl_runtime_py  ros2/rosidl_runtime_py 0.14.0
#   SRC/launch             ros2/launch 3.7.1
#   SRC/launch_ros         ros2/launch_ros 0.28.0
# e.g. GitHub's archive of each tag (https://github.com/ros2/<repo>/archive/refs/tags/<tag>.tar.gz)
# extracted to SRC/<repo>. The versions are checked against each package.xml. VENV is created
# (or reused: the script is idempotent). The ROS wheels come from PyPI at the project's pins
# (requirements.txt). Then, from the repository root:
#   . scripts/setup.sh                                # the project venv and the colcon workspace
#   FEEDER_ROS_CLI_VENV=VENV python -m pytest tests/test_ros_cli.py
# or, for a shell with `ros2` on PATH:
#   . VENV/bin/activate; export AMENT_PREFIX_PATH=$VIRTUAL_ENV
#   . ros2_ws/install/local_setup.bash; . scripts/ros-env.sh     # DDS on loopback
#   ros2 launch feeder_bringup sim.launch.py ...
# Two adjustments are made in VENV, nowhere else:
# * launch_ros imports composition_interfaces (composable nodes), which has no wheel: a stand-in
#   module is written that imports and refuses any use, so composable nodes do not work.
# * ros2cli 0.36.1's `ros2 param load` counts the parameters of every node in the file, while
#   rclpy 9.1 sets only those of the target node: a file keyed by the node's full name then
#   fails its count check; the count is made over the target node's parameters only.
set -euo pipefail
usage='usage: scripts/ros-cli-venv.sh SRC VENV (see the comment at the top of this script)'
SRC=${1:?$usage}
VENV=${2:?$usage}
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# Each source tree: where its package.xml is, and the version it must have.
check_version() {
  local xml="$SRC/$1/package.xml" want=$2 got
  if [ ! -f "$xml" ]; then
    echo "ros-cli-venv: $xml is missing: extract the ros2/${1%%/*} $want source tree to" \
      "$SRC/${1%%/*}" >&2
    return 1
  fi
  got=$(sed -n 's:.*<version>\(.*\)</version>.*:\1:p' "$xml" | head -n 1)
  if [ "$got" != "$want" ]; then
    echo "ros-cli-venv: $xml is version $got; this script builds $want (Kilted):" \
      "extract that release to $SRC/${1%%/*}" >&2
    return 1
  fi
}
status=0
check_version ros2cli/ros2cli 0.36.1 || status=1
check_version rosidl_runtime_py 0.14.0 || status=1
check_version launch/launch 3.7.1 || status=1
check_version launch_ros/launch_ros 0.28.0 || status=1
[ "$status" = 0 ] || exit 1

if [ ! -x "$VENV/bin/python" ]; then
  echo "ros-cli-venv: creating $VENV"
  "${PYTHON:-python3}" -m venv "$VENV"
fi
pip_install() {
  # (the grep drops notes about absent local index mirrors some machines configure)
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check "$@" \
    2> >(grep -v 'is ignored: it is neither a file nor a directory' >&2)
}
# The ROS wheels at the project's pins (one place for them: requirements.txt).
mapfile -t ros_pins < <(grep -E '^ros-kilted-(rclpy|common-interfaces|rmw-fastrtps-cpp)==' \
  "$ROOT/requirements.txt")
if [ "${#ros_pins[@]}" != 3 ]; then
  echo "ros-cli-venv: $ROOT/requirements.txt does not pin ros-kilted-rclpy," \
    "ros-kilted-common-interfaces and ros-kilted-rmw-fastrtps-cpp" >&2
  exit 1
fi
echo "ros-cli-venv: installing the ROS wheels and the command line's Python dependencies"
# The dependencies ros2cli and launch declare (their package.xml exec_depends), at the
# versions this was verified with (2026-11-26).
pip_install "${ros_pins[@]}" wheel==0.48.0 pyyaml==6.0.3 packaging==26.4 psutil==7.2.2 \
  argcomplete==3.7.2 netifaces==0.11.0 lark==1.3.1 catkin-pkg==1.1.1 osrf-pycommon==2.0.2
echo "ros-cli-venv: installing ros2cli, rosidl_runtime_py, launch, launch_ros from $SRC"
for pkg in rosidl_runtime_py \
    ros2cli/ros2cli ros2cli/ros2pkg ros2cli/ros2run ros2cli/ros2node ros2cli/ros2topic \
    ros2cli/ros2service ros2cli/ros2param ros2cli/ros2lifecycle ros2cli/ros2action \
    ros2cli/ros2interface ros2cli/ros2doctor \
    launch/launch launch/launch_xml launch/launch_yaml launch_ros/launch_ros \
    launch_ros/ros2launch; do
  pip_install --no-deps --no-build-isolation "$SRC/$pkg"
done

"$VENV/bin/python" - <<'EOF'
import pathlib
import sysconfig

site = pathlib.Path(sysconfig.get_paths()['purelib'])

# ros2 param load: count the target node's parameters only (what rclpy 9.1 sets).
api = site / 'ros2param' / 'api' / '__init__.py'
text = api.read_text()
old = 'parameter_dict_from_yaml_file(parameter_file, use_wildcard).values()'
new = ('parameter_dict_from_yaml_file(parameter_file, use_wildcard, '
       'target_nodes=[node_name]).values()')
if old in text:
    api.write_text(text.replace(old, new))
elif new not in text:
    raise SystemExit(f'ros-cli-venv: {api} has neither the line to adjust nor the adjusted '
                     'one: is it ros2cli 0.36.1?')

# composition_interfaces: importable, refusing every use.
pkg = site / 'composition_interfaces'
pkg.mkdir(exist_ok=True)
(pkg / '__init__.py').write_text(
    '"""Stand-in written by the feeder ros-cli-venv.sh: composition_interfaces has no '
    'wheel."""\n')
(pkg / 'srv.py').write_text('''"""Stand-in services: composable nodes are not available here."""


class _Missing:
    class Request:
        def __init__(self, *args, **kwargs):
            raise RuntimeError('composition_interfaces is not installed in this venv '
                               '(no wheel exists): composable nodes are not available')

    Response = Request


class LoadNode(_Missing):
    pass


class UnloadNode(_Missing):
    pass


class ListNodes(_Missing):
    pass
''')
EOF
if ! AMENT_PREFIX_PATH="$VENV" "$VENV/bin/ros2" pkg prefix launch_ros >/dev/null; then
  echo "ros-cli-venv: $VENV/bin/ros2 does not find launch_ros: the build did not work" >&2
  exit 1
fi
echo "ros-cli-venv: built $VENV (ros2cli 0.36.1, launch 3.7.1, launch_ros 0.28.0)"
