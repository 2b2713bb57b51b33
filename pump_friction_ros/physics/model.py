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
The pump model: friction components, theoretical and input torque, torque efficiency.

Four quadrants
--------------
Inputs are signed: shaft speed omega [rad/s] and pressure difference dp = p_A - p_B [Pa].

* Theoretical torque T_th = V_g dp / (2 pi) follows the pressure.
* Each friction component is a magnitude (computed from the full dynamics at the signed
  operating point) times the direction factor tanh(omega / omega_0) of
  ``friction.smooth_sign``: friction opposes the motion, smoothly through zero speed.
* Input torque at the shaft T_in = T_th + T_f (signed sum).
* Pump mode (T_th omega > 0): efficiency = T_th / T_in. Motor mode (T_th omega < 0):
  efficiency = T_in / T_th (shaft torque delivered per ideal torque), floored at 0 where
  friction exceeds the hydraulic torque. Undefined (NaN) where |omega| or |dp| is below the
  pump file's ``operation.efficiency_min_*`` thresholds.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, Literal, overload

import numpy as np
from numpy.typing import ArrayLike

from .dynamics import solve_piston_loads
from .friction import (
    bearing_torque_nm,
    smooth_sign,
    valve_plate_coulomb_torque_nm,
    valve_plate_viscous_torque_nm,
)
from .kinematics import piston_kinematics
from .pressure import chamber_pressure
from .pump_parameters import barrel_effective_area_m2, PumpParams

__all__ = [
    'COMPONENTS',
    'PumpModel',
    'TorqueResult',
    'TorqueResultWithWaveforms',
    'Waveforms',
    'angle_count',
    'efficiency_of',
    'input_torque_nm',
    'theoretical_torque_nm',
    'torque_efficiency',
]

COMPONENTS = ('valve_plate', 'bearing', 'spherical_joints', 'piston_heads')
"""Names of the friction components, in the order used by tables and messages."""


def theoretical_torque_nm(displacement_m3: float, pressure_diff_pa: Any) -> Any:
    """
    Theoretical (ideal) torque V_g dp / (2 pi), sec. 5.

    Plain arithmetic: a float gives a float (the estimator's per-sample path), an array an
    array.

    Parameters
    ----------
    displacement_m3 : float
        Displacement per revolution V_g [m^3].
    pressure_diff_pa : float or ndarray
        Pressure difference p_A - p_B [Pa].

    Returns
    -------
    float or ndarray
        Torque [N*m], with the sign of the pressure difference.

    """
    return displacement_m3 / (2.0 * math.pi) * pressure_diff_pa


def input_torque_nm(theoretical_nm: Any, friction_magnitude_nm: Any, direction: Any,
                    drive_loss_nm: Any = 0.0) -> Any:
    """
    Shaft input torque: theoretical torque plus friction and drive loss opposing the motion.

    T_in = T_th + d (T_f + L), with d = `friction.smooth_sign` of the speed: the one rule of
    the signed torque, used by the model, the table, the estimator, the simulator and the
    calibration. Plain arithmetic: floats or arrays alike.

    Parameters
    ----------
    theoretical_nm : float or ndarray
        Theoretical torque [N*m].
    friction_magnitude_nm : float or ndarray
        Friction torque magnitude [N*m].
    direction : float or ndarray
        Smooth sign of the speed, in (-1, 1) [-].
    drive_loss_nm : float or ndarray
        Constant drive loss magnitude (seals, gears) [N*m].

    Returns
    -------
    float or ndarray
        Input torque [N*m].

    """
    return theoretical_nm + direction * (friction_magnitude_nm + drive_loss_nm)


