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

"""With the temperature topic the baseline learns the drive's k_t drift: warm-ups of set truth."""

import math

import numpy as np
from pump_friction_ros.core.attribution import AttributionSettings, CAUSES, FaultIsolation, Verdict
from pump_friction_ros.core.gain_follow import GainFollow
from pump_friction_ros.core.monitor import MonitorSettings, OK, WearMonitor
from pump_friction_ros.core.node_parameters import EstimatorConfig, settings_view
from pump_friction_ros.core.oil_allowance import OilAllowance
import pytest

from .test_oil_allowance import VG68, warm

MEASURED = OilAllowance([0.0], [0.0], VG68)  # the temperature topic, no allowance
NOTHING = {'torque_gain_per_k': 0.0, 'pressure_gain_per_k': 0.0, 'times': 0}
FORGOTTEN = {**NOTHING, 'g': [0.0, 0.0], 'b': [0.0, 0.0]}  # nor any window of a fit
MEMORY_S = 120.0
ONE_SIDED = (5.0, 8.0)  # pumping at 5-8 N m: the offset's signature and the gains' collinear


def _learnt(mon):
    """Return what the monitor learnt of the drift (not the windows of its fit)."""
    return {key: mon.state_dict()['gain_follow'][key] for key in NOTHING}


def _monitor(assumed=False, **overrides):
    config = EstimatorConfig(**overrides)
    return WearMonitor(settings_view(config, MonitorSettings),
                       settings_view(config, AttributionSettings), 0.0, assumed, 0.0,
                       MEASURED)


@pytest.mark.parametrize('seed', [31, 32, 33])
@pytest.mark.parametrize('drift_per_k', [0.4e-3, 0.9e-3, 1.3e-3])
def test_a_torque_constant_drifting_as_the_oil_warms_is_learnt_and_raises_no_alarm(
        seed, drift_per_k):
    mon = _monitor()
    assert warm(mon, drift_per_k, seed) == ''
    assert not mon.learning and mon.baseline.temperature_c == pytest.approx(20.0)
    assert mon.state_dict()['gain_follow']['times'] >= 1
    # learnt where the detection first saw it, within what the CUSUM allowance hides:
    # k / (35 K x ~4 N m) = 0.2e-3 / K
    assert mon.measurement_drift_per_k == pytest.approx(drift_per_k, abs=0.3e-3)
    assert 'measured torque against pressure follows the oil temperature' in mon.oil_note
    # with nothing learnt the same warm-up is an alarm, as a change of the measurement
    never = _monitor(torque_constant_drift_max_per_k=0.0)
    assert warm(never, drift_per_k, seed) == Verdict.NOT_FRICTION
    assert never.state_dict()['gain_follow']['times'] == 0 and never.oil_note == ''


def test_a_pressure_sensor_reading_low_as_it_warms_is_learnt_as_the_same_drift():
    mon = _monitor()
    assert warm(mon, 0.9e-3, 38, pressure=True) == ''
    learnt = mon.state_dict()['gain_follow']
    # the pressure gain's own signature: T_th s alone, without the friction's part
    assert learnt['pressure_gain_per_k'] == pytest.approx(-0.9e-3, abs=0.3e-3)
    assert learnt['torque_gain_per_k'] == 0.0
    never = _monitor(torque_constant_drift_max_per_k=0.0)
    assert warm(never, 0.9e-3, 38, pressure=True) == Verdict.NOT_FRICTION


def test_the_learnt_drift_follows_the_oil_as_it_cools_back():
    mon = _monitor()
    # warm to 55 degC, then back to 20 degC from 3000 s: the k_t returns, so does the reading
    assert warm(mon, 1.0e-3, 34, windows=6000, cool_from_s=3000.0) == ''
    assert mon.state_dict()['gain_follow']['times'] >= 1
    assert mon.level == OK


def test_a_torque_constant_reading_low_as_the_oil_warms_is_an_alarm():
    mon = _monitor()
    assert warm(mon, -1.0e-3, 35) == Verdict.NOT_FRICTION  # not the drift of a magnet
    assert _learnt(mon) == NOTHING


