"""Calibration: fit a pump's open friction parameters to bench points or recorded bags.

The friction model is linear, or very nearly, in the parameters a pump file leaves open:
with the base pump's friction split into components C_k (valve plate coulomb and viscous,
bearing load and viscous terms by their closed forms, spherical joints, piston heads), the
measured input torque is

    T - V_g dp / 2 pi = sum_k theta_k d C_k + J a + L d        (d = tanh(w / w_0))

where theta_k scales component k (1 = the base pump), J is the rotor inertia and L a constant
drive loss (bags only: a bench point is steady). The fit is bounded robust least squares
(``scipy.optimize.least_squares``, soft-L1 loss); the parameter covariance
s^2 (X^T X)^-1, inflated by the residuals' integral correlation time (samples of a 1 kHz
record are not independent), gives 95 % intervals. A parameter whose interval is wider
than half its reference value cannot be identified from the data (e.g. one speed cannot
separate coulomb from viscous friction): it is reported, fixed at its base value and the
fit repeated. Bags: friction and drive loss are fitted on near-steady samples (the speed
derivative's filter lag biases the rest), the rotor inertia on the whole record through
the same filter (see `_fit_inertia`).
The "after" errors come from the full model of the fitted pump (bench points) or its
rebuilt table (bags), not from the linear fit.
"""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import json
import math
import os
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import __version__
from .config import EstimatorConfig
from .errors import PumpFrictionError
from .friction import bearing_torque_nm, valve_plate_viscous_torque_nm
from .model import COMPONENTS, PumpModel, theoretical_torque_nm
from .oil import WaltherViscosity
from .params import Curve, PumpParams, load_pump
from .table import FrictionTable, build_table
from .units import BAR_TO_PA, CST_PER_M2_S, RPM_TO_RAD_S

__all__ = ['FIT_PARAMETERS', 'CalibrationError', 'CalibrationResult', 'calibrate',
           'load_bench_csv']


class CalibrationError(PumpFrictionError):
    """Unusable calibration input: no samples, NaN, inconsistent units, too few points."""


@dataclass(frozen=True)
class FitParameter:
    """One fitted quantity: name (for ``--fix``), meaning, reference size, bags only."""

    name: str
    meaning: str
    reference: float  # identifiable if the 95 % half-interval is below half of this
    bags_only: bool = False


FIT_PARAMETERS = (
    FitParameter('valve_plate.coulomb', 'valve-plate coulomb friction (scale of the Fig. 6 '
                 'curve)', 1.0),
    FitParameter('valve_plate.viscous', 'valve-plate viscous friction (base film clearance / '
                 'fitted clearance)', 1.0),
    FitParameter('bearing.f1', 'bearing load coefficient f1 (scale)', 1.0),
    FitParameter('bearing.f0', 'bearing viscous coefficient f0 (scale)', 1.0),
    FitParameter('piston_friction.joint', 'spherical-joint friction (scale of its curve)', 1.0),
    FitParameter('piston_friction.head', 'piston-head friction (scale of its curve)', 1.0),
    FitParameter('rotor_inertia_kg_m2', 'rotor inertia [kg m^2]', 1e-4, bags_only=True),
    FitParameter('drive_loss_torque_nm', 'constant drive loss [N m]', 0.05, bags_only=True),
)
NAMES = [p.name for p in FIT_PARAMETERS]
MIN_SPEED_RAD_S = 10.0  # below: stick-slip, the paper's model does not claim to hold
K_FOLDS = 5


@dataclass
class Samples:
    """Calibration data (SI); ``accel`` is 0 for bench points; ``block`` orders folds."""

    speed: np.ndarray
    dp: np.ndarray
    viscosity: np.ndarray
    torque: np.ndarray
    accel: np.ndarray
    block: np.ndarray
    is_bag: bool
    selection: str
    inputs: list[dict] = field(default_factory=list)
    timeline: list[dict] = field(default_factory=list)  # bags: every sample, per input