def torque_efficiency(theoretical_nm: np.ndarray, input_nm: np.ndarray, speed_rad_s: np.ndarray,
                      pressure_diff_pa: np.ndarray, min_speed_rad_s: float,
                      min_pressure_pa: float) -> np.ndarray:
    """
    Torque efficiency per mode; NaN where it means nothing.

    Parameters
    ----------
    theoretical_nm : ndarray
        Theoretical torque [N*m].
    input_nm : ndarray
        Input (shaft) torque [N*m].
    speed_rad_s : ndarray
        Shaft speed [rad/s].
    pressure_diff_pa : ndarray
        Pressure difference [Pa].
    min_speed_rad_s : float
        |speed| below which the efficiency is undefined [rad/s].
    min_pressure_pa : float
        |dp| below which the efficiency is undefined [Pa].

    Returns
    -------
    ndarray
        Efficiency in [0, 1] [-], NaN where undefined.

    """
    th = np.asarray(theoretical_nm, dtype=float)
    tin = np.asarray(input_nm, dtype=float)
    speed = np.asarray(speed_rad_s, dtype=float)
    dp = np.asarray(pressure_diff_pa, dtype=float)
    pumping = th * speed > 0.0
    with np.errstate(divide='ignore', invalid='ignore'):
        eff = np.where(pumping, th / tin, np.maximum(tin / th, 0.0))
    valid = (np.abs(speed) >= min_speed_rad_s) & (np.abs(dp) >= min_pressure_pa) & \
        np.isfinite(eff)
    return np.where(valid, eff, np.nan)


def efficiency_of(theoretical_nm: float, shaft_nm: float, speed_rad_s: float,
                  pressure_diff_pa: float, min_speed_rad_s: float,
                  min_pressure_pa: float) -> float:
    """
    Scalar twin of `torque_efficiency` (pure Python, for the per-sample paths).

    Parameters
    ----------
    theoretical_nm : float
        Theoretical torque [N*m].
    shaft_nm : float
        Steady-state shaft torque [N*m].
    speed_rad_s : float
        Shaft speed [rad/s].
    pressure_diff_pa : float
        Pressure difference [Pa].
    min_speed_rad_s : float
        |speed| below which the efficiency is undefined [rad/s].
    min_pressure_pa : float
        |dp| below which the efficiency is undefined [Pa].

    Returns
    -------
    float
        Efficiency [-] per mode, NaN where undefined.

    """
    if abs(speed_rad_s) < min_speed_rad_s or abs(pressure_diff_pa) < min_pressure_pa \
            or shaft_nm == 0.0 or theoretical_nm == 0.0:
        return math.nan
    if theoretical_nm * speed_rad_s > 0.0:
        return theoretical_nm / shaft_nm
    return max(shaft_nm / theoretical_nm, 0.0)


@dataclass(frozen=True)
class Waveforms:
    """Torques and loads over one revolution (shape (m, n) unless stated)."""

    shaft_angle_rad: np.ndarray  # (n,)
    valve_plate_nm: np.ndarray  # magnitudes
    bearing_nm: np.ndarray
    spherical_joints_nm: np.ndarray
    piston_heads_nm: np.ndarray
    pressure_torque_nm: np.ndarray  # instantaneous sum_i p_i A_p ds_i/dphi, signed
    chamber_pressure_pa: np.ndarray  # piston 0
    head_force_n: np.ndarray  # |F_A| of piston 0
    joint_force_n: np.ndarray  # |F_B| of piston 0
    bearing_load_n: np.ndarray  # |sum_i F_B,i|
    head_velocity_m_s: np.ndarray  # V'_A of piston 0, signed
    piston_omega_rad_s: np.ndarray  # (m, n, 3) piston 0 angular velocity rel. barrel

    @property
    def friction_nm(self) -> np.ndarray:
        """Total friction torque magnitude over the revolution [N*m]."""
        return self.valve_plate_nm + self.bearing_nm + self.spherical_joints_nm + \
            self.piston_heads_nm


