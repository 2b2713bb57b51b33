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
Calibration data: steady bench points from CSV files and bag samples as the replay reads them.

Everything is converted to SI at this edge; `Samples` is what the fit consumes.
"""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..core.inputs import TEMPERATURE_RANGE_C
from ..core.node_parameters import EstimatorConfig, PARAMETERS
from ..errors import CalibrationError, quote
from ..input_files import open_regular
from ..physics.oil import WaltherViscosity
from ..physics.units import BAR_TO_PA, cst_to_m2_s, m2_s_to_cst, RPM_TO_RAD_S
from ..table.friction_table import FrictionTable

__all__ = ['BAG_COLUMNS', 'MIN_SPEED_RAD_S', 'Samples', 'bag_estimates', 'load_bag_samples',
           'load_bench_csv', 'merge_samples', 'timeline_samples']

MIN_SPEED_RAD_S = 10.0  # below: stick-slip, the paper's model does not claim to hold
BAG_COLUMNS = ('speed_rad_s', 'pressure_diff_pa', 'viscosity_m2_s', 'measured_nm',
               'accel_rad_s2', 'stamp_ns')
"""Estimate fields a bag contributes, one array each (see `bag_estimates`)."""

# the top of the node's range of oil_viscosity_m2_s: a bench oil beyond it is a mistake
_MOST_VISCOSITY_M2_S = next(p.high for p in PARAMETERS
                            if p.name == 'oil_viscosity_m2_s') or math.inf


@dataclasses.dataclass
class Samples:
    """
    Calibration data in SI units.

    Attributes
    ----------
    speed : ndarray
        Shaft speed [rad/s].
    dp : ndarray
        Pressure difference [Pa].
    viscosity : ndarray
        Oil kinematic viscosity [m^2/s].
    torque : ndarray
        Measured input torque [N m].
    accel : ndarray
        Filtered shaft acceleration [rad/s^2]; 0 for bench points.
    block : ndarray
        Order of the samples for contiguous cross-validation folds: time [ns] for bags,
        file order for bench points.
    is_bag : bool
        The samples come from bags.
    selection : str
        Which samples were kept, for the report.
    inputs : list of dict
        Provenance of each input file (path, kind, sha256, samples).
    timeline : list of dict
        Bags: every sample with a measured torque, per input (`BAG_COLUMNS` arrays).

    """

    speed: np.ndarray
    dp: np.ndarray
    viscosity: np.ndarray
    torque: np.ndarray
    accel: np.ndarray
    block: np.ndarray
    is_bag: bool
    selection: str
    inputs: list[dict[str, Any]] = dataclasses.field(default_factory=list)
    timeline: list[dict[str, Any]] = dataclasses.field(default_factory=list)

    def subset(self, keep: np.ndarray) -> Samples:
        """
        Return the samples where ``keep`` is true (provenance and timeline unchanged).

        Parameters
        ----------
        keep : ndarray of bool
            Mask over the samples.

        Returns
        -------
        Samples
            The kept samples.

        """
        return dataclasses.replace(self, speed=self.speed[keep], dp=self.dp[keep],
                                   viscosity=self.viscosity[keep], torque=self.torque[keep],
                                   accel=self.accel[keep], block=self.block[keep])


def _sha256_of(path: Path) -> str:
    digest = hashlib.sha256()
    files = [path] if path.is_file() else sorted(p for p in path.rglob('*') if p.is_file())
    for item in files:
        digest.update(item.name.encode())
        with open(item, 'rb') as handle:
            for block in iter(lambda: handle.read(1 << 20), b''):
                digest.update(block)
    return digest.hexdigest()


def load_bench_csv(path: str | Path, oil: WaltherViscosity, default_viscosity_m2_s: float
                   ) -> Samples:
    """
    Read steady-state bench points.

    Columns: ``speed_rpm``, ``pressure_bar``, ``torque_nm`` and optionally
    ``viscosity_cst`` or ``temperature_c`` (else the pump's oil viscosity).

    Parameters
    ----------
    path : str or Path
        CSV file with a header row.
    oil : WaltherViscosity
        Viscosity law for a ``temperature_c`` column.
    default_viscosity_m2_s : float
        Viscosity without such a column [m^2/s].

    Returns
    -------
    Samples
        The points in SI units.

    Raises
    ------
    CalibrationError
        Missing file or column, a non-number or NaN, values in the wrong unit.

    """
    path = Path(path)
    try:
        with open_regular(path) as handle:  # a named pipe would block, /dev/zero fill memory
            text = handle.read().decode('utf-8')
    except (OSError, UnicodeDecodeError) as exc:
        raise CalibrationError(f'cannot read {path}: '
                               f'{getattr(exc, "strerror", None) or exc}') from None
    lines = text.splitlines()
    rows = list(csv.DictReader(lines))
    needed = ('speed_rpm', 'pressure_bar', 'torque_nm')
    header = next(csv.reader(lines[:1]), [])
    missing = [c for c in needed if c not in header]
    if missing:
        raise CalibrationError(f'{path}: missing column(s) {", ".join(missing)} (header: '
                               f'{", ".join(header) or "none"})')
    extra = [c for c in ('viscosity_cst', 'temperature_c') if c in header]
    if len(extra) > 1:
        raise CalibrationError(f'{path}: give viscosity_cst or temperature_c, not both')
    columns = [*needed, *extra]
    values = np.empty((len(rows), len(columns)))
    for i, row in enumerate(rows, start=2):
        for j, name in enumerate(columns):
            try:
                values[i - 2, j] = float(row[name])
            except (TypeError, ValueError) as exc:
                raise CalibrationError(f'{path}:{i}: {name} is not a number: '
                                       f'{quote(row[name])}') from exc
            if not math.isfinite(values[i - 2, j]):
                raise CalibrationError(f'{path}:{i}: {name} is not finite: '
                                       f'{quote(row[name])}')
    if not len(rows):
        raise CalibrationError(f'{path}: no data rows')
    column = dict(zip(columns, values.T, strict=True))
    speed_rpm, bar, torque = column['speed_rpm'], column['pressure_bar'], column['torque_nm']
    if np.abs(bar).max() > 1000.0:
        raise CalibrationError(f'{path}: pressure_bar reaches {np.abs(bar).max():g}: that '
                               'looks like Pa or psi, the column is in bar')
    if np.abs(speed_rpm).max() > 60000.0:
        raise CalibrationError(f'{path}: speed_rpm reaches {np.abs(speed_rpm).max():g}: the '
                               'column is in rpm')
    if np.abs(torque).max() > 1000.0:
        raise CalibrationError(f'{path}: torque_nm reaches {np.abs(torque).max():g} N m: '
                               'the column is in N m')
    viscosity = np.full(len(rows), default_viscosity_m2_s)
    if extra == ['viscosity_cst']:
        cst = column['viscosity_cst']
        if cst.min() < 0.5:
            raise CalibrationError(f'{path}: viscosity_cst down to {cst.min():g}: that looks '
                                   'like m^2/s, the column is in cSt')
        viscosity = cst_to_m2_s(cst)
        if viscosity.max() > _MOST_VISCOSITY_M2_S:
            raise CalibrationError(f'{path}: viscosity_cst up to {cst.max():g}: above '
                                   f'{m2_s_to_cst(_MOST_VISCOSITY_M2_S):g} cSt, the most '
                                   'the node takes (oil_viscosity_m2_s)')
    elif extra == ['temperature_c']:
        temp = column['temperature_c']
        low, high = TEMPERATURE_RANGE_C  # the estimator's plausible oil temperatures
        if temp.max() > high or temp.min() < low:
            raise CalibrationError(f'{path}: temperature_c outside {low:g}..{high:g} degC '
                                   '(kelvin?)')
        viscosity = np.array([oil(t) for t in temp])
        if viscosity.max() > _MOST_VISCOSITY_M2_S:
            raise CalibrationError(f'{path}: temperature_c down to {temp.min():g} degC: the '
                                   f'oil is {m2_s_to_cst(viscosity.max()):.0f} cSt there, above '
                                   f'the {m2_s_to_cst(_MOST_VISCOSITY_M2_S):g} cSt the node '
                                   'takes (oil_viscosity_m2_s)')
    n = len(rows)
    return Samples(speed=speed_rpm * RPM_TO_RAD_S, dp=bar * BAR_TO_PA, viscosity=viscosity,
                   torque=torque, accel=np.zeros(n), block=np.arange(n), is_bag=False,
                   selection='steady bench points',
                   inputs=[{'path': str(path), 'kind': 'csv', 'sha256': _sha256_of(path),
                            'samples': n}])


def bag_estimates(path: str | Path, config: EstimatorConfig, table: FrictionTable,
                  default_viscosity_m2_s: float, remaps: dict[str, str] | None
                  ) -> dict[str, np.ndarray]:
    """
    Replay a bag through the estimator core and return its estimates as columns.

    The only place calibration reads a bag: same reader, parameters, core and stamps as
    ``pump_friction replay``.

    Parameters
    ----------
    path : str or Path
        Bag directory.
    config : EstimatorConfig
        Node parameters (topics, filter, thresholds).
    table : FrictionTable
        Table of the base pump.
    default_viscosity_m2_s : float
        The base pump's oil viscosity [m^2/s].
    remaps : dict, optional
        Topic remappings.

    Returns
    -------
    dict of str to ndarray
        One array per name of `BAG_COLUMNS`, in SI units (``stamp_ns`` [ns]).

    """
    from ..bags.replay import bag_estimates
    from ..core.estimator import TorqueEstimator

    core = TorqueEstimator(config, table, default_viscosity_m2_s, 'calibration')
    columns: dict[str, list[float]] = {name: [] for name in BAG_COLUMNS}
    for estimate in bag_estimates(path, config, core, remaps):
        for name in BAG_COLUMNS:
            columns[name].append(getattr(estimate, name))
    return {name: np.array(values, dtype=float) for name, values in columns.items()}


def load_bag_samples(path: str | Path, config: EstimatorConfig, table: FrictionTable,
                     default_viscosity_m2_s: float, remaps: dict[str, str] | None,
                     steady_only: bool = True) -> Samples:
    """
    Read a bag's samples as the replay reads it (same reader, same core, same stamps).

    Parameters
    ----------
    path : str or Path
        Bag directory.
    config : EstimatorConfig
        Node parameters (topics, filter, thresholds).
    table : FrictionTable
        Table of the base pump.
    default_viscosity_m2_s : float
        The base pump's oil viscosity [m^2/s].
    remaps : dict, optional
        Topic remappings.
    steady_only : bool
        Keep only near-steady samples (|accel| below ``monitor_max_accel_rad_s2`` for five
        filter time constants either side); the whole record is kept in ``timeline``.

    Returns
    -------
    Samples
        Samples with a measured torque above ``MIN_SPEED_RAD_S`` [rad/s].

    """
    get = bag_estimates(path, config, table, default_viscosity_m2_s, remaps)
    measured = np.isfinite(get['measured_nm'])
    keep = measured & (np.abs(get['speed_rad_s']) >= MIN_SPEED_RAD_S)
    if steady_only:
        # offline, look both ways: steady for 5 filter time constants before and after, so
        # that the filter's lag at the start and end of a ramp does not let transients in
        from scipy.ndimage import minimum_filter1d

        steady = np.abs(get['accel_rad_s2']) <= config.monitor_max_accel_rad_s2
        stamps = get['stamp_ns']
        step_s = float(np.median(np.diff(stamps))) * 1e-9 if stamps.size > 1 else 1e-3
        half = max(1, round(5.0 * config.accel_filter_time_constant_s / step_s))
        keep &= minimum_filter1d(steady.astype(np.uint8), 2 * half + 1).astype(bool)
    t = get['stamp_ns'][keep]
    return Samples(speed=get['speed_rad_s'][keep], dp=get['pressure_diff_pa'][keep],
                   viscosity=get['viscosity_m2_s'][keep], torque=get['measured_nm'][keep],
                   accel=get['accel_rad_s2'][keep],
                   block=(t - t.min()) if t.size else t, is_bag=True,
                   selection=('friction and drive loss from near-steady samples (|accel| <= '
                              f'{config.monitor_max_accel_rad_s2:g} rad/s^2 for +-5 filter time '
                              'constants); rotor inertia from the whole record'
                              if steady_only else 'whole record'),
                   inputs=[{'path': str(path), 'kind': 'bag', 'sha256': _sha256_of(Path(path)),
                            'samples': int(keep.sum())}],
                   timeline=[{k: v[measured] for k, v in get.items()}])


def timeline_samples(samples: Samples) -> list[Samples]:
    """
    Return each bag's whole record as `Samples`, ``block`` holding the stamps.

    Parameters
    ----------
    samples : Samples
        Samples read by `load_bag_samples` (merged or not).

    Returns
    -------
    list of Samples
        One per input bag, every sample with a measured torque; ``block`` [ns].

    """
    return [Samples(record['speed_rad_s'], record['pressure_diff_pa'], record['viscosity_m2_s'],
                    record['measured_nm'], record['accel_rad_s2'], record['stamp_ns'], True, '')
            for record in samples.timeline]


def merge_samples(parts: list[Samples]) -> Samples:
    """
    Concatenate the samples of several inputs, later inputs after earlier ones in time.

    Parameters
    ----------
    parts : list of Samples
        Samples of each input, all bags or all bench files.

    Returns
    -------
    Samples
        All samples, ``block`` offset so that the folds stay contiguous per input.

    Raises
    ------
    CalibrationError
        Bags and bench CSV files mixed.

    """
    if len({p.is_bag for p in parts}) > 1:
        raise CalibrationError('give either bags or bench CSV files, not both')
    offset = 0
    blocks = []
    for p in parts:
        blocks.append(p.block + offset)
        offset += (p.block.max() + 1) if p.block.size else 0
    speed, dp, viscosity, torque, accel = (np.concatenate([getattr(p, f) for p in parts])
                                           for f in ('speed', 'dp', 'viscosity', 'torque',
                                                     'accel'))
    return Samples(speed, dp, viscosity, torque, accel, block=np.concatenate(blocks),
                   is_bag=parts[0].is_bag, selection=parts[0].selection,
                   inputs=[i for p in parts for i in p.inputs],
                   timeline=[t for p in parts for t in p.timeline])
