"""Imports flow one way: node / replay / cli -> estimator, monitor -> table -> model."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'pump_friction_ros'
ROS_MODULES = {'rclpy', 'rcl_interfaces', 'std_msgs', 'sensor_msgs', 'diagnostic_msgs',
               'std_srvs', 'builtin_interfaces', 'launch', 'launch_ros'}
LAYERS = {  # a module may import modules of its own layer or below
    0: {'__init__', 'units', 'errors', 'params', 'kinematics', 'pressure', 'dynamics',
        'friction', 'model', 'paper', 'oil'},
    1: {'table', 'progress'},
    2: {'config', 'monitor', 'estimator', 'simulate', 'ros_messages'},
    3: {'node', 'replay', 'bags', 'samples', 'cli', 'plots', 'benchmark', 'calibrate'},
}
LAYER_OF = {name: layer for layer, names in LAYERS.items() for name in names}


def imports_of(path):
    tree = ast.parse(path.read_text())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative: from .x import y / from . import x
                if node.module:
                    found.add('.' + node.module.split('.')[0])
                else:
                    found.update('.' + alias.name for alias in node.names)
            else:
                found.add(node.module.split('.')[0])
    return found


MODULES = sorted(p for p in PACKAGE.glob('*.py'))


def test_every_module_has_a_layer():
    assert {p.stem for p in MODULES} <= set(LAYER_OF)


@pytest.mark.parametrize('path', MODULES, ids=[p.stem for p in MODULES])
def test_only_the_node_imports_ros(path):
    ros = imports_of(path) & ROS_MODULES
    assert not ros or path.stem == 'node', f'{path.stem} imports {ros}'


@pytest.mark.parametrize('path', MODULES, ids=[p.stem for p in MODULES])
def test_imports_flow_one_way(path):
    mine = LAYER_OF[path.stem]
    for name in imports_of(path):
        if name.startswith('.'):
            other = name[1:]
            if other in LAYER_OF:
                assert LAYER_OF[other] <= mine, f'{path.stem} (layer {mine}) imports {other}'