@dataclass(frozen=True)
class TorqueResult:
    """Revolution-mean torques at each operating point (arrays of shape (m,))."""

    speed_rad_s: np.ndarray
    pressure_diff_pa: np.ndarray
    viscosity_m2_s: np.ndarray
    direction: np.ndarray  # smooth sign of the speed, in (-1, 1)
    theoretical_nm: np.ndarray
    magnitudes_nm: dict[str, np.ndarray]  # friction component magnitudes, keys COMPONENTS
    efficiency: np.ndarray
    head_force_max_n: np.ndarray
    joint_force_max_n: np.ndarray
    max_moment_residual_nm: float
    waveforms: Waveforms | None = None

    def component_nm(self, name: str) -> np.ndarray:
        """Signed friction torque of one component [N*m] (opposes the speed)."""
        return self.direction * self.magnitudes_nm[name]

    @property
    def friction_magnitude_nm(self) -> np.ndarray:
        """Total friction torque magnitude [N*m]."""
        return np.asarray(sum(self.magnitudes_nm[c] for c in COMPONENTS))

    @property
    def friction_nm(self) -> np.ndarray:
        """Signed total friction torque [N*m]."""
        return self.direction * self.friction_magnitude_nm

    @property
    def input_nm(self) -> np.ndarray:
        """Shaft input torque [N*m]."""
        return input_torque_nm(self.theoretical_nm, self.friction_magnitude_nm, self.direction)


@dataclass(frozen=True)
class TorqueResultWithWaveforms(TorqueResult):
    """The `TorqueResult` of `PumpModel.evaluate` with ``waveforms=True``: waveforms set."""

    waveforms: Waveforms


MIN_ANGLES = 360
"""Shaft angles per revolution at least (1 deg): the revolution means converge to 2e-3."""


