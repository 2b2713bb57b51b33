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

"""Friction tables on disk: loading with checks, and the per-user cache of default tables."""

from __future__ import annotations

from collections.abc import Callable
import hashlib
import json
import math
import os
from pathlib import Path
import re

import numpy as np

from .friction_table import (
    _ARRAYS,
    _validate_arrays,
    build_table,
    FrictionTable,
    TABLE_FORMAT,
    TableSpec,
)
from .. import MODEL_VERSION
from ..errors import TableError
from ..input_files import open_regular
from ..physics.model import COMPONENTS
from ..physics.pump_parameters import PumpParams
from ..physics.units import m2_s_to_cst

__all__ = ['cache_dir', 'cached_table', 'cached_table_path', 'load_table']

# the metadata's numbers: must they be > 0 (True) or >= 0 (False)?
_NUMBERS = {'displacement_m3': True, 'zero_speed_threshold_rad_s': False,
            'efficiency_min_speed_rad_s': False, 'efficiency_min_pressure_pa': False,
            'default_viscosity_m2_s': True}


def load_table(path: str | Path, params: PumpParams | None = None) -> FrictionTable:
    """
    Load a table file, check every array, and (given ``params``) its provenance.

    Parameters
    ----------
    path : str or Path
        ``.npz`` file written by `FrictionTable.save`.
    params : PumpParams, optional
        The pump in use: the table is refused unless built from it.

    Returns
    -------
    FrictionTable
        The table.

    Raises
    ------
    TableError
        Missing or unreadable file, wrong arrays, or a pump / model mismatch.

    """
    path = Path(path)
    try:
        with open_regular(path) as handle, np.load(handle, allow_pickle=False) as data:
            missing = [name for name in _ARRAYS if name not in data.files]
            if missing:
                raise TableError(f'{path}: not a friction table (missing {", ".join(missing)})')
            arrays = {name: data[name] for name in _ARRAYS}
    except FileNotFoundError:
        raise TableError(f'table file not found: {path}') from None
    except TableError:
        raise
    except Exception as exc:  # zipfile.BadZipFile, ValueError, OSError, EOFError ...
        raise TableError(f'{path}: cannot read table ({type(exc).__name__}: {exc})') from None
    for name in _ARRAYS[:4]:
        if arrays[name].dtype != np.float64:
            raise TableError(f'{path}: {name} has dtype {arrays[name].dtype}, expected float64')
    meta = arrays['metadata']
    if meta.shape != () or meta.dtype.kind != 'U':
        raise TableError(f'{path}: metadata must be a JSON string')
    try:
        metadata = json.loads(str(meta))
    except json.JSONDecodeError as exc:
        raise TableError(f'{path}: metadata is not valid JSON ({exc})') from None
    if not isinstance(metadata, dict) or metadata.get('format') != TABLE_FORMAT \
            or metadata.get('components') != list(COMPONENTS):
        raise TableError(f'{path}: unsupported table format or components')
    needed = ('pump_sha256', 'model_version', *_NUMBERS)
    absent = [k for k in needed if k not in metadata]
    if absent:
        raise TableError(f'{path}: metadata lacks {", ".join(absent)}')
    for key, positive in _NUMBERS.items():
        value = metadata[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
                math.isfinite(value) and (value > 0.0 if positive else value >= 0.0)):
            raise TableError(f'{path}: metadata {key}: expected a finite number '
                             f'{"> 0" if positive else ">= 0"}, got {value!r}')
    _validate_arrays(arrays['speed_axis_rad_s'], arrays['pressure_axis_pa'],
                     arrays['viscosity_axis_m2_s'], arrays['torque_nm'], str(path))
    metadata['source'] = str(path)
    table = FrictionTable(arrays['speed_axis_rad_s'], arrays['pressure_axis_pa'],
                          arrays['viscosity_axis_m2_s'], arrays['torque_nm'], metadata)
    if params is not None:
        table.check_matches(params)
    return table


def cache_dir() -> Path:
    """
    Folder of tables built on first use: ``$XDG_CACHE_HOME/pump_friction_ros``.

    Returns
    -------
    Path
        The cache folder (``~/.cache/pump_friction_ros`` by default).

    """
    root = os.environ.get('XDG_CACHE_HOME') or Path.home() / '.cache'
    return Path(root) / 'pump_friction_ros'


def cached_table_path(params: PumpParams, spec: TableSpec | None = None) -> Path:
    """
    Return where the table of ``params`` on the grid ``spec`` is cached.

    The file name holds the pump name, its parameter hash, the viscosity axis' ends, a hash
    of the whole grid and the model version, so a changed pump file, another oil or a new
    model never meets a stale table.

    Parameters
    ----------
    params : PumpParams
        The pump.
    spec : TableSpec, optional
        The grid (default `TableSpec()`); the node's covers its oil (``core.oil_range``).

    Returns
    -------
    Path
        ``<cache dir>/<name>-<hash>-nu<low>-<high>cSt-s<grid hash>-m<model version>.npz``,
        the name made a plain file-name part (`_file_safe`).

    """
    spec = spec or TableSpec()
    key = hashlib.sha256(repr(spec).encode()).hexdigest()[:8]
    low, high = m2_s_to_cst(spec.min_viscosity_m2_s), m2_s_to_cst(spec.max_viscosity_m2_s)
    return cache_dir() / (f'{_file_safe(params.name)}-{params.sha256[:16]}-nu{low:.3g}-'
                          f'{high:.4g}cSt-s{key}-m{MODEL_VERSION}.npz')


def _file_safe(name: str) -> str:
    """
    Return a pump name as one plain file-name part: ``/abs/x`` or ``../..`` stays in the cache.

    Letters, digits, ``.``, ``_`` and ``-`` are kept, anything else (a slash, a space, a
    byte of another encoding) is ``_``, leading dots dropped, at most 64 characters; the
    parameter hash beside it tells pumps apart.

    """
    return re.sub(r'[^A-Za-z0-9._-]', '_', name).lstrip('.')[:64] or 'pump'


def cached_table(params: PumpParams, progress: Callable[[float], None] | None = None,
                 spec: TableSpec | None = None) -> FrictionTable:
    """
    Return the table of ``params`` on the grid ``spec``: from the cache, or built and cached.

    The cache file is `cached_table_path`'s, so a changed pump file, oil or model never meets
    a stale table; an entry whose axes are not the grid's is rebuilt.

    Parameters
    ----------
    params : PumpParams
        The pump.
    progress : callable, optional
        Build progress callback (fraction done), used only when building.
    spec : TableSpec, optional
        The grid (default `TableSpec()`: 10-100 cSt).

    Returns
    -------
    FrictionTable
        The table.

    """
    spec = spec or TableSpec()
    path = cached_table_path(params, spec)
    if path.exists():
        try:
            table = load_table(path, params)
            if all(np.array_equal(a, b) for a, b in zip(
                    (table.speed_axis_rad_s, table.pressure_axis_pa, table.viscosity_axis_m2_s),
                    spec.axes(params), strict=True)):
                return table
        except TableError:
            pass  # corrupt or foreign cache entry: rebuild it below
    table = build_table(params, spec, progress=progress)
    table.metadata['source'] = str(path)
    try:
        table.save(path)
    except OSError:
        pass  # read-only home: the table still works, it is just not cached
    return table
