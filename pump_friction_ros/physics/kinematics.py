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
Piston kinematics of the bent-axis pump: Hong & Doh (2004) eqs. (1), (2) and derivatives.

Frames and conventions
----------------------
The shaft (flange) axis is Z of the global frame XYZ; the barrel axis z' is inclined by
delta in the XZ plane and meets Z in the drive-flange plane (point O). The barrel turns with
the shaft (1:1 bevel gears). Everything here is written in the *bore frame* of one piston:
x = radial (outward) direction of that bore, y = tangential, z = barrel axis z', rotating with
the barrel. ``phi`` is the piston's phase angle, the shaft angle plus 2*pi*i/N for piston i;
phi = 0 is bottom dead centre (chamber largest), phi = pi top dead centre.

All derivatives are exact (closed form) with respect to phi; at a constant shaft speed
omega [rad/s] a time derivative is omega * d/dphi and a second one omega**2 * d2/dphi2, so
this module is speed-free and the dynamics scale its vectors by omega and omega**2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .pump_parameters import Geometry

__all__ = ['PistonKinematics', 'head_position', 'joint_position', 'piston_kinematics']


def joint_position(geom: Geometry, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Spherical-joint centre B in the bore frame and its phi-derivatives (Fig. 2(a)).

    The joint turns with the flange on a circle of radius R_S about Z; seen from the bore
    frame it is ``R_S (cos^2 phi cos d + sin^2 phi, sin phi cos phi (1 - cos d),
    -cos phi sin d)`` with d the barrel inclination.

    Parameters
    ----------
    geom : Geometry
        Pump geometry.
    phi : ndarray, shape (n,)
        Piston phase angle [rad].

    Returns
    -------
    tuple of ndarray, each shape (n, 3)
        B [m], dB/dphi [m/rad], d2B/dphi2 [m/rad^2].

    """
    r_s = geom.joint_pitch_radius_m
    cd, sd = np.cos(geom.inclination_rad), np.sin(geom.inclination_rad)
    c, s = np.cos(phi), np.sin(phi)
    c2, s2 = np.cos(2.0 * phi), np.sin(2.0 * phi)
    pos = r_s * np.stack([c * c * cd + s * s, s * c * (1.0 - cd), -c * sd], axis=-1)
    d1 = r_s * np.stack([(1.0 - cd) * s2, (1.0 - cd) * c2, s * sd], axis=-1)
    d2 = r_s * np.stack([2.0 * (1.0 - cd) * c2, -2.0 * (1.0 - cd) * s2, c * sd], axis=-1)
    return pos, d1, d2


def head_position(geom: Geometry, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Position s of the piston-head centre A along its bore axis, and phi-derivatives.

    A = (R_C, 0, s) in the bore frame and |A - B| = L (the rod length) give the closed form
    ``s = -R_S sin d cos phi + sqrt(Q0 + Q1 cos^2 phi)``, the exact solution of the
    constraint behind eqs. (1)-(2). Since Q depends on cos^2 phi only,
    s(pi) - s(0) = 2 R_S sin d: the stroke is independent of L and R_C.

    Parameters
    ----------
    geom : Geometry
        Pump geometry.
    phi : ndarray, shape (n,)
        Piston phase angle [rad].

    Returns
    -------
    tuple of ndarray, each shape (n,)
        s [m], ds/dphi [m/rad], d2s/dphi2 [m/rad^2].

    """
    r_s, r_c, rod = geom.joint_pitch_radius_m, geom.bore_pitch_radius_m, geom.rod_length_m
    cd, sd = np.cos(geom.inclination_rad), np.sin(geom.inclination_rad)
    b = r_s * sd
    k1 = r_c**2 - 2.0 * r_c * r_s * cd + r_s**2  # |A0 - B|^2 coefficient of cos^2 phi
    k2 = (r_c - r_s) ** 2  # ... and of sin^2 phi
    q0 = rod**2 - k2
    q1 = b**2 - k1 + k2
    c, s = np.cos(phi), np.sin(phi)
    q = q0 + q1 * c * c
    dq = -q1 * np.sin(2.0 * phi)
    d2q = -2.0 * q1 * np.cos(2.0 * phi)
    root = np.sqrt(q)
    pos = -b * c + root
    d1 = b * s + dq / (2.0 * root)
    d2 = b * c + d2q / (2.0 * root) - dq * dq / (4.0 * q * root)
    return pos, d1, d2


@dataclass(frozen=True)
class PistonKinematics:
    """
    Speed-free kinematics of one piston over its phase angle, in the bore frame.

    Multiply ``*_per_speed`` by omega [rad/s] and ``*_per_speed2`` by omega**2 to get the
    quantity at a constant shaft speed omega (either sign).
    """

    phi_rad: np.ndarray  # (n,)
    head_pos_m: np.ndarray  # s (n,)
    head_vel_per_speed: np.ndarray  # ds/dphi [m/rad] (n,)
    head_acc_per_speed2: np.ndarray  # d2s/dphi2 [m/rad^2] (n,)
    joint_pos_m: np.ndarray  # B (n, 3)
    rod_dir: np.ndarray  # unit vector d from B to A (n, 3)
    omega_rel_per_speed: np.ndarray  # piston angular velocity relative to the barrel (n, 3)
    omega_abs_per_speed: np.ndarray  # absolute piston angular velocity (n, 3)
    alpha_abs_per_speed2: np.ndarray  # absolute piston angular acceleration (n, 3)
    cg_acc_per_speed2: np.ndarray  # absolute acceleration of the centre of mass G (n, 3)
    flange_axis: np.ndarray  # unit Z (shaft axis) in the bore frame (n, 3)


def piston_kinematics(geom: Geometry, phi: np.ndarray, joint_to_cg_m: float) -> PistonKinematics:
    """
    Piston kinematics from eqs. (1), (2) and (8), exact in phi.

    Eq. (1) V_B = V_A + w x R_BA with eq. (2) w . R_BA = 0 give, with d = (A - B)/L,
    w = d x dd/dt (the angular velocity relative to the barrel) and V'_A = ds/dt along the
    bore. The absolute angular velocity adds the barrel's omega z'; accelerations follow by
    differentiating in the rotating bore frame (Coriolis and centripetal terms included),
    eq. (8) for the centre of mass.

    Parameters
    ----------
    geom : Geometry
        Pump geometry.
    phi : ndarray, shape (n,)
        Piston phase angle [rad].
    joint_to_cg_m : float
        Distance from the joint centre B to the piston's centre of mass G along the rod [m].

    Returns
    -------
    PistonKinematics
        Arrays over phi, scaled to unit shaft speed.

    """
    phi = np.asarray(phi, dtype=float)
    b, db, d2b = joint_position(geom, phi)
    s, ds, d2s = head_position(geom, phi)
    rod = geom.rod_length_m
    zeros = np.zeros_like(phi)
    a = np.stack([np.full_like(phi, geom.bore_pitch_radius_m), zeros, s], axis=-1)
    da = np.stack([zeros, zeros, ds], axis=-1)
    d2a = np.stack([zeros, zeros, d2s], axis=-1)
    d = (a - b) / rod
    dd = (da - db) / rod
    d2d = (d2a - d2b) / rod
    z = np.array([0.0, 0.0, 1.0])

    omega_rel = np.cross(d, dd)  # eqs. (1)-(2): w = d x d'
    omega_abs = z + omega_rel
    # d/dt of omega_abs in the inertial frame = rotating-frame derivative + z x omega_abs
    alpha_abs = np.cross(d, d2d) + np.cross(z, omega_rel)
    # eq. (8) written for the rotating frame: G = B + g d
    g = joint_to_cg_m
    r = b + g * d
    dr = db + g * dd
    d2r = d2b + g * d2d
    cg_acc = d2r + 2.0 * np.cross(z, dr) + np.cross(z, np.cross(z, r))
    sd, cd = np.sin(geom.inclination_rad), np.cos(geom.inclination_rad)
    flange_axis = np.stack([sd * np.cos(phi), -sd * np.sin(phi), np.full_like(phi, cd)],
                           axis=-1)
    return PistonKinematics(
        phi_rad=phi,
        head_pos_m=s,
        head_vel_per_speed=ds,
        head_acc_per_speed2=d2s,
        joint_pos_m=b,
        rod_dir=d,
        omega_rel_per_speed=omega_rel,
        omega_abs_per_speed=omega_abs,
        alpha_abs_per_speed2=alpha_abs,
        cg_acc_per_speed2=cg_acc,
        flange_axis=flange_axis,
    )
