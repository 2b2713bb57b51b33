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

"""What the oil's temperature does to the torque is not a change of the pump: the allowances."""

import math

import numpy as np
from pump_friction_ros.core.attribution import AttributionSettings, DETECTED_CAUSES, Verdict
from pump_friction_ros.core.baseline import baseline_regressors
from pump_friction_ros.core.estimator import TorqueEstimator
from pump_friction_ros.core.monitor import MonitorSettings, OK, WearMonitor
from pump_friction_ros.core.node_parameters import EstimatorConfig, settings_view
from pump_friction_ros.core.oil_allowance import band_friction_nm, OilAllowance
from pump_friction_ros.errors import ConfigError
from pump_friction_ros.physics.friction import valve_plate_viscous_torque_nm
from pump_friction_ros.physics.oil import WaltherViscosity
from pump_friction_ros.table.friction_table import build_table
import pytest

VG68 = WaltherViscosity(68e-6, 8.7e-6)  # ISO VG 68, viscosity index ~100
TRUTH = np.array([0.2, -0.15, 0.03, 0.01, -0.03, 1.2e-4])  # a pump unlike its model
WINDOW_SAMPLES = 250
DT = 1e-3


@pytest.fixture(scope='module')
def table(paper_params):
    return build_table(paper_params)


def test_band_friction_holds_the_valve_plates_couette_shear_over_the_band(
        table, paper_params):
    nu = VG68(50.0)
    speeds, change, other = band_friction_nm(table, nu, VG68, 3.0)
    vp, rho = paper_params.valve_plate, paper_params.oil.density_kg_m3
    # sec. 4.2: the film shear rho nu |w| / h * int r^3 is linear in nu; 3 K colder
    shear = [float(valve_plate_viscous_torque_nm(w, VG68(47.0), rho, vp)
                   - valve_plate_viscous_torque_nm(w, nu, rho, vp)) for w in speeds]
    assert change == pytest.approx(shear, rel=1e-6, abs=1e-12)  # the valve plate's: exactly
    # 3 K of VG 68 at 50 degC are 14 % of its viscosity (ASTM D341)
    assert 0.13 < VG68(47.0) / nu - 1.0 < 0.15
    # the bearing's drag, the other components' part, less than the film shear at speed
    top = speeds.index(max(speeds))
    assert 0.0 < other[top] < shear[top] and min(other) >= 0.0
    # no band, no allowance; a wider band, a larger one
    assert band_friction_nm(table, nu, VG68, 0.0)[1:] == ([0.0] * len(speeds),) * 2
    _, wider, wider_other = band_friction_nm(table, nu, VG68, 6.0)
    assert all(w >= c for w, c in zip(wider, change, strict=True)) and wider[top] > change[top]
    assert all(w >= c for w, c in zip(wider_other, other, strict=True)) and \
        wider_other[top] > other[top]


def test_allowance_interpolates_along_speed_and_holds_beyond_the_axis():
    oil = OilAllowance([0.0, 100.0, 300.0], [0.0, 0.02, 0.08])
    assert oil.window_nm(50.0) == pytest.approx(0.01)
    assert oil.window_nm(200.0) == pytest.approx(0.05)
    assert oil.window_nm(1e4) == pytest.approx(0.08)


def _monitor(oil, **config_overrides):
    config = EstimatorConfig(**config_overrides)
    return WearMonitor(settings_view(config, MonitorSettings),
                       settings_view(config, AttributionSettings), 0.0, True, 0.0, oil)


SLOPE = 1e-4
"""The band's friction change per speed in these tests [N m / (rad/s)]: a film shear."""


def oil_window(rng):
    """
    Draw one window of these tests' pump: speed, modelled frictions, direction, torque.

    Returns (speed [rad/s], valve-plate and other friction [N m], direction, theoretical
    torque [N m], the baseline's regressors).
    """
    speed = rng.uniform(50.0, 900.0)
    vp, other = 0.05 + 4e-4 * speed, 0.1 + rng.uniform(0.0, 0.4)
    sign = 1.0 if rng.random() < 0.5 else -1.0
    th = rng.uniform(-3.0, 3.0)
    return speed, vp, other, sign, th, baseline_regressors(vp, other, th * sign, sign, 0.0)


