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
Calibration run: read the inputs, fit, check, write the pump file and the report.

Bags: friction and drive loss are fitted on near-steady samples (the speed derivative's
filter lag biases the rest), the rotor inertia on the whole record through the same filter
(see `fit_inertia`). The "after" errors come from the full model of the fitted pump (bench
points) or its rebuilt table (bags), not from the linear fit.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from .data import load_bag_samples, load_bench_csv, merge_samples, MIN_SPEED_RAD_S
from .fit import (
    cross_validate,
    fit_inertia,
    FIT_PARAMETERS,
    fitted_pump,
    INDEX,
    NAMES,
    predict,
    regressors,
    rms,
    upper_bounds,
)
from .identifiability import fit_identifiable
from .report import (
    CalibrationResult,
    ParameterReport,
    round_trip_yaml,
    write_pump_file,
    write_report,
)
from ..core.node_parameters import EstimatorConfig
from ..errors import CalibrationError
from ..paths import resolve_path
from ..physics.model import theoretical_torque_nm
from ..physics.oil import WaltherViscosity
from ..physics.pump_parameters import load_pump
from ..staging import refuse_at_inputs, Staged, StagedOutputs
from ..table.friction_table import build_table

__all__ = ['calibrate']

INERTIA = INDEX['rotor_inertia_kg_m2']
DRIVE_LOSS = INDEX['drive_loss_torque_nm']


def calibrate(inputs: list[str | Path], base_file: str | Path, out_file: str | Path | None,
              *, report_dir: str | Path | None = None, fix: list[str] | None = None,
              config: EstimatorConfig | None = None, remaps: dict[str, str] | None = None,
              steady_only: bool = True, force: bool = False) -> CalibrationResult:
    """
    Fit the open friction parameters of ``base_file`` to the inputs; write the pump file.

    Parameters
    ----------
    inputs : list of str or Path
        Bench CSV files or rosbag2 bags (not mixed).
    base_file : str or Path
        Base pump parameter YAML.
    out_file : str or Path, optional
        Calibrated pump YAML to write (atomically; nothing on error).
    report_dir : str or Path, optional
        Folder for report.json and PNG plots.
    fix : list of str, optional
        Parameters held at their base values (names of `FIT_PARAMETERS`).
    config : EstimatorConfig, optional
        Node parameters (bags: topics and filter; inertia and drive loss start values; oil).
    remaps : dict, optional
        Topic remappings for bags.
    steady_only : bool
        Bags: fit friction and drive loss on near-steady samples only (default; the
        derivative filter's lag biases the rest) and the rotor inertia on the whole record.
    force : bool
        Replace an existing output file and report.

    Returns
    -------
    CalibrationResult
        The fit and its checks.

    Raises
    ------
    CalibrationError
        Unusable input or arguments, or ruamel.yaml missing for the output; no output is
        written.
    OutputError
        An output exists (without ``force``) or cannot be made; checked before the fit.

    """
    config = config or EstimatorConfig()
    fix = list(fix or [])
    unknown = [f for f in fix if f not in NAMES]
    if unknown:
        raise CalibrationError(f'--fix: unknown parameter(s) {", ".join(unknown)}; choose '
                               f'from {", ".join(NAMES)}')
    if not inputs:
        raise CalibrationError('no input given')
    if out_file is not None:
        round_trip_yaml()  # fail before the fit, not after it
    # every output location is checked and made before anything is computed or written
    for flag, target in (('--out', out_file), ('--report', report_dir)):
        if target is not None:  # --force would replace the data, or a folder holding it
            refuse_at_inputs(flag, target, inputs)
    staged = StagedOutputs()
    try:
        pump_out = None if out_file is None else staged.add(out_file, force, False,
                                                            flag='--out')
        report_out = None if report_dir is None else staged.add(
            report_dir, force, True, looks_like=lambda p: (p / 'report.json').is_file(),
            flag='--report')
        result = _calibrate(inputs, base_file, pump_out, report_out, fix, config, remaps,
                            steady_only)
        staged.commit()
    except BaseException:
        staged.discard()
        raise
    if out_file is not None:
        result.output = str(out_file)
    if report_dir is not None:
        result.report_dir = str(report_dir)
    return result


