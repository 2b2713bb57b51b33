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

"""Kinematics (eqs. 1, 2, 8) against the geometry's closed forms and numerical derivatives."""

import numpy as np
from pump_friction_ros.physics.kinematics import head_position, joint_position, piston_kinematics
import pytest

# Fig. 2(a) / Table 1, typed in from the paper (not read from the code's parameter file)
R_S, DELTA = 10.75e-3, np.radians(40.0)


def _world(points, phi, delta):
    """Bore-frame vectors to the fixed tilted frame (x', y', z') then to XYZ."""
    c, s = np.cos(phi), np.sin(phi)
    xp = points[..., 0] * c - points[..., 1] * s
    yp = points[..., 0] * s + points[..., 1] * c
    zp = points[..., 2]
    # x' = (cos d, 0, sin d), y' = (0, 1, 0), z' = (-sin d, 0, cos d)
    return np.stack([xp * np.cos(delta) - zp * np.sin(delta), yp,
                     xp * np.sin(delta) + zp * np.cos(delta)], axis=-1)


def test_rod_length_constraint_holds_at_every_angle(paper_params):
    g = paper_params.geometry
    phi = np.linspace(0, 2 * np.pi, 1001)
    b, _, _ = joint_position(g, phi)
    s, _, _ = head_position(g, phi)
    a = np.stack([np.full_like(phi, g.bore_pitch_radius_m), 0 * phi, s], axis=-1)
    np.testing.assert_allclose(np.linalg.norm(a - b, axis=-1), g.rod_length_m, rtol=1e-12)


def test_joint_moves_on_the_flange_circle(paper_params):
    g = paper_params.geometry
    phi = np.linspace(0, 2 * np.pi, 73)
    b, _, _ = joint_position(g, phi)
    world = _world(b, phi, g.inclination_rad)
    expected = R_S * np.stack([np.cos(phi), np.sin(phi), 0 * phi], axis=-1)
    np.testing.assert_allclose(world, expected, atol=1e-15)


def test_stroke_equals_twice_joint_radius_times_sine_of_inclination(paper_params):
    s, _, _ = head_position(paper_params.geometry, np.linspace(0, 2 * np.pi, 20001))
    assert s.max() - s.min() == pytest.approx(2 * R_S * np.sin(DELTA), rel=1e-9)
    assert paper_params.geometry.stroke_m == pytest.approx(13.82e-3, abs=0.005e-3)


@pytest.mark.parametrize('func', [head_position, joint_position])
def test_exact_derivatives_match_central_differences(paper_params, func):
    phi = np.linspace(0, 2 * np.pi, 4001)
    h = 1e-5
    pos, d1, d2 = func(paper_params.geometry, phi)
    plus, _, _ = func(paper_params.geometry, phi + h)
    minus, _, _ = func(paper_params.geometry, phi - h)
    np.testing.assert_allclose(d1, (plus - minus) / (2 * h), atol=1e-11)
    np.testing.assert_allclose(d2, (plus - 2 * pos + minus) / h**2, atol=1e-6)


def test_velocities_satisfy_eq1_and_eq2(paper_params):
    g = paper_params.geometry
    phi = np.linspace(0, 2 * np.pi, 721)
    kin = piston_kinematics(g, phi, 0.02)
    _, vb, _ = joint_position(g, phi)  # per unit speed, bore frame
    va = np.zeros_like(vb)
    va[:, 2] = kin.head_vel_per_speed
    r_ba = kin.joint_pos_m - (kin.joint_pos_m + g.rod_length_m * kin.rod_dir)
    w = kin.omega_rel_per_speed
    np.testing.assert_allclose(vb, va + np.cross(w, r_ba), atol=1e-14)  # eq. (1)
    np.testing.assert_allclose(np.sum(w * r_ba, axis=-1), 0.0, atol=1e-16)  # eq. (2)


def test_cg_acceleration_matches_second_difference_of_inertial_position(paper_params):
    """Eq. (8) with Coriolis and centripetal terms vs the inertial frame, differentiated twice."""
    g = paper_params.geometry
    joint_to_cg = 0.02
    omega = 1000.0
    t = np.linspace(0, 2 * np.pi / omega, 241)[:-1]
    h = 1e-7

    def cg_world(time):
        phi = omega * time
        kin = piston_kinematics(g, phi, joint_to_cg)
        return _world(kin.joint_pos_m + joint_to_cg * kin.rod_dir, phi, g.inclination_rad)

    acc_fd = (cg_world(t + h) - 2 * cg_world(t) + cg_world(t - h)) / h**2
    kin = piston_kinematics(g, omega * t, joint_to_cg)
    acc = _world(omega**2 * kin.cg_acc_per_speed2, omega * t, g.inclination_rad)
    np.testing.assert_allclose(acc, acc_fd, atol=2e-3 * np.abs(acc).max())


def test_angular_acceleration_is_derivative_of_inertial_angular_velocity(paper_params):
    g = paper_params.geometry
    omega = 800.0
    t = np.linspace(0, 2 * np.pi / omega, 181)[:-1]
    h = 1e-7

    def w_world(time):
        phi = omega * time
        kin = piston_kinematics(g, phi, 0.0)
        return _world(omega * kin.omega_abs_per_speed, phi, g.inclination_rad)

    alpha_fd = (w_world(t + h) - w_world(t - h)) / (2 * h)
    kin = piston_kinematics(g, omega * t, 0.0)
    alpha = _world(omega**2 * kin.alpha_abs_per_speed2, omega * t, g.inclination_rad)
    np.testing.assert_allclose(alpha, alpha_fd, atol=1e-4 * np.abs(alpha).max())


def test_head_speed_peak_is_close_to_the_harmonic_approximation(paper_params):
    omega = 10000 * 2 * np.pi / 60
    kin = piston_kinematics(paper_params.geometry, np.linspace(0, 2 * np.pi, 3601), 0.0)
    peak = np.abs(omega * kin.head_vel_per_speed).max()
    assert peak == pytest.approx(R_S * np.sin(DELTA) * omega, rel=0.01)
    assert peak == pytest.approx(7.0, rel=0.05)  # sec. 2: "approximately 7 m/s"
