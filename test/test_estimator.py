"""Torque estimator core and wear monitor, driven by simulated EHA streams."""

import itertools
import math

import numpy as np
import pytest

from pump_friction_ros.config import EstimatorConfig
from pump_friction_ros.estimator import COUNTERS, TorqueEstimator
from pump_friction_ros.monitor import ERROR, OK, STALE, WARN
from pump_friction_ros.oil import WaltherViscosity
from pump_friction_ros.simulate import DutyCycle, feed, simulate_duty_cycle, wear_step
from pump_friction_ros.table import build_table

NS = 1_000_000_000
CONFIG = EstimatorConfig(oil_viscosity_m2_s=46e-6, drive_loss_torque_nm=0.05)


@pytest.fixture(scope='module')
def table(paper_params):
    return build_table(paper_params)


def make(table, config=CONFIG):
    return TorqueEstimator(config, table, 46e-6, 'hong_doh_2004')


def test_expected_torque_at_steady_state_is_table_input_torque_plus_drive_loss(table):
    est = make(table)
    for k in range(200):
        est.on_pressure(k * NS // 1000, 150e5)
        e = est.on_joint_state(k * NS // 1000, 600.0, 20.0)
    ref = table.lookup(600.0, 150e5, 46e-6)
    assert e.inertia_nm == pytest.approx(0.0, abs=1e-12)
    assert e.expected_nm == pytest.approx(ref.input_nm + 0.05, rel=1e-12)
    assert e.theoretical_nm == pytest.approx(4.898e-6 * 150e5 / (2 * math.pi), rel=1e-3)
    assert e.residual_nm == pytest.approx(20.0 - e.expected_nm)
    assert e.efficiency == pytest.approx(e.theoretical_nm / (e.expected_nm - e.inertia_nm))


def test_filtered_derivative_follows_a_ramp_and_tames_noise(table):
    est = make(table)
    rng = np.random.default_rng(0)
    accel, accels = 2000.0, []
    for k in range(2000):  # 2 s at 1 kHz
        t = k / 1000
        est.on_pressure(k * NS // 1000, 100e5)
        e = est.on_joint_state(k * NS // 1000, 100.0 + accel * t + rng.normal(0, 1.0), None)
        accels.append(e.inertia_nm / CONFIG.rotor_inertia_kg_m2)
    steady = np.array(accels[500:])
    assert steady.mean() == pytest.approx(accel, rel=0.01)
    raw_noise = 1.0 * math.sqrt(2) / 1e-3  # std of a plain difference of the noisy speed
    assert steady.std() < 0.05 * raw_noise


def test_port_pressures_give_the_difference(table):
    est = make(table, EstimatorConfig(pressure_source='ports', oil_viscosity_m2_s=46e-6))
    est.on_port_pressure('a', 0, 180e5)
    assert est.on_speed(1000, 300.0) is None  # port b missing: stale
    est.on_port_pressure('b', 0, 30e5)
    e = est.on_speed(2000, 300.0)
    assert e.pressure_diff_pa == 150e5
    assert est.counts['stale_skips'] == 1


def test_viscosity_from_temperature_uses_the_walther_law(table):
    cfg = EstimatorConfig(viscosity_source='temperature')
    est = make(table, cfg)
    est.on_pressure(0, 100e5)
    assert est.on_speed(1, 300.0) is None  # no temperature yet
    est.on_temperature(2, 40.0)
    assert est.on_speed(3, 300.0).viscosity_m2_s == pytest.approx(46e-6, rel=1e-9)
    est.on_temperature(4, 100.0)
    est.on_pressure(4, 100e5)
    assert est.on_speed(5, 300.0).viscosity_m2_s == pytest.approx(6.8e-6, rel=1e-9)


def test_walther_law_matches_iso_vg_46_data():
    vg46 = WaltherViscosity(46e-6, 6.8e-6)
    temps = np.arange(0.0, 121.0, 5.0)
    nu = np.array([vg46(t) for t in temps])
    assert np.all(np.diff(nu) < 0)
    assert vg46(60.0) == pytest.approx(20.5e-6, rel=0.05)  # typical VG 46 datasheet value
    assert vg46(0.0) == pytest.approx(580e-6, rel=0.15)


def test_stale_inputs_skip_the_estimate_and_diagnostics_say_stale(table):
    est = make(table)
    assert est.diagnostics(0).level == STALE
    est.on_pressure(0, 100e5)
    assert est.on_speed(10_000_000, 300.0) is not None
    assert est.on_speed(100_000_000, 300.0) is None  # pressure 100 ms old > 50 ms
    assert est.counts['stale_skips'] == 1
    snap = est.diagnostics(100_000_000)
    assert snap.level == OK  # last estimate 90 ms ago < stale_timeout_s
    snap = est.diagnostics(700_000_000)
    assert snap.level == STALE and 'pressure' in snap.message
    est.on_pressure(710_000_000, 100e5)
    assert est.on_speed(720_000_000, 300.0) is not None
    assert est.diagnostics(720_000_000).level == OK


@pytest.mark.parametrize(('call', 'counter'), [
    (lambda e: e.on_speed(5, math.nan), 'rejected_non_finite'),
    (lambda e: e.on_pressure(5, math.inf), 'rejected_non_finite'),
    (lambda e: e.on_torque(5, -math.inf), 'rejected_non_finite'),
    (lambda e: e.on_speed(1, 300.0), 'rejected_out_of_order'),
    (lambda e: e.on_speed(2, 300.0), 'rejected_duplicate'),
    (lambda e: e.on_speed(5, 1e6), 'rejected_out_of_range'),
    (lambda e: e.on_pressure(5, 1e10), 'rejected_out_of_range'),
    (lambda e: e.on_temperature(5, 900.0), 'rejected_out_of_range'),
])
def test_bad_samples_are_rejected_counted_and_change_nothing(table, call, counter):
    est = make(table)
    est.on_pressure(0, 100e5)
    est.on_torque(0, 10.0)
    before = est.on_speed(2, 300.0)
    assert call(est) in (None, False)
    assert est.counts[counter] == 1
    assert est.last == before
    after = est.on_speed(10, 300.0)
    assert after is not None and after.pressure_diff_pa == 100e5


def test_output_decimation_publishes_every_nth_estimate(table):
    est = make(table, EstimatorConfig(output_decimation=4, oil_viscosity_m2_s=46e-6))
    flags = []
    for k in range(12):
        est.on_pressure(k * 1000, 100e5)
        flags.append(est.on_speed(k * 1000, 300.0).publish)
    assert flags == [True, False, False, False] * 3


def test_diagnostic_values_are_numbers_with_units_in_their_keys(table):
    est = make(table)
    est.on_pressure(0, 100e5)
    est.on_torque(0, 9.0)
    est.on_speed(1, 300.0)
    values = dict(est.diagnostics(2).values)
    assert values['level'] == '0' and values['level_name'] == 'OK'
    for key, text in values.items():
        if key == 'level_name':
            continue
        float(text)  # every other value parses as a number (PlotJuggler graphs them)
        assert key in COUNTERS or key in ('level', 'efficiency') or \
            key.endswith(('_nm', '_nm_s', '_pa', '_rad_s', '_m2_s', '_s', 'scale', '_std'))


def _feed(table, run, config=CONFIG):
    est = make(table, config)
    return est, feed(est, run)


def test_ten_minutes_of_nominal_noisy_data_at_1khz_raise_no_alarm(table):
    run = simulate_duty_cycle(table, DutyCycle(duration_s=600.0), seed=21)
    est, out = _feed(table, run)
    assert len(out) == run.t_s.size
    assert max(e.level for e in out) == OK
    assert est.monitor.cusum_pos_nm_s < 0.1 * CONFIG.cusum_warn_nm_s
    assert est.last.valve_plate_scale == pytest.approx(1.0, abs=0.05)
    assert est.monitor.theta_rest == pytest.approx(1.0, abs=0.05)
    assert est.counts['stale_skips'] == 0


def test_valve_plate_step_of_fifty_percent_is_flagged_and_attributed(table):
    """+50 % valve-plate friction at t = 30 s: WARN within 20 s, scale -> 1.5."""
    run = simulate_duty_cycle(table, DutyCycle(duration_s=180.0), seed=3,
                              wear=wear_step(30.0, 1.5))
    _, out = _feed(table, run)
    t = np.array([e.stamp_ns for e in out]) / NS
    level = np.array([e.level for e in out])
    assert level[t < 30.0].max() == OK
    first_warn = t[level >= WARN].min()
    assert 30.0 < first_warn < 50.0
    assert level[-1] == ERROR
    final = out[-1]
    assert final.valve_plate_scale == pytest.approx(1.5, abs=0.05)


def test_reversals_through_zero_speed_do_not_alarm(table):
    """A slow sinusoid through zero: friction flips sign each half period."""
    est = make(table)
    rng = np.random.default_rng(2)
    for k in range(60_000):  # 60 s at 1 kHz
        t = k / 1000
        speed = 400.0 * math.sin(2 * math.pi * t / 3.0)
        accel = 400.0 * 2 * math.pi / 3.0 * math.cos(2 * math.pi * t / 3.0)
        dp = 80e5 + 40e5 * math.sin(2 * math.pi * t / 11.0)
        truth = table.lookup(speed, dp, 46e-6).input_nm + 2e-4 * accel + \
            0.05 * math.tanh(speed / table.zero_speed_threshold_rad_s)
        est.on_pressure(k * NS // 1000, dp + rng.normal(0, 1e5))
        est.on_joint_state(k * NS // 1000, speed + rng.normal(0, 0.5),
                           truth + rng.normal(0, 0.05))
    assert est.monitor.level == OK
    assert est.monitor.cusum_pos_nm_s < 0.2 * CONFIG.cusum_warn_nm_s
    assert est.monitor.cusum_neg_nm_s < 0.2 * CONFIG.cusum_warn_nm_s


def test_alarm_clears_with_hysteresis_after_repair(table):
    run = simulate_duty_cycle(table, DutyCycle(duration_s=150.0), seed=5,
                              wear=lambda t: np.where((t > 10.0) & (t < 60.0), 1.6, 1.0))
    _, out = _feed(table, run)
    levels = [e.level for e in out]
    changes = sum(a != b for a, b in itertools.pairwise(levels))
    assert max(levels) >= WARN
    assert levels[-1] == OK
    assert changes <= 4  # OK -> WARN (-> ERROR -> WARN) -> OK, no chatter


def test_counters_cover_every_rejection(table):
    est = make(table)
    assert set(est.counts) == set(COUNTERS)