def _isolate(change_nm, seed, windows=600, onset=300, duration_s=0.25, noise_nm=0.01):
    """
    Feed an isolation and a gain follow windows of a pump always pumping as the oil warms.

    T - T_0 rises 0 -> 35 K while the load falls as 150 / (T - T_0 + 20) N m (7.5 -> 2.7):
    a drift c (T - T_0) of the torque gain then changes the torque by a near constant, as an
    offset would. The CUSUMs leave zero at window ``onset``. ``change_nm(delta_c, load,
    signatures, window)`` is the change [N m]. Returns both.
    """
    config = EstimatorConfig()
    isolation = FaultIsolation(settings_view(config, AttributionSettings), False)
    follow = GainFollow(1.5e-3, config.isolation_memory_s)
    rng = np.random.default_rng(seed)
    for w in range(windows):
        delta_c = 35.0 * w / windows
        load = 150.0 / (delta_c + 20.0)
        vp, other = 0.05 + 4e-4 * rng.uniform(50.0, 900.0), rng.uniform(0.1, 0.5)
        s = np.array([vp, other, load + vp + other, -load, 1.0, 1.0])
        d = change_nm(delta_c, load, s, w) + rng.normal(0.0, noise_nm)
        isolation.add(s, d, noise_nm ** -2, duration_s, w >= onset)
        follow.add(s, d, noise_nm ** -2, duration_s, delta_c)
    return isolation, follow


@pytest.mark.parametrize('seed', [41, 42, 43])
def test_a_drift_the_isolation_reads_as_a_torque_offset_is_learnt_as_the_drift(seed):
    # the change since the CUSUMs left zero is near constant: an offset explains it best
    # (the bank's seed 1 cold start, installation 1, named the offset by 1631 against 1589);
    # the drift explains it and the windows before alike
    isolation, follow = _isolate(lambda delta_c, load, s, w: 1e-3 * delta_c * s[2], seed)
    verdict, phrase, named = isolation.verdict()
    assert verdict == Verdict.NOT_FRICTION and 'torque offset' in phrase
    assert CAUSES[named] in ('torque_offset', 'drive_loss')
    assert follow.follow(isolation, 55.0, 20.0)
    assert follow.per_k[0] == pytest.approx(1e-3, rel=0.02) and follow.per_k[1] == 0.0


@pytest.mark.parametrize('alarm_verdict', [Verdict.VALVE_PLATE, Verdict.OTHER_FRICTION])
def test_no_drift_is_learnt_while_the_alarm_under_way_named_a_friction(alarm_verdict):
    # the windows of the drift above, which is learnt when the alarm begins (no verdict yet)
    # or when its height named no friction; an intermittent fault named the valve plate at
    # its height then reads "not friction" in its off episodes (the bank's seed 2 cold start,
    # installation 0, where a drift learnt ended its alarm): its alarm is to clear instead
    drift = lambda delta_c, load, s, w: 1e-3 * delta_c * s[2]  # noqa: E731
    for height in (Verdict.NONE, '', Verdict.NOT_FRICTION, Verdict.CANNOT_TELL):
        isolation, follow = _isolate(drift, 41)
        assert follow.follow(isolation, 55.0, 20.0, height)
    isolation, follow = _isolate(drift, 41)
    assert isolation.verdict()[0] == Verdict.NOT_FRICTION
    assert not follow.follow(isolation, 55.0, 20.0, alarm_verdict)
    assert follow.per_k.tolist() == [0.0, 0.0] and follow.times == 0


