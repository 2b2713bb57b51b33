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

"""
The ament linter trio (flake8, pep257, copyright) of ROS 2 Jazzy (ament_lint 0.17.3).

The checks are the ament_python template's. ament_flake8 and ament_pep257 come from PyPI in
the test command (requirements-ros.txt) and from apt on a ROS install; ament_copyright is
not on PyPI and runs in ``colcon test`` only, so its rule is also checked here by hand. Where
a tool is missing its test skips with the reason; ruff (test_lint.py) covers much of the
same ground everywhere.
"""

import importlib.metadata
from pathlib import Path
import re

import pytest

# The flake8 plugins a Jazzy install of ament_flake8 brings (its package.xml exec_depends;
# versions in requirements-lint.txt): without them ament_flake8 checks less and still passes.
FLAKE8_PLUGINS = ('flake8-builtins', 'flake8-comprehensions', 'flake8-docstrings',
                  'flake8-import-order', 'flake8-quotes', 'flake8-blind-except',
                  'flake8-class-newline', 'flake8-deprecated')


def _missing(names):
    missing = []
    for name in names:
        try:
            importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            missing.append(name)
    return missing


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    ament_flake8 = pytest.importorskip('ament_flake8.main', reason='ament_flake8 not installed')
    missing = _missing(FLAKE8_PLUGINS)
    assert not missing, f'ament_flake8 without the plugins Jazzy brings: {", ".join(missing)} ' \
        '(pip install -r requirements-lint.txt)'
    rc, errors = ament_flake8.main_with_errors(argv=[])
    assert rc == 0, f'Found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    ament_pep257 = pytest.importorskip('ament_pep257.main', reason='ament_pep257 not installed')
    rc = ament_pep257.main(argv=['.', 'test'])
    assert rc == 0, 'Found code style errors / warnings'


@pytest.mark.copyright
@pytest.mark.linter
def test_copyright():
    ament_copyright = pytest.importorskip(
        'ament_copyright.main', reason='ament_copyright is not on PyPI: it runs in colcon test '
        'on a ROS 2 Jazzy install (test_every_source_file_carries_the_apache_header runs here)')
    rc = ament_copyright.main(argv=['.', 'test'])
    assert rc == 0, 'Found errors'


APACHE_2_NOTICE = """
Licensed under the Apache License, Version 2.0 (the "License");
you may not use this file except in compliance with the License.
You may obtain a copy of the License at

    http://www.apache.org/licenses/LICENSE-2.0

Unless required by applicable law or agreed to in writing, software
distributed under the License is distributed on an "AS IS" BASIS,
WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
See the License for the specific language governing permissions and
limitations under the License.""".strip()


def _first_comment_block(text):
    lines = text.splitlines()
    while lines and (lines[0].startswith('#!') or 'coding' in lines[0] or not lines[0].strip()):
        lines.pop(0)
    block = []
    for line in lines:
        if not line.startswith('#'):
            break
        block.append(line[2:] if line.startswith('# ') else line[1:])
    return '\n'.join(block)


def test_every_source_file_carries_the_apache_header():
    """ament_copyright's rule (ament_lint 0.17): a copyright line, then the apache2 notice."""
    root = Path(__file__).resolve().parents[1]
    bad = []
    for path in sorted(root.rglob('*.py')):
        rel = path.relative_to(root)
        if any(part[0] in '._' for part in rel.parts[:-1]) or rel == Path('setup.py'):
            continue  # as ament's crawler: no '.*' or '_*' directories, no package setup.py
        block = _first_comment_block(path.read_text())
        first, _, rest = block.partition('\n')
        if not re.match(r'Copyright \d{4}(-\d{4})? \S', first) or \
                rest.strip() != APACHE_2_NOTICE:
            bad.append(str(rel))
    assert not bad, 'without the Apache-2.0 header (package.xml licence): ' + ', '.join(bad)
