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

"""Errors: one module defines them, bag errors keep their cause, the CLI prints one line."""

import ast
import importlib
import importlib.util
import os
from pathlib import Path
import sys
import types

from pump_friction_ros import errors
from pump_friction_ros.app.cli import main
from pump_friction_ros.bags import sources
from pump_friction_ros.bags.fleet import ReplayJob, run_jobs
from pump_friction_ros.core.node_parameters import EstimatorConfig
from pump_friction_ros.errors import BagError, PumpFrictionError
import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'pump_friction_ros'
REPO = PACKAGE.parent
MODULES = sorted(PACKAGE.rglob('*.py'))
IDS = [str(p.relative_to(PACKAGE)) for p in MODULES]
NAMED = ('BagError', 'CalibrationError', 'ConfigError', 'TableError', 'UsageError')


def _module_name(path):
    parts = path.relative_to(REPO).with_suffix('').parts
    return '.'.join(parts[:-1] if parts[-1] == '__init__' else parts)


@pytest.mark.parametrize('name', NAMED)
def test_named_errors_are_defined_in_errors_py(name):
    cls = getattr(errors, name)
    assert cls.__module__ == 'pump_friction_ros.errors' and issubclass(cls, PumpFrictionError)
    assert name in errors.__all__


@pytest.mark.parametrize('path', MODULES, ids=IDS)
def test_no_module_but_errors_py_defines_a_package_error(path):
    """A second class of the same name would not be caught as the one in errors.py."""
    if path.name == 'errors.py':
        return
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef):
            bases = {b.id if isinstance(b, ast.Name) else getattr(b, 'attr', '')
                     for b in node.bases}
            assert not bases & set(errors.__all__), f'{path}: class {node.name}'
    if path.stem == 'node' and importlib.util.find_spec('rclpy') is None:
        return
    module = importlib.import_module(_module_name(path))
    for value in vars(module).values():  # re-exports are the same classes
        if isinstance(value, type) and issubclass(value, PumpFrictionError):
            assert value.__module__ == 'pump_friction_ros.errors', f'{path}: {value}'


@pytest.mark.parametrize('path', sorted((PACKAGE / 'bags').glob('*.py')),
                         ids=lambda p: p.name)
def test_bag_errors_raised_while_handling_an_exception_keep_it_as_their_cause(path):
    for handler in ast.walk(ast.parse(path.read_text())):
        if isinstance(handler, ast.ExceptHandler):
            for node in ast.walk(handler):
                if isinstance(node, ast.Raise) and isinstance(node.cause, ast.Constant):
                    pytest.fail(f'{path.name}:{node.lineno}: raise ... from None')


def test_missing_dask_is_a_bag_error_caused_by_the_import_error(monkeypatch):
    monkeypatch.setitem(sys.modules, 'dask.distributed', None)  # import fails
    with pytest.raises(BagError, match=r'needs dask\.distributed') as info:
        run_jobs([ReplayJob(bag='b', config=EstimatorConfig())], dask_address='tcp://x:1')
    assert isinstance(info.value.__cause__, ImportError)


def _unreachable_scheduler(monkeypatch):
    def refuse(*args, **kwargs):
        raise OSError('connection refused')

    monkeypatch.setitem(sys.modules, 'dask.distributed',
                        types.SimpleNamespace(Client=refuse))


def test_unreachable_scheduler_is_a_bag_error_caused_by_the_os_error(monkeypatch):
    _unreachable_scheduler(monkeypatch)
    with pytest.raises(BagError, match='cannot reach the Dask scheduler') as info:
        run_jobs([ReplayJob(bag='b', config=EstimatorConfig())], dask_address='tcp://x:1')
    assert isinstance(info.value.__cause__, OSError)


@pytest.mark.parametrize('address', ['::::', 'foo://bar:1', 'tls://127.0.0.1:1'])
def test_a_malformed_scheduler_address_is_one_line_naming_it(capsys, address):
    pytest.importorskip('dask.distributed', reason='dask[distributed] missing')
    code = main(['replay', str(REPO / 'bags' / 'eha_nominal'), '--dask', address])
    err = capsys.readouterr().err
    assert code == 2 and err.count('\n') == 1
    assert err.startswith(f'pump_friction: error: --dask {address}: not a scheduler address')


def _die(conn, parent_end, *args):
    """Stand-in for the bag reader process: ends at once, sending nothing."""
    os._exit(3)


def test_reader_process_death_is_a_bag_error_caused_by_the_broken_pipe(monkeypatch):
    monkeypatch.setattr(sources, '_reader_process', _die)
    with pytest.raises(BagError, match='the bag reader process died') as info:
        sources.ProcessSource('no-bag', EstimatorConfig(), None)
    assert isinstance(info.value.__cause__, (EOFError, OSError))


def test_cli_prints_only_the_message_of_an_error_with_a_cause(monkeypatch, capsys):
    _unreachable_scheduler(monkeypatch)
    code = main(['replay', str(REPO / 'bags' / 'eha_nominal'), '--dask', 'tcp://x:1'])
    captured = capsys.readouterr()
    assert code == 2 and captured.out == ''
    assert captured.err == ('pump_friction: error: cannot reach the Dask scheduler at '
                            'tcp://x:1: connection refused\n')


@pytest.mark.parametrize(('argv', 'message'), [
    (['replay', str(REPO / 'bags' / 'eha_nominal'), '--workers', '0'],
     '--workers must be >= 1'),
    (['no-such-command'], 'invalid choice'),
])
def test_usage_errors_are_the_errors_module_class_and_print_one_line(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith('pump_friction: error: ') and message in err and err.count('\n') == 1
    from pump_friction_ros.app.arguments import Parser
    with pytest.raises(errors.UsageError, match='unrecognized arguments: --nope'):
        Parser(prog='pump_friction').parse_args(['--nope'])  # the errors module's class
