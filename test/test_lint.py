"""Code style: ruff (pycodestyle, pyflakes, numpydoc docstrings) over the whole package."""

import importlib.util
from pathlib import Path
import subprocess
import sys

import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(importlib.util.find_spec('ruff') is None,
                    reason='ruff is not installed (pip install -e .[test])')
def test_ruff_reports_no_problem():
    result = subprocess.run([sys.executable, '-m', 'ruff', 'check', '--no-cache', str(REPO)],
                            capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stdout + result.stderr