@pytest.mark.parametrize('seed', [41, 42, 43])
@pytest.mark.parametrize('change', ['offset', 'growing from the onset'])
def test_a_change_that_began_at_the_onset_is_not_learnt_as_drift(seed, change):
    # the same loads. An offset of 0.05 N m from the onset: a drift would fit it with
    # 0.42e-3 / K, within the largest, but it would have shown before the onset, where
    # nothing changed. A change growing as 1e-3 (T - T_0) from the onset on: fitted on the
    # windows since the onset alone it is a drift (1.0e-3 / K), but it was not there before
    def offset(delta_c, load, s, w):
        return 0.05 * (w >= 300)

    def growing(delta_c, load, s, w):
        return 1e-3 * delta_c * s[2] * (w >= 300)

    isolation, follow = _isolate(offset if change == 'offset' else growing, seed)
    assert isolation.verdict()[0] == Verdict.NOT_FRICTION
    assert not follow.follow(isolation, 55.0, 20.0)
    assert follow.per_k.tolist() == [0.0, 0.0] and follow.times == 0


@pytest.mark.parametrize('seed', [31, 32, 33])
@pytest.mark.parametrize('offset_nm', [-0.2, 0.2])
@pytest.mark.parametrize('drift_per_k', [0.0, 1.0e-3])
def test_an_offset_on_the_warm_pump_is_an_alarm_and_not_learnt_as_drift(
        seed, offset_nm, drift_per_k):
    # from 1500 s the oil stays within 2 K of 53 degC: there an offset and a drift fit the
    # windows since the change alike, but the drift would have shown at the cooler windows
    # before it, where nothing changed
    mon = _monitor()
    assert warm(mon, drift_per_k, seed, loads=ONE_SIDED, offset_nm=offset_nm) == \
        Verdict.NOT_FRICTION
    assert mon.alarm_onset_s > 150.0  # after the offset, 1500 s of wall time
    assert 'torque offset' in mon.verdict(1.0)[1]
    assert mon.measurement_drift_per_k == pytest.approx(drift_per_k, abs=0.1e-3)
    assert (_learnt(mon)['times'] == 0) == (drift_per_k == 0.0)


@pytest.mark.parametrize('seed', [31, 32, 33])
@pytest.mark.parametrize('step', [0.02, 0.03])
def test_a_torque_gain_step_the_drifts_way_on_the_warm_pump_is_an_alarm(seed, step):
    # +2 or +3 % at 33 K above commissioning would pass for 0.6-0.9e-3 / K of drift, within
    # the largest; the windows before the step, cooler and unchanged, say it is no drift
    mon = _monitor()
    assert warm(mon, 0.0, seed, gain_step=step) == Verdict.NOT_FRICTION
    assert mon.alarm_onset_s > 150.0
    phrase = mon.verdict(1.0)[1]
    assert phrase.startswith('not friction: torque-measurement gain +')
    assert float(phrase.split('+')[1]) == pytest.approx(step, abs=0.003)
    assert _learnt(mon) == NOTHING


@pytest.mark.parametrize('step', [-0.05, 0.08])
def test_a_gain_change_beyond_the_drift_on_a_warm_pump_is_an_alarm(step):
    # the drive's 1e-3 / K (no alarm alone: above), then on the warm pump (53 degC, 33 K
    # above commissioning) a torque constant 5 % low, or 8 % high: 1e-3 + 0.08 / 33 K is
    # beyond the largest drift, 1.5e-3 / K
    mon = _monitor()
    assert warm(mon, 1.0e-3, 31, gain_step=step) == Verdict.NOT_FRICTION
    assert mon.measurement_drift_per_k <= 1.5e-3
    assert mon.alarm_onset_s > 150.0  # 1500 s of wall time: after the step


@pytest.mark.parametrize('seed', [37, 38, 39])
def test_valve_plate_wear_during_the_warm_up_is_found_and_named_not_followed(seed):
    mon = _monitor()
    warm(mon, 1.0e-3, seed, wear=1.8)  # from 37 degC on, while the drift still grows
    assert mon.level > OK
    assert mon.verdict(1.0)[0] == Verdict.VALVE_PLATE
    assert abs(mon.theta_vp - 1.8) < 1.96 * mon.valve_plate_scale_std < 0.3
    assert mon.measurement_drift_per_k <= 1.5e-3


