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
Where files named by parameters and flags are: package folders, shipped pump sets, paths.

A file parameter (``pump_file``, ``table_file``) or flag (``--pump``) may be

* a path: absolute, ``~/...``, or relative to the current directory. A relative path in a
  params file resolves against the current directory, not the params file's folder: the
  node does so too, for it never learns which file a value came from (``ros2 run`` and
  ``ros2 launch`` merge them before it starts);
* ``package://pump_friction_ros/<path in the package>``, as ROS users write it, found in
  the package's share folder (a colcon or pip install) or source checkout, without ROS;
  another package's share folder is found through ament_index when ROS is sourced;
* for a pump file only: the name of a shipped pump set (``hong_doh_2004_consistent``),
  i.e. ``config/pumps/<name>.yaml`` of this package.

An error names the parameter, where the value came from and the directory a relative path
was resolved against.
"""

from __future__ import annotations

import os
from pathlib import Path
import sys

from .errors import ConfigError, quote

__all__ = ['PACKAGE', 'config_dir', 'created_file_mode', 'default_pump_file',
           'package_share_dir', 'resolve_path', 'shipped_pump_sets']

PACKAGE = 'pump_friction_ros'
_SCHEME = 'package://'


def config_dir() -> Path:
    """
    Locate the package's ``config`` folder (source checkout, pip or colcon install).

    Returns
    -------
    Path
        The folder holding ``torque_estimator.yaml`` and ``pumps/``.

    """
    here = Path(__file__).resolve().parent
    candidates = [here.parent / 'config']
    candidates.append(Path(sys.prefix) / 'share' / PACKAGE / 'config')
    try:  # a colcon / ament install
        from ament_index_python.packages import get_package_share_directory
        candidates.append(Path(get_package_share_directory(PACKAGE)) / 'config')
    except Exception:  # ament_index missing, or the package is not in the index
        pass
    for candidate in candidates:
        if (candidate / 'pumps').is_dir():
            return candidate
    raise ConfigError(f'cannot find the {PACKAGE} config folder; pass --pump FILE')


def package_share_dir(package: str = PACKAGE) -> Path:
    """
    Return a package's share folder, as ``package://<package>/`` means it.

    Parameters
    ----------
    package : str
        Package name; this package's is found without ROS (the folder holding ``config``).

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    ConfigError
        Another package, and ament_index cannot find it (or ROS is not sourced).

    """
    if package == PACKAGE:
        return config_dir().parent
    try:
        from ament_index_python.packages import get_package_share_directory
        return Path(get_package_share_directory(package))
    except Exception:
        raise ConfigError(f'package://{package}: package not found (only {PACKAGE} is found '
                          'without a sourced ROS 2 install)') from None


def default_pump_file() -> Path:
    """
    Path of the default pump parameter file (the paper's pump).

    Returns
    -------
    Path
        ``config/pumps/hong_doh_2004.yaml``.

    """
    return config_dir() / 'pumps' / 'hong_doh_2004.yaml'


def shipped_pump_sets() -> list[str]:
    """
    Return the names of the pump sets shipped in ``config/pumps``.

    Returns
    -------
    list of str
        File stems, sorted (``hong_doh_2004``, ``hong_doh_2004_consistent``).

    """
    return sorted(p.stem for p in (config_dir() / 'pumps').glob('*.yaml'))


def _is_set_name(text: str) -> bool:
    return bool(text) and '/' not in text and os.sep not in text and \
        not text.endswith(('.yaml', '.yml', '.npz')) and not text.startswith(('.', '~'))


def resolve_path(value: str | Path, what: str, *, origin: str = '', pump_set: bool = False,
                 must_exist: bool = True, cwd: Path | None = None) -> Path:
    """
    Resolve a file parameter or flag to an absolute path (see the module docstring).

    Parameters
    ----------
    value : str or Path
        As given.
    what : str
        The parameter or flag, for messages (``pump_file``, ``--pump``).
    origin : str
        Where the value came from, for messages (``params file /x/p.yaml``).
    pump_set : bool
        A bare name (no ``/``, no ``.yaml``) names a shipped pump set.
    must_exist : bool
        Raise when the file does not exist.
    cwd : Path, optional
        Directory of relative paths (default: the current directory).

    Returns
    -------
    Path
        Absolute path.

    Raises
    ------
    ConfigError
        An unknown package or pump set, or (``must_exist``) a missing file; the message
        names the parameter, its origin and the directory a relative path resolved against.

    """
    text = str(value)
    source = f' (from {origin})' if origin else ''
    if text.startswith(_SCHEME):
        package, _, inner = text[len(_SCHEME):].partition('/')
        if not package or not inner:
            raise ConfigError(f'{what} {quote(text)}{source}: expected '
                              f'package://<package>/<path>')
        try:
            path = package_share_dir(package) / inner
        except ConfigError as exc:
            raise ConfigError(f'{what} {quote(text)}{source}: {exc}') from None
        how = f'in the share folder of {package}'
    elif pump_set and _is_set_name(text):
        path = config_dir() / 'pumps' / f'{text}.yaml'
        if not path.is_file():
            raise ConfigError(f'{what} {quote(text)}{source}: no such shipped pump set; '
                              f'shipped: {", ".join(shipped_pump_sets())} (or give a path)')
        return path
    else:
        path = Path(text).expanduser()
        base = Path.cwd() if cwd is None else cwd
        how = 'absolute' if path.is_absolute() else \
            f'relative, resolved against the current directory {base}'
        path = path if path.is_absolute() else base / path
    path = Path(os.path.normpath(path))
    if must_exist and not path.is_file():
        state = 'is not a file' if path.exists() else 'not found'
        hint = ''
        if origin and how.startswith('relative'):
            hint = ('; a relative path in a params file resolves against the current '
                    "directory, as the node's do: give an absolute path, a package:// path"
                    + (f' or a shipped pump set ({", ".join(shipped_pump_sets())})'
                       if pump_set else ''))
        raise ConfigError(f'{what} {quote(text)}{source} {state}: {path} ({how}){hint}')
    return path


def created_file_mode() -> int:
    """
    Return the permissions an ``open()`` would give a new file: 0o666 less the umask.

    ``tempfile.mkstemp`` makes its file 0o600; a file written through one (a baseline, a
    table) is given these instead, so that the node's user can read a baseline that the
    maintenance user learnt, as it could a file copied there.

    Returns
    -------
    int
        The mode bits.

    """
    try:  # Linux: read, never set (os.umask would change it for every thread a moment)
        with open('/proc/self/status', encoding='ascii') as status:
            for line in status:
                if line.startswith('Umask:'):
                    return 0o666 & ~int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask
