#!/usr/bin/env bash
# Sets up everything on a fresh machine (idempotent): the project venv in .venv with ROS 2
# Kilted from PyPI, the throwmap library (editable) and the colcon workspace in ros2_ws/.
# Source it (". scripts/setup.sh") to get the environment, or let scripts/demo and scripts/test
# do it.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
PY="${PYTHON:-python3}"
VENV="$ROOT/.venv"
stamp="$VENV/.feeder-requirements"
if [ ! -x "$VENV/bin/python" ]; then
  echo "setup: creating $VENV"
  "$PY" -m venv "$VENV"
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
# DDS stays on loopback, on a domain of this shell's own.
# shellcheck disable=SC1091
. "$ROOT/scripts/ros-env.sh"
export AMENT_PREFIX_PATH="$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
if [ "${FEEDER_SKIP_COLCON:-0}" != 1 ] && ls "$ROOT"/src/feeder_*/package.xml >/dev/null 2>&1; then
  echo "setup: colcon build (ros2_ws)"
  (cd "$ROOT/ros2_ws" && colcon build --event-handlers console_direct- > "$ROOT/ros2_ws/colcon-build.log" 2>&1) \
    || { cat "$ROOT/ros2_ws/colcon-build.log"; echo "setup: colcon build failed"; exit 1; }
  # colcon's setup scripts read unset variables: source them without `set -u`.
  case $- in *u*) _feeder_u=1; set +u ;; *) _feeder_u=0 ;; esac
  # shellcheck disable=SC1091
  . "$ROOT/ros2_ws/install/local_setup.bash"
  [ "$_feeder_u" = 1 ] && set -u
  unset _feeder_u
fi
