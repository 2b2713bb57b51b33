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

"""Without a temperature topic, a start or a pause waits for the oil: windows of set truth."""

from dataclasses import replace
import json
import math
import re

import numpy as np
from pump_friction_ros.core.attribution import Verdict
from pump_friction_ros.core.baseline import baseline_regressors
from pump_friction_ros.core.baseline_file import baseline_document, load_baseline, write_baseline
from pump_friction_ros.core.diagnostics import level_message
from pump_friction_ros.core.estimator import TorqueEstimator
from pump_friction_ros.core.monitor import OK
from pump_friction_ros.core.node_parameters import EstimatorConfig
from pump_friction_ros.core.warm_up_hold import HOLD_LIMIT_TIME_CONSTANTS
from pump_friction_ros.physics.oil import WaltherViscosity
from pump_friction_ros.table.friction_table import build_table
import pytest

from .test_baseline_file import CONFIG as BASELINE_FILE_CONFIG, feed as feed_estimator, NS
from .test_baseline_monitor import feed, monitor, operating_points, run, TRUTH

WALL_PER_WINDOW_S = 2.5  # 0.25 s windows, 10 % of the time monitored (the bank's EHA: 7-22 %)
VG46 = WaltherViscosity(46e-6, 6.8e-6)  # ISO VG 46 (ASTM D341)
COLD = VG46(20.0) / VG46(50.0)  # a morning at 20 degC, commissioned at 50: 4.47
TAU_S = 600.0  # the oil's warm-up time constant (a small EHA: 5-15 min)
SETTLE_S = EstimatorConfig().baseline_settle_time_constant_s  # the slowest waited for: 900 s
LIMIT_S = HOLD_LIMIT_TIME_CONSTANTS * SETTLE_S


def warm_commissioned(seed, assumed=True, **overrides):
    """Commission a pump on warm oil; return its saved state, the rng and the time after."""
    mon = monitor(viscosity_assumed=assumed, **overrides)
    rng = np.random.default_rng(seed)
    t = run(mon, rng, 240, TRUTH)
    assert not mon.learning and mon.level == OK
    return mon.state_dict(), rng, t


def restarted(state, assumed=True, **overrides):
    mon = monitor(viscosity_assumed=assumed, **overrides)
    mon.load_state_dict(state)
    return mon


def warming(mon, rng, t0, seconds, cold=COLD, wear=1.0, tau_s=TAU_S):
    """
    Run a pump whose oil warms from ``cold`` times the commissioning's viscosity.

    The valve plate's film shear (all of its modelled friction here) is linear in the
    viscosity and the other friction (bearing drag) follows it to the 2/3 power, each
    settling as exp(-t / tau); ``wear`` multiplies the valve plate's. Returns the levels
    after each window, why the detection was held there ('' where not), and the end time.
    """
    n = int(seconds / WALL_PER_WINDOW_S)
    vp, other, th_s, sign, a_s = operating_points(rng, n)
    levels, held = [], []
    for k in range(n):
        t = t0 + k * WALL_PER_WINDOW_S
        viscosity = 1.0 + (cold - 1.0) * math.exp(-(t - t0) / tau_s)
        h = baseline_regressors(vp[k], other[k], th_s[k], sign[k], a_s[k])
        e = float(h @ TRUTH) + rng.normal(0.0, 0.01) \
            + (viscosity * wear - 1.0) * (1.0 + TRUTH[0]) * vp[k] \
            + (viscosity ** (2.0 / 3.0) - 1.0) * (1.0 + TRUTH[1]) * other[k]
        feed(mon, t, e, vp[k], other[k], th_s[k] * sign[k], sign[k], a_s[k] * sign[k])
        levels.append(mon.level)
        held.append(mon.held)
    return levels, held, t0 + n * WALL_PER_WINDOW_S


@pytest.mark.parametrize(('seed', 'cold', 'tau_s'), [
    (31, COLD, TAU_S), (32, COLD, TAU_S), (33, COLD, TAU_S),
    (31, COLD, SETTLE_S),  # as slow as the settling waited for
    (31, 1.2, SETTLE_S), (32, 1.2, SETTLE_S)])  # a cool oil, as slow
def test_a_cold_start_from_a_warm_baseline_waits_for_the_oil_and_raises_no_alarm(seed, cold,
                                                                                 tau_s):
    state, rng, t = warm_commissioned(seed)
    mon = restarted(state)
    assert mon.held == ''  # nothing is known of the pause before the next window
    levels, held, _ = warming(mon, rng, t + 12 * 3600.0, LIMIT_S + 600.0, cold, tau_s=tau_s)
    assert held[0].startswith('holding the detection after 12 h without monitored running')
    assert max(levels) == OK
    # held while the oil warms (the friction up to 1.2 N m above the baseline at first),
    # released once it has settled; an oil faster than the settling waited for before the
    # limit
    released_s = held.index('') * WALL_PER_WINDOW_S
    assert held.index('') + 1 > 240  # not at the first check (60 s of monitored running)
    assert released_s <= LIMIT_S + WALL_PER_WINDOW_S
    if cold == COLD:
        assert released_s > tau_s
    if tau_s < SETTLE_S:
        assert released_s < LIMIT_S - 600.0
    assert mon.oil_moved  # its check restarted: the oil was seen moving
    # the same morning without the hold: an alarm, valve plate or oil viscosity
    again = restarted(state, warm_up_pause_s=0.0)
    levels, held, _ = warming(again, np.random.default_rng(seed), t + 12 * 3600.0, 2400.0,
                              cold, tau_s=tau_s)
    assert max(levels) > OK and not any(held)


