r"""
The ament_flake8 and ament_pep257 checks of ROS 2 Jazzy without ROS, from PyPI tools.

ament_lint 0.17.1 (Jazzy) runs, from the package root:

* ament_flake8 (``main_with_errors(argv=[])``): flake8 over ``.`` with only its
  ``ament_flake8.ini`` (copied next to this file) and the plugins a Jazzy install brings,
  excluding every directory named ``.*`` or ``_*`` and every directory holding an
  ``AMENT_IGNORE`` file.
* ament_pep257 (``main(argv=['.', 'test'])``): pydocstyle's API with
  ``--match '.*\\.py' --match-dir '[^\\._].*'`` (so test files and ``*.launch.py`` are
  included, directories ``.*`` / ``_*`` are not) and the "ament" convention, i.e.
  ``--ignore D100,D101,D102,D103,D104,D105,D106,D107,D203,D212,D404``. ament calls
  ``pydocstyle.check()`` without property decorators, so D401 applies to ``@property``
  docstrings too (pydocstyle's own CLI would skip them); this test does the same.

Both run in a subprocess with this interpreter. Install the tools with
``pip install -r requirements-lint.txt``; a test is skipped, with the reason, when its
tool is missing.
"""

import importlib.metadata
import importlib.util
import os
from pathlib import Path
import re
import subprocess
import sys

import pytest

REPO = Path(__file__).resolve().parents[1]
AMENT_FLAKE8_INI = Path(__file__).resolve().with_name('ament_flake8.ini')
FLAKE8_PLUGINS = ('flake8-builtins', 'flake8-comprehensions', 'flake8-docstrings',
                  'flake8-import-order', 'flake8-quotes', 'flake8-blind-except',
                  'flake8-class-newline', 'flake8-deprecated')
AMENT_PEP257_IGNORE = 'D100,D101,D102,D103,D104,D105,D106,D107,D203,D212,D404'
INSTALL_HINT = 'pip install -r requirements-lint.txt'

# ament_pep257.main.generate_pep257_report (ament_lint 0.17.1), minus the xunit output.
PEP257_SCRIPT = r"""
import sys
from pydocstyle import check
from pydocstyle.config import ConfigurationParser
from pydocstyle.violations import Error

ignore, paths = sys.argv[1], sys.argv[2:]
conf = ConfigurationParser()
sys.argv = ['main', '--match', r'.*\.py', '--match-dir', r'[^\._].*', '--ignore', ignore]
sys.argv += paths
conf.parse()
files = {}
for filename, checked_codes, ignore_decorators, *_ in conf.get_files_to_check():
    files[filename] = {'select': checked_codes, 'ignore_decorators': ignore_decorators}
count = 0
for filename in sorted(files):
    for error in check([filename], **files[filename]):
        count += 1
        if isinstance(error, Error):
            print('%s:%d %s: %s' % (error.filename, error.line, error.definition,
                                    error.message))
        else:
            print('%s: %s' % (filename, error))
print('%d files checked, %d errors' % (len(files), count))
sys.exit(1 if count else 0)
"""


def _missing_distributions(names):
    missing = []
    for name in names:
        try:
            importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            missing.append(name)
    return missing


def _ament_flake8_excludes(root):
    """Directories ament_flake8 excludes: AMENT_IGNORE ones, and names starting with . or _."""
    excludes = []
    for dirpath, dirnames, filenames in os.walk(root):
        if 'AMENT_IGNORE' in dirnames + filenames:
            dirnames[:] = []
            excludes.append(dirpath)
        else:
            excludes.extend(d for d in dirnames if d[0] in ('.', '_'))
            # Excluded directories need not be walked (ament walks them, to no effect).
            dirnames[:] = [d for d in dirnames if d[0] not in ('.', '_')]
    return sorted(set(excludes))


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8_as_ament_flake8():
    missing = _missing_distributions(('flake8', *FLAKE8_PLUGINS))
    if missing:
        pytest.skip(f'not installed: {", ".join(missing)} ({INSTALL_HINT})')
    assert AMENT_FLAKE8_INI.is_file(), f'{AMENT_FLAKE8_INI} is missing (copy it from /tmp/lint)'
    cmd = [sys.executable, '-m', 'flake8', f'--config={AMENT_FLAKE8_INI}']
    excludes = _ament_flake8_excludes(REPO)
    if excludes:
        cmd.append('--exclude=' + ','.join(excludes))
    cmd.append('.')
    result = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, check=False)
    errors = re.findall(r'^\S+:\d+:\d+: [A-Z]+\d+ .*$', result.stdout, re.MULTILINE)
    assert result.returncode == 0, (
        f'flake8 with ament_flake8.ini found {len(errors)} code style errors / warnings '
        f'(rc {result.returncode}):\n{result.stdout}\n{result.stderr}')


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257_as_ament_pep257():
    if importlib.util.find_spec('pydocstyle') is None:
        pytest.skip(f'pydocstyle is not installed ({INSTALL_HINT})')
    # ament's own test passes ['.', 'test']; '.' alone covers test/ as well (with both,
    # pydocstyle checks test files twice, as './test/x.py' and 'test/x.py').
    cmd = [sys.executable, '-c', PEP257_SCRIPT, AMENT_PEP257_IGNORE, '.']
    result = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, check=False)
    assert result.returncode == 0, (
        f'pydocstyle with the ament_pep257 settings found errors:\n'
        f'{result.stdout}\n{result.stderr}')
