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

"""Whole-model behaviour: symmetry, four quadrants, scaling laws, theoretical torque."""

import math

import numpy as np
from pump_friction_ros.physics.dynamics import solve_piston_loads
from pump_friction_ros.physics.kinematics import piston_kinematics
from pump_friction_ros.physics.model import COMPONENTS, PumpModel
from pump_friction_ros.physics.pressure import chamber_pressure
import pytest

RPM = math.pi / 30


def test_theoretical_torque_is_displacement_times_pressure_over_two_pi(paper_model):
    v_g = 5 * math.pi / 4 * 9.5e-3**2 * 2 * 10.75e-3 * math.sin(math.radians(40))
    res = paper_model.evaluate(1000.0, np.array([300e5, -136e5]))
    np.testing.assert_allclose(res.theoretical_nm, v_g * np.array([300e5, -136e5]) / (2 * math.pi))
    assert v_g == pytest.approx(4.898e-6, rel=1e-3)


def test_mean_pressure_torque_over_a_revolution_is_close_to_theoretical(paper_model):
    """
    Kinematic torque sum_i p_i A_p ds_i/dphi averages to V_g dp / 2 pi.

    Less the small pre-compression loss over the bridges.
    """
    res = paper_model.evaluate(1000.0, 300e5, waveforms=True)
    mean = res.waveforms.pressure_torque_nm[0].mean()
    assert mean == pytest.approx(res.theoretical_nm[0], rel=0.02)
    assert mean < res.theoretical_nm[0]


def test_summed_waveform_equals_pistons_evaluated_at_their_own_phase(paper_model):
    """Five-fold periodicity from first principles: piston i evaluated at theta + 72 deg i."""
    p = paper_model.params
    theta = paper_model.phi
    speed, dp = 900.0, 250e5
    res = paper_model.evaluate(speed, dp, waveforms=True)
    total = np.zeros_like(theta)
    for i in range(5):
        phi = theta + 2 * math.pi * i / 5
        kin = piston_kinematics(p.geometry, phi, p.piston.joint_to_cg_m)
        pc = chamber_pressure(phi, np.array([dp]), 0.0, p.valve_plate.bridge_angle_rad)
        total += solve_piston_loads(p, kin, np.array([speed]), pc).joint_friction_torque_nm[0]
    np.testing.assert_allclose(res.waveforms.spherical_joints_nm[0], total, rtol=1e-9)
    shift = len(theta) // 5
    friction = res.waveforms.friction_nm[0]
    np.testing.assert_allclose(np.roll(friction, shift), friction, rtol=1e-9)
    spectrum = np.abs(np.fft.rfft(friction))
    harmonics = np.arange(spectrum.size)
    assert spectrum[(harmonics % 5 != 0)].max() < 1e-9 * spectrum[0]


def test_reversing_speed_and_pressure_mirrors_the_pump(paper_model):
    """(w, dp) -> (-w, -dp) is the mirror image of the pump: same magnitudes, opposite torque."""
    speeds = np.array([50.0, 400.0, 1000.0])
    dps = np.array([20e5, 150e5, 300e5])
    fwd = paper_model.evaluate(speeds, dps)
    rev = paper_model.evaluate(-speeds, -dps)
    for c in COMPONENTS:
        np.testing.assert_allclose(rev.magnitudes_nm[c], fwd.magnitudes_nm[c], rtol=1e-9)
    np.testing.assert_allclose(rev.input_nm, -fwd.input_nm, rtol=1e-9)
    np.testing.assert_allclose(rev.efficiency, fwd.efficiency, rtol=1e-9)


def test_motoring_friction_reduces_shaft_torque_and_efficiency_is_output_over_ideal(paper_model):
    pump = paper_model.evaluate(600.0, 200e5)
    motor = paper_model.evaluate(-600.0, 200e5)
    assert motor.theoretical_nm[0] == pump.theoretical_nm[0] > 0
    # same friction within the small direction-dependent terms (Coriolis, head friction)
    assert motor.friction_magnitude_nm[0] == pytest.approx(pump.friction_magnitude_nm[0],
                                                           rel=0.02)
    assert motor.input_nm[0] == pytest.approx(motor.theoretical_nm[0]
                                              - motor.friction_magnitude_nm[0])
    assert pump.efficiency[0] == pytest.approx(pump.theoretical_nm[0] / pump.input_nm[0])
    assert motor.efficiency[0] == pytest.approx(motor.input_nm[0] / motor.theoretical_nm[0])


def test_input_torque_changes_smoothly_through_zero_speed(paper_model):
    speeds = np.linspace(-20.0, 20.0, 401)
    res = paper_model.evaluate(speeds, 100e5)
    tin = res.input_nm
    # friction opposes motion on both sides (not monotonic: the coulomb curve falls with
    # speed, Stribeck-like), and there is no jump: < 20 mNm per 0.1 rad/s
    np.testing.assert_array_equal(np.sign(tin - res.theoretical_nm), np.sign(speeds))
    assert np.abs(np.diff(tin)).max() < 0.02
    assert tin[200] == pytest.approx(res.theoretical_nm[200], abs=1e-12)
    far = paper_model.evaluate(np.array([-8.0, 8.0]), 100e5)
    np.testing.assert_allclose(far.direction, [-np.tanh(4.0), np.tanh(4.0)])


