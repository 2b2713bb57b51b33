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
Calibration fit: regressors, bounded robust solve, cross-validation, inertia.

(Which parameters these data can identify: `identifiability`.)

With the base pump's friction split into components C_k (valve plate coulomb and viscous,
bearing load and viscous terms by their closed forms, spherical joints, piston heads), the
measured input torque is

    T - V_g dp / 2 pi = sum_k theta_k d C_k + J a + L d        (d = smooth_sign(w))

where theta_k scales component k (1 = the base pump), J is the rotor inertia and L a constant
drive loss (bags only: a bench point is steady). Parameters are addressed by name
(`FIT_PARAMETERS`, `INDEX`); arrays over them are in `NAMES` order.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .data import Samples, timeline_samples
from ..core.speed_filter import filter_two_stage
from ..physics.friction import bearing_torque_nm, smooth_sign, valve_plate_viscous_torque_nm
from ..physics.model import COMPONENTS, input_torque_nm, PumpModel, theoretical_torque_nm
from ..physics.pump_parameters import Curve, PumpParams
from ..table.friction_table import FrictionTable

__all__ = ['FIT_PARAMETERS', 'INDEX', 'K_FOLDS', 'NAMES', 'FitParameter', 'correlation_time',
           'cross_validate', 'fit_inertia', 'fitted_pump', 'predict', 'regressors', 'solve',
           'upper_bounds']


@dataclasses.dataclass(frozen=True)
class FitParameter:
    """
    One fitted quantity.

    Attributes
    ----------
    name : str
        Name, as given to ``--fix``.
    meaning : str
        What it is, for the report.
    reference : float
        Size against which identifiability is judged: the parameter is identifiable if its
        95 % half-interval is below half of this [its unit].
    upper : float
        Upper bound of the fit [its unit]; the friction coefficient scales are bounded
        further by their curves (see `upper_bounds`).
    bags_only : bool
        Only bags can identify it (bench points are steady, at the pump shaft).

    """

    name: str
    meaning: str
    reference: float
    upper: float = 50.0
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
    FitParameter('rotor_inertia_kg_m2', 'rotor inertia [kg m^2]', 1e-4, upper=1.0,
                 bags_only=True),
    FitParameter('drive_loss_torque_nm', 'constant drive loss [N m]', 0.05, upper=100.0,
                 bags_only=True),
)
NAMES = tuple(p.name for p in FIT_PARAMETERS)
INDEX = {name: k for k, name in enumerate(NAMES)}
"""Position of each parameter in arrays over `FIT_PARAMETERS`."""
K_FOLDS = 5


def _magnitudes(params: PumpParams, samples: Samples, table: FrictionTable | None
                ) -> dict[str, np.ndarray]:
    """Component magnitudes [N m] by name: full model, or the table for bags."""
    if table is None:
        res = PumpModel(params).evaluate(samples.speed, samples.dp, samples.viscosity)
        return {c: res.magnitudes_nm[c] for c in COMPONENTS}
    mags, _ = table.magnitudes_array(np.abs(samples.speed), np.abs(samples.dp),
                                     samples.viscosity, samples.speed * samples.dp < 0.0)
    return dict(zip(COMPONENTS, mags.T, strict=True))


def regressors(params: PumpParams, samples: Samples, table: FrictionTable | None
               ) -> np.ndarray:
    """
    Design matrix X (n, 8), columns in `FIT_PARAMETERS` order, at the base pump.

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
        Signed regressors [N m per unit of each parameter].

    """
    mag = _magnitudes(params, samples, table)
    speed_abs = np.abs(samples.speed)
    direction = smooth_sign(samples.speed, params.operation.zero_speed_threshold_rad_s)
    viscous_vp = valve_plate_viscous_torque_nm(speed_abs, samples.viscosity,
                                               params.oil.density_kg_m3, params.valve_plate)
    _, viscous_b = bearing_torque_nm(0.0, speed_abs, samples.viscosity, params.bearing)
    column = {
        'valve_plate.coulomb': direction * (mag['valve_plate'] - viscous_vp),
        'valve_plate.viscous': direction * viscous_vp,
        'bearing.f1': direction * (mag['bearing'] - viscous_b),
        'bearing.f0': direction * viscous_b,
        'piston_friction.joint': direction * mag['spherical_joints'],
        'piston_friction.head': direction * mag['piston_heads'],
        'rotor_inertia_kg_m2': samples.accel,
        'drive_loss_torque_nm': direction,
    }
    return np.column_stack([column[name] for name in NAMES])


