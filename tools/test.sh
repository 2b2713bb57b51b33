#!/usr/bin/env bash
# The test command (README, .ci/run): the whole suite twice, in two fresh virtual environments:
#   .venv-newest  the newest releases of every dependency on PyPI;
#   .venv-jazzy   the library versions of ROS 2 Jazzy's platform, Ubuntu 24.04
#                 (constraints/jazzy.txt: numpy 1.26.4, scipy 1.11.4, matplotlib 3.6.3, ...).
# A result that depends on the library version fails here, not on a user's robot.
set -euo pipefail
cd "$(dirname "$0")/.."
python="${PYTHON:-python3}"
run() {  # run VENV [pip arguments...]
  local venv=$1
  shift
  "$python" -m venv "$venv"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check --upgrade \
    --upgrade-strategy eager "$@" -e '.[test]'
  echo "== $venv: $("$venv/bin/python" -c 'import numpy, scipy, matplotlib, sys; print(
    "python", sys.version.split()[0], "numpy", numpy.__version__, "scipy", scipy.__version__,
    "matplotlib", matplotlib.__version__)')"
  "$venv/bin/python" -m pytest -q test
}
run .venv-newest -r requirements-lint.txt  # and the linters of a ROS user's colcon test
run .venv-jazzy -c constraints/jazzy.txt