def test_efficiency_is_undefined_near_zero_speed_or_pressure(paper_model):
    op = paper_model.params.operation
    res = paper_model.evaluate(np.array([0.0, 0.5 * op.efficiency_min_speed_rad_s, 500.0,
                                         500.0]),
                               np.array([100e5, 100e5, 0.0, 100e5]))
    assert np.isnan(res.efficiency[:3]).all()
    assert 0.5 < res.efficiency[3] < 1.0


def test_piston_torques_scale_with_pressure_at_low_speed(paper_model):
    res = paper_model.evaluate(300 * RPM, np.array([150e5, 300e5]))
    for c in ('spherical_joints', 'piston_heads'):
        assert res.magnitudes_nm[c][1] / res.magnitudes_nm[c][0] == pytest.approx(2.0, rel=0.01)


def test_viscous_losses_follow_viscosity(paper_model):
    """Valve-plate film torque ~ nu, bearing viscous torque ~ nu^(2/3), at zero load."""
    w = 6000 * RPM
    lo = paper_model.evaluate(w, 0.0, 30e-6)
    hi = paper_model.evaluate(w, 0.0, 60e-6)
    vp_ratio = hi.magnitudes_nm['valve_plate'][0] / lo.magnitudes_nm['valve_plate'][0]
    assert vp_ratio == pytest.approx(2.0, rel=1e-9)  # coulomb term is zero at 0 bar
    b = paper_model.params.bearing
    d_mm = b.mean_diameter_m * 1e3
    visc = [1e-7 * b.f0 * (nu * 6000) ** (2 / 3) * d_mm**3 * 1e-3 for nu in (30, 60)]
    delta = hi.magnitudes_nm['bearing'][0] - lo.magnitudes_nm['bearing'][0]
    assert delta == pytest.approx(visc[1] - visc[0], rel=1e-6)


def test_friction_torque_times_speed_equals_dissipated_power(paper_model):
    """Mean friction torque x speed = mean dissipated power summed over the contacts."""
    p = paper_model.params
    speed, dp = 700.0, 200e5
    res = paper_model.evaluate(speed, dp, waveforms=True)
    wf = res.waveforms
    kin = paper_model.kin
    pc = chamber_pressure(kin.phi_rad, np.array([dp]), 0.0, p.valve_plate.bridge_angle_rad)
    loads = solve_piston_loads(p, kin, np.array([speed]), pc)
    fr = p.piston_friction
    g = p.geometry
    # power at each contact from its own force and sliding velocity
    joint_power = (g.joint_ball_radius_m * fr.joint_coefficient(loads.joint_sliding_speed_m_s[0])
                   * np.linalg.norm(loads.joint_force_n[0], axis=-1)
                   * speed * np.linalg.norm(kin.omega_rel_per_speed, axis=-1))
    head_power = -loads.head_friction_n[0] * speed * kin.head_vel_per_speed
    dissipated = 5 * (joint_power.mean() + head_power.mean()) \
        + speed * (wf.valve_plate_nm[0].mean() + wf.bearing_nm[0].mean())
    friction_power = res.friction_magnitude_nm[0] * speed
    # the head-moment term (M_fA . w_rel) is the only piece not in this sum: it is tiny
    assert friction_power == pytest.approx(dissipated, rel=2e-3)


def test_angle_resolution_does_not_change_the_means(paper_params):
    coarse = PumpModel(paper_params, n_angles=120).evaluate(800.0, 200e5)
    fine = PumpModel(paper_params, n_angles=1800).evaluate(800.0, 200e5)
    for c in COMPONENTS:
        assert coarse.magnitudes_nm[c][0] == pytest.approx(fine.magnitudes_nm[c][0], rel=2e-3)


def test_model_rejects_non_finite_inputs_and_bad_angle_counts(paper_model, paper_params):
    with pytest.raises(ValueError, match='finite'):
        paper_model.evaluate(np.nan, 1e5)
    with pytest.raises(ValueError, match='viscosity'):
        paper_model.evaluate(100.0, 1e5, -1e-6)
    with pytest.raises(ValueError, match='multiple'):
        PumpModel(paper_params, n_angles=362)


def test_mean_only_path_equals_the_mean_of_the_waveforms(paper_model):
    speeds = np.array([-900.0, 30.0, 1200.0])
    dps = np.array([120e5, -300e5, 50e5])
    fast = paper_model.evaluate(speeds, dps)
    wf = paper_model.evaluate(speeds, dps, waveforms=True).waveforms
    for c in COMPONENTS:
        np.testing.assert_allclose(fast.magnitudes_nm[c], getattr(wf, f'{c}_nm').mean(axis=1),
                                   rtol=1e-12)