# -- reading --------------------------------------------------------------------------------


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
    """Read steady-state bench points.

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
        text = path.read_text(encoding='utf-8')
    except (OSError, UnicodeDecodeError) as exc:
        raise CalibrationError(f'cannot read {path}: {exc}') from None
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
            except (TypeError, ValueError):
                raise CalibrationError(f'{path}:{i}: {name} is not a number: '
                                       f'{row[name]!r}') from None
            if not math.isfinite(values[i - 2, j]):
                raise CalibrationError(f'{path}:{i}: {name} is not finite: {row[name]!r}')
    if not len(rows):
        raise CalibrationError(f'{path}: no data rows')
    speed_rpm, bar, torque = values[:, 0], values[:, 1], values[:, 2]
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
        cst = values[:, 3]
        if cst.min() < 0.5:
            raise CalibrationError(f'{path}: viscosity_cst down to {cst.min():g}: that looks '
                                   'like m^2/s, the column is in cSt')
        viscosity = cst / CST_PER_M2_S
    elif extra == ['temperature_c']:
        temp = values[:, 3]
        if temp.max() > 250.0 or temp.min() < -60.0:
            raise CalibrationError(f'{path}: temperature_c outside -60..250 degC (kelvin?)')
        viscosity = np.array([oil(t) for t in temp])
    n = len(rows)
    return Samples(speed=speed_rpm * RPM_TO_RAD_S, dp=bar * BAR_TO_PA, viscosity=viscosity,
                   torque=torque, accel=np.zeros(n), block=np.arange(n), is_bag=False,
                   selection='steady bench points',
                   inputs=[{'path': str(path), 'kind': 'csv', 'sha256': _sha256_of(path),
                            'samples': n}])


def load_bag_samples(path: str | Path, config: EstimatorConfig, table: FrictionTable,
                     default_viscosity_m2_s: float, remaps: dict[str, str] | None,
                     steady_only: bool = True) -> Samples:
    """Read a bag's samples as the replay reads it (same reader, same core, same stamps).

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
        Samples with a measured torque above ``MIN_SPEED_RAD_S``.
    """
    from .estimator import TorqueEstimator
    from .replay import replay_bag

    core = TorqueEstimator(config, table, default_viscosity_m2_s, 'calibration')
    summary = replay_bag(path, config, remaps=remaps, keep_estimates=True, core=core)
    est = summary.estimates_list or []
    get = {name: np.array([getattr(e, name) for e in est], dtype=float)
           for name in ('speed_rad_s', 'pressure_diff_pa', 'viscosity_m2_s', 'measured_nm',
                        'accel_rad_s2', 'stamp_ns')}
    keep = np.isfinite(get['measured_nm']) & (np.abs(get['speed_rad_s']) >= MIN_SPEED_RAD_S)
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
    timeline = {k: get[k][np.isfinite(get['measured_nm'])] for k in get}
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
                   timeline=[timeline])


def _merge(parts: list[Samples]) -> Samples:
    if len({p.is_bag for p in parts}) > 1:
        raise CalibrationError('give either bags or bench CSV files, not both')
    offset = 0
    blocks = []
    for p in parts:  # later inputs come after earlier ones in time-ordered folds
        blocks.append(p.block + offset)
        offset += (p.block.max() + 1) if p.block.size else 0
    return Samples(*(np.concatenate([getattr(p, f) for p in parts]) for f in (
        'speed', 'dp', 'viscosity', 'torque', 'accel')), block=np.concatenate(blocks),
        is_bag=parts[0].is_bag, selection=parts[0].selection,
        inputs=[i for p in parts for i in p.inputs],
        timeline=[t for p in parts for t in p.timeline])


# -- the regression -------------------------------------------------------------------------


def _magnitudes(params: PumpParams, samples: Samples, table: FrictionTable | None):
    """Component magnitudes (n, 4) at the samples: full model, or the table for bags."""
    if table is None:
        res = PumpModel(params).evaluate(samples.speed, samples.dp, samples.viscosity)
        return np.column_stack([res.magnitudes_nm[c] for c in COMPONENTS])
    mags, _ = table.magnitudes_array(np.abs(samples.speed), np.abs(samples.dp),
                                     samples.viscosity, samples.speed * samples.dp < 0.0)
    return mags


def regressors(params: PumpParams, samples: Samples, table: FrictionTable | None
               ) -> np.ndarray:
    """Design matrix X (n, 8), columns in `FIT_PARAMETERS` order, at the base pump.

    Parameters
    ----------
    params : PumpParams
        Base pump.
    samples : Samples
        Data.
    table : FrictionTable or None
        Base pump's table (bags), or None to evaluate the full model (bench points).

    Returns
    -------
    ndarray
        Signed regressors [N m per unit parameter].
    """
    mags = _magnitudes(params, samples, table)
    speed_abs = np.abs(samples.speed)
    direction = np.tanh(samples.speed / params.operation.zero_speed_threshold_rad_s)
    viscous_vp = valve_plate_viscous_torque_nm(speed_abs, samples.viscosity,
                                               params.oil.density_kg_m3, params.valve_plate)
    _, viscous_b = bearing_torque_nm(0.0, speed_abs, samples.viscosity, params.bearing)
    columns = [mags[:, 0] - viscous_vp, viscous_vp, mags[:, 1] - viscous_b, viscous_b,
               mags[:, 2], mags[:, 3]]
    return np.column_stack([direction * c for c in columns]
                           + [samples.accel, direction])


def _upper_bounds(params: PumpParams) -> np.ndarray:
    """Keep friction coefficients <= 1 and the rest sane."""
    vp_max = max(params.valve_plate.coulomb_coefficient.y)
    joint_max = max(params.piston_friction.joint_coefficient.y)
    head_max = max(params.piston_friction.head_coefficient.y)
    return np.array([1.0 / vp_max if vp_max > 0 else 50.0, 50.0, 50.0, 50.0,
                     1.0 / joint_max if joint_max > 0 else 50.0,
                     1.0 / head_max if head_max > 0 else 50.0, 1.0, 100.0])


def _solve(x: np.ndarray, y: np.ndarray, theta0: np.ndarray, free: np.ndarray,
           upper: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Robust bounded least squares on the free columns; (theta, covariance, noise std)."""
    from scipy.optimize import least_squares

    target = y - x[:, ~free] @ theta0[~free]
    xf = x[:, free]
    if not free.any():
        r = target
        return theta0.copy(), np.zeros((0, 0)), float(np.sqrt(np.mean(r * r)))
    ols, *_ = np.linalg.lstsq(xf, target, rcond=None)
    r0 = xf @ ols - target
    f_scale = max(1.4826 * float(np.median(np.abs(r0 - np.median(r0)))), 1e-6)
    x0 = np.clip(theta0[free], 0.0, upper[free])
    res = least_squares(lambda th: xf @ th - target, x0, jac=lambda th: xf,
                        bounds=(np.zeros(free.sum()), upper[free]), loss='soft_l1',
                        f_scale=f_scale, method='trf')
    theta = theta0.copy()
    theta[free] = res.x
    r = xf @ res.x - target
    dof = max(len(r) - int(free.sum()), 1)
    inlier = np.abs(r) <= 3.0 * f_scale
    s2 = float(np.sum(r[inlier] ** 2) / max(inlier.sum() - int(free.sum()), 1)) \
        if inlier.sum() > free.sum() else float(np.sum(r * r) / dof)
    cov = s2 * correlation_time(r) * np.linalg.pinv(xf.T @ xf)
    return theta, cov, math.sqrt(s2)


