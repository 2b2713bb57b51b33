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

"""Piston dynamics (eqs. 3-8): closed forms without friction and inertia; energy balance."""

import dataclasses

import numpy as np
from pump_friction_ros.physics.dynamics import joint_angular_velocity_per_speed, solve_piston_loads
from pump_friction_ros.physics.pressure import chamber_pressure
from pump_friction_ros.physics.pump_parameters import Curve
import pytest

AREA = np.pi / 4 * 9.5e-3**2  # Table 1 bore


def _frictionless_massless(params):
    zero = Curve((0.0,), (0.0,))
    return dataclasses.replace(
        params,
        piston=dataclasses.replace(params.piston, mass_kg=1e-12, inertia_axial_kg_m2=0.0,
                                   inertia_transverse_kg_m2=0.0),
        piston_friction=dataclasses.replace(params.piston_friction, joint_coefficient=zero,
                                            head_coefficient=zero))


def test_without_friction_and_inertia_the_piston_is_a_two_force_member(paper_model):
    params = _frictionless_massless(paper_model.params)
    kin = paper_model.kin
    p = np.full((1, kin.phi_rad.size), 300e5)
    loads = solve_piston_loads(params, kin, np.array([1000.0]), p)
    d = kin.rod_dir
    # F_B along the rod with axial component p A_p; F_A = p A_p tan(gamma) sideways
    np.testing.assert_allclose(np.linalg.norm(loads.joint_force_n[0], axis=-1),
                               300e5 * AREA / d[:, 2], rtol=1e-9)
    lateral = np.hypot(d[:, 0], d[:, 1]) / d[:, 2]
    np.testing.assert_allclose(np.linalg.norm(loads.head_force_n[0], axis=-1),
                               300e5 * AREA * lateral, rtol=1e-7)


def test_joint_force_follows_pressure_times_piston_area(paper_model):
    """Sec. 4.4: F_B is 'mainly dependent on the cylinder chamber pressure'."""
    res = paper_model.evaluate(500 * np.pi / 30, 300e5, waveforms=True)
    assert res.joint_force_max_n[0] == pytest.approx(300e5 * AREA, rel=0.01)


def test_fixed_point_iteration_converges(paper_model):
    kin = paper_model.kin
    pc = chamber_pressure(kin.phi_rad, np.array([350e5, -350e5]), 0.0,
                          paper_model.params.valve_plate.bridge_angle_rad)
    loads = solve_piston_loads(paper_model.params, kin, np.array([1300.0, -1300.0]), pc)
    assert loads.moment_residual_nm.max() < 1e-9


def _shaft_torque_balance(params, kin, speed, dp):
    """Mean shaft torque by direct moments on flange and barrel, and by energy."""
    pc = chamber_pressure(kin.phi_rad, np.array([dp]), 0.0, params.valve_plate.bridge_angle_rad)
    loads = solve_piston_loads(params, kin, np.array([speed]), pc)
    fb, fa = loads.joint_force_n[0], loads.head_force_n[0]
    g = params.geometry
    wj = joint_angular_velocity_per_speed(params, kin)
    wj_norm = np.linalg.norm(wj, axis=-1)
    mu_b = params.piston_friction.joint_coefficient(g.joint_ball_radius_m * abs(speed) * wj_norm)
    m_fb = -(g.joint_ball_radius_m * mu_b * np.linalg.norm(fb, axis=-1))[:, None] \
        * np.sign(speed) * wj / wj_norm[:, None]
    # torque the shaft supplies to the flange (about Z) and, via the gears, to the barrel
    flange = np.sum((np.cross(kin.joint_pos_m, fb) + m_fb) * kin.flange_axis, axis=-1)
    barrel = g.bore_pitch_radius_m * fa[:, 1] + loads.spin_moment_nm[0] * kin.rod_dir[:, 2]
    direct = float(np.mean(flange + barrel))
    fluid = float(np.mean(pc[0] * g.piston_area_m2 * kin.head_vel_per_speed))
    dissipated = float(np.mean(loads.joint_friction_torque_nm[0]
                               + loads.head_friction_torque_nm[0]))
    return direct, fluid + np.sign(speed) * dissipated, dissipated


@pytest.mark.parametrize(('speed', 'dp'), [(1047.2, 300e5), (300.0, 100e5), (-500.0, 200e5),
                                           (700.0, -250e5)])
def test_shaft_power_equals_fluid_power_plus_dissipation(consistent_model, speed, dp):
    """Conservation: direct moments on flange and barrel vs work-energy, per piston."""
    direct, energy, dissipated = _shaft_torque_balance(consistent_model.params,
                                                       consistent_model.kin, speed, dp)
    assert dissipated > 1e-3
    assert direct == pytest.approx(energy, abs=1e-9)


def test_paper_reading_of_joint_sliding_breaks_the_energy_balance(paper_model):
    """The paper's joint slides relative to the barrel, not the flange holding its socket."""
    direct, energy, _ = _shaft_torque_balance(paper_model.params, paper_model.kin,
                                              1047.2, 300e5)
    assert abs(direct - energy) > 1e-3
