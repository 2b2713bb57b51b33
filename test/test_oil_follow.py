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

"""Without a temperature topic the baseline follows the oil down: windows of set truth."""

import numpy as np
from pump_friction_ros.core.attribution import Verdict
from pump_friction_ros.core.baseline import Baseline, baseline_regressors
from pump_friction_ros.core.monitor import OK, WARN
from pump_friction_ros.core.oil_follow import followed
import pytest

from .test_baseline_monitor import _changed, monitor, run, TRUTH


def thinning(mon, rng, t, to, steps=6, windows=120, then=None):
    """
    Thin the oil: the valve plate's level falls in steps to ``to`` times the learnt one.

    Returns the time after it and the highest level seen (fed 4 windows at a time).
    """
    highest = OK
    for k in range(1, steps + 1):
        factor = 1.0 + (to - 1.0) * k / steps
        for _ in range(windows // 4):
            t = run(mon, rng, 4, TRUTH, change=_changed('valve_plate', factor - 1.0), t0=t)
            highest = max(highest, mon.level)
    return t, highest


def commissioned(assumed, seed):
    mon = monitor(viscosity_assumed=assumed)
    rng = np.random.default_rng(seed)
    t = run(mon, rng, 240, TRUTH)
    assert not mon.learning and mon.level == OK
    return mon, rng, t


@pytest.mark.parametrize('seed', [21, 22, 23])
def test_without_temperature_topic_a_thinning_oil_lowers_the_baseline_and_raises_no_alarm(seed):
    mon, rng, t = commissioned(True, seed)
    t, highest = thinning(mon, rng, t, 0.6)
    follow = mon.state_dict()['oil_follow']
    assert highest == OK
    assert follow['times'] >= 1
    # followed down to where the oil is, within the detection's reach of it
    assert follow['factor'] == pytest.approx(0.6, abs=0.1)
    assert 'lowered' in mon.allowance_note and 'oil thinning' in mon.allowance_note
    # the scale is relative to the followed baseline: the pump is healthy
    assert abs(mon.theta_vp - 1.0) < 1.96 * mon.valve_plate_scale_std


def test_with_the_temperature_topic_the_same_fall_is_an_alarm():
    mon, rng, t = commissioned(False, 21)
    _, highest = thinning(mon, rng, t, 0.6)
    assert highest >= WARN
    assert 'oil_follow' not in mon.state_dict()


def test_wear_after_the_oil_thinned_is_detected_against_the_thinner_oil():
    mon, rng, t = commissioned(True, 22)
    t, _ = thinning(mon, rng, t, 0.6)
    factor = mon.state_dict()['oil_follow']['factor']
    # valve plate x1.8 of where the oil now is (0.6 of the learnt level)
    run(mon, rng, 240, TRUTH, change=_changed('valve_plate', 0.6 * 1.8 - 1.0), t0=t)
    assert mon.level >= WARN
    assert mon.verdict(1.0)[0] == Verdict.VALVE_PLATE
    truth = 0.6 * 1.8 / factor  # relative to the followed baseline
    assert abs(mon.theta_vp - truth) < 1.96 * mon.valve_plate_scale_std < 0.3


@pytest.mark.parametrize(('cause', 'size'), [('torque_gain', -0.05), ('torque_offset', -0.1)])
def test_a_fall_that_is_not_the_valve_plate_is_still_an_alarm(cause, size):
    mon, rng, t = commissioned(True, 23)
    run(mon, rng, 240, TRUTH, change=_changed(cause, size), t0=t)
    assert mon.level >= WARN
    assert mon.verdict(1.0)[0] == Verdict.NOT_FRICTION
    assert mon.state_dict()['oil_follow'] == {'factor': 1.0, 'times': 0}


def test_a_rise_of_the_valve_plate_is_never_followed():
    mon, rng, t = commissioned(True, 24)
    run(mon, rng, 240, TRUTH, change=_changed('valve_plate', 0.4), t0=t)
    assert mon.level >= WARN
    assert mon.state_dict()['oil_follow']['times'] == 0


def test_the_followed_baseline_survives_a_restart_and_a_reset_forgets_it():
    mon, rng, t = commissioned(True, 21)
    thinning(mon, rng, t, 0.6)
    state = mon.state_dict()
    again = monitor(viscosity_assumed=True)
    again.load_state_dict(state)
    assert again.state_dict()['oil_follow'] == state['oil_follow']
    np.testing.assert_array_equal(again.baseline.coefficients, mon.baseline.coefficients)
    # a file written before the following existed: nothing followed
    older = dict(state)
    del older['oil_follow']
    again.load_state_dict(older)
    np.testing.assert_array_equal(again.baseline.coefficients, again.fit.coefficients)
    bad = dict(state, oil_follow={'factor': 1.5, 'times': 1})
    with pytest.raises(ValueError, match='malformed'):
        again.load_state_dict(bad)
    mon.reset()
    assert mon.state_dict()['oil_follow'] == {'factor': 1.0, 'times': 0}


def test_followed_scales_the_valve_plate_level_and_only_it():
    rng = np.random.default_rng(7)
    coefficients = np.array([0.2, -0.1, 0.02, 0.01, 0.03, 1e-4])
    root = rng.normal(size=(6, 6)) * 0.01
    base = Baseline(coefficients, root @ root.T, 1e-4, 30.0)
    assert followed(base, 1.0) is base
    low = followed(base, 0.7)
    for _ in range(20):
        vp, other, th, a = rng.uniform(0.0, 1.0), rng.uniform(0.0, 1.0), rng.normal(), rng.normal()
        h = baseline_regressors(vp, other, th, 1.0, a)
        # e_hat moves by the valve-plate level's change only: (0.7 - 1) l_vp T_vp
        assert low.predict(h) - base.predict(h) == pytest.approx(-0.3 * 1.2 * vp)
    h_vp = np.eye(6)[0]  # the valve-plate term alone
    assert low.prediction_var(h_vp) == pytest.approx(0.49 * base.prediction_var(h_vp))
