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

"""Reading a YAML file (pump files, node parameters files) with one-line errors; writing one."""

from __future__ import annotations

import math
from pathlib import Path
import re
import sys
from typing import Any

import numpy as np
import yaml

from .errors import ConfigError
from .input_files import read_regular, YAML_LIMIT_BYTES

__all__ = ['SafeDumper', 'number_as_float', 'read_yaml']

_EXPONENT_FLOAT = re.compile(r'^[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[eE][-+]?[0-9]+$')
"""A plain number with an exponent and no dot (``1e-3``): a string to YAML 1.1, a double to
ROS 2 (`_Loader`)."""


def number_as_float(value: int | float) -> float:
    """
    Return a number read from a file as a float: an integer beyond float's range as +-inf.

    YAML reads a 400-digit integer exactly, and ``float()`` of it raises OverflowError;
    as +-inf it is refused by a range or finiteness check like any other number.

    Parameters
    ----------
    value : int or float
        The number.

    Returns
    -------
    float
        ``float(value)``, or +-inf where that would overflow.

    """
    if isinstance(value, int) and abs(value) > sys.float_info.max:
        return math.inf if value > 0 else -math.inf
    return float(value)


class _Loader(yaml.SafeLoader):
    """
    PyYAML's safe loader, reading a plain ``1e-3`` as a number, as ROS 2 does.

    PyYAML follows YAML 1.1, where a float needs a dot: ``1e-3`` is the string '1e-3'. ROS 2
    reads a parameters file with ``rcl_yaml_param_parser``, which takes any unquoted scalar
    that ``strtod`` reads whole as a double (``parse.c``, ``get_value``); so must this
    package, or a file that ``ros2 launch`` accepts is refused by ``pump_friction replay``.
    A quoted '1e-3' stays a string in both.
    """


_Loader.add_implicit_resolver('tag:yaml.org,2002:float', _EXPONENT_FLOAT,
                              list('-+0123456789.'))


class _UniqueKeys:
    """
    A loader mixin refusing a mapping that gives one key twice.

    PyYAML keeps the last of the two silently: in a pump file, a second ``film_clearance_m``
    pasted below the first changes the model with nothing said. Keys brought in by a merge
    (``<<``) may still be overridden, as YAML means them to be.
    """

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> Any:
        """Construct the mapping after checking that no key is given twice."""
        seen: set[Any] = set()
        for key_node, _ in node.value:
            if key_node.tag == 'tag:yaml.org,2002:merge':
                continue
            key = self.construct_object(key_node, deep=True)  # type: ignore[attr-defined]
            try:
                twice = key in seen
                seen.add(key)
            except TypeError:  # an unhashable key: PyYAML's own error below
                continue
            if twice:
                raise yaml.constructor.ConstructorError(
                    'while constructing a mapping', node.start_mark,
                    f'key {key!r} given twice (the second would silently win)',
                    key_node.start_mark)
        return super().construct_mapping(node, deep=deep)  # type: ignore[misc]


class _UniqueLoader(_UniqueKeys, _Loader):
    """`_Loader` (ROS 2's numbers) refusing a key given twice."""


class _UniqueSafeLoader(_UniqueKeys, yaml.SafeLoader):
    """PyYAML's safe loader refusing a key given twice."""


_LOADERS = {(True, True): _UniqueLoader, (True, False): _Loader,
            (False, True): _UniqueSafeLoader, (False, False): yaml.SafeLoader}
"""(ros_numbers, unique_keys) -> loader, every one safe: plain data, no objects."""


class SafeDumper(getattr(yaml, 'CSafeDumper', yaml.SafeDumper)):  # type: ignore[misc]
    """
    PyYAML's safe dumper (libyaml's where built), quoting a string that reads as ``1e-3``.

    The loader above reads such a plain scalar as a number; so a string of that form (a
    hardware id '1e5') is written quoted, and a file this package writes reads back as written.
    """


SafeDumper.add_implicit_resolver('tag:yaml.org,2002:float', _EXPONENT_FLOAT,
                                 list('-+0123456789.'))


def _numpy_scalar(dumper: yaml.SafeDumper, value: np.generic) -> yaml.Node:
    """Represent a numpy scalar as the plain number (or bool) it holds."""
    return dumper.represent_data(value.item())


def _text(dumper: yaml.SafeDumper, value: str) -> yaml.Node:
    """Represent a string; bytes of a file name that were not UTF-8 are written escaped."""
    try:
        value.encode('utf-8')
    except UnicodeEncodeError:  # lone surrogates: a bag found in a folder, named in Latin-1
        value = value.encode('utf-8', 'surrogateescape').decode('utf-8', 'backslashreplace')
    return dumper.represent_str(value)


SafeDumper.add_representer(str, _text)

# a numpy float is a subclass of float, but PyYAML's safe dumper matches types exactly and
# refuses it: a state with one in it (the monitor's, the isolation's sums) was not written
SafeDumper.add_multi_representer(np.generic, _numpy_scalar)


def read_yaml(path: Path, what: str, ros_numbers: bool = True,
              unique_keys: bool = True) -> Any:
    """
    Parse a YAML file safely; every failure is one `ConfigError` line naming the file.

    Parameters
    ----------
    path : Path
        The file.
    what : str
        What the file is, for the messages (``pump file``, ``parameters file``).
    ros_numbers : bool
        Read a plain ``1e-3`` as a number, as ROS 2 does (`_Loader`); False for a file only
        this package writes (a baseline file): PyYAML's own reading, as it was written.
    unique_keys : bool
        Refuse a key given twice in one mapping (`_UniqueKeys`); False for a ROS 2
        parameters file, where ``rcl_yaml_param_parser`` lets the later value overwrite the
        earlier (``parse.c``: "Overwriting, deallocate original"), as across files.

    Returns
    -------
    Any
        The parsed content (PyYAML's safe loader: plain data, no objects; a plain ``1e-3``
        a number, as ROS 2 reads it).

    Raises
    ------
    ConfigError
        The file is missing or unreadable (not a regular file: a named pipe, a device; or
        larger than `YAML_LIMIT_BYTES`), is not valid YAML (with the line and column), or
        holds a number of thousands of digits or nesting too deep to parse, or (with
        ``unique_keys``) gives a key twice.

    """
    try:
        text = read_regular(path, YAML_LIMIT_BYTES).decode('utf-8')
        return yaml.load(text, Loader=_LOADERS[ros_numbers, unique_keys])
    except FileNotFoundError:
        raise ConfigError(f'{what} not found: {path}') from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f'cannot read {what} {path}: '
                          f'{getattr(exc, "strerror", None) or exc}') from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        at = f' (line {mark.line + 1}, column {mark.column + 1})' if mark else ''
        problem = getattr(exc, 'problem', None)
        raise ConfigError(f'{path}: invalid YAML{at}' + (f': {problem}' if problem else '')) \
            from None
    except (ValueError, RecursionError):  # a number of thousands of digits, deep nesting
        raise ConfigError(f'{path}: invalid YAML: a number too long or nesting too deep') \
            from None