def upper_bounds(params: PumpParams) -> np.ndarray:
    """
    Upper bounds of the fit: friction coefficients stay <= 1, the rest sane.

    Parameters
    ----------
    params : PumpParams
        Base pump.

    Returns
    -------
    ndarray
        One bound per parameter, in `NAMES` order [unit of each parameter].

    """
    upper = {p.name: p.upper for p in FIT_PARAMETERS}
    for name, curve in (('valve_plate.coulomb', params.valve_plate.coulomb_coefficient),
                        ('piston_friction.joint', params.piston_friction.joint_coefficient),
                        ('piston_friction.head', params.piston_friction.head_coefficient)):
        peak = max(curve.y)
        if peak > 0:
            upper[name] = 1.0 / peak
    return np.array([upper[name] for name in NAMES])


def solve(x: np.ndarray, y: np.ndarray, theta0: np.ndarray, free: np.ndarray,
          upper: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """
    Robust (soft-L1) bounded least squares on the free columns.

    Parameters
    ----------
    x : ndarray
        Design matrix (n, 8) from `regressors` [N m per unit].
    y : ndarray
        Measured torque minus the theoretical torque [N m].
    theta0 : ndarray
        Start values; the values of the fixed parameters [unit of each].
    free : ndarray of bool
        Parameters to fit.
    upper : ndarray
        Upper bounds [unit of each]; the lower bounds are 0.

    Returns
    -------
    theta : ndarray
        All parameters, the free ones fitted [unit of each].
    cov : ndarray
        Covariance of the free ones, inflated by the residuals' correlation time.
    noise : float
        Residual noise std (inliers) [N m].

    """
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
    # jac must return a fresh array: with a robust loss, SciPy < 1.16 rescales the returned
    # Jacobian in place, which would corrupt xf (and so the residual and the covariance).
    # xf is read-only so that such a write fails loudly instead.
    xf.setflags(write=False)
    res = least_squares(lambda th: xf @ th - target, x0, jac=lambda th: xf.copy(),
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


def cross_validate(x: np.ndarray, y: np.ndarray, theta0: np.ndarray, free: np.ndarray,
                   upper: np.ndarray, block: np.ndarray) -> float:
    """
    K-fold RMSE over contiguous blocks in time (bags) or in file order (bench points).

    Parameters
    ----------
    x, y, theta0, free, upper : ndarray
        As for `solve`.
    block : ndarray
        Order of the samples (`Samples.block`).

    Returns
    -------
    float
        RMSE of the held-out predictions [N m].

    """
    order = np.argsort(block, kind='stable')
    errors = []
    for held in np.array_split(order, K_FOLDS):
        if not held.size:
            continue
        train = np.setdiff1d(order, held)
        theta, _, _ = solve(x[train], y[train], theta0, free, upper)
        errors.append(x[held] @ theta - y[held])
    return rms(np.concatenate(errors))


def rms(r: np.ndarray) -> float:
    """Root mean square of ``r`` [its unit]."""
    return float(np.sqrt(np.mean(r * r)))


def correlation_time(residual: np.ndarray) -> float:
    """
    Integral correlation time of a residual series, in samples (1 for white noise).

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


def fitted_pump(base: PumpParams, theta: np.ndarray, name: str) -> PumpParams:
    """
    Return the base pump with the fitted scales applied.

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
    value = dict(zip(NAMES, theta, strict=True))
    vp, br, fr = base.valve_plate, base.bearing, base.piston_friction

    def scaled(curve: Curve, k: float) -> Curve:
        return Curve(curve.x, tuple(float(v * k) for v in curve.y))

    return dataclasses.replace(
        base, name=name,
        valve_plate=dataclasses.replace(
            vp, coulomb_coefficient=scaled(vp.coulomb_coefficient, value['valve_plate.coulomb']),
            film_clearance_m=vp.film_clearance_m / max(value['valve_plate.viscous'], 1e-9)),
        bearing=dataclasses.replace(br, f1=br.f1 * value['bearing.f1'],
                                    f0=br.f0 * value['bearing.f0']),
        piston_friction=dataclasses.replace(
            fr, joint_coefficient=scaled(fr.joint_coefficient, value['piston_friction.joint']),
            head_coefficient=scaled(fr.head_coefficient, value['piston_friction.head'])))


def predict(params: PumpParams, samples: Samples, inertia_kg_m2: float, loss_nm: float,
            table: FrictionTable | None) -> np.ndarray:
    """
    Input torque the (fitted) pump predicts: full model (bench) or its rebuilt table (bags).

    Parameters
    ----------
    params : PumpParams
        The pump.
    samples : Samples
        Operating points.
    inertia_kg_m2 : float
        Rotor inertia [kg m^2].
    loss_nm : float
        Constant drive loss [N m].
    table : FrictionTable or None
        The pump's table, or None for the full model.

    Returns
    -------
    ndarray
        Input torque [N m].

    """
    mag = _magnitudes(params, samples, table)
    direction = smooth_sign(samples.speed, params.operation.zero_speed_threshold_rad_s)
    return (input_torque_nm(theoretical_torque_nm(params.geometry.displacement_m3, samples.dp),
                            sum(mag.values()), direction, loss_nm)
            + inertia_kg_m2 * samples.accel)


def fit_inertia(pump: PumpParams, samples: Samples, drive_loss_nm: float,
                table: FrictionTable | None, tau_s: float) -> tuple[float, float, str]:
    """
    Rotor inertia from the whole record, free of the derivative filter's lag.

    The residual of the steady model, r = T - T_steady, holds J dw/dt plus noise. Passed
    through the same two low-pass stages H as the speed, H(J dw/dt) = J a_filtered exactly
    (linear filters commute with differentiation), so regressing H(r) on the estimator's
    filtered acceleration gives J without the lag of a_filtered behind dw/dt.

    Parameters
    ----------
    pump : PumpParams
        The fitted pump (steady model).
    samples : Samples
        Bag samples with their ``timeline``.
    drive_loss_nm : float
        Fitted constant drive loss [N m].
    table : FrictionTable or None
        Table of the fitted pump, or None for the full model.
    tau_s : float
        Time constant of each speed filter stage [s].

    Returns
    -------
    inertia : float
        Rotor inertia [kg m^2] (NaN without a long enough record).
    ci95 : float
        95 % half-interval [kg m^2].
    note : str
        Why it cannot be identified, or empty.

    """
    from scipy.optimize import least_squares

    hr_parts: list[np.ndarray] = []
    acc_parts: list[np.ndarray] = []
    for part in timeline_samples(samples):
        if part.speed.size < 10:
            continue
        steady = predict(pump, part, 0.0, drive_loss_nm, table)
        dt = float(np.median(np.diff(part.block))) * 1e-9
        hr_parts.append(filter_two_stage(part.torque - steady, dt, tau_s))
        acc_parts.append(part.accel)
    if not hr_parts:
        return math.nan, math.nan, 'rotor_inertia_kg_m2: no record long enough to fit it'
    hr, acc = np.concatenate(hr_parts), np.concatenate(acc_parts)
    k = INDEX['rotor_inertia_kg_m2']
    res = least_squares(lambda j: acc * j[0] - hr, [1e-4],
                        bounds=([0.0], [FIT_PARAMETERS[k].upper]),
                        loss='soft_l1', f_scale=max(float(np.std(hr)), 1e-6))
    inertia = float(res.x[0])
    r = acc * inertia - hr
    sigma = math.sqrt(float(np.mean(r * r)) * correlation_time(r)
                      / max(float(np.sum(acc * acc)), 1e-300))
    ci = 1.96 * sigma
    if not math.isfinite(ci) or ci > 0.5 * max(inertia, FIT_PARAMETERS[k].reference):
        return inertia, ci, ('rotor_inertia_kg_m2 cannot be identified from these data (too '
                             'little acceleration): kept at its start value')
    return inertia, ci, ''