@pytest.mark.parametrize('seed', [31, 32])
def test_the_drift_is_extrapolated_from_the_first_check_on(seed):
    # an oil only 1.1 times as viscous, as slow as the settling waited for: its drift
    # between the first check's halves alone is within the tolerance (released at once,
    # after 240 windows, when not extrapolated); a start is a change until shown otherwise
    state, rng, t = warm_commissioned(seed)
    mon = restarted(state)
    levels, held, _ = warming(mon, rng, t + 12 * 3600.0, LIMIT_S, 1.1, tau_s=SETTLE_S)
    assert max(levels) == OK and held.index('') + 1 > 240


def test_wear_that_came_with_the_start_is_detected_once_the_oil_has_settled():
    state, rng, t = warm_commissioned(34)
    mon = restarted(state)
    levels, held, _ = warming(mon, rng, t + 12 * 3600.0, LIMIT_S + 600.0, wear=1.8)
    first = levels.index(next(x for x in levels if x > OK))
    assert not held[first] and held[0]  # judged after the hold, not during it
    verdict, words = mon.verdict(1.0)
    assert verdict == Verdict.VALVE_PLATE and 'oil viscosity' in words


@pytest.mark.parametrize('seed', range(10))
def test_a_steady_pump_is_released_after_about_one_check(seed):
    state, rng, t = warm_commissioned(40 + seed)
    mon = restarted(state)
    levels, held, _ = warming(mon, rng, t + 3600.0, 1800.0, cold=1.0)
    assert max(levels) == OK
    # two halves of baseline_learn_s (60 s of monitored running: 240 windows), or a few
    # more where the noise makes the halves disagree
    assert 240 <= held.index('') + 1 <= 720, held.index('')
    assert not mon.oil_moved or mon.commissioning.restarts  # a steady pump did not move


def test_a_pause_longer_than_warm_up_pause_s_holds_and_a_shorter_one_does_not():
    state, rng, t = warm_commissioned(35)
    mon = restarted(state)
    _, held, t = warming(mon, rng, t, 900.0, cold=1.0)
    assert not held[-1]
    pause_s = EstimatorConfig().warm_up_pause_s
    _, held, t = warming(mon, rng, t + 0.9 * pause_s, 10.0, cold=1.0)
    assert not any(held)
    _, held, t = warming(mon, rng, t + 1.1 * pause_s, 10.0, cold=1.0)
    assert all(held)
    said = re.match(r'holding the detection after (\d+) s without monitored running', mon.held)
    # from the last window's close to the next's: the pause and one window's wall time
    assert said and float(said.group(1)) == pytest.approx(1.1 * pause_s + WALL_PER_WINDOW_S,
                                                          abs=1.0)
    assert level_message(OK, mon) == mon.held  # /diagnostics says why, at OK


def test_with_the_temperature_topic_nothing_is_held():
    state, rng, t = warm_commissioned(36, assumed=False)
    mon = restarted(state, assumed=False)
    _, held, _ = warming(mon, rng, t + 12 * 3600.0, 300.0, cold=1.0)
    assert not any(held) and mon.held == ''
    assert 'warm_up_hold' not in mon.state_dict()


def test_a_friction_that_never_settles_is_judged_after_the_limit():
    state, rng, t = warm_commissioned(37)
    mon = restarted(state, baseline_settle_time_constant_s=300.0)
    # an oil warming ten times as slowly as the settling waited for: still moving at the
    # limit, with most of its friction still to come
    _, held, _ = warming(mon, rng, t + 3600.0, 2000.0, tau_s=3000.0)
    released_s = held.index('') * WALL_PER_WINDOW_S
    assert released_s == pytest.approx(HOLD_LIMIT_TIME_CONSTANTS * 300.0,
                                       abs=2 * WALL_PER_WINDOW_S)


