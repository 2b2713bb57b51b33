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

"""Torque estimator core and wear monitor, driven by simulated EHA streams."""

import dataclasses
import itertools
import math

import numpy as np
from pump_friction_ros.core.estimator import COUNTERS, TorqueEstimator
from pump_friction_ros.core.inputs import InputKind as K
from pump_friction_ros.core.monitor import ERROR, OK, STALE, WARN
from pump_friction_ros.core.node_parameters import EstimatorConfig
from pump_friction_ros.physics.oil import WaltherViscosity
from pump_friction_ros.sim.duty_cycle import DutyCycle, simulate_duty_cycle, wear_step
from pump_friction_ros.table.friction_table import build_table
import pytest

NS = 1_000_000_000


def feed(estimator, run):
    """Feed a simulated run through `on_input` in time order, as the node would see it."""
    t_joint = np.round(run.t_s * 1e9).astype(np.int64)
    t_press = np.round(run.pressure_t_s * 1e9).astype(np.int64)
    events = sorted([(t, 0, k) for k, t in enumerate(t_press.tolist())]
                    + [(t, 1, k) for k, t in enumerate(t_joint.tolist())])  # pressure first
    out = []
    for stamp, is_joint, k in events:
        if is_joint:
            est = estimator.on_input(K.JOINT_STATE, stamp, float(run.speed_rad_s[k]),
                                     float(run.torque_nm[k]))
            if est is not None:
                out.append(est)
        else:
            estimator.on_input(K.LOAD_PRESSURE, stamp, float(run.pressure_diff_pa[k]))
    return out


class WithOilTemperature:
    """An estimator whose every pressure sample comes after the oil temperature at its stamp."""

    def __init__(self, estimator, celsius_at):
        self.estimator, self.celsius_at = estimator, celsius_at

    def on_input(self, kind, stamp, *values):
        if kind == K.LOAD_PRESSURE:
            self.estimator.on_input(K.OIL_TEMPERATURE, stamp, self.celsius_at(stamp))
        return self.estimator.on_input(kind, stamp, *values)


CONFIG = EstimatorConfig(oil_viscosity_m2_s=46e-6, drive_loss_torque_nm=0.05)
QUICK_BASELINE = dataclasses.replace(CONFIG, baseline_learn_s=10.0)
"""Commissioning of 10 s of monitored running, so that a fault can start early in a test."""


@pytest.fixture(scope='module')
def table(paper_params):
    return build_table(paper_params)


def make(table, config=CONFIG):
    return TorqueEstimator(config, table, 46e-6, 'hong_doh_2004')