def angle_count(n_pistons: int, minimum: int = MIN_ANGLES) -> int:
    """
    Return the number of shaft angles for a pump: a multiple of its piston count.

    The pistons are 2 pi / N apart, so the angle grid must hold a multiple of N samples for
    their phase shifts to fall on samples; at least ``minimum`` and 4 per piston pitch.

    Parameters
    ----------
    n_pistons : int
        Number of pistons N (>= 1).
    minimum : int
        Fewest samples wanted.

    Returns
    -------
    int
        The smallest multiple of N that is >= ``minimum`` and >= 4 N (360 for 5 or 9
        pistons, 364 for 7).

    """
    need = max(minimum, 4 * n_pistons)
    return -(-need // n_pistons) * n_pistons


class PumpModel:
    """
    Hong & Doh (2004) friction model of one pump, vectorised over operating points.

    Parameters
    ----------
    params : PumpParams
        Validated pump parameters.
    n_angles : int, optional
        Samples of the shaft angle over one revolution; a multiple of the number of
        pistons so that the pistons' phase shifts fall on samples. Default: `angle_count`
        of the pump's piston count (any piston count works).

    """

    def __init__(self, params: PumpParams, n_angles: int | None = None) -> None:
        n_pistons = params.geometry.n_pistons
        if n_angles is None:
            n_angles = angle_count(n_pistons)
        if n_angles < 4 * n_pistons or n_angles % n_pistons:
            raise ValueError(f'n_angles must be a multiple of {n_pistons} and >= '
                             f'{4 * n_pistons}, got {n_angles}')
        self.params = params
        self.n_angles = n_angles
        self.phi = 2.0 * math.pi * np.arange(n_angles) / n_angles
        self.kin = piston_kinematics(params.geometry, self.phi, params.piston.joint_to_cg_m)
        self.barrel_area_m2 = barrel_effective_area_m2(params.geometry, params.valve_plate)
        self._shift = n_angles // n_pistons

    @property
    def displacement_m3(self) -> float:
        """Geometric displacement V_g [m^3/rev]."""
        return self.params.geometry.displacement_m3

    def sum_pistons(self, per_piston: np.ndarray) -> np.ndarray:
        """
        Sum a per-piston waveform over all pistons, each shifted by 2 pi / N.

        Parameters
        ----------
        per_piston : ndarray, shape (..., n)
            Quantity of piston 0 over its phase angle.

        Returns
        -------
        ndarray, shape (..., n)
            Sum over the N pistons at each shaft angle.

        """
        return np.asarray(sum(np.roll(per_piston, -i * self._shift, axis=-1)
                              for i in range(self.params.geometry.n_pistons)))

    @overload
    def evaluate(self, speed_rad_s: ArrayLike, pressure_diff_pa: ArrayLike,
                 viscosity_m2_s: ArrayLike | None = None, *, waveforms: Literal[False] = False,
                 chunk: int = 256) -> TorqueResult:
        ...

    @overload
    def evaluate(self, speed_rad_s: ArrayLike, pressure_diff_pa: ArrayLike,
                 viscosity_m2_s: ArrayLike | None = None, *, waveforms: Literal[True],
                 chunk: int = 256) -> TorqueResultWithWaveforms:
        ...

    @overload
    def evaluate(self, speed_rad_s: ArrayLike, pressure_diff_pa: ArrayLike,
                 viscosity_m2_s: ArrayLike | None = None, *, waveforms: bool,
                 chunk: int = 256) -> TorqueResult:
        ...

    def evaluate(self, speed_rad_s: ArrayLike, pressure_diff_pa: ArrayLike,
                 viscosity_m2_s: ArrayLike | None = None, *, waveforms: bool = False,
                 chunk: int = 256) -> TorqueResult:
        """
        Revolution-mean torques at operating points (broadcast against each other).

        Parameters
        ----------
        speed_rad_s : float or array_like
            Shaft speed [rad/s], either sign.
        pressure_diff_pa : float or array_like
            Pressure difference p_A - p_B [Pa], either sign.
        viscosity_m2_s : float or array_like, optional
            Oil kinematic viscosity [m^2/s]; default the pump file's.
        waveforms : bool
            Also return the waveforms over the shaft angle.
        chunk : int
            Operating points solved at once (bounds memory).

        Returns
        -------
        TorqueResult
            Flattened, broadcast operating points and their torques
            (`TorqueResultWithWaveforms` with ``waveforms=True``).

        """
        if viscosity_m2_s is None:
            viscosity_m2_s = self.params.oil.viscosity_m2_s
        speed, dp, visc = (np.ravel(a).astype(float) for a in np.broadcast_arrays(
            np.asarray(speed_rad_s, dtype=float), np.asarray(pressure_diff_pa, dtype=float),
            np.asarray(viscosity_m2_s, dtype=float)))
        if not (np.all(np.isfinite(speed)) and np.all(np.isfinite(dp))
                and np.all(np.isfinite(visc)) and np.all(visc > 0.0)):
            raise ValueError('speed, pressure and viscosity must be finite, viscosity > 0')
        parts = [self._evaluate_chunk(speed[i:i + chunk], dp[i:i + chunk], visc[i:i + chunk],
                                      waveforms)
                 for i in range(0, max(len(speed), 1), chunk)] if len(speed) else []
        if not parts:
            raise ValueError('no operating point given')
        return _concat(parts, waveforms)

    def _evaluate_chunk(self, speed: np.ndarray, dp: np.ndarray, visc: np.ndarray,
                        want_waveforms: bool) -> TorqueResult:
        p = self.params
        op = p.operation
        speed_abs = np.abs(speed)
        pc = chamber_pressure(self.phi, dp, op.charge_pressure_pa,
                              p.valve_plate.bridge_angle_rad)
        loads = solve_piston_loads(p, self.kin, speed, pc)

        # Linear in the per-piston waveforms: without waveforms, the revolution mean of the
        # sum over pistons is N times one piston's mean (no phase-shifted sum needed).
        def piston_sum(per_piston: np.ndarray) -> np.ndarray:
            if want_waveforms:
                return self.sum_pistons(per_piston)
            return p.geometry.n_pistons * per_piston.mean(axis=1, keepdims=True)

        # valve plate: eq. (9) coulomb on the summed chamber forces + Couette film shear
        normal = self.barrel_area_m2 * piston_sum(pc)
        vp = (valve_plate_coulomb_torque_nm(normal, speed_abs[:, None], p.valve_plate)
              + valve_plate_viscous_torque_nm(speed_abs, visc, p.oil.density_kg_m3,
                                              p.valve_plate)[:, None])
        # bearing: eq. (10) with F_L = |sum of joint forces| (on the flange) in a fixed frame
        fb = loads.joint_force_n
        c, s = np.cos(self.phi), np.sin(self.phi)
        fx = fb[..., 0] * c - fb[..., 1] * s
        fy = fb[..., 0] * s + fb[..., 1] * c
        load = np.sqrt(self.sum_pistons(fx) ** 2 + self.sum_pistons(fy) ** 2
                       + self.sum_pistons(fb[..., 2]) ** 2)
        t_mech, t_visc = bearing_torque_nm(load, speed_abs[:, None], visc[:, None], p.bearing)
        bearing = t_mech + t_visc
        joints = piston_sum(loads.joint_friction_torque_nm)
        heads = piston_sum(loads.head_friction_torque_nm)

        theoretical = theoretical_torque_nm(self.displacement_m3, dp)
        mags = {'valve_plate': vp.mean(axis=1), 'bearing': bearing.mean(axis=1),
                'spherical_joints': joints.mean(axis=1), 'piston_heads': heads.mean(axis=1)}
        direction = smooth_sign(speed, op.zero_speed_threshold_rad_s)
        tin = input_torque_nm(theoretical, sum(mags.values()), direction)
        eff = torque_efficiency(theoretical, tin, speed, dp, op.efficiency_min_speed_rad_s,
                                op.efficiency_min_pressure_pa)
        wf = None
        if want_waveforms:
            pressure_torque = self.sum_pistons(
                pc * p.geometry.piston_area_m2 * self.kin.head_vel_per_speed[None])
            pressure_torque = np.where(speed[:, None] >= 0.0, 1.0, -1.0) * pressure_torque
            wf = Waveforms(
                shaft_angle_rad=self.phi, valve_plate_nm=vp, bearing_nm=bearing,
                spherical_joints_nm=joints, piston_heads_nm=heads,
                pressure_torque_nm=pressure_torque, chamber_pressure_pa=pc,
                head_force_n=np.linalg.norm(loads.head_force_n, axis=-1),
                joint_force_n=np.linalg.norm(loads.joint_force_n, axis=-1),
                bearing_load_n=load,
                head_velocity_m_s=speed[:, None] * self.kin.head_vel_per_speed[None],
                piston_omega_rad_s=speed[:, None, None] * self.kin.omega_rel_per_speed[None])
        result_type: type[TorqueResult] = (TorqueResultWithWaveforms if want_waveforms
                                           else TorqueResult)
        return result_type(
            speed_rad_s=speed, pressure_diff_pa=dp, viscosity_m2_s=visc, direction=direction,
            theoretical_nm=theoretical, magnitudes_nm=mags, efficiency=eff,
            head_force_max_n=np.linalg.norm(loads.head_force_n, axis=-1).max(axis=1),
            joint_force_max_n=np.linalg.norm(loads.joint_force_n, axis=-1).max(axis=1),
            max_moment_residual_nm=float(loads.moment_residual_nm.max(initial=0.0)),
            waveforms=wf)


def _concat(parts: list[TorqueResult], waveforms: bool) -> TorqueResult:
    if len(parts) == 1:
        return parts[0]

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(r, name) for r in parts])

    wf = None
    if waveforms:
        fields = Waveforms.__dataclass_fields__
        wfs = [r.waveforms for r in parts if r.waveforms is not None]
        wf = Waveforms(**{f: (wfs[0].shaft_angle_rad if f == 'shaft_angle_rad'
                              else np.concatenate([getattr(w, f) for w in wfs]))
                          for f in fields})
    result_type: type[TorqueResult] = TorqueResultWithWaveforms if waveforms else TorqueResult
    return result_type(
        speed_rad_s=cat('speed_rad_s'), pressure_diff_pa=cat('pressure_diff_pa'),
        viscosity_m2_s=cat('viscosity_m2_s'), direction=cat('direction'),
        theoretical_nm=cat('theoretical_nm'),
        magnitudes_nm={c: np.concatenate([r.magnitudes_nm[c] for r in parts])
                       for c in COMPONENTS},
        efficiency=cat('efficiency'), head_force_max_n=cat('head_force_max_n'),
        joint_force_max_n=cat('joint_force_max_n'),
        max_moment_residual_nm=max(r.max_moment_residual_nm for r in parts), waveforms=wf)