def test_the_holds_seen_moving_survive_a_restart_and_a_reset_forgets_them():
    state, rng, t = warm_commissioned(38)
    mon = restarted(state)
    warming(mon, rng, t + 3600.0, LIMIT_S + 600.0)
    saved = mon.state_dict()['warm_up_hold']
    assert saved['moved'] >= 1 and mon.oil_moved and not saved['held']
    again = restarted(mon.state_dict())
    assert json.dumps(again.state_dict()['warm_up_hold']) == json.dumps(saved)
    assert again.oil_moved
    # the next window 5 s after the last one saved: a restart without a pause, not held
    _, held, _ = warming(again, rng, saved['last_s'] + 5.0, 2.5, cold=1.0)
    assert held == ['']
    older = dict(mon.state_dict())
    del older['warm_up_hold']  # a file written before the hold: no move seen, when unknown
    older_restart = restarted(older)
    assert older_restart.state_dict()['warm_up_hold']['moved'] == 0
    assert older_restart.held.startswith('holding the detection after a restart from a '
                                         'baseline file without its time')
    # a refused state leaves the monitor, its hold included, as it was
    before = json.dumps(older_restart.state_dict())
    check = {key: value for key, value in saved.items() if key != 'check'}
    for bad in (dict(saved, moved=-1), dict(saved, last_s=math.inf), dict(saved, held=1),
                check):
        with pytest.raises(ValueError, match='malformed'):
            older_restart.load_state_dict(dict(older, warm_up_hold=bad))
        assert json.dumps(older_restart.state_dict()) == before and older_restart.held
    again.reset()
    assert again.state_dict()['warm_up_hold']['moved'] == 0 and again.held == ''


def test_a_pause_right_after_commissioning_holds_and_a_clock_gone_back_does_not():
    mon = monitor(viscosity_assumed=True)
    rng = np.random.default_rng(39)
    t = run(mon, rng, 240, TRUTH)
    assert not mon.learning and mon.held == ''  # commissioning's windows are never held
    _, held, _ = warming(mon, rng, t - 3600.0, 10.0, cold=1.0)  # a clock set back an hour
    assert not any(held)
    _, held, _ = warming(mon, rng, t + 2 * EstimatorConfig().warm_up_pause_s, 10.0, cold=1.0)
    assert all(held)  # the pause counted from the last window commissioning learnt


def test_a_pause_during_a_hold_starts_it_afresh():
    state, rng, t = warm_commissioned(51)
    mon = restarted(state)
    levels, held, t = warming(mon, rng, t + 12 * 3600.0, 1500.0)  # 25 min warming
    assert all(held)
    levels, held, _ = warming(mon, rng, t + 900.0, LIMIT_S + 600.0)  # 15 min off: cold again
    assert max(levels) == OK and held[0].startswith('holding the detection after 15 min')
    assert held.index('') * WALL_PER_WINDOW_S > TAU_S


def test_a_restart_during_a_hold_resumes_it():
    state, rng, t = warm_commissioned(52)
    mon = restarted(state)
    levels, held, t = warming(mon, rng, t + 12 * 3600.0, 300.0)
    assert all(held)
    again = restarted(mon.state_dict())  # a respawn, 5 s later: no pause
    assert again.held == mon.held
    # the oil goes on warming where it was: 300 s into its warm-up
    left = 1.0 + (COLD - 1.0) * math.exp(-300.0 / TAU_S)
    levels, held, _ = warming(again, rng, t + 5.0, LIMIT_S, left)
    assert max(levels) == OK and held[0] and not held[-1]


def test_a_window_without_a_time_keeps_the_hold_and_the_last_time():
    state, rng, t = warm_commissioned(53)
    mon = restarted(state)
    _, held, t = warming(mon, rng, t + 12 * 3600.0, 100.0)
    assert all(held)
    last = mon.state_dict()['warm_up_hold']['last_s']
    feed(mon, math.nan, 0.5, 0.1, 0.1, 0.0, 1.0)  # one window, its stamps not numbers
    assert mon.held and mon.state_dict()['warm_up_hold']['last_s'] == last


def test_with_the_drift_alone_a_hold_ends_at_its_first_check():
    state, rng, t = warm_commissioned(54, baseline_settle_time_constant_s=0.0)
    mon = restarted(state, baseline_settle_time_constant_s=0.0)
    _, held, _ = warming(mon, rng, t + 12 * 3600.0, 900.0)
    assert held[0] and held.index('') + 1 == 240  # two halves of 30 s of monitored running


@pytest.fixture(scope='module')
def table(paper_params):
    return build_table(paper_params)


def test_a_node_restart_the_next_morning_holds_and_one_a_second_later_does_not(
        table, tmp_path):
    """Through the estimator and its baseline file: the pause counted from the saved time."""
    config = replace(BASELINE_FILE_CONFIG, baseline_learn_s=0.05)
    core = TorqueEstimator(config, table, 46e-6, 'hong_doh_2004')
    for k in range(20):  # steady running, each burst 1 s after the last
        feed_estimator(core, start=k * NS)
    assert not core.monitor.learning
    path = tmp_path / 'baseline.yaml'
    write_baseline(path, baseline_document(core, origin='test'))
    for pause_ns, held in ((12 * 3600 * NS, True), (NS, False)):
        again = TorqueEstimator(config, table, 46e-6, 'hong_doh_2004')
        load_baseline(again, path)
        for k in range(5):  # 0.4 s of monitored running: windows of 0.25 s close
            feed_estimator(again, start=(20 + k) * NS + pause_ns)
        values = dict(again.diagnostics(0).values)
        assert values['detection_held'] == str(int(held))
        assert again.diagnostics(0).message.startswith(
            'holding the detection after 12 h without monitored running') == held