def test_expected_torque_at_steady_state_is_the_full_models_plus_drive_loss(
        table, paper_model):
    est = make(table)
    for k in range(200):
        est.on_input(K.LOAD_PRESSURE, k * NS // 1000, 150e5)
        e = est.on_input(K.JOINT_STATE, k * NS // 1000, 600.0, 20.0)
    # the reference: the full model (Newton-Euler over all pistons), not the table
    full = paper_model.evaluate(600.0, 150e5, 46e-6)
    model_input_nm = float(full.input_nm[0])
    assert e.inertia_nm == pytest.approx(0.0, abs=1e-12)  # constant speed
    assert e.expected_nm == pytest.approx(model_input_nm + 0.05, rel=5e-4)
    assert e.theoretical_nm == pytest.approx(4.898e-6 * 150e5 / (2 * math.pi), rel=1e-3)
    assert e.residual_nm == pytest.approx(20.0 - model_input_nm - 0.05, rel=5e-4)
    # pump mode: T_th / T_in, the drive loss part of the input torque
    assert e.efficiency == pytest.approx(float(full.theoretical_nm[0]) / (model_input_nm + 0.05),
                                         rel=5e-4)


def test_filtered_derivative_follows_a_ramp_and_tames_noise(table):
    est = make(table)
    rng = np.random.default_rng(0)
    accel, accels = 2000.0, []
    for k in range(2000):  # 2 s at 1 kHz
        t = k / 1000
        est.on_input(K.LOAD_PRESSURE, k * NS // 1000, 100e5)
        e = est.on_input(K.JOINT_STATE, k * NS // 1000, 100.0 + accel * t + rng.normal(0, 1.0),
                         None)
        accels.append(e.inertia_nm / CONFIG.rotor_inertia_kg_m2)
    steady = np.array(accels[500:])
    assert steady.mean() == pytest.approx(accel, rel=0.01)
    raw_noise = 1.0 * math.sqrt(2) / 1e-3  # std of a plain difference of the noisy speed
    assert steady.std() < 0.05 * raw_noise


def test_port_pressures_give_the_difference(table):
    est = make(table, EstimatorConfig(pressure_source='ports', oil_viscosity_m2_s=46e-6))
    est.on_input(K.PRESSURE_A, 0, 180e5)
    assert est.on_input(K.SHAFT_SPEED, 1000, 300.0) is None  # port b missing: stale
    est.on_input(K.PRESSURE_B, 0, 30e5)
    e = est.on_input(K.SHAFT_SPEED, 2000, 300.0)
    assert e.pressure_diff_pa == 150e5
    assert est.counts['stale_skips'] == 1


def test_viscosity_from_temperature_uses_the_walther_law(table):
    cfg = EstimatorConfig(viscosity_source='temperature')
    est = make(table, cfg)
    est.on_input(K.LOAD_PRESSURE, 0, 100e5)
    assert est.on_input(K.SHAFT_SPEED, 1, 300.0) is None  # no temperature yet
    est.on_input(K.OIL_TEMPERATURE, 2, 40.0)
    assert est.on_input(K.SHAFT_SPEED, 3, 300.0).viscosity_m2_s == pytest.approx(46e-6, rel=1e-9)
    est.on_input(K.OIL_TEMPERATURE, 4, 100.0)
    est.on_input(K.LOAD_PRESSURE, 4, 100e5)
    assert est.on_input(K.SHAFT_SPEED, 5, 300.0).viscosity_m2_s == pytest.approx(6.8e-6, rel=1e-9)


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
    est.on_input(K.LOAD_PRESSURE, 0, 100e5)
    assert est.on_input(K.SHAFT_SPEED, 10_000_000, 300.0) is not None
    assert est.on_input(K.SHAFT_SPEED, 100_000_000, 300.0) is None  # pressure 100 ms old > 50 ms
    assert est.counts['stale_skips'] == 1
    snap = est.diagnostics(100_000_000)
    assert snap.level == OK  # last estimate 90 ms ago < stale_timeout_s
    snap = est.diagnostics(700_000_000)
    assert snap.level == STALE and 'pressure' in snap.message
    est.on_input(K.LOAD_PRESSURE, 710_000_000, 100e5)
    assert est.on_input(K.SHAFT_SPEED, 720_000_000, 300.0) is not None
    assert est.diagnostics(720_000_000).level == OK


def test_a_stale_status_names_what_the_samples_meet_now_not_an_old_skip(table):
    est = make(table)
    est.on_input(K.SHAFT_SPEED, 10_000_000, 300.0)  # before any pressure: a stale skip
    assert est.counts['stale_skips'] == 1
    est.on_input(K.LOAD_PRESSURE, 20_000_000, 100e5)
    assert est.on_input(K.SHAFT_SPEED, 30_000_000, 300.0) is not None
    assert est.diagnostics(40_000_000).level == OK
    # later the speed reads NaN while the pressure stays fresh: no estimate, none stale
    for i in range(20):
        t_ns = 100_000_000 + i * 40_000_000
        est.on_input(K.LOAD_PRESSURE, t_ns, 100e5)
        assert est.on_input(K.SHAFT_SPEED, t_ns + 1, math.nan) is None
    assert est.counts['stale_skips'] == 1  # the old skip only
    snap = est.diagnostics(900_000_000)
    assert snap.level == STALE
    assert 'pressure' not in snap.message
    assert 'rejected_non_finite 20' in snap.message
    # the pressure goes missing now: its skips grow and the status says so
    est.on_input(K.SHAFT_SPEED, 1_000_000_000, 300.0)
    snap = est.diagnostics(1_000_000_000)
    assert snap.level == STALE and 'pressure' in snap.message
    assert 'rejected' not in snap.message


def test_estimates_stamped_an_hour_behind_the_clock_are_stale_and_the_status_says_why(table):
    est = make(table)
    hour_ns = 3600 * 10**9

    def second(k):  # the inputs' header stamps an hour behind the node's clock, 1 kHz
        for i in range(1000):
            t_ns = k * 10**9 + i * 10**6
            est.on_input(K.LOAD_PRESSURE, t_ns, 100e5)
            assert est.on_input(K.SHAFT_SPEED, t_ns + 1, 300.0) is not None

    second(0)
    assert est.diagnostics(hour_ns + 10**9).level == STALE  # no earlier status to judge by
    second(1)
    snap = est.diagnostics(hour_ns + 2 * 10**9)
    assert snap.level == STALE
    assert snap.message.startswith('stale: the latest estimate is stamped 3600 s before')


def test_a_clock_gone_back_behind_the_latest_estimate_is_stale_not_its_old_level(table):
    est = make(table)
    t0 = 100 * 10**9
    for i in range(300):
        est.on_input(K.LOAD_PRESSURE, t0 + i * 10**6, 100e5)
        assert est.on_input(K.SHAFT_SPEED, t0 + i * 10**6 + 1, 300.0) is not None
    lead_s = est.config.max_stamp_lead_s
    assert est.diagnostics(t0 + 300 * 10**6).level == OK
    # stamped ahead by no more than an input may lead its receipt: still the estimate's level
    assert est.diagnostics(t0 + 299 * 10**6 - round(0.9 * lead_s * 1e9)).level == OK
    snap = est.diagnostics(10**9)  # the simulation restarted: its clock 99 s back
    assert snap.level == STALE
    assert snap.message.startswith('stale: the latest estimate is stamped 99.3 s after this '
                                   'clock: the clock went back')


def test_inputs_that_stop_between_two_statuses_are_a_dropout_not_another_clock(table):
    est = make(table)
    assert est.diagnostics(0).level == STALE
    for i in range(300):  # 0.3 s of inputs, then nothing
        est.on_input(K.LOAD_PRESSURE, i * 10**6, 100e5)
        assert est.on_input(K.SHAFT_SPEED, i * 10**6 + 1, 300.0) is not None
    snap = est.diagnostics(10**9)  # the latest estimate 0.7 s old > stale_timeout_s 0.5 s
    assert snap.level == STALE and snap.message == 'stale: no shaft speed'


def test_inputs_that_stop_after_an_old_stale_skip_are_no_shaft_speed_not_that_skip(table):
    est = make(table)
    est.on_input(K.SHAFT_SPEED, 1, 300.0)  # before any pressure: a stale skip
    assert est.counts['stale_skips'] == 1
    for i in range(1, 300):  # then 0.3 s of estimates, then nothing
        est.on_input(K.LOAD_PRESSURE, i * 10**6, 100e5)
        assert est.on_input(K.SHAFT_SPEED, i * 10**6 + 1, 300.0) is not None
    snap = est.diagnostics(10**9)
    assert snap.level == STALE and snap.message == 'stale: no shaft speed'
    est.on_input(K.SHAFT_SPEED, 10**9 + 1, 300.0)  # the pressure gone: a skip, said as such
    assert est.diagnostics(10**9 + 10**8).message == 'stale: no fresh pressure'


def test_a_stale_status_does_not_repeat_the_old_estimates_table_flags(table):
    est = make(table)
    est.on_input(K.LOAD_PRESSURE, 0, 100e5)
    fast = float(table.speed_axis_rad_s[-1]) * 1.5  # above the table: clamped and flagged
    assert est.on_input(K.SHAFT_SPEED, 1_000_000, fast) is not None
    assert 'outside the table' in est.diagnostics(2_000_000).message
    snap = est.diagnostics(5_000_000_000)
    assert snap.level == STALE and 'outside the table' not in snap.message


@pytest.mark.parametrize(('call', 'counter'), [
    (lambda e: e.on_input(K.SHAFT_SPEED, 5, math.nan), 'rejected_non_finite'),
    (lambda e: e.on_input(K.LOAD_PRESSURE, 5, math.inf), 'rejected_non_finite'),
    (lambda e: e.on_input(K.MOTOR_TORQUE, 5, -math.inf), 'rejected_non_finite'),
    (lambda e: e.on_input(K.SHAFT_SPEED, 1, 300.0), 'rejected_out_of_order'),
    (lambda e: e.on_input(K.SHAFT_SPEED, 2, 300.0), 'rejected_duplicate'),
    (lambda e: e.on_input(K.SHAFT_SPEED, 5, 1e6), 'rejected_out_of_range'),
    (lambda e: e.on_input(K.LOAD_PRESSURE, 5, 1e10), 'rejected_out_of_range'),
    (lambda e: e.on_input(K.OIL_TEMPERATURE, 5, 900.0), 'rejected_out_of_range'),
])
def test_bad_samples_are_rejected_counted_and_change_nothing(table, call, counter):
    est = make(table)
    est.on_input(K.LOAD_PRESSURE, 0, 100e5)
    est.on_input(K.MOTOR_TORQUE, 0, 10.0)
    before = est.on_input(K.SHAFT_SPEED, 2, 300.0)
    assert call(est) in (None, False)
    assert est.counts[counter] == 1
    assert est.last == before
    after = est.on_input(K.SHAFT_SPEED, 10, 300.0)
    assert after is not None and after.pressure_diff_pa == 100e5


def test_output_decimation_publishes_every_nth_estimate(table):
    est = make(table, EstimatorConfig(output_decimation=4, oil_viscosity_m2_s=46e-6))
    flags = []
    for k in range(12):
        est.on_input(K.LOAD_PRESSURE, k * 1000, 100e5)
        flags.append(est.on_input(K.SHAFT_SPEED, k * 1000, 300.0).publish)
    assert flags == [True, False, False, False] * 3


def test_diagnostic_values_are_numbers_with_units_in_their_keys(table):
    est = make(table)
    est.on_input(K.LOAD_PRESSURE, 0, 100e5)
    est.on_input(K.MOTOR_TORQUE, 0, 9.0)
    est.on_input(K.SHAFT_SPEED, 1, 300.0)
    values = dict(est.diagnostics(2).values)
    assert values['level'] == '0' and values['level_name'] == 'OK'
    for key, text in values.items():
        if key == 'level_name':
            continue
        float(text)  # every other value parses as a number (PlotJuggler graphs them)
        assert key in COUNTERS or key in ('level', 'last_alarm_level', 'efficiency',
                                          'baseline_complete', 'detection_held') or \
            key.endswith(('_nm', '_nm_s', '_pa', '_rad_s', '_m2_s', '_kg_m2', '_s', 'scale',
                          '_std', '_per_k', '_c'))


def test_diagnostics_give_the_oil_temperature_now_and_the_one_the_baseline_was_learnt_at(
        table):
    run = simulate_duty_cycle(table, DutyCycle(duration_s=120.0), seed=4)
    change_ns = 60 * NS  # the oil at 41.5 degC for the first minute, 44.0 after it
    topic = make(table, dataclasses.replace(QUICK_BASELINE, viscosity_source='temperature'))
    out = feed(WithOilTemperature(topic, lambda ns: 41.5 if ns < change_ns else 44.0), run)
    learnt_s = topic.monitor.baseline.learnt_s  # learnt within the first minute
    assert 0.0 < learnt_s < 60.0 and out[-1].stamp_ns > change_ns
    values = dict(topic.diagnostics(out[-1].stamp_ns).values)
    # the temperature in, back through the oil's law (to the law's round trip)
    assert float(values['oil_temperature_c']) == pytest.approx(44.0, abs=1e-9)
    assert float(values['baseline_oil_temperature_c']) == pytest.approx(41.5, abs=1e-9)
    # without the topic the node does not know the oil's temperature, and says NaN
    assumed = make(table, QUICK_BASELINE)
    out = feed(assumed, run)
    assert not assumed.monitor.learning
    values = dict(assumed.diagnostics(out[-1].stamp_ns).values)
    assert values['oil_temperature_c'] == 'nan' and values['baseline_oil_temperature_c'] == 'nan'


def _feed(table, run, config=CONFIG):
    est = make(table, config)
    return est, feed(est, run)


BANDED = dataclasses.replace(CONFIG, oil_temperature_band_c=3.0)
"""An installation that states its oil may swing 3 K about commissioning's temperature (the
simulations' oil stays at the viscosity the node is told)."""


def _band_viscosity_rise(config):
    """Return the oil's relative viscosity rise over the band, colder [-]."""
    law = WaltherViscosity(config.oil_viscosity_40c_m2_s, config.oil_viscosity_100c_m2_s)
    told_c = law.temperature_c(config.oil_viscosity_m2_s)
    return law(told_c - config.oil_temperature_band_c) / config.oil_viscosity_m2_s - 1.0


def test_ten_minutes_of_nominal_noisy_data_at_1khz_raise_no_alarm(table):
    run = simulate_duty_cycle(table, DutyCycle(duration_s=600.0), seed=21)
    banded, banded_out = _feed(table, run, BANDED)  # the oil may have moved 3 K
    assert max(e.level for e in banded_out) == OK
    est, out = _feed(table, run)
    assert len(out) == run.t_s.size
    assert max(e.level for e in out) == OK
    mon = est.monitor
    assert not mon.learning and mon.baseline.learnt_s >= CONFIG.baseline_learn_s
    assert mon.cusum_pos_nm_s < 0.1 * CONFIG.cusum_warn_nm_s
    # the pump is the model: the baseline finds it so, within its reported uncertainty
    coef, std = mon.baseline.coefficients, mon.baseline.std()
    assert np.all(np.abs(coef) < 3.0 * std), (coef, std)
    # the truth (no change) lies within the reported 95 % intervals, and those are narrow
    assert abs(est.last.valve_plate_scale - 1.0) < 1.96 * mon.valve_plate_scale_std < 0.15
    assert abs(mon.theta_rest - 1.0) < 1.96 * mon.rest_scale_std < 0.15
    assert est.counts['stale_skips'] == 0
    # with the band the interval also spans what an oil 3 K colder does to the reading: at
    # most the viscosity's rise (the film shear is linear in it, sec. 4.2) beyond the above
    held = 1.96 * mon.valve_plate_scale_std
    wide = 1.96 * banded.monitor.valve_plate_scale_std
    assert abs(banded.last.valve_plate_scale - 1.0) < wide
    assert held < wide < held + _band_viscosity_rise(BANDED)


def test_no_alarm_while_the_baseline_is_learnt_and_diagnostics_say_so(table):
    run = simulate_duty_cycle(table, DutyCycle(duration_s=20.0), seed=3,
                              wear=lambda t: np.full_like(t, 2.0))  # a worn pump from the start
    est, out = _feed(table, run, dataclasses.replace(CONFIG, baseline_learn_s=1e6))
    assert max(e.level for e in out) == OK and est.monitor.learning
    status = est.diagnostics(out[-1].stamp_ns)
    assert 'learning the healthy baseline' in status.message
    assert status.message.endswith('the scales are the pump against the model')
    # meanwhile the published scales are the fit's against the model: twice the valve plate
    assert abs(est.last.valve_plate_scale - 2.0) < 0.3


def test_valve_plate_step_of_fifty_percent_is_flagged_and_attributed(table):
    """+50 % valve-plate friction at t = 40 s, after commissioning: WARN within 20 s."""
    run = simulate_duty_cycle(table, DutyCycle(duration_s=180.0), seed=3,
                              wear=wear_step(40.0, 1.5))
    banded, banded_out = _feed(table, run, dataclasses.replace(
        QUICK_BASELINE, oil_temperature_band_c=BANDED.oil_temperature_band_c))
    est, out = _feed(table, run, QUICK_BASELINE)
    t = np.array([e.stamp_ns for e in out]) / NS
    level = np.array([e.level for e in out])
    assert level[t < 40.0].max() == OK and not est.monitor.learning
    first_warn = t[level >= WARN].min()
    assert 40.0 < first_warn < 60.0
    assert level[-1] == ERROR
    final = out[-1]
    # the truth (1.5 of healthy) lies within the reported 95 % interval, which is narrow,
    # and the status message names the valve plate
    assert abs(final.valve_plate_scale - 1.5) < 1.96 * final.valve_plate_scale_std < 0.25
    assert est.monitor.verdict(1.0)[0] == 'valve_plate'
    assert 'valve plate' in est.diagnostics(final.stamp_ns).message
    # with a 3 K band: the same verdict, later, and an interval that also spans what the
    # band's oil moves the reading, at most the viscosity's rise times the truth
    t_band = np.array([e.stamp_ns for e in banded_out]) / NS
    level_band = np.array([e.level for e in banded_out])
    assert first_warn < t_band[level_band >= WARN].min() < 60.0
    wide = 1.96 * banded_out[-1].valve_plate_scale_std
    assert abs(banded_out[-1].valve_plate_scale - 1.5) < wide
    held = 1.96 * final.valve_plate_scale_std
    assert held < wide < held + 1.5 * _band_viscosity_rise(BANDED)
    assert banded.monitor.verdict(1.0)[0] == 'valve_plate'


def test_a_bearing_fault_is_not_named_valve_plate(table):
    run = simulate_duty_cycle(table, DutyCycle(duration_s=180.0), seed=4)
    dp = np.interp(run.t_s, run.pressure_t_s, run.pressure_diff_pa)
    bearing = table.lookup_array(run.true_speed_rad_s, dp, 46e-6)['bearing_nm']
    extra = np.where(run.t_s > 40.0, 1.0, 0.0) * bearing  # twice the bearing friction
    run = dataclasses.replace(run, torque_nm=run.torque_nm + extra)
    est, out = _feed(table, run, QUICK_BASELINE)
    assert out[-1].level >= WARN
    assert est.monitor.verdict(1.0)[0] == 'other_friction'


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
        est.on_input(K.LOAD_PRESSURE, k * NS // 1000, dp + rng.normal(0, 1e5))
        est.on_input(K.JOINT_STATE, k * NS // 1000, speed + rng.normal(0, 0.5),
                     truth + rng.normal(0, 0.05))
    assert est.monitor.level == OK
    assert est.monitor.cusum_pos_nm_s < 0.2 * CONFIG.cusum_warn_nm_s
    assert est.monitor.cusum_neg_nm_s < 0.2 * CONFIG.cusum_warn_nm_s


def test_alarm_clears_with_hysteresis_after_repair(table):
    # the sums fall by k per second of monitored running from their cap: (1.2 x 5 - 0.5 x
    # 0.6) / 0.025 = 228 s of monitored running, 390 s here (~reset_monitor: at once)
    run = simulate_duty_cycle(table, DutyCycle(duration_s=540.0), seed=5,
                              wear=lambda t: np.where((t > 30.0) & (t < 80.0), 1.6, 1.0))
    _, out = _feed(table, run, QUICK_BASELINE)
    levels = [e.level for e in out]
    changes = sum(a != b for a, b in itertools.pairwise(levels))
    assert max(levels) >= WARN
    assert levels[-1] == OK
    assert changes <= 4  # OK -> WARN (-> ERROR -> WARN) -> OK, no chatter


def test_counters_cover_every_rejection(table):
    est = make(table)
    assert set(est.counts) == set(COUNTERS)


# -- stamps that cannot be trusted: one bad sample must not hold the later ones hostage ----

TEN_YEARS_NS = 10 * 365 * 86400 * NS
T0 = 1_700_000_000 * NS  # a wall-clock epoch, as in a recorded bag


def _stream(est, n=3000, bad=None, receive=True, start=T0, warm_up=1000):
    """
    1 kHz joint states and 500 Hz pressure after a warm-up; receive time = true time.

    ``bad`` = (kind, lead [ns]): the first sample of that kind after the warm-up carries a
    header stamp that far ahead. Returns the estimates made after it (``n`` expected).
    """
    out = []
    for k in range(warm_up + n + 1):
        t = start + k * NS // 1000
        lead = dict.fromkeys((K.JOINT_STATE, K.LOAD_PRESSURE), 0)
        if bad is not None and k == warm_up:
            lead[bad[0]] = bad[1]
        if k % 2 == 0:
            est.on_input(K.LOAD_PRESSURE, t + lead[K.LOAD_PRESSURE], 120e5, None,
                         t if receive else None)
        e = est.on_input(K.JOINT_STATE, t + lead[K.JOINT_STATE], 400.0, 6.0,
                         t if receive else None)
        if k > warm_up and e is not None:
            out.append(e)
    return out


@pytest.mark.parametrize(('kind', 'lead_ns'), [
    (K.JOINT_STATE, TEN_YEARS_NS),
    (K.JOINT_STATE, 0xFFFFFFFF),  # nanosec = 0xFFFFFFFF reads as 4.29 s ahead
    (K.LOAD_PRESSURE, TEN_YEARS_NS),
])
def test_a_stamp_far_ahead_of_its_receive_time_is_rejected_and_loses_nothing(table, kind,
                                                                             lead_ns):
    est = make(table)
    out = _stream(est, bad=(kind, lead_ns))
    assert len(out) == 3000  # 3,000 of the 3,000 following estimates are made
    assert est.counts['rejected_future_stamp'] == 1
    assert est.counts['rejected_out_of_order'] == est.counts['stale_skips'] == 0
    values = dict(est.diagnostics(out[-1].stamp_ns).values)
    assert values['rejected_future_stamp'] == '1' and values['stamp_resyncs'] == '0'


def test_nanosec_all_ones_reads_as_four_seconds_ahead():
    from types import SimpleNamespace

    from pump_friction_ros.messages.conversions import stamp_to_ns
    stamp = SimpleNamespace(sec=T0 // NS, nanosec=0xFFFFFFFF)
    assert stamp_to_ns(stamp) - T0 == 4_294_967_295  # > max_stamp_lead_s (1 s): rejected


@pytest.mark.parametrize('kind', [K.JOINT_STATE, K.LOAD_PRESSURE])
def test_without_a_receive_time_a_future_stamp_costs_at_most_the_resync_count(table, kind):
    """The API without receive times: the bad stamp is taken, then the input resyncs."""
    est = make(table)
    out = _stream(est, bad=(kind, TEN_YEARS_NS), receive=False)
    resync = CONFIG.stamp_resync_samples
    slots = 2 if kind == K.JOINT_STATE else 1  # a JointState carries speed and torque
    assert est.counts['stamp_resyncs'] == slots
    assert est.counts['rejected_out_of_order'] == slots * (resync - 1)
    # speed: the resync count of speed samples; pressure (500 Hz): the resync count of
    # pressure samples, i.e. twice as many 1 kHz speed samples go without a fresh pressure
    lost = resync if kind == K.JOINT_STATE else 2 * resync + 1
    assert 3000 - lost <= len(out) < 3000
    assert all(math.isfinite(e.expected_nm) and abs(e.inertia_nm) < 1e-9 for e in out)
    assert est.monitor.cusum_pos_nm_s >= 0.0 and math.isfinite(est.monitor.ewma_nm)
    values = dict(est.diagnostics(out[-1].stamp_ns).values)
    assert values['stamp_resyncs'] == str(slots)


def test_a_clock_restart_backwards_restarts_the_speed_filter_cleanly(table):
    est = make(table)
    _stream(est, n=500, warm_up=0)
    ramp = []
    for k in range(200):  # the source's clock restarts 100 s back, on a 1000 rad/s^2 ramp
        t = T0 - 100 * NS + k * NS // 1000
        est.on_input(K.LOAD_PRESSURE, t, 120e5, None, t)
        e = est.on_input(K.JOINT_STATE, t, 400.0 + 1.0 * k, 6.0, t)
        if e is not None:
            ramp.append(e)
    assert est.counts['stamp_resyncs'] == 3  # speed, torque and pressure followed it
    assert ramp[0].accel_rad_s2 == 0.0  # restarted at rest, no derivative across the jump
    assert all(math.isfinite(e.accel_rad_s2) for e in ramp)
    assert ramp[-1].accel_rad_s2 == pytest.approx(1000.0, rel=0.05)  # and tracks the ramp


def test_speed_filter_restarts_on_a_negative_step():
    from pump_friction_ros.core.speed_filter import SpeedFilter
    f = SpeedFilter(0.01, 50_000_000)
    for k in range(100):
        f.update(10 * NS + k * 1_000_000, 100.0 + 0.5 * k)  # 500 rad/s^2
    assert f.accel_rad_s2 > 100.0
    assert f.update(5 * NS, 300.0) == 0.0  # backwards: restart at rest
    assert f.update(5 * NS + 1_000_000, 300.0) == pytest.approx(0.0, abs=1e-9)
