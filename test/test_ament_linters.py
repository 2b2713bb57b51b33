"""
The ament linter trio (flake8, pep257, copyright) of ROS 2 Jazzy (ament_lint 0.17.3).

The checks are the ament_python template's. ament_flake8 and ament_pep257 come from PyPI in
the test command (requirements-ros.txt) and from apt on a ROS install; ament_copyright is
not on PyPI and runs in ``colcon test`` only. Where a tool is missing its test skips with
the reason; ruff (test_lint.py) covers much of the same ground everywhere.
"""

import importlib.metadata

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
@pytest.mark.skip(reason='no per-file copyright headers: the licence is in package.xml '
                  '(as in the ament_python template, which ships this test skipped)')
def test_copyright():
    ament_copyright = pytest.importorskip('ament_copyright.main')
    rc = ament_copyright.main(argv=['.', 'test'])
    assert rc == 0, 'Found errors'
