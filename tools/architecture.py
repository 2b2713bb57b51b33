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
Print the package's layers as the code draws them: a Mermaid graph and the modules per layer.

    python3 tools/architecture.py            # the block docs/architecture.md embeds
    python3 tools/architecture.py --write    # replace that block in the page

Layers are the folders of ``pump_friction_ros`` (``base``: the modules directly in it);
an arrow A --> B means some module of A imports one of B, labelled with how many import
statements do. Nothing is kept by hand: test_architecture.py checks the page against this.
"""

import ast
from collections import Counter
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / 'pump_friction_ros'
BASE = 'base'
BEGIN, END = '<!-- architecture:begin -->', '<!-- architecture:end -->'


def layer_of(path):
    """Return a module's layer: its folder under the package, or ``base``."""
    parts = path.relative_to(PACKAGE).parts
    return parts[0] if len(parts) > 1 else BASE


def edges():
    """Count import statements from one layer into another (relative imports only)."""
    count = Counter()
    for path in sorted(PACKAGE.rglob('*.py')):
        parts = list(path.relative_to(PACKAGE).with_suffix('').parts)
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level:
                target = parts[:len(parts) - node.level] + (node.module or '').split('.')
                target = [t for t in target if t]
                other = target[0] if target and (PACKAGE / target[0]).is_dir() else BASE
                if other != layer_of(path):
                    count[layer_of(path), other] += 1
    return count


def modules():
    """Return the module names of each layer."""
    found = {}
    for path in sorted(PACKAGE.rglob('*.py')):
        if path.name not in ('__init__.py', '__main__.py'):
            found.setdefault(layer_of(path), []).append(path.stem)
    return found


def block():
    """Return the Markdown block: the graph, then a table of the modules per layer."""
    lines = [BEGIN, '```mermaid', 'graph TD']
    for (a, b), n in sorted(edges().items()):
        lines.append(f'  {a} -->|{n}| {b}')
    lines += ['```', '', '| layer | modules |', '| --- | --- |']
    mods = modules()
    order = sorted(mods, key=lambda layer: (layer != BASE, layer))
    for layer in order:
        lines.append(f'| `{layer}` | ' + ', '.join(f'`{m}`' for m in mods[layer]) + ' |')
    lines.append(END)
    return '\n'.join(lines)


def write(page=PACKAGE.parent / 'docs' / 'architecture.md'):
    """Replace the block between the markers of ``page`` with the current one."""
    text = page.read_text()
    start, end = text.index(BEGIN), text.index(END) + len(END)
    page.write_text(text[:start] + block() + text[end:])


if __name__ == '__main__':
    import sys

    if sys.argv[1:] == ['--write']:
        write()
    else:
        print(block())
