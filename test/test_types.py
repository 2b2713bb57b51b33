"""Static types: mypy over the package, with the configuration in setup.cfg."""

import importlib.util
import os
from pathlib import Path
import subprocess
import sys

import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(importlib.util.find_spec('mypy') is None,
                    reason='mypy is not installed (pip install -e .[test])')
def test_mypy_reports_no_error():
    # cache-dir os.devnull: nothing written into the checkout, every run from scratch
    result = subprocess.run(
        [sys.executable, '-m', 'mypy', '--config-file', str(REPO / 'setup.cfg'),
         '--cache-dir', os.devnull, str(REPO / 'pump_friction_ros')],
        capture_output=True, text=True, check=False, cwd=REPO)
    output = result.stdout + result.stderr
    print(output)
    assert result.returncode == 0, output
