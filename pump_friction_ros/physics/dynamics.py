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
Piston dynamics, Hong & Doh (2004) eqs. (3)-(8), and the work-energy friction torques.

For each piston, operating point and phase angle the reaction on the head, F_A (in the
plane normal to the bore, eq. 4-5 notation), and on the spherical joint, F_B, follow from
Newton-Euler (eqs. 6-7) with the kinematics of ``kinematics``:

* moments about the joint centre B, projected on the two directions normal to the rod
  (the moment about the rod axis is the "no spin" constraint of eq. 2), give F_A from a
  2 x 2 linear system;
* the force balance, eq. (6), then gives F_B = m a_G - F_A - F_f - F_p.

The friction terms (eq. 3: joint moment against the joint's angular velocity; eqs. 4-5:
head force against V'_A and its moment) depend on |F_A| and |F_B|, so the system is solved by
fixed-point iteration; with friction coefficients below 0.1 it contracts by more than 10x
per step. The friction torque at the shaft is the dissipated power divided by the shaft
speed (work-energy method, sec. 5), computed per unit speed so it stays finite at rest.

Eq. (5) as printed pairs M_fAx' with F_Ax'; a moment about x' can only come from a force
along y', so the moment is taken as r_contact x F_f with the contact point at -R_A F_A/|F_A|,
which is eq. (5) with the force components on the axes where they act.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kinematics import PistonKinematics
from .pump_parameters import PumpParams

__all__ = ['PistonLoads', 'joint_angular_velocity_per_speed', 'solve_piston_loads']

_X = np.array([1.0, 0.0, 0.0])
_Y = np.array([0.0, 1.0, 0.0])
_Z = np.array([0.0, 0.0, 1.0])
_DEAD_CENTRE_SCALE_M = 1e-7
"""ds/dphi [m/rad] over which the head friction turns round at a dead centre (~1e-5 rad)."""


@dataclass(frozen=True)
class PistonLoads:
    """Loads on one piston over its phase angle, for each operating point (shape (m, n))."""

    head_force_n: np.ndarray  # F_A in the bore frame (m, n, 3); z component is 0
    joint_force_n: np.ndarray  # F_B on the piston, bore frame (m, n, 3)
    head_friction_n: np.ndarray  # F_f along the bore axis, signed (m, n)
    joint_friction_torque_nm: np.ndarray  # joint dissipation / |omega| (m, n)
    head_friction_torque_nm: np.ndarray  # head dissipation / |omega| (m, n)
    joint_sliding_speed_m_s: np.ndarray  # (m, n)
    head_sliding_speed_m_s: np.ndarray  # (m, n)
    moment_residual_nm: np.ndarray  # residual of the projected moment balance (m, n)
    spin_moment_nm: np.ndarray  # constraint moment about the rod axis (eq. 2), on the piston


def joint_angular_velocity_per_speed(params: PumpParams, kin: PistonKinematics) -> np.ndarray:
    """
    Angular velocity of the sliding in the spherical joint, per unit shaft speed.

    ``barrel`` (the paper's reading, sec. 2: 50 rad/s and 0.275 m/s at 10,000 rpm): the
    piston's angular velocity relative to the barrel. ``flange``: relative to the drive
    flange that holds the joint socket, i.e. absolute piston velocity minus the flange's
    omega Z; this includes the barrel-flange relative rotation of about omega sin(delta).

    Parameters
    ----------
    params : PumpParams
        Pump parameters (``piston_friction.joint_sliding_frame``).
    kin : PistonKinematics
        Piston kinematics.

    Returns
    -------
    ndarray, shape (n, 3)
        Joint angular velocity per unit shaft speed [rad/rad].

    """
    if params.piston_friction.joint_sliding_frame == 'flange':
        return kin.omega_abs_per_speed - kin.flange_axis
    return kin.omega_rel_per_speed


def _inertial_moment_per_speed2(params: PumpParams, kin: PistonKinematics) -> np.ndarray:
    """Right-hand side of eq. (7) about B per unit omega^2: I_G alpha + w x I_G w + BG x m a_G."""
    pis = params.piston
    d = kin.rod_dir
    w = kin.omega_abs_per_speed
    al = kin.alpha_abs_per_speed2
    i_t, i_a = pis.inertia_transverse_kg_m2, pis.inertia_axial_kg_m2
    d_al = np.sum(d * al, axis=-1, keepdims=True)
    d_w = np.sum(d * w, axis=-1, keepdims=True)
    # axisymmetric piston: I_G = I_t (1 - d d^T) + I_a d d^T
    i_alpha = i_t * al + (i_a - i_t) * d_al * d
    gyro = (i_a - i_t) * d_w * np.cross(w, d)
    transfer = pis.mass_kg * pis.joint_to_cg_m * np.cross(d, kin.cg_acc_per_speed2)
    return i_alpha + gyro + transfer


def solve_piston_loads(params: PumpParams, kin: PistonKinematics, speed_rad_s: np.ndarray,
                       chamber_pressure_pa: np.ndarray, iterations: int = 6) -> PistonLoads:
    """
    Reaction and friction loads of one piston, eqs. (3)-(8).

    Parameters
    ----------
    params : PumpParams
        Pump parameters.
    kin : PistonKinematics
        Kinematics over the phase angle (n samples).
    speed_rad_s : ndarray, shape (m,)
        Shaft speed [rad/s], either sign; 0 gives the quasi-static limit of positive speed.
    chamber_pressure_pa : ndarray, shape (m, n)
        Chamber pressure over the phase angle [Pa].
    iterations : int
        Fixed-point iterations on the friction terms.

    Returns
    -------
    PistonLoads
        Loads and per-piston friction torques.

    """
    geom, pis, fr = params.geometry, params.piston, params.piston_friction
    omega = np.asarray(speed_rad_s, dtype=float)[:, None]  # (m, 1)
    sgn_omega = np.where(omega >= 0.0, 1.0, -1.0)
    omega2 = omega * omega
    rod = geom.rod_length_m
    area = geom.piston_area_m2

    # friction coefficients from the sliding speeds (Fig. 9)
    w_joint = joint_angular_velocity_per_speed(params, kin)  # (n, 3)
    w_joint_norm = np.linalg.norm(w_joint, axis=-1)  # (n,)
    joint_speed = geom.joint_ball_radius_m * np.abs(omega) * w_joint_norm  # (m, n)
    head_speed = np.abs(omega * kin.head_vel_per_speed)  # (m, n)
    mu_b = fr.joint_coefficient(joint_speed)
    mu_a = fr.head_coefficient(head_speed)
    # direction of V'_A (m, n); continuous through the dead centres, where ds/dphi = 0 and a
    # plain sign() would depend on round-off
    head_dir = sgn_omega * np.tanh(kin.head_vel_per_speed / _DEAD_CENTRE_SCALE_M)

    # basis normal to the rod: e1 in the plane of x and d, e2 = d x e1
    e1 = _X - np.sum(kin.rod_dir * _X, axis=-1, keepdims=True) * kin.rod_dir
    e1 /= np.linalg.norm(e1, axis=-1, keepdims=True)
    e2 = np.cross(kin.rod_dir, e1)
    d_x_x = np.cross(kin.rod_dir, _X)
    d_x_y = np.cross(kin.rod_dir, _Y)
    d_x_z = np.cross(kin.rod_dir, _Z)[None]  # (1, n, 3)
    k = geom.head_radius_m * mu_a * head_dir  # head friction moment gain (m, n)
    # columns of F_A = a_r x + a_t y in:  L d x F_A + k F_A x z  (F_A x z = (a_t, -a_r, 0))
    m11 = rod * np.sum(e1 * d_x_x, -1) - k * e1[:, 1]
    m12 = rod * np.sum(e1 * d_x_y, -1) + k * e1[:, 0]
    m21 = rod * np.sum(e2 * d_x_x, -1) - k * e2[:, 1]
    m22 = rod * np.sum(e2 * d_x_y, -1) + k * e2[:, 0]
    det = m11 * m22 - m12 * m21

    # Everything geometric is projected once on e1, e2 (normal to the rod) and d, so that the
    # iteration below works on (m, n) scalars only.
    h = _inertial_moment_per_speed2(params, kin)  # (n, 3)
    h1, h2, hd = (np.sum(h * e, -1) for e in (e1, e2, kin.rod_dir))
    dz1, dz2 = np.sum(d_x_z[0] * e1, -1), np.sum(d_x_z[0] * e2, -1)
    unit_joint = w_joint / np.maximum(w_joint_norm, 1e-300)[:, None]
    j1, j2, jd = (np.sum(unit_joint * e, -1) for e in (e1, e2, kin.rod_dir))
    mag = pis.mass_kg * kin.cg_acc_per_speed2  # (n, 3)
    inertia_x, inertia_y, inertia_z = (omega2 * mag[:, i] for i in range(3))
    pressure_force = -chamber_pressure_pa * area  # along z (m, n)
    joint_gain = geom.joint_ball_radius_m * mu_b * sgn_omega  # |F_B| -> joint moment (m, n)

    head_force_abs = np.zeros_like(chamber_pressure_pa)
    joint_force_abs = np.sqrt(inertia_x**2 + inertia_y**2 + (inertia_z - pressure_force) ** 2)
    for _ in range(iterations):
        axial = pressure_force - head_dir * mu_a * head_force_abs  # F_p + F_f along z
        jm = joint_gain * joint_force_abs
        r1 = omega2 * h1 - rod * axial * dz1 + jm * j1
        r2 = omega2 * h2 - rod * axial * dz2 + jm * j2
        a_r = (r1 * m22 - m12 * r2) / det
        a_t = (m11 * r2 - m21 * r1) / det
        head_force_abs = np.hypot(a_r, a_t)
        fx, fy, fz = inertia_x - a_r, inertia_y - a_t, inertia_z - axial
        joint_force_abs = np.sqrt(fx * fx + fy * fy + fz * fz)

    head_friction = -head_dir * mu_a * head_force_abs
    axial = pressure_force + head_friction
    jm = joint_gain * joint_force_abs
    residual = np.hypot(m11 * a_r + m12 * a_t - (omega2 * h1 - rod * axial * dz1 + jm * j1),
                        m21 * a_r + m22 * a_t - (omega2 * h2 - rod * axial * dz2 + jm * j2))
    head_force = np.stack([a_r, a_t, np.zeros_like(a_r)], axis=-1)
    joint_force = np.stack([fx, fy, fz], axis=-1)
    # eq. (2) forbids spin relative to the barrel: the barrel supplies whatever moment about
    # the rod axis the balance about B lacks (M_fA = k (F_A x z); (L d x F_A) . d = 0)
    d = kin.rod_dir
    spin = omega2 * hd + jm * jd - k * (a_t * d[:, 0] - a_r * d[:, 1])

    joint_torque = geom.joint_ball_radius_m * mu_b * joint_force_abs * w_joint_norm
    # head moment M_fA = R_A mu_A sgn(V'_A) (F_A x z); dissipation = -(F_f V'_A + M_fA . w_rel)
    m_fa_dot_w = k * (a_t * kin.omega_rel_per_speed[:, 0] - a_r * kin.omega_rel_per_speed[:, 1])
    head_torque = (mu_a * head_force_abs * np.abs(kin.head_vel_per_speed)
                   - sgn_omega * m_fa_dot_w)
    return PistonLoads(
        head_force_n=head_force,
        joint_force_n=joint_force,
        head_friction_n=head_friction,
        joint_friction_torque_nm=joint_torque,
        head_friction_torque_nm=head_torque,
        joint_sliding_speed_m_s=joint_speed,
        head_sliding_speed_m_s=head_speed,
        moment_residual_nm=residual,
        spin_moment_nm=spin,
    )