def test_the_monitor_asks_the_gain_follow_with_the_height_of_the_alarm_under_way():
    # the wear above: its alarm's first window has no height yet; every later one the
    # verdict at the alarm's height, the valve plate at the end
    mon = _monitor()
    asked, follow = [], mon._gain_follow.follow

    def spy(isolation, temperature_c, reference_c, alarm_verdict=Verdict.NONE):
        asked.append(alarm_verdict)
        return follow(isolation, temperature_c, reference_c, alarm_verdict)

    mon._gain_follow.follow = spy
    warm(mon, 1.0e-3, 37, wear=1.8)
    assert mon.level > OK and len(asked) > 1
    assert asked[0] == '' and asked[-1] == mon.last_alarm.verdict == Verdict.VALVE_PLATE


def test_the_learnt_drift_survives_a_restart_and_a_reset_forgets_it():
    mon = _monitor()
    warm(mon, 1.0e-3, 31)
    state = mon.state_dict()
    again = _monitor()
    again.load_state_dict(state)
    assert again.state_dict() == state
    assert again.measurement_drift_per_k == mon.measurement_drift_per_k > 0.0
    mon.reset()
    assert mon.state_dict()['gain_follow'] == FORGOTTEN


def test_a_state_saved_before_the_gain_follow_loads_with_nothing_learnt():
    mon = _monitor()
    warm(mon, 1.0e-3, 31)
    state = mon.state_dict()
    del state['gain_follow']
    again = _monitor()
    again.load_state_dict(state)
    assert not again.learning and again.state_dict()['gain_follow'] == FORGOTTEN


@pytest.mark.parametrize('bad', [
    {**NOTHING, 'torque_gain_per_k': -1e-4}, {**NOTHING, 'pressure_gain_per_k': 1e-4},
    {**NOTHING, 'torque_gain_per_k': math.nan}, {**NOTHING, 'times': -1}, {'times': 1},
    {**FORGOTTEN, 'g': [-1.0, 0.0]}, {**FORGOTTEN, 'g': [0.0]},
    {**FORGOTTEN, 'b': [math.nan, 0.0]}, {**NOTHING, 'b': [0.0, 0.0]}])
def test_a_bad_learnt_drift_is_refused_and_changes_nothing(bad):
    mon = _monitor()
    warm(mon, 1.0e-3, 31)
    state = mon.state_dict()
    before = mon.state_dict()
    with pytest.raises(ValueError, match='malformed monitor state'):
        mon.load_state_dict({**state, 'gain_follow': bad})
    assert mon.state_dict() == before


def test_a_drift_above_a_lowered_largest_drift_loads_scaled_to_the_largest():
    follow = GainFollow(0.5e-3, MEMORY_S)
    follow.load({'torque_gain_per_k': 0.8e-3, 'pressure_gain_per_k': -0.4e-3, 'times': 2,
                 'g': [4.0, 1.0], 'b': [0.1, 0.0]})
    assert follow.drift_per_k == pytest.approx(0.5e-3)
    # the fit's sums were of the change less the larger drift: forgotten
    assert follow.state()['g'] == follow.state()['b'] == [0.0, 0.0]
    assert follow.per_k.tolist() == pytest.approx([0.8e-3 / 2.4, -0.4e-3 / 2.4])
    assert follow.times == 2


def test_without_temperature_topic_nothing_is_learnt():
    mon = _monitor(assumed=True)
    assert 'gain_follow' not in mon.state_dict()
    assert math.isnan(mon.measurement_drift_per_k)  # /diagnostics: not learnt, not zero
    # the drift's term needs both temperatures: none where either is not known
    follow = GainFollow(1.5e-3, MEMORY_S)
    follow.per_k[:] = [1e-3, -0.5e-3]
    signatures = np.zeros(len(CAUSES))
    signatures[CAUSES.index('torque_gain')] = 4.0
    signatures[CAUSES.index('pressure_gain')] = -3.5
    assert follow.term_nm(signatures, math.nan, 20.0) == 0.0
    assert follow.term_nm(signatures, 30.0, math.nan) == 0.0
    # 10 K: 1e-3 x 10 x 4 N m + (-0.5e-3) x 10 x (-3.5 N m)
    assert follow.term_nm(signatures, 30.0, 20.0) == pytest.approx(0.04 + 0.0175)
