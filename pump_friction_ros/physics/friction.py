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
Friction laws of the valve plate (eq. 9) and the shaft bearing (eq. 10), Hong & Doh (2004).

The spherical-joint and piston-head friction come from the piston dynamics
(``dynamics``, eqs. 3-8, work-energy method).
"""

from __future__ import annotations

import math

import numpy as np

from .pump_parameters import Bearing, ValvePlate
from .units import m2_s_to_cst, MM_TO_M, NMM_TO_NM, rad_s_to_rpm

__all__ = [
    'PALMGREN_THRESHOLD_CST_RPM',
    'bearing_torque_nm',
    'couette_land_integral_m4',
    'smooth_sign',
    'smooth_sign_scalar',
    'valve_plate_coulomb_torque_nm',
    'valve_plate_viscous_torque_nm',
]

PALMGREN_THRESHOLD_CST_RPM = 2000.0
"""Product nu * n [cSt * rpm] above which eq. (10) uses its speed-dependent viscous branch."""


def smooth_sign(speed_rad_s: np.ndarray, threshold_rad_s: float) -> np.ndarray:
    """
    Direction factor of a friction torque: tanh(speed / threshold).

    Friction opposes the shaft's motion. Instead of a sign step at zero speed (which would
    make the input torque jump and a table-based estimator chatter on reversals) the
    direction changes smoothly: 76 % of full friction at |speed| = threshold, 99.9 % at four
    times it.

    Parameters
    ----------
    speed_rad_s : ndarray
        Shaft speed [rad/s].
    threshold_rad_s : float
        Speed scale of the transition [rad/s].

    Returns
    -------
    ndarray
        Factor in (-1, 1) [-].

    """
    return np.tanh(np.asarray(speed_rad_s, dtype=float) / threshold_rad_s)


def smooth_sign_scalar(speed_rad_s: float, threshold_rad_s: float) -> float:
    """
    Return `smooth_sign` of one speed, without numpy (the estimator's per-sample path).

    Parameters
    ----------
    speed_rad_s : float
        Shaft speed [rad/s].
    threshold_rad_s : float
        Speed scale of the transition [rad/s].

    Returns
    -------
    float
        tanh(speed / threshold) [-].

    """
    return math.tanh(speed_rad_s / threshold_rad_s)


def valve_plate_coulomb_torque_nm(normal_force_n: np.ndarray, speed_abs_rad_s: np.ndarray,
                                  vp: ValvePlate) -> np.ndarray:
    """
    Coulomb part of eq. (9): T = [sum_i A_b p_ci] mu_c(|omega|) R_c.

    Parameters
    ----------
    normal_force_n : ndarray
        sum_i A_b p_ci, the barrel's net contact force [N].
    speed_abs_rad_s : ndarray
        |shaft speed| [rad/s], broadcastable against the force.
    vp : ValvePlate
        Coulomb coefficient curve (Fig. 6) and radii; R_c is the mean of R_o and R_i.

    Returns
    -------
    ndarray
        Torque magnitude [N*m].

    """
    return normal_force_n * vp.coulomb_coefficient(speed_abs_rad_s) * vp.friction_radius_m


def couette_land_integral_m4(vp: ValvePlate) -> float:
    """
    Integral of r^3 dr dphi over the valve-plate lands (annulus minus two kidneys).

    Parameters
    ----------
    vp : ValvePlate
        Radii and bridge angle.

    Returns
    -------
    float
        Integral [m^4].

    """
    annulus = 0.5 * math.pi * (vp.land_outer_radius_m**4 - vp.land_inner_radius_m**4)
    kidney_angle = math.pi - vp.bridge_angle_rad
    ports = 2.0 * kidney_angle / 4.0 * (vp.port_outer_radius_m**4 - vp.port_inner_radius_m**4)
    return annulus - ports


def valve_plate_viscous_torque_nm(speed_abs_rad_s: np.ndarray, viscosity_m2_s: np.ndarray,
                                  density_kg_m3: float, vp: ValvePlate) -> np.ndarray:
    """
    Viscous part of the valve-plate friction: Couette shear of the film, sec. 4.2.

    The paper treats barrel and plate as circular rings with a constant clearance h and
    radial flow; shear stress rho nu omega r / h integrated over the lands gives
    T = rho nu |omega| / h * int r^3 dr dphi. It does not depend on the load pressure (the
    film is sheared whatever presses on it), which is why it is added to eq. (9) rather
    than folded into its friction coefficient (see docs/model.md, "paper fidelity").

    Parameters
    ----------
    speed_abs_rad_s : ndarray
        |shaft speed| [rad/s].
    viscosity_m2_s : ndarray
        Oil kinematic viscosity [m^2/s].
    density_kg_m3 : float
        Oil density [kg/m^3].
    vp : ValvePlate
        Film clearance and land geometry.

    Returns
    -------
    ndarray
        Torque magnitude [N*m].

    """
    dynamic_viscosity = density_kg_m3 * np.asarray(viscosity_m2_s, dtype=float)
    return (dynamic_viscosity * speed_abs_rad_s / vp.film_clearance_m
            * couette_land_integral_m4(vp))


def bearing_torque_nm(load_n: np.ndarray | float, speed_abs_rad_s: np.ndarray,
                      viscosity_m2_s: np.ndarray, bearing: Bearing) -> tuple[np.ndarray,
                                                                             np.ndarray]:
    """
    Shaft-bearing friction by Palmgren, eq. (10): T = T_m + T_v.

    T_m = f1 F_L^a d_m^b and T_v = 1e-7 f0 (nu n)^(2/3) d_m^3 when nu n >= 2000, else
    160e-7 f0 d_m^3; the formula is empirical in N*mm with F_L in N, d_m in mm, nu in cSt
    and n in rpm. The conversion to those units happens here and nowhere else.

    Parameters
    ----------
    load_n : float or ndarray
        Bearing load F_L [N].
    speed_abs_rad_s : ndarray
        |shaft speed| [rad/s].
    viscosity_m2_s : ndarray
        Oil kinematic viscosity [m^2/s].
    bearing : Bearing
        Palmgren coefficients and mean diameter.

    Returns
    -------
    tuple of ndarray
        Mechanical (load) torque T_m and viscous torque T_v, magnitudes [N*m].

    """
    d_m_mm = bearing.mean_diameter_m / MM_TO_M
    mechanical = bearing.f1 * np.power(load_n, bearing.a) * d_m_mm**bearing.b * NMM_TO_NM
    nu_n = (m2_s_to_cst(np.asarray(viscosity_m2_s, dtype=float))
            * rad_s_to_rpm(np.asarray(speed_abs_rad_s, dtype=float)))
    fast = 1e-7 * bearing.f0 * np.power(np.maximum(nu_n, 0.0), 2.0 / 3.0) * d_m_mm**3
    slow = 160e-7 * bearing.f0 * d_m_mm**3
    viscous = np.where(nu_n >= PALMGREN_THRESHOLD_CST_RPM, fast, slow) * NMM_TO_NM
    return mechanical, viscous
