#!/usr/bin/env bash
# The test command (README, .ci/run): the whole suite twice, in two fresh virtual environments:
#   .venv-newest  the newest releases of every dependency on PyPI;
#   .venv-jazzy   the library versions of ROS 2 Jazzy's platform, Ubuntu 24.04
#                 (constraints/jazzy.txt: numpy 1.26.4, scipy 1.11.4, matplotlib 3.6.3, ...).
# A result that depends on the library version fails here, not on a user's robot.
#
# Both get ROS 2 Jazzy's rclpy, Fast DDS, message packages and ament_flake8 / ament_pep257
# from PyPI (requirements-ros.txt), every ros-* pinned to Jazzy's version by
# constraints/ros-jazzy.txt on every pip call and checked after the install
# (tools/check_ros_pins.py): the node's rclpy tests and the real ament linters run here, not
# skipped. Only what needs launch / launch_testing (not on PyPI) skips; pytest -rs lists
# every skip with its reason.
set -euo pipefail
cd "$(dirname "$0")/.."
python="${PYTHON:-python3}"
run() {  # run VENV [pip arguments...]
  local venv=$1
  shift
  "$python" -m venv "$venv"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check --upgrade \
    --upgrade-strategy eager -c constraints/ros-jazzy.txt -r requirements-ros.txt \
    -r requirements-lint.txt "$@" -e '.[test]'
  "$venv/bin/python" tools/check_ros_pins.py
  echo "== $venv: $("$venv/bin/python" -c 'import numpy, scipy, matplotlib, sys; print(
    "python", sys.version.split()[0], "numpy", numpy.__version__, "scipy", scipy.__version__,
    "matplotlib", matplotlib.__version__)')"
  "$venv/bin/python" -m pytest -q -rs test
}
run .venv-newest
run .venv-jazzy -c constraints/jazzy.txt
