# Copyright 2026 pump_friction_ros developers
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
