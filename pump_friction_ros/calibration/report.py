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
Calibration report: the result and its text, the calibrated pump file, report.json and plots.

The pump file is the base file with the fitted values and a provenance block, comments kept
(ruamel.yaml round trip, imported only here and only when a file is written).
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
import time
from typing import TYPE_CHECKING

import numpy as np

from .data import Samples
from .fit import K_FOLDS
from .. import __version__
from ..errors import CalibrationError, ConfigError
from ..physics.pump_parameters import load_pump, PumpParams
from ..physics.units import pa_to_bar, rad_s_to_rpm

if TYPE_CHECKING:
    from ruamel.yaml import YAML

__all__ = ['CalibrationResult', 'ParameterReport', 'round_trip_yaml', 'write_pump_file',
           'write_report']


@dataclasses.dataclass
class ParameterReport:
    """
    One parameter's outcome.

    Attributes
    ----------
    name : str
        Parameter name (`FIT_PARAMETERS`).
    meaning : str
        What it is.
    base : float
        Start value: the base pump's (1 for the scales) or the node parameter's [its unit].
    fitted : float
        Fitted value [its unit].
    ci95 : float
        95 % half-interval, NaN when not fitted [its unit].
    status : str
        'fitted', 'fixed' (``--fix``), 'unidentifiable' or 'not applicable'.

    """

    name: str
    meaning: str
    base: float
    fitted: float
    ci95: float
    status: str


@dataclasses.dataclass
class CalibrationResult:
    """
    Everything `calibrate` found and wrote.

    Attributes
    ----------
    parameters : list of ParameterReport
        Every parameter of `FIT_PARAMETERS`, in order.
    points : int
        Samples fitted.
    selection : str
        Which samples were used.
    rmse_before_nm, rmse_after_nm : float
        Torque RMSE of the base and of the fitted pump [N m].
    max_error_before_nm, max_error_after_nm : float
        Largest torque error of the base and of the fitted pump [N m].
    cv_rmse_nm : float
        `K_FOLDS`-fold cross-validated RMSE of the linear fit [N m].
    noise_std_nm : float
        Residual noise std [N m].
    warnings : list of str
        Parameters the data cannot identify, and the like.
    fitted : PumpParams
        The calibrated pump.
    output : str
        Pump file written, or empty.
    report_dir : str
        Report folder written, or empty.

    """

    parameters: list[ParameterReport]
    points: int
    selection: str
    rmse_before_nm: float
    rmse_after_nm: float
    max_error_before_nm: float
    max_error_after_nm: float
    cv_rmse_nm: float
    noise_std_nm: float
    warnings: list[str]
    fitted: PumpParams
    output: str = ''
    report_dir: str = ''

    def formatted(self) -> str:
        """
        Human-readable report.

        Returns
        -------
        str
            The report.

        """
        lines = [f'calibration of {self.points} samples ({self.selection})', '',
                 f'{"parameter":<24} {"base":>10} {"fitted":>10} {"+-95%":>9} '
                 f'{"change":>8}  status']
        for p in self.parameters:
            change = (f'{100 * (p.fitted / p.base - 1):+.1f}%' if p.base and
                      p.status == 'fitted' else '')
            ci = f'{p.ci95:.3g}' if math.isfinite(p.ci95) else ''
            lines.append(f'{p.name:<24} {p.base:>10.4g} {p.fitted:>10.4g} {ci:>9} '
                         f'{change:>8}  {p.status}')
        lines += ['',
                  f'torque RMSE  before {self.rmse_before_nm:.4f} N m, after '
                  f'{self.rmse_after_nm:.4f} N m (full model of the fitted pump)',
                  f'max error    before {self.max_error_before_nm:.4f} N m, after '
                  f'{self.max_error_after_nm:.4f} N m',
                  f'{K_FOLDS}-fold cross-validated RMSE {self.cv_rmse_nm:.4f} N m '
                  f'(residual noise {self.noise_std_nm:.4f} N m)']
        lines += [f'warning: {w}' for w in self.warnings]
        if self.output:
            lines.append(f'wrote {self.output}')
        if self.report_dir:
            lines.append(f'report in {self.report_dir}')
        return '\n'.join(lines)


def round_trip_yaml() -> YAML:
    """
    Return a comment-keeping YAML reader and writer (``ruamel.yaml.YAML``).

    Returns
    -------
    ruamel.yaml.YAML
        Round-trip instance that keeps quotes.

    Raises
    ------
    CalibrationError
        ruamel.yaml is not installed.

    """
    try:
        from ruamel.yaml import YAML
    except ImportError as exc:
        raise CalibrationError('writing a calibrated pump file needs ruamel.yaml: '
                               'pip install ruamel.yaml') from exc
    yaml = YAML()
    yaml.preserve_quotes = True
    return yaml