@dataclass
class ParameterReport:
    """One parameter's outcome."""

    name: str
    meaning: str
    base: float
    fitted: float
    ci95: float  # half-width; NaN when not fitted
    status: str  # 'fitted', 'fixed' (--fix), 'unidentifiable', 'not applicable'


@dataclass
class CalibrationResult:
    """Everything `calibrate` found and wrote."""

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

    def format(self) -> str:
        """Human-readable report.

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


def fitted_pump(base: PumpParams, theta: np.ndarray, name: str) -> PumpParams:
    """Return the base pump with the fitted scales applied.

    Parameters
    ----------
    base : PumpParams
        Base pump.
    theta : ndarray
        Fitted values in `FIT_PARAMETERS` order (scales are relative to the base).
    name : str
        Name of the new pump.

    Returns
    -------
    PumpParams
        The fitted pump.
    """
    vp, br, fr = base.valve_plate, base.bearing, base.piston_friction

    def scaled(curve: Curve, k: float) -> Curve:
        return Curve(curve.x, tuple(float(v * k) for v in curve.y))

    return dataclasses.replace(
        base, name=name,
        valve_plate=dataclasses.replace(
            vp, coulomb_coefficient=scaled(vp.coulomb_coefficient, theta[0]),
            film_clearance_m=vp.film_clearance_m / max(theta[1], 1e-9)),
        bearing=dataclasses.replace(br, f1=br.f1 * theta[2], f0=br.f0 * theta[3]),
        piston_friction=dataclasses.replace(
            fr, joint_coefficient=scaled(fr.joint_coefficient, theta[4]),
            head_coefficient=scaled(fr.head_coefficient, theta[5])))


def _predict(params: PumpParams, samples: Samples, inertia: float, loss: float,
             table: FrictionTable | None) -> np.ndarray:
    """Input torque the (fitted) pump predicts: full model or its rebuilt table."""
    mags = _magnitudes(params, samples, table)
    direction = np.tanh(samples.speed / params.operation.zero_speed_threshold_rad_s)
    return (theoretical_torque_nm(params.geometry.displacement_m3, samples.dp)
            + direction * mags.sum(axis=1) + inertia * samples.accel + loss * direction)


def calibrate(inputs: list[str | Path], base_file: str | Path, out_file: str | Path | None,
              *, report_dir: str | Path | None = None, fix: list[str] | None = None,
              config: EstimatorConfig | None = None, remaps: dict[str, str] | None = None,
              steady_only: bool = True, force: bool = False) -> CalibrationResult:
    """Fit the open friction parameters of ``base_file`` to the inputs; write the pump file.

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
        Replace an existing output file.

    Returns
    -------
    CalibrationResult
        The fit and its checks.

    Raises
    ------
    CalibrationError
        Unusable input or arguments; no output is written.
    """
    config = config or EstimatorConfig()
    fix = list(fix or [])
    unknown = [f for f in fix if f not in NAMES]
    if unknown:
        raise CalibrationError(f'--fix: unknown parameter(s) {", ".join(unknown)}; choose '
                               f'from {", ".join(NAMES)}')
    if out_file is not None and Path(out_file).exists() and not force:
        raise CalibrationError(f'output exists: {out_file} (pass --force to replace it)')
    if not inputs:
        raise CalibrationError('no input given')
    base = load_pump(base_file)
    oil = WaltherViscosity(config.oil_viscosity_40c_m2_s, config.oil_viscosity_100c_m2_s)
    visc0 = config.oil_viscosity_m2_s or base.oil.viscosity_m2_s
    bag_inputs = [Path(p) for p in inputs if Path(p).is_dir()]
    table = build_table(base) if bag_inputs else None
    parts = []
    for item in map(Path, inputs):
        if item.is_dir():
            parts.append(load_bag_samples(item, config, table, visc0, remaps, steady_only))
        elif item.suffix.lower() == '.csv' or item.is_file():
            parts.append(load_bench_csv(item, oil, visc0))
        else:
            raise CalibrationError(f'input not found: {item}')
    samples = _merge(parts)
    keep = np.abs(samples.speed) >= MIN_SPEED_RAD_S
    if not samples.is_bag:
        samples = Samples(samples.speed[keep], samples.dp[keep], samples.viscosity[keep],
                          samples.torque[keep], samples.accel[keep], samples.block[keep],
                          False, samples.selection, samples.inputs)
    n = samples.speed.size
    if n == 0:
        raise CalibrationError('no usable samples (speed above '
                               f'{MIN_SPEED_RAD_S:g} rad/s with a measured torque)')
    x = regressors(base, samples, table)
    y = samples.torque - theoretical_torque_nm(base.geometry.displacement_m3, samples.dp)
    theta0 = np.array([1, 1, 1, 1, 1, 1, config.rotor_inertia_kg_m2,
                       config.drive_loss_torque_nm], dtype=float)
    free = np.array([name not in fix for name in NAMES])
    status = {name: ('fixed' if name in fix else 'fitted') for name in NAMES}
    for k, p in enumerate(FIT_PARAMETERS):
        if p.bags_only and not samples.is_bag:  # a bench point is steady, at the pump shaft
            free[k], status[p.name], theta0[k] = False, 'not applicable', 0.0
    if samples.is_bag:  # fitted below, from the whole record (state-variable filter)
        free[6] = False
    if n < 2 * int(free.sum()) + 2:
        raise CalibrationError(f'{n} usable samples are too few for {int(free.sum())} free '
                               f'parameters (need at least {2 * int(free.sum()) + 2})')
    upper = _upper_bounds(base)
    warnings = []
    while True:
        theta, cov, noise = _solve(x, y, theta0, free, upper)
        ci = np.full(len(NAMES), math.nan)
        ci[free] = 1.96 * np.sqrt(np.clip(np.diag(cov), 0.0, None)) if free.any() else []
        refs = np.array([p.reference for p in FIT_PARAMETERS])
        ratio = np.where(free, ci / (0.5 * refs), 0.0)
        column_scale = np.abs(x).max(axis=0)
        ratio = np.where(free & (column_scale < 1e-12), np.inf, ratio)
        worst = int(np.argmax(ratio))
        if not free.any() or ratio[worst] <= 1.0:
            break
        free[worst] = False
        status[NAMES[worst]] = 'unidentifiable'
        warnings.append(f'{NAMES[worst]} cannot be identified from these data (95 % interval '
                        f'+-{ci[worst]:.3g}): kept at its base value {theta0[worst]:g}')
    fitted = fitted_pump(base, theta, Path(out_file).stem if out_file else
                         f'{base.name}_calibrated')
    fitted = dataclasses.replace(fitted, description=(
        f'{fitted.name}: {base.description} Calibrated by pump_friction calibrate on '
        f'{len(samples.inputs)} input(s).'))
    fitted_table = build_table(fitted) if samples.is_bag else None
    if samples.is_bag and 'rotor_inertia_kg_m2' not in fix:
        theta[6], ci[6], note = _fit_inertia(fitted, samples, theta[7], fitted_table,
                                             config.accel_filter_time_constant_s)
        if note:
            warnings.append(note)
            status['rotor_inertia_kg_m2'] = 'unidentifiable'
            theta[6] = theta0[6]
    before = _predict(base, samples, theta0[6], theta0[7], table)
    after = _predict(fitted, samples, theta[6], theta[7], fitted_table)
    cv = _cross_validate(x, y, theta0, free, upper, samples.block)
    result = CalibrationResult(
        parameters=[ParameterReport(p.name, p.meaning, float(theta0[k]), float(theta[k]),
                                    float(ci[k]), status[p.name])
                    for k, p in enumerate(FIT_PARAMETERS)],
        points=n, selection=samples.selection,
        rmse_before_nm=_rms(before - samples.torque), rmse_after_nm=_rms(after - samples.torque),
        max_error_before_nm=float(np.abs(before - samples.torque).max()),
        max_error_after_nm=float(np.abs(after - samples.torque).max()),
        cv_rmse_nm=cv, noise_std_nm=noise, warnings=warnings, fitted=fitted)
    if out_file is not None:
        _write_pump_file(Path(base_file), Path(out_file), fitted, result, samples, fix)
        result.output = str(out_file)
    if report_dir is not None:
        _write_report(Path(report_dir), result, samples, before, after)
        result.report_dir = str(report_dir)
    return result


def _filter_two_stage(x: np.ndarray, dt_s: float, tau_s: float) -> np.ndarray:
    """Apply the estimator's two first-order-hold low-pass stages along time."""
    from scipy.signal import lfilter

    b = math.exp(-dt_s / tau_s)
    a = 1.0 - b
    c = 1.0 - tau_s * a / dt_s
    num, den = [c, a - c], [1.0, -b]
    for _ in range(2):  # start at rest on the first value, as the estimator does
        x = lfilter(num, den, x - x[0]) + x[0]
    return x


