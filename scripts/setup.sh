#!/usr/bin/env bash
# Sets up everything on a fresh machine (idempotent): the project venv in .venv with ROS 2
# Kilted from PyPI, the throwmap library (editable) and the colcon workspace in ros2_ws/.
# Source it (". scripts/setup.sh") to get the environment in your shell, or let scripts/demo
# and scripts/test do it. It leaves the caller's shell options alone (no set -e leaking into an
# interactive shell) and returns non-zero if a step fails.
_feeder_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# The installing steps run in a subshell with strict options; they export nothing.
(
  set -euo pipefail
  ROOT="$_feeder_root"
  VENV="$ROOT/.venv"
  stamp="$VENV/.feeder-requirements"
  if [ ! -x "$VENV/bin/python" ]; then
    echo "setup: creating $VENV"
    "${PYTHON:-python3}" -m venv "$VENV"
  fi
  # shellcheck disable=SC1091
  . "$VENV/bin/activate"
  if ! cmp -s "$ROOT/requirements.txt" "$stamp" 2>/dev/null; then
    echo "setup: installing requirements (ROS 2 Kilted wheels, numpy, numba, ...)"
    # (the grep drops this machine's notes about absent local index mirrors)
    python -m pip install --quiet --disable-pip-version-check -r "$ROOT/requirements.txt" \
      2> >(grep -v 'is ignored: it is neither a file nor a directory' >&2)
    cp "$ROOT/requirements.txt" "$stamp"
  fi
  if ! python -c 'import throwmap' 2>/dev/null; then
    python -m pip install --quiet --disable-pip-version-check --no-deps -e "$ROOT/src/throwmap"
  fi
  # An editable install follows setup.cfg's [develop] script_dir (lib/throwmap, where
  # `ros2 run` looks after colcon build --symlink-install): put the CLI on the venv's PATH too.
  if [ ! -e "$VENV/bin/throwmap" ] && [ -x "$VENV/lib/throwmap/throwmap" ]; then
    ln -s ../lib/throwmap/throwmap "$VENV/bin/throwmap"
  fi
  # The message wheels' exported CMake targets name the wheel builder's Python and numpy
  # include folders: point this venv's copies at its own (idempotent; nothing to do on a
  # normal ROS install, whose files never name them).
  python "$ROOT/scripts/wheel_cmake_paths.py"
  if [ "${FEEDER_SKIP_COLCON:-0}" != 1 ] && ls "$ROOT"/src/feeder_*/package.xml >/dev/null 2>&1
  then
    if ! command -v cc >/dev/null || ! command -v c++ >/dev/null; then
      echo "setup: building feeder_interfaces (messages) needs a C and a C++ compiler (cc, c++)" \
        "on PATH: install them (Debian/Ubuntu: apt-get install g++)" >&2
      exit 1
    fi
    echo "setup: colcon build (ros2_ws)"
    # The wheels install their share/ (ament index, CMake configs) into the venv: the message
    # generators look their typesupports up there.
    case ":${AMENT_PREFIX_PATH:-}:" in
      *":$VIRTUAL_ENV:"*) ;;
      *) export AMENT_PREFIX_PATH="$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}" ;;
    esac
    if ! (cd "$ROOT/ros2_ws" && colcon build --event-handlers console_direct- \
          > "$ROOT/ros2_ws/colcon-build.log" 2>&1); then
      cat "$ROOT/ros2_ws/colcon-build.log"
      echo "setup: colcon build failed"
      exit 1
    fi
  fi
) || { echo "setup: failed" >&2; unset _feeder_root; return 1 2>/dev/null || exit 1; }

# The environment, in the caller's shell.
# shellcheck disable=SC1091
. "$_feeder_root/.venv/bin/activate"
# DDS stays on loopback, on a domain of this shell's own.
# shellcheck disable=SC1091
. "$_feeder_root/scripts/ros-env.sh"
case ":${AMENT_PREFIX_PATH:-}:" in
  *":$VIRTUAL_ENV:"*) ;;
  *) export AMENT_PREFIX_PATH="$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}" ;;
esac
if [ -f "$_feeder_root/ros2_ws/install/local_setup.bash" ] && [ "${FEEDER_SKIP_COLCON:-0}" != 1 ]
then
  # colcon's setup scripts read unset variables: source them without `set -u`.
  case $- in *u*) _feeder_u=1; set +u ;; *) _feeder_u=0 ;; esac
  # shellcheck disable=SC1091
  . "$_feeder_root/ros2_ws/install/local_setup.bash"
  if [ "$_feeder_u" = 1 ]; then set -u; fi
  unset _feeder_u
fi
unset _feeder_root