def write_pump_file(base_file: Path, out_file: Path, fitted: PumpParams,
                    result: CalibrationResult, samples: Samples, fix: list[str]) -> None:
    """
    Write the base YAML (comments kept) with the fitted values and a provenance block.

    Written under a temporary name, checked to load as the fitted pump, then renamed.

    Parameters
    ----------
    base_file : Path
        Base pump file.
    out_file : Path
        Calibrated pump file.
    fitted : PumpParams
        The calibrated pump.
    result : CalibrationResult
        The fit, for the provenance block.
    samples : Samples
        The data, for the provenance block.
    fix : list of str
        Parameters held at their base values.

    Raises
    ------
    CalibrationError
        ruamel.yaml missing, or the written file does not mean the fitted pump.

    """
    yaml = round_trip_yaml()
    data = yaml.load(base_file.read_text(encoding='utf-8'))
    data['name'] = fitted.name
    data['description'] = fitted.description
    vp, br, fr = fitted.valve_plate, fitted.bearing, fitted.piston_friction
    data['valve_plate']['coulomb_coefficient']['coefficient'] = \
        [float(v) for v in vp.coulomb_coefficient.y]
    data['valve_plate']['film_clearance_m'] = float(vp.film_clearance_m)
    data['bearing']['f1'] = float(br.f1)
    data['bearing']['f0'] = float(br.f0)
    data['piston_friction']['joint_coefficient']['coefficient'] = \
        [float(v) for v in fr.joint_coefficient.y]
    data['piston_friction']['head_coefficient']['coefficient'] = \
        [float(v) for v in fr.head_coefficient.y]
    by_name = {p.name: p for p in result.parameters}
    data['provenance'] = {
        'tool': f'pump_friction calibrate {__version__}',
        'created_utc': time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime()),
        'base_pump': {'file': str(base_file), 'sha256': load_pump(base_file).sha256},
        'inputs': samples.inputs,
        'data_selection': samples.selection,
        'fit': {'samples': result.points, 'rmse_before_nm': result.rmse_before_nm,
                'rmse_after_nm': result.rmse_after_nm,
                'max_error_before_nm': result.max_error_before_nm,
                'max_error_after_nm': result.max_error_after_nm,
                'cv_rmse_nm': result.cv_rmse_nm, 'noise_std_nm': result.noise_std_nm},
        'parameters': {p.name: {'base': p.base, 'fitted': p.fitted,
                                'ci95': None if math.isnan(p.ci95) else p.ci95,
                                'status': p.status} for p in result.parameters},
        'fixed': fix,
        'warnings': result.warnings,
    }
    if samples.is_bag:
        data['provenance']['suggested_node_parameters'] = {
            'rotor_inertia_kg_m2': by_name['rotor_inertia_kg_m2'].fitted,
            'drive_loss_torque_nm': by_name['drive_loss_torque_nm'].fitted}
    with open(out_file, 'w', encoding='utf-8') as handle:  # a staged path: moved at the end
        yaml.dump(data, handle)
    try:  # the file must load and mean the fitted pump
        check = load_pump(out_file)
    except ConfigError as exc:  # a fit beyond a pump file's ranges: not the staged path's
        raise CalibrationError(str(exc).replace(str(out_file), 'the fitted pump')) from exc
    if check.sha256 != dataclasses.replace(fitted, source='').sha256:
        raise CalibrationError('internal: the written pump file differs from the fit')


def write_report(out_dir: Path, result: CalibrationResult, samples: Samples,
                 before: np.ndarray, after: np.ndarray) -> None:
    """
    Write report.json, report.txt and PNG plots of measured vs predicted torque.

    Parameters
    ----------
    out_dir : Path
        Report folder (created).
    result : CalibrationResult
        The fit.
    samples : Samples
        The data.
    before, after : ndarray
        Torque predicted by the base and by the fitted pump [N m].

    """
    from ..plotting import pyplot

    payload = {'points': result.points, 'selection': result.selection,
               'rmse_before_nm': result.rmse_before_nm, 'rmse_after_nm': result.rmse_after_nm,
               'max_error_before_nm': result.max_error_before_nm,
               'max_error_after_nm': result.max_error_after_nm,
               'cv_rmse_nm': result.cv_rmse_nm, 'warnings': result.warnings,
               'parameters': [dataclasses.asdict(p) for p in result.parameters]}
    (out_dir / 'report.json').write_text(json.dumps(payload, indent=2, default=float))
    (out_dir / 'report.txt').write_text(result.formatted() + '\n')
    plt = pyplot()
    rpm = rad_s_to_rpm(samples.speed)
    bar = pa_to_bar(samples.dp)
    step = max(1, samples.speed.size // 20000)  # plot at most ~20k points
    sel = slice(None, None, step)
    for stem, axis, label in (('torque_vs_speed', rpm, 'shaft speed [rpm]'),
                              ('torque_vs_pressure', bar, 'pressure difference [bar]')):
        fig, ax = plt.subplots(figsize=(7, 4.5))
        ax.plot(axis[sel], samples.torque[sel], '.', ms=2, label='measured')
        ax.plot(axis[sel], before[sel], '.', ms=2, label='base pump')
        ax.plot(axis[sel], after[sel], '.', ms=2, label='calibrated pump')
        ax.set(xlabel=label, ylabel='input torque [N m]')
        ax.legend(fontsize=8)
        fig.suptitle('Measured vs predicted input torque')
        fig.tight_layout()
        fig.savefig(out_dir / f'{stem}.png', dpi=110)
        plt.close(fig)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(rpm[sel], (before - samples.torque)[sel], '.', ms=2, label='base pump')
    ax.plot(rpm[sel], (after - samples.torque)[sel], '.', ms=2, label='calibrated pump')
    ax.axhline(0.0, color='k', lw=0.8)
    ax.set(xlabel='shaft speed [rpm]', ylabel='predicted - measured [N m]')
    ax.legend(fontsize=8)
    fig.suptitle('Residual of the torque prediction')
    fig.tight_layout()
    fig.savefig(out_dir / 'residual.png', dpi=110)
    plt.close(fig)