def _fit_inertia(pump: PumpParams, samples: Samples, drive_loss: float,
                 table: FrictionTable, tau_s: float) -> tuple[float, float, str]:
    """Rotor inertia from the whole record, free of the derivative filter's lag.

    The residual of the steady model, r = T - T_steady, holds J dw/dt plus noise. Passed
    through the same two low-pass stages H as the speed, H(J dw/dt) = J a_filtered exactly
    (linear filters commute with differentiation), so regressing H(r) on the estimator's
    filtered acceleration gives J without the lag of a_filtered behind dw/dt.
    """
    from scipy.optimize import least_squares

    hr, acc = [], []
    for record in samples.timeline:
        part = Samples(record['speed_rad_s'], record['pressure_diff_pa'],
                       record['viscosity_m2_s'], record['measured_nm'], record['accel_rad_s2'],
                       record['stamp_ns'], True, '')
        if part.speed.size < 10:
            continue
        steady = _predict(pump, part, 0.0, drive_loss, table)
        dt = float(np.median(np.diff(record['stamp_ns']))) * 1e-9
        hr.append(_filter_two_stage(part.torque - steady, dt, tau_s))
        acc.append(part.accel)
    if not hr:
        return math.nan, math.nan, 'rotor_inertia_kg_m2: no record long enough to fit it'
    hr, acc = np.concatenate(hr), np.concatenate(acc)
    res = least_squares(lambda j: acc * j[0] - hr, [1e-4], bounds=([0.0], [1.0]),
                        loss='soft_l1', f_scale=max(float(np.std(hr)), 1e-6))
    inertia = float(res.x[0])
    r = acc * inertia - hr
    sigma = math.sqrt(float(np.mean(r * r)) * correlation_time(r)
                      / max(float(np.sum(acc * acc)), 1e-300))
    ci = 1.96 * sigma
    if not math.isfinite(ci) or ci > 0.5 * max(inertia, FIT_PARAMETERS[6].reference):
        return inertia, ci, ('rotor_inertia_kg_m2 cannot be identified from these data (too '
                             'little acceleration): kept at its start value')
    return inertia, ci, ''


