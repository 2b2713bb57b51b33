"""
The ament linter trio (flake8, pep257, copyright), where ament is installed (a ROS shell).

The checks are the ament_python template's, with a skip instead of an import error when the
ament linters are not installed; ruff (test_lint.py) covers the same ground everywhere.
"""

import pytest


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    ament_flake8 = pytest.importorskip('ament_flake8.main', reason='ament_flake8 not installed')
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
