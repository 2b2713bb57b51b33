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
The node's command line checked as the replay checks its parameters files.

rcl merges several ``--params-file`` s parameter by parameter; where a later file gives a
parameter a value of another type than an earlier one (``output_decimation: 20.0`` over
``10``), the merged override keeps the earlier value and the node started on it without a
word (measured on Jazzy's rclpy: ``test_node_rclpy.py``). A misspelt name (``joint_nam``) is
an override that no declared parameter takes, which rclpy ignores. `check_command_line`
reads every parameters file on the command line the way `load_estimator_config` does and
refuses both, in one line naming the file, its section and the parameter.

Which sections apply follows rclcpp's and rclpy's wildcard matching of a section's node name
against the node's fully qualified name (``/*`` one namespace token, ``/**`` any number; a
name without the leading slash is taken from the root). A section that names this node
(its last token is the node's name, not a wildcard) is checked for unknown names and types;
a wildcard section (``/**``, ``/eha1/*``) is shared with other nodes, so only the
estimator's parameters in it are checked, for their types.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path
import re
from typing import Any

from .node_parameters import checked_values, PARAMETERS, ROS_PARAMETERS
from ..errors import ConfigError, quote
from ..yaml_files import read_yaml

__all__ = ['check_command_line', 'parameter_sources', 'section_applies']

_WITH_VALUE = frozenset({'-r', '--remap', '--log-level', '-e', '--enclave',
                         '--log-config-file'})
"""``--ros-args`` options that take a value (skipped with it)."""

_OWN = frozenset(spec.name for spec in PARAMETERS)


def parameter_sources(args: Sequence[str]) -> tuple[list[str], list[str]]:
    """
    Return the ``--params-file`` files and ``-p`` rules of a command line's ROS arguments.

    Parameters
    ----------
    args : sequence of str
        The command line (``sys.argv``; only what stands in ``--ros-args ... [--]`` blocks
        counts, as for rcl).

    Returns
    -------
    tuple of two lists of str
        The files in the order given, and the ``name:=value`` rules of ``-p`` /
        ``--param``.

    """
    files: list[str] = []
    rules: list[str] = []
    inside, expect = False, ''
    for arg in args:
        if expect:
            if expect == 'file':
                files.append(arg)
            elif expect == 'rule':
                rules.append(arg)
            expect = ''
        elif arg == '--ros-args':
            inside = True
        elif not inside:
            continue
        elif arg == '--':
            inside = False
        elif arg == '--params-file':
            expect = 'file'
        elif arg in ('-p', '--param'):
            expect = 'rule'
        elif arg in _WITH_VALUE:
            expect = 'skip'
    return files, rules


def section_applies(section: str, node_fqn: str) -> bool:
    """
    Say whether a parameters file's section (its node name) applies to a node.

    Parameters
    ----------
    section : str
        The section's key: ``/**``, ``torque_estimator``, ``/eha1/*``, ...
    node_fqn : str
        The node's fully qualified name (``/eha1/torque_estimator``).

    Returns
    -------
    bool
        True where rclpy would give the node the section's parameters.

    """
    name = section if section.startswith('/') else f'/{section}'
    pattern = ''.join('(/\\w+)*' if token == '/**' else '/\\w+' if token == '/*'
                      else re.escape(token) for token in re.split(r'(/\*\*|/\*)', name))
    return re.fullmatch(pattern, node_fqn) is not None


def _flat(values: dict[str, Any], prefix: str = '') -> Iterator[tuple[str, Any]]:
    """Yield nested parameter names as rcl flattens them (``a: {b: 1}`` is ``a.b``)."""
    for key, value in values.items():
        if isinstance(value, dict):
            yield from _flat(value, f'{prefix}{key}.')
        else:
            yield f'{prefix}{key}', value


def check_command_line(args: Sequence[str], node_fqn: str) -> None:
    """
    Refuse what rclpy would drop or ignore silently in the node's parameter sources.

    Parameters
    ----------
    args : sequence of str
        The node's command line (``sys.argv`` or the arguments given to ``rclpy.init``).
    node_fqn : str
        The node's fully qualified name, after any ``__node`` / ``__ns`` remapping.

    Raises
    ------
    ConfigError
        A parameter of another type than the estimator declares it, out of its range, or
        (in a section or ``-p`` rule naming this node) a name the estimator does not
        have: one line naming the file and section, or the rule.

    """
    files, rules = parameter_sources(args)
    basename = node_fqn.rsplit('/', 1)[-1]
    for path in map(Path, files):
        data = read_yaml(path, 'parameters file', unique_keys=False)
        if not isinstance(data, dict):
            continue  # rcl has refused it already (rclpy.init)
        for section, body in data.items():
            if not section_applies(str(section), node_fqn) or not isinstance(body, dict):
                continue
            values = body.get('ros__parameters')
            if not isinstance(values, dict):
                continue
            flat = dict(_flat(values))
            if str(section).rsplit('/', 1)[-1] in ('*', '**'):  # shared with other nodes
                flat = {name: value for name, value in flat.items() if name in _OWN}
            checked_values(flat, f'{path}: {section}: ', ros_types=True)
    for rule in rules:
        name, _, _value = rule.partition(':=')
        node, _, name = name.rpartition(':')
        if node not in ('', basename):
            continue
        if name not in _OWN | ROS_PARAMETERS:
            raise ConfigError(f'-p {rule}: unknown parameter {quote(name)}')