def correlation_time(residual: np.ndarray) -> float:
    """Integral correlation time of a residual series, in samples (1 for white noise).

    1 + 2 sum_k rho_k up to the first lag where the autocorrelation falls below 0.05. The
    variance of a mean (and of a least-squares estimate) of correlated samples is larger by
    about this factor than the white-noise formula says.

    Parameters
    ----------
    residual : ndarray
        Residuals in time (or file) order.

    Returns
    -------
    float
        Factor >= 1 [samples].
    """
    r = np.asarray(residual, dtype=float) - float(np.mean(residual))
    n = r.size
    if n < 4 or not np.any(r):
        return 1.0
    spectrum = np.fft.rfft(r, 2 * n)
    ac = np.fft.irfft(spectrum * np.conj(spectrum))[:n]
    ac /= ac[0]
    below = np.flatnonzero(ac[1:] < 0.05)
    stop = (below[0] + 1) if below.size else n
    return max(1.0, 1.0 + 2.0 * float(np.sum(ac[1:stop])))


def _rms(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(r * r)))


def _cross_validate(x, y, theta0, free, upper, block) -> float:
    """K-fold RMSE: contiguous blocks in time (bags) or in file order (bench points)."""
    order = np.argsort(block, kind='stable')
    folds = np.array_split(order, K_FOLDS)
    errors = []
    for held in folds:
        if not held.size:
            continue
        train = np.setdiff1d(order, held)
        theta, _, _ = _solve(x[train], y[train], theta0, free, upper)
        errors.append(x[held] @ theta - y[held])
    return _rms(np.concatenate(errors))