def _calibrate(inputs: list[str | Path], base_file: str | Path, pump_out: Staged | None,
               report_out: Staged | None, fix: list[str], config: EstimatorConfig,
               remaps: dict[str, str] | None, steady_only: bool) -> CalibrationResult:
    """Run the fit and write the outputs into their staged paths (pump file, report)."""
    base_file = resolve_path(base_file, '--pump', pump_set=True)  # a path or a set name
    base = load_pump(base_file)
    oil = WaltherViscosity(config.oil_viscosity_40c_m2_s, config.oil_viscosity_100c_m2_s)
    visc0 = config.viscosity_m2_s(base.oil.viscosity_m2_s)
    table = build_table(base) if any(Path(p).is_dir() for p in inputs) else None
    parts = []
    for item in map(Path, inputs):
        if item.is_dir():
            assert table is not None  # built above: an input is a folder
            parts.append(load_bag_samples(item, config, table, visc0, remaps, steady_only))
        elif item.suffix.lower() == '.csv' or item.exists():  # a pipe: refused as it is read
            parts.append(load_bench_csv(item, oil, visc0))
        else:
            raise CalibrationError(f'input not found: {item}')
    samples = merge_samples(parts)
    if not samples.is_bag:  # bags: selected while reading
        samples = samples.subset(np.abs(samples.speed) >= MIN_SPEED_RAD_S)
    n = samples.speed.size
    if n == 0:
        raise CalibrationError('no usable samples (speed above '
                               f'{MIN_SPEED_RAD_S:g} rad/s with a measured torque)')
    x = regressors(base, samples, table)
    y = samples.torque - theoretical_torque_nm(base.geometry.displacement_m3, samples.dp)
    theta0 = np.ones(len(NAMES))  # the scales: 1 = the base pump
    theta0[INERTIA] = config.rotor_inertia_kg_m2
    theta0[DRIVE_LOSS] = config.drive_loss_torque_nm
    free = np.array([name not in fix for name in NAMES])
    status = {name: ('fixed' if name in fix else 'fitted') for name in NAMES}
    for k, p in enumerate(FIT_PARAMETERS):
        if p.bags_only and not samples.is_bag:  # a bench point is steady, at the pump shaft
            free[k], status[p.name], theta0[k] = False, 'not applicable', 0.0
    if samples.is_bag:  # fitted below, from the whole record (state-variable filter)
        free[INERTIA] = False
    # a row repeated exactly (a logger stuck on one reading) tells nothing new: count the
    # distinct samples (regressors and torque together)
    distinct = len(np.unique(np.column_stack([x, y]), axis=0))
    if distinct < 2 * int(free.sum()) + 2:
        repeated = f' ({n - distinct} repeat others exactly)' if distinct < n else ''
        raise CalibrationError(f'{distinct} distinct usable samples{repeated} are too few for '
                               f'{int(free.sum())} free parameters (need at least '
                               f'{2 * int(free.sum()) + 2})')
    upper = upper_bounds(base)
    linear = fit_identifiable(x, y, theta0, free, upper)
    theta, ci, free = linear.theta, linear.ci95, linear.free
    status.update(dict.fromkeys(linear.unidentifiable, 'unidentifiable'))
    warnings = list(linear.unidentifiable.values())
    fitted = fitted_pump(base, theta, pump_out.target.stem if pump_out else
                         f'{base.name}_calibrated')
    fitted = dataclasses.replace(fitted, description=(
        f'{fitted.name}: {base.description} Calibrated by pump_friction calibrate on '
        f'{len(samples.inputs)} input(s).'))
    fitted_table = build_table(fitted) if samples.is_bag else None
    if samples.is_bag and 'rotor_inertia_kg_m2' not in fix:
        theta[INERTIA], ci[INERTIA], note = fit_inertia(
            fitted, samples, theta[DRIVE_LOSS], fitted_table,
            config.accel_filter_time_constant_s)
        if note:
            warnings.append(note)
            status['rotor_inertia_kg_m2'] = 'unidentifiable'
            theta[INERTIA] = theta0[INERTIA]
    before = predict(base, samples, theta0[INERTIA], theta0[DRIVE_LOSS], table)
    after = predict(fitted, samples, theta[INERTIA], theta[DRIVE_LOSS], fitted_table)
    result = CalibrationResult(
        parameters=[ParameterReport(p.name, p.meaning, float(theta0[k]), float(theta[k]),
                                    float(ci[k]), status[p.name])
                    for k, p in enumerate(FIT_PARAMETERS)],
        points=n, selection=samples.selection,
        rmse_before_nm=rms(before - samples.torque), rmse_after_nm=rms(after - samples.torque),
        max_error_before_nm=float(np.abs(before - samples.torque).max()),
        max_error_after_nm=float(np.abs(after - samples.torque).max()),
        cv_rmse_nm=cross_validate(x, y, theta0, free, upper, samples.block),
        noise_std_nm=linear.noise_std_nm, warnings=warnings, fitted=fitted)
    if pump_out is not None:
        with pump_out.writing():
            write_pump_file(Path(base_file), pump_out.path, fitted, result, samples, fix)
    if report_out is not None:
        with report_out.writing():
            write_report(report_out.path, result, samples, before, after)
    return result
