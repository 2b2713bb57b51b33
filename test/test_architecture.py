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
Layers are folders, and imports flow one way: what each layer's ``__init__`` allows.

Each subpackage's docstring ends with ``May import: a, b, base.``; the modules directly in
the package (errors, paths, ...) are the layer ``base`` and may import only each other. The
test reads those lines and the code's imports, nothing kept by hand here.
"""

import ast
import importlib.util
from pathlib import Path
import re

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'pump_friction_ros'
ROS_MODULES = {'rclpy', 'rcl_interfaces', 'std_msgs', 'sensor_msgs', 'diagnostic_msgs',
               'std_srvs', 'builtin_interfaces', 'launch', 'launch_ros'}
ROS_LAYERS = {'node'}  # the only layer that imports ROS
BASE = 'base'
MAX_TOP_LEVEL_MODULES = 11


def layer_of(path):
    """Return the layer of a module: its top folder under the package, or ``base``."""
    parts = path.relative_to(PACKAGE).parts
    return parts[0] if len(parts) > 1 else BASE


def allowed_imports():
    """Return each layer's allowed layers, from the ``May import:`` line of its __init__."""
    allowed = {}
    for init in [PACKAGE / '__init__.py', *sorted(PACKAGE.glob('*/__init__.py'))]:
        doc = ast.get_docstring(ast.parse(init.read_text())) or ''
        match = re.search(r'^May import: ([a-z_, ]+)\.$', doc, re.MULTILINE)
        assert match, f'{init}: its docstring must end with "May import: ..."'
        layer = layer_of(init) if init.parent != PACKAGE else BASE
        allowed[layer] = {name.strip() for name in match.group(1).split(',')} | {layer}
    return allowed


def imported_layers(path, text=None):
    """Return the package layers and the outside top-level modules a file imports."""
    parts = list(path.relative_to(PACKAGE).with_suffix('').parts)
    tree = ast.parse(path.read_text() if text is None else text)
    layers, outside = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            outside.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if not node.level:
                outside.add(node.module.split('.')[0])
                continue
            target = parts[:len(parts) - node.level] + (node.module.split('.')
                                                        if node.module else [])
            if not target:  # from . import x (the package's own names)
                layers.add(BASE)
            else:
                sub = PACKAGE / target[0]
                layers.add(target[0] if sub.is_dir() else BASE)
    return layers, outside


MODULES = sorted(PACKAGE.rglob('*.py'))
IDS = [str(p.relative_to(PACKAGE)) for p in MODULES]
ALLOWED = allowed_imports()


def test_every_folder_of_the_package_is_a_layer_and_the_top_is_small():
    folders = {p.name for p in PACKAGE.iterdir() if p.is_dir() and p.name != '__pycache__'}
    assert folders == set(ALLOWED) - {BASE}  # each folder says what it may import
    top = list(PACKAGE.glob('*.py'))
    assert len(top) <= MAX_TOP_LEVEL_MODULES, sorted(p.name for p in top)


def test_layers_form_no_cycle():
    order, seen = [], set()

    def visit(layer, stack):
        assert layer not in stack, f'import cycle through {[*stack, layer]}'
        if layer in seen:
            return
        for other in sorted(ALLOWED[layer] - {layer}):
            visit(other, [*stack, layer])
        seen.add(layer)
        order.append(layer)

    for layer in sorted(ALLOWED):
        visit(layer, [])
    assert order[0] == BASE


@pytest.mark.parametrize('path', MODULES, ids=IDS)
def test_only_the_node_layer_imports_ros(path):
    ros = imported_layers(path)[1] & ROS_MODULES
    assert not ros or layer_of(path) in ROS_LAYERS, f'{path} imports {ros}'


@pytest.mark.parametrize('path', MODULES, ids=IDS)
def test_imports_flow_one_way(path):
    mine = layer_of(path)
    for other in imported_layers(path)[0]:
        assert other in ALLOWED[mine], f'{path} (layer {mine}) imports layer {other}'


@pytest.mark.parametrize('text, layers', [
    ('from ..core.estimator import TorqueEstimator\n', {'core'}),
    ('from ..node import torque_estimator\n', {'node'}),
    ('import rclpy\nfrom .. import errors\n', {BASE}),
])
def test_the_checker_sees_an_upward_import_in_physics(text, layers):
    found, _ = imported_layers(PACKAGE / 'physics' / 'kinematics.py', text)
    assert found == layers
    assert (found <= ALLOWED['physics']) == (layers == {BASE})


@pytest.mark.parametrize('path', MODULES, ids=IDS)
def test_no_long_module_without_a_reason_at_its_top(path):
    text = path.read_text()
    if text.count('\n') > 500:
        docstring = ast.get_docstring(ast.parse(text)) or ''
        assert 'Longer than 500 lines because' in docstring, f'{path}: split it or say why'


def test_the_architecture_page_shows_the_code_as_it_is():
    """docs/architecture.md embeds tools/architecture.py's output: regenerate it when it fails."""
    root = PACKAGE.parent
    spec = importlib.util.spec_from_file_location('architecture',
                                                  root / 'tools' / 'architecture.py')
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    page = (root / 'docs' / 'architecture.md').read_text()
    start, end = page.index(tool.BEGIN), page.index(tool.END) + len(tool.END)
    assert page[start:end] == tool.block(), 'run: python3 tools/architecture.py --write'