def _swing(oil, amplitude, seed=4, windows=3000, truth=TRUTH):
    """
    Run a pump as learnt at commissioning whose viscous friction then swings with the oil.

    The swing's torque is amplitude x SLOPE x |speed|, over a 20-minute period of wall time
    at 10 % monitored running, from 60 s on (commissioning learns in the first 30 s of
    running). Returns the monitor and whether it ever left OK.
    """
    rng = np.random.default_rng(seed)
    mon = _monitor(oil)
    t, alarmed, n = 0.0, False, WINDOW_SAMPLES
    for _ in range(windows):
        speed, vp, other, sign, th, h = oil_window(rng)
        wall = 10.0 * t
        swing = amplitude * SLOPE * speed * math.sin(2.0 * math.pi * wall / 1200.0) \
            if wall > 600.0 else 0.0
        e = float(h @ truth) + swing + rng.normal(0.0, 0.01)
        trace = mon.update_many([t + i * DT for i in range(n)], [DT] * n, [e] * n, [vp] * n,
                                [other] * n, [th] * n, [sign] * n, None, [speed] * n)
        alarmed = alarmed or max(trace.level) > OK
        t += n * DT
    return mon, alarmed


BAND = OilAllowance([0.0, 1000.0], [0.0, 1000.0 * SLOPE])


@pytest.mark.parametrize('seed', [4, 5, 6])
def test_an_oil_swing_within_the_band_raises_no_alarm_and_one_beyond_it_does(seed):
    mon, alarmed = _swing(BAND, 0.95, seed)
    assert not mon.learning and not alarmed
    # the same swing without the allowance alarms, and three times the band with it
    assert _swing(None, 0.95, seed)[1] and _swing(BAND, 3.0, seed)[1]


WIDE = OilAllowance([0.0, 1000.0], [0.0, 0.4])
"""A band of 0.02-0.36 N m at 50-900 rad/s: many times the CUSUM's allowance k."""