def _write_pump_file(base_file: Path, out_file: Path, fitted: PumpParams,
                     result: CalibrationResult, samples: Samples, fix: list[str]) -> None:
    """Write the base YAML (comments kept) with the fitted values and a provenance block."""
    from ruamel.yaml import YAML

    yaml = YAML()
    yaml.preserve_quotes = True
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
    out_file.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=out_file.name + '.', suffix='.tmp', dir=out_file.parent)
    try:
        with os.fdopen(fd, 'w', encoding='utf-8') as handle:
            yaml.dump(data, handle)
        check = load_pump(tmp)  # the file must load and mean the fitted pump
        if check.sha256 != dataclasses.replace(fitted, source='').sha256:
            raise CalibrationError('internal: the written pump file differs from the fit')
        os.replace(tmp, out_file)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _write_report(out_dir: Path, result: CalibrationResult, samples: Samples,
                  before: np.ndarray, after: np.ndarray) -> None:
    """report.json and PNG plots: measured vs predicted over speed and pressure, residual."""
    from .plots import _pyplot

    out_dir.mkdir(parents=True, exist_ok=True)
    payload = {'points': result.points, 'selection': result.selection,
               'rmse_before_nm': result.rmse_before_nm, 'rmse_after_nm': result.rmse_after_nm,
               'max_error_before_nm': result.max_error_before_nm,
               'max_error_after_nm': result.max_error_after_nm,
               'cv_rmse_nm': result.cv_rmse_nm, 'warnings': result.warnings,
               'parameters': [dataclasses.asdict(p) for p in result.parameters]}
    (out_dir / 'report.json').write_text(json.dumps(payload, indent=2, default=float))
    (out_dir / 'report.txt').write_text(result.format() + '\n')
    plt = _pyplot()
    rpm = samples.speed / RPM_TO_RAD_S
    bar = samples.dp / BAR_TO_PA
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