# -- any piston count (issue 11): 5, 7 and 9 pistons against the classic ripple formula -----

def pump_with(paper_raw, n, bore_pitch_radius_m=None, bore_diameter_m=None,
              narrow_ports=False):
    """
    Return the paper pump redrawn with ``n`` pistons (validated like a pump file).

    ``narrow_ports`` shrinks the bridges to 0.6 deg, so that chambers switch pressure at the
    dead centres as the closed-form ripple assumes.
    """
    import copy

    from pump_friction_ros.physics.pump_parameters import pump_from_mapping

    raw = copy.deepcopy(paper_raw)
    g = raw['geometry']
    g['n_pistons'] = n
    if bore_pitch_radius_m is not None:
        g['bore_pitch_radius_m'] = bore_pitch_radius_m
    if bore_diameter_m is not None:
        g['bore_diameter_m'] = bore_diameter_m
    if narrow_ports:
        raw['valve_plate'].update(port_inner_radius_m=9.45e-3, port_outer_radius_m=9.55e-3)
    return pump_from_mapping(raw, f'{n} pistons')


@pytest.fixture(scope='module')
def paper_raw():
    import yaml

    from .conftest import PAPER_PUMP
    return yaml.safe_load(PAPER_PUMP.read_text())


def ripple(model, speed=1000.0, dp=200e5):
    res = model.evaluate(speed, dp, waveforms=True)
    torque = res.waveforms.pressure_torque_nm[0]
    return res, (torque.max() - torque.min()) / torque.mean(), torque.mean()


@pytest.mark.parametrize('n', [5, 6, 7, 9])
def test_any_piston_count_follows_the_closed_form_ripple_and_mean(paper_raw, n):
    """
    Ideal switching: (max - min) / mean = pi/(2N) tan(pi/(4N)) for odd N, pi/N tan(pi/(2N)).

    The paper's barrel (R_C = R_S (1 + cos delta) / 2: near-sinusoidal strokes), with
    bores as wide as fit on its pitch circle (at most the paper's 9.5 mm).
    """
    r_c, r_s, delta = 9.5e-3, 10.75e-3, math.radians(40.0)
    d = min(9.5e-3, 0.9 * 2 * r_c * math.sin(math.pi / n))
    model = PumpModel(pump_with(paper_raw, n, bore_diameter_m=d, narrow_ports=True))
    assert model.n_angles % n == 0 and model.n_angles >= 360  # the default angle grid
    res, got, mean = ripple(model)
    closed = (math.pi / (2 * n) * math.tan(math.pi / (4 * n)) if n % 2
              else math.pi / n * math.tan(math.pi / (2 * n)))
    assert got == pytest.approx(closed, rel=2e-3)
    v_g = n * math.pi / 4 * d**2 * 2 * r_s * math.sin(delta)  # N A_p 2 R_S sin(delta)
    assert mean == pytest.approx(v_g * 200e5 / (2 * math.pi), rel=2e-3)  # V_g dp / 2 pi
    assert res.theoretical_nm[0] == pytest.approx(v_g * 200e5 / (2 * math.pi), rel=2e-3)
    assert all(np.isfinite(res.magnitudes_nm[c][0]) and res.magnitudes_nm[c][0] > 0
               for c in COMPONENTS)


def test_nine_pistons_of_the_same_displacement_give_less_ripple_same_torque(paper_raw):
    """
    5, 7, 9 pistons of one displacement (bores 9.5 mm sqrt(5/N) on an 11.5 mm pitch circle).

    With the real 25.5 deg bridges the ripple falls with N, roughly as the closed form's
    1/N^2 (by (5/9)^2 = 0.31 from 5 to 9), while the mean theoretical torque stays
    V_g dp / 2 pi.
    """
    results = {n: ripple(PumpModel(pump_with(paper_raw, n, bore_pitch_radius_m=11.5e-3,
                                             bore_diameter_m=9.5e-3 * math.sqrt(5 / n))))
               for n in (5, 7, 9)}
    assert results[9][1] < results[7][1] < results[5][1]
    assert results[9][1] / results[5][1] < 0.31
    v_g = 5 * math.pi / 4 * 9.5e-3**2 * 2 * 10.75e-3 * math.sin(math.radians(40.0))
    for n, (res, _, mean) in results.items():
        assert res.theoretical_nm[0] == pytest.approx(v_g * 200e5 / (2 * math.pi), rel=1e-9)
        assert mean == pytest.approx(res.theoretical_nm[0], rel=1e-2), n  # bridges: < 1 %
        assert all(res.magnitudes_nm[c][0] > 0 for c in COMPONENTS), n


def test_angle_grid_is_a_multiple_of_the_piston_count():
    from pump_friction_ros.physics.model import angle_count
    assert [angle_count(n) for n in (3, 5, 7, 9, 11, 100)] == [360, 360, 364, 360, 363, 400]
    assert angle_count(7, 180) == 182  # the table's coarser grid