def _directions(oil, side, stretch_windows, seed, windows=1200):
    """
    Run the tests' pump with each direction held for ``stretch_windows`` windows (of 0.25 s).

    From 60 s of running on, the oil sits at ``side`` times the WIDE band's change (> 0:
    colder). Returns the monitor, the largest CUSUM of each cause over the run [N m s], and
    whether it ever left OK.
    """
    rng = np.random.default_rng(seed)
    mon = _monitor(oil)
    t, alarmed, n = 0.0, False, WINDOW_SAMPLES
    largest = np.zeros(len(DETECTED_CAUSES))
    for w in range(windows):
        speed, vp, other, _, th, _ = oil_window(rng)
        sign = 1.0 if (w // stretch_windows) % 2 == 0 else -1.0
        h = baseline_regressors(vp, other, th * sign, sign, 0.0)
        e = float(h @ TRUTH) + rng.normal(0.0, 0.01)
        if t > 60.0:
            e += side * (1.0 + TRUTH[0]) * WIDE.window_nm(speed)
        trace = mon.update_many([t + i * DT for i in range(n)], [DT] * n, [e] * n, [vp] * n,
                                [other] * n, [th] * n, [sign] * n, None, [speed] * n)
        alarmed = alarmed or max(trace.level) > OK
        largest = np.maximum(largest, np.maximum(mon._pos, mon._neg))
        t += n * DT
    return mon, largest, alarmed


@pytest.mark.parametrize('seed', [11, 12])
@pytest.mark.parametrize('stretch_windows', [1, 40])
@pytest.mark.parametrize('side', [0.9, -0.9])
def test_an_oil_within_its_band_moves_no_causes_sum_however_long_each_direction_lasts(
        stretch_windows, side, seed):
    # The band is taken off every cause's change whole, in every window. Taken off each
    # cause only along its signature over the isolation's memory (stop 47's prototype), an
    # offset's or a gain's, which reverse with the direction, would keep their sensitivity
    # where the oil is constant, but within one direction they move with the oil as the
    # friction does: on 10 s stretches an oil at 0.9 of this band drove the offset's sum to
    # 1.96 N m s and the torque gain's to 6.0 (WARN at 0.6). The CUSUM reacts in seconds;
    # the signatures part over the cycle.
    mon, largest, alarmed = _directions(WIDE, side, stretch_windows, seed)
    assert not mon.learning and not alarmed
    assert np.all(largest < 0.05 * mon.settings.cusum_warn_nm_s)  # (measured: <= 0.001)
    # the same oil colder without the band alarms (warmer, the baseline follows it thinning)
    assert _directions(None, side, stretch_windows, seed)[2] == (side > 0.0)


@pytest.mark.parametrize('seed', [4, 5])
def test_the_band_is_the_installations_friction_level_times_the_models(seed):
    # a pump whose valve plate is twice the model's (its oil colder than the one assumed):
    # its film shear, and the shear's swing with the oil, are twice the model's; a swing of
    # 2.4 times the band's model N m is within its band (and the CUSUM's allowance k, about
    # half the band's N m at these speeds) ...
    cold = TRUTH.copy()
    cold[0] = 1.0
    mon, alarmed = _swing(BAND, 2.4, seed, truth=cold)
    assert not mon.learning and not alarmed
    assert 1.0 + mon.baseline.coefficients[0] == pytest.approx(2.0, abs=0.05)
    # ... and beyond it on a pump as modelled
    as_modelled = TRUTH.copy()
    as_modelled[0] = 0.0
    assert _swing(BAND, 2.4, seed, truth=as_modelled)[1]
    # the levels scale each component's part; a level below 0 allows nothing
    oil = OilAllowance([0.0, 100.0], [0.0, 0.02], other_change_nm=[0.0, 0.01])
    assert oil.window_nm(100.0) == pytest.approx(0.03)
    assert oil.window_nm(50.0, 1.9, 0.5) == pytest.approx(1.9 * 0.01 + 0.5 * 0.005)
    assert oil.window_nm(100.0, -0.2, 1.0) == pytest.approx(0.01)
    with pytest.raises(ValueError):
        OilAllowance([0.0, 100.0], [0.0, 0.02], other_change_nm=[0.0])


def test_the_undetectable_change_grows_by_the_allowance():
    without, _ = _swing(None, 0.0)
    with_band, _ = _swing(BAND, 0.0)
    unseen = without.undetectable_change['valve_plate']
    grown = with_band.undetectable_change['valve_plate'] - unseen
    # the mean allowance over the windows (speed uniform on 50-900 rad/s: 475 x SLOPE) over
    # the RMS of the valve-plate signature over the recent windows, which the same windows
    # give both monitors
    rms = math.sqrt(with_band._recent_s2[0, 0] / with_band._recent_s)
    assert rms == pytest.approx(math.sqrt(without._recent_s2[0, 0] / without._recent_s))
    # times the valve plate's level the baseline learnt (TRUTH's: 1.2)
    level = 1.0 + float(with_band.baseline.coefficients[0])
    assert level == pytest.approx(1.0 + TRUTH[0], abs=0.05)
    assert grown == pytest.approx(level * 475.0 * SLOPE / rms, rel=0.15)
    # and a healthy reading's interval spans it
    assert 1.96 * with_band.valve_plate_scale_std >= with_band.undetectable_change[
        'valve_plate'] * 0.99


def test_the_estimator_allows_for_the_band_only_where_the_viscosity_is_assumed(table):
    assumed = TorqueEstimator(EstimatorConfig(oil_temperature_band_c=3.0), table, 46e-6,
                              'hong_doh_2004')
    measured = TorqueEstimator(EstimatorConfig(viscosity_source='temperature',
                                               oil_temperature_band_c=3.0), table, 46e-6,
                               'hong_doh_2004')
    none = TorqueEstimator(EstimatorConfig(), table, 46e-6, 'hong_doh_2004')  # the default
    assert assumed.monitor._oil.window_nm(300.0) > 0.0
    assert measured.monitor._oil.window_nm(300.0) == 0.0  # the table follows the viscosity
    assert none.monitor._oil.window_nm(300.0) == 0.0


def test_a_state_saved_before_the_allowance_loads_and_restarts_its_sums():
    mon, _ = _swing(BAND, 0.5, windows=400)
    state = mon.state_dict()
    assert state['allowance_s'] > 0.0
    old = {key: value for key, value in state.items()
           if key not in ('allowance_nm_s', 'allowance_s')}
    again = _monitor(BAND)
    again.load_state_dict(old)
    assert not again.learning and again.level == mon.level
    assert again.state_dict()['allowance_s'] == 0.0
    # the undetectable change falls back to k and the baseline's margin alone
    assert again.undetectable_change['valve_plate'] < mon.undetectable_change['valve_plate']


def test_gain_allowance_is_one_sided_the_drift_times_the_temperature_change_times_the_torque():
    oil = OilAllowance([0.0], [0.0], VG68, 1.2e-3, 3.0)
    drift = 1.2e-3 * 34.0 * 10.0
    # warmer than at commissioning: pumping reads high, motoring reads low (more negative)
    assert oil.gain_interval_nm(10.0, 57.0, 23.0) == pytest.approx((0.0, drift))
    assert oil.gain_interval_nm(-10.0, 57.0, 23.0) == pytest.approx((-drift, 0.0))
    assert oil.gain_interval_nm(10.0, 23.0, 57.0) == pytest.approx((-drift, 0.0))  # cooler
    band = 1.2e-3 * 3.0 * 10.0  # the temperature not known: the band, either way
    assert oil.gain_interval_nm(-10.0, math.nan, 23.0) == pytest.approx((-band, band))
    assert oil.temperature_c(VG68(57.0)) == pytest.approx(57.0)
    assert math.isnan(OilAllowance([0.0], [0.0]).temperature_c(VG68(57.0)))  # assumed


def warm(mon, drift_per_k, seed, windows=2400, gain_step=0.0, wear=1.0, cool_from_s=math.inf,
         pressure=False, loads=(-8.0, 8.0), offset_nm=0.0):
    """
    Commission at 20 degC, then warm the oil to 55 degC (from 500 s, tau 300 s of wall time).

    The measured torque reads drift_per_k (T - 20 degC) high: the drive's k_t. From 1500 s of
    wall time (the oil at 53 degC) the gain is ``gain_step`` off besides, and from 700 s the
    valve plate is ``wear`` times healthy. From ``cool_from_s`` the oil cools back to 20 degC
    (tau 300 s). ``pressure``: the drift is the pressure sensor's, reading low as it warms
    (the theoretical torque's part only). ``loads``: the range of the theoretical torque
    [N m] (always pumping where it is one-sided), ``offset_nm``: a torque offset from 1500 s
    of wall time. Returns the first alarm's verdict ('' if none).
    """
    rng = np.random.default_rng(seed)
    t, verdict, n = 0.0, '', WINDOW_SAMPLES
    for _ in range(windows):
        wall = 10.0 * t  # monitored running is a tenth of the time
        temperature = 20.0 if wall < 500.0 else 55.0 - 35.0 * math.exp(-(wall - 500.0) / 300.0)
        if wall > cool_from_s:
            temperature = 20.0 + (temperature - 20.0) * math.exp(-(wall - cool_from_s) / 300.0)
        speed = rng.uniform(50.0, 900.0)
        vp, other = 0.05 + 4e-4 * speed, 0.1 + rng.uniform(0.0, 0.4)
        sign = 1.0 if rng.random() < 0.5 or loads[0] >= 0.0 else -1.0
        th = rng.uniform(*loads)  # 60-120 bar: a 3 % gain error is 0.2-0.45 N m
        h = baseline_regressors(vp, other, th * sign, sign, 0.0)
        delivered = th * sign + (1 + TRUTH[0]) * vp + (1 + TRUTH[1]) * other
        gain = drift_per_k * (temperature - 20.0) + (gain_step if wall > 1500.0 else 0.0)
        e = float(h @ TRUTH) + gain * (th * sign if pressure else delivered)
        e += offset_nm if wall > 1500.0 else 0.0
        if wall > 700.0:
            e += (wear - 1.0) * (1 + TRUTH[0]) * vp
        e += rng.normal(0.0, 0.01)
        trace = mon.update_many([t + i * DT for i in range(n)], [DT] * n, [e] * n, [vp] * n,
                                [other] * n, [th] * n, [sign] * n, None, [speed] * n,
                                [VG68(temperature)] * n)
        if not verdict and max(trace.level) > OK:
            verdict = mon.verdict(1.0)[0]
        t += n * DT
    return verdict


def _warm_up(oil, drift_per_k, wear=1.0, seed=7, windows=2400):
    """`warm` a monitor with ``oil``'s allowances; return it and its first alarm's verdict."""
    mon = _monitor(oil)
    return mon, warm(mon, drift_per_k, seed, windows, wear=wear)


def test_a_torque_constant_drifting_as_the_oil_warms_is_no_alarm_and_wear_is_still_named():
    measured = OilAllowance([0.0], [0.0], VG68, 1.2e-3)  # the temperature topic
    mon, verdict = _warm_up(measured, 1.0e-3)
    assert not mon.learning and mon.baseline.temperature_c == pytest.approx(20.0)
    assert verdict == ''  # 3.5 % of the torque over 35 K: within the drift taken as normal
    # without the allowance the same warm-up alarms, as a change of the measurement
    _, verdict = _warm_up(None, 1.0e-3)
    assert verdict == Verdict.NOT_FRICTION
    # the valve plate keeps its sensitivity: +80 % during the warm-up is found and named
    _, verdict = _warm_up(measured, 1.0e-3, wear=1.8)
    assert verdict == Verdict.VALVE_PLATE


def test_a_state_saved_before_the_gain_allowance_loads():
    measured = OilAllowance([0.0], [0.0], VG68, 1.2e-3)
    mon, _ = _warm_up(measured, 1.0e-3, windows=600)
    state = mon.state_dict()
    assert state['gain_allowance_nm_s'] > 0.0
    del state['gain_allowance_nm_s']
    for key in ('temperature_sum_c_s', 'temperature_time_s'):  # nor the learnt temperature
        for part in ('learner', 'older', 'recent'):
            del state['commissioning'][part][key]
    again = _monitor(measured)
    again.load_state_dict(state)
    assert not again.learning and math.isnan(again.baseline.temperature_c)


def test_the_undetectable_change_grows_by_half_the_drift_interval():
    measured = OilAllowance([0.0], [0.0], VG68, 1.2e-3)
    with_drift, _ = _warm_up(measured, 1.0e-3)
    without, _ = _warm_up(OilAllowance([0.0], [0.0], VG68, 0.0), 1.0e-3)
    mean = with_drift._gain_allowance_nm_s / with_drift._allowance_s  # half the width
    assert mean > 0.05  # 1.2e-3 x ~30 K x ~4 N m, halved
    # each sum i sees a change of cause j from (k n_i + (2 sigma + mean) r_i) / |C_ij| on,
    # against (k n_i + 2 sigma r_i) / |C_ij|: the same baseline (n_i, sigma) and the same
    # recent points (C, the mean of s s^T over them; r_i = sqrt(C_ii)): the least sum
    # grows by one of mean r_i / |C_ij|, each at least mean / r_j (Cauchy-Schwarz: the own)
    assert with_drift._unseen_nm == without._unseen_nm
    second = with_drift._recent_s2 / with_drift._recent_s
    assert second == pytest.approx(without._recent_s2 / without._recent_s, rel=1e-12)
    rms = np.sqrt(np.diag(second))
    for j, (cause, grown) in enumerate(with_drift.undetectable_change.items()):
        unseen = without.undetectable_change[cause]
        growth = mean * rms / np.abs(second[:, j])
        assert mean / rms[j] * (1.0 - 1e-9) <= grown - unseen <= growth.max() * (1.0 + 1e-9)


def test_the_estimator_wires_the_oil_law_the_drift_and_the_band(table):
    config = EstimatorConfig(viscosity_source='temperature', oil_viscosity_40c_m2_s=68e-6,
                             oil_viscosity_100c_m2_s=8.7e-6, oil_temperature_band_c=2.0,
                             torque_constant_drift_per_k=1.1e-3)
    oil = TorqueEstimator(config, table, 46e-6, 'hong_doh_2004').monitor._oil
    assert oil.temperature_c(VG68(57.0)) == pytest.approx(57.0)  # the topic: read back
    assert (oil.drift_per_k, oil.band_c) == (1.1e-3, 2.0)
    assumed = TorqueEstimator(EstimatorConfig(torque_constant_drift_per_k=1.1e-3), table,
                              46e-6, 'hong_doh_2004').monitor._oil
    assert math.isnan(assumed.temperature_c(VG68(57.0)))  # a parameter: not known


def test_a_drift_that_cannot_act_says_so_in_the_diagnostics(table):
    quiet = TorqueEstimator(EstimatorConfig(torque_constant_drift_per_k=1.2e-3), table, 46e-6,
                            'hong_doh_2004')
    assert 'torque_constant_drift_per_k has no effect' in quiet.diagnostics(0).message
    for config in (EstimatorConfig(), EstimatorConfig(torque_constant_drift_per_k=1.2e-3,
                                                      oil_temperature_band_c=3.0)):
        assert 'no effect' not in TorqueEstimator(config, table, 46e-6).diagnostics(0).message
    # with the topic, a baseline learnt without the oil temperature (an older file)
    measured = OilAllowance([0.0], [0.0], VG68, 1.2e-3)
    mon, _ = _warm_up(measured, 0.0, windows=400)
    assert mon.oil_note == ''
    state = mon.state_dict()
    for part in ('learner', 'older', 'recent'):
        for key in ('temperature_sum_c_s', 'temperature_time_s'):
            del state['commissioning'][part][key]
    mon.load_state_dict(state)
    assert 'until the baseline is learnt again' in mon.oil_note


def test_a_band_beyond_the_oil_law_is_refused_in_one_line_and_a_thin_oil_has_no_temperature(
        table):
    with pytest.raises(ConfigError, match='outside the viscosity law') as error:
        band_friction_nm(table, 0.3e-6, VG68, 3.0)  # 0.3 cSt: log log (nu + 0.7) undefined
    assert '\n' not in str(error.value)
    assert math.isnan(OilAllowance([0.0], [0.0], VG68).temperature_c(0.2e-6))
