"""Imports flow one way: node / replay / cli -> estimator, monitor -> table -> model."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'pump_friction_ros'
ROS_MODULES = {'rclpy', 'rcl_interfaces', 'std_msgs', 'sensor_msgs', 'diagnostic_msgs',
               'std_srvs', 'builtin_interfaces', 'launch', 'launch_ros'}
LAYERS = {  # a module may import modules of its own layer or below
    0: {'__init__', 'units', 'errors', 'paths', 'params', 'kinematics', 'pressure', 'dynamics',
        'friction', 'model', 'paper', 'oil'},
    1: {'table', 'table_exact', 'table_io', 'progress', 'staging'},
    2: {'config', 'inputs', 'estimate', 'speed_filter', 'attribution', 'monitor', 'diagnostics',
        'estimator', 'chunk_path',
        'simulate', 'ros_messages'},
    3: {'node', 'bags', 'samples', 'cli', 'cli_data', 'plots', 'benchmark', 'calibration',
        'evaluation', 'measure_cpu'},
}
LAYER_OF = {name: layer for layer, names in LAYERS.items() for name in names}
ROS_IMPORTERS = {'node', 'measure_cpu'}  # the node, and the benchmark that runs it


def unit_of(path):
    """Top-level unit of a module: its own name, or its subpackage's (bags/replay.py: bags)."""
    parts = path.relative_to(PACKAGE).with_suffix('').parts
    return parts[0]


def imports_of(path):
    """Package units (relative imports, as '.name') and outside modules a file imports."""
    parts = list(path.relative_to(PACKAGE).with_suffix('').parts)
    tree = ast.parse(path.read_text())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative: resolve against the module's own package
                base = parts[:len(parts) - node.level]
                if node.module:
                    target = base + node.module.split('.')
                    found.add('.' + target[0])
                elif base:
                    found.add('.' + base[0])
                else:
                    found.update('.' + alias.name for alias in node.names)
            else:
                found.add(node.module.split('.')[0])
    return found


MODULES = sorted(PACKAGE.rglob('*.py'))
IDS = [str(p.relative_to(PACKAGE)) for p in MODULES]


def test_every_module_has_a_layer():
    assert {unit_of(p) for p in MODULES} <= set(LAYER_OF)


def test_subpackage_modules_are_found():
    assert 'bags/replay.py' in IDS and 'bags/cdr.py' in IDS


@pytest.mark.parametrize('path', MODULES, ids=IDS)
def test_only_the_node_imports_ros(path):
    ros = imports_of(path) & ROS_MODULES
    assert not ros or path.stem in ROS_IMPORTERS, f'{path.stem} imports {ros}'


@pytest.mark.parametrize('path', MODULES, ids=IDS)
def test_imports_flow_one_way(path):
    mine = LAYER_OF[unit_of(path)]
    for name in imports_of(path):
        if name.startswith('.'):
            other = name[1:]
            if other in LAYER_OF:
                assert LAYER_OF[other] <= mine, f'{path} (layer {mine}) imports {other}'


@pytest.mark.parametrize('path', MODULES, ids=IDS)
def test_no_long_module_without_a_reason_at_its_top(path):
    text = path.read_text()
    if text.count('\n') > 500:
        docstring = ast.get_docstring(ast.parse(text)) or ''
        assert 'Longer than 500 lines because' in docstring, f'{path}: split it or say why'
