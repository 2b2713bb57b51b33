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

import math

import numpy as np
from pump_friction_ros.core.attribution import Verdict
from pump_friction_ros.core.baseline import Baseline, baseline_regressors
from pump_friction_ros.core.monitor import OK, WARN
from pump_friction_ros.core.oil_follow import followed, friction_fall, OilFollow
import pytest

from .test_baseline_monitor import (
    _changed,
    DT,
    feed,
    monitor,
    operating_points,
    run,
    TRUTH,
    WINDOW_SAMPLES,
)


def thinning(mon, rng, t, to, cause='valve_plate', steps=6, windows=120):
    """
    Thin the oil: one friction's level falls in steps to ``to`` times the learnt one.

    Returns the time after it and the highest level seen after any window.
    """
    highest = OK
    for k in range(1, steps + 1):
        factor = 1.0 + (to - 1.0) * k / steps
        for _ in range(windows):
            t = run(mon, rng, 1, TRUTH, change=_changed(cause, factor - 1.0), t0=t)
            highest = max(highest, mon.level)
    return t, highest


def commissioned(assumed, seed, **overrides):
    mon = monitor(viscosity_assumed=assumed, **overrides)
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
    # followed down to where the oil is, within the detection's reach of it; the other
    # friction did not move
    assert follow['valve_plate'] == pytest.approx(0.6, abs=0.1)
    assert follow['other_friction'] == 1.0
    assert 'lowered' in mon.oil_note and 'oil thinning' in mon.oil_note
    # the scale is relative to the followed baseline: the pump is healthy
    assert abs(mon.theta_vp - 1.0) < 1.96 * mon.valve_plate_scale_std


def test_a_thinning_oil_that_shows_in_the_bearing_drag_lowers_the_other_friction():
    mon, rng, t = commissioned(True, 25)
    t, highest = thinning(mon, rng, t, 0.6, 'other_friction')
    follow = mon.state_dict()['oil_follow']
    assert highest == OK
    assert follow['other_friction'] == pytest.approx(0.6, abs=0.1)
    assert follow['valve_plate'] == 1.0


def test_with_the_temperature_topic_the_same_fall_is_an_alarm():
    mon, rng, t = commissioned(False, 21)
    _, highest = thinning(mon, rng, t, 0.6)
    assert highest >= WARN
    assert 'oil_follow' not in mon.state_dict()


def test_wear_after_the_oil_thinned_is_detected_against_the_thinner_oil():
    # the pump has the model's shapes: its levels carry no model error
    # (`test_level_systematic` pins that floor)
    mon, rng, t = commissioned(True, 22, level_systematic_std=0.0)
    t, _ = thinning(mon, rng, t, 0.6)
    factor = mon.state_dict()['oil_follow']['valve_plate']
    assert factor == pytest.approx(0.6, abs=0.1)
    # valve plate x1.8 of where the oil now is (0.6 of the learnt level)
    run(mon, rng, 240, TRUTH, change=_changed('valve_plate', 0.6 * 1.8 - 1.0), t0=t)
    assert mon.level >= WARN
    assert mon.verdict(1.0)[0] == Verdict.VALVE_PLATE
    # the wear over the healthy pump now (1.8), and over the followed baseline: the oil
    # was seen moving, so the interval holds every healthy level within the unseen change
    # (healthy_level); its half-width is the reading's (< 0.15) carried over that range
    half = 1.96 * mon.valve_plate_scale_std
    unseen = mon.undetectable_change['valve_plate']
    assert abs(mon.theta_vp - 1.8) < half and abs(mon.theta_vp - 0.6 * 1.8 / factor) < half
    assert half < 0.5 * ((1.8 + 0.15) / (1.0 - unseen) - (1.8 - 0.15) / (1.0 + unseen))
    # published about the reading: its upper end over the least healthy level is the farther
    assert half < (mon.theta_vp + 0.15) / (1.0 - unseen) - mon.theta_vp < 0.5


@pytest.mark.parametrize(('cause', 'size'), [('torque_gain', -0.05), ('torque_offset', -0.1)])
def test_a_fall_that_is_not_the_valve_plate_is_still_an_alarm(cause, size):
    mon, rng, t = commissioned(True, 23)
    run(mon, rng, 240, TRUTH, change=_changed(cause, size), t0=t)
    assert mon.level >= WARN
    assert mon.verdict(1.0)[0] == Verdict.NOT_FRICTION
    assert mon.state_dict()['oil_follow']['times'] == 0


def test_a_rise_of_the_valve_plate_is_never_followed():
    mon, rng, t = commissioned(True, 24)
    run(mon, rng, 240, TRUTH, change=_changed('valve_plate', 0.4), t0=t)
    assert mon.level >= WARN
    assert mon.state_dict()['oil_follow']['times'] == 0
    # named valve plate, and not a fall: nothing to follow whatever calls it
    assert mon.verdict(1.0)[0] == Verdict.VALVE_PLATE
    j, change = friction_fall(mon.isolation)
    assert j == -1 and math.isnan(change)
    assert OilFollow().follow(mon.isolation, mon.fit) is None


def test_the_fall_followed_is_the_one_the_isolation_names():
    mon, rng, t = commissioned(True, 21)
    seen = []
    for _ in range(240):  # valve plate at 0.6 at once: the fall as the isolation sees it
        t = run(mon, rng, 1, TRUTH, change=_changed('valve_plate', -0.4), t0=t)
        if mon.cusum_neg_nm_s > 0.0:
            seen.append((*friction_fall(mon.isolation), mon.isolation.verdict()[0]))
    named = [change for j, change, _ in seen if j == 0]
    assert named and all(-0.6 < change < -0.2 for change in named)
    # the other friction only while the first windows cannot tell the two apart; the
    # follow itself (at the alarm) is the valve plate's
    assert all(j in (-1, 0) or verdict == Verdict.CANNOT_TELL for j, _, verdict in seen)
    follow = mon.state_dict()['oil_follow']
    assert follow['times'] == 1 and follow['other_friction'] == 1.0


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
    assert again.state_dict()['oil_follow']['times'] == 0 and again.oil_note == ''
    bad = dict(state, oil_follow={'valve_plate': 1.5, 'other_friction': 1.0, 'times': 1})
    with pytest.raises(ValueError, match='malformed'):
        again.load_state_dict(bad)
    mon.reset()
    assert mon.state_dict()['oil_follow'] == {'valve_plate': 1.0, 'other_friction': 1.0,
                                              'times': 0}


def test_followed_scales_the_friction_levels_and_nothing_else():
    rng = np.random.default_rng(7)
    coefficients = np.array([0.2, -0.1, 0.02, 0.01, 0.03, 1e-4])
    root = rng.normal(size=(6, 6)) * 0.01
    base = Baseline(coefficients, root @ root.T, 1e-4, 30.0)
    assert followed(base, np.ones(2)) is base
    low = followed(base, np.array([0.7, 0.9]))
    for _ in range(20):
        vp, other, th, a = rng.uniform(0.0, 1.0), rng.uniform(0.0, 1.0), rng.normal(), rng.normal()
        h = baseline_regressors(vp, other, th, 1.0, a)
        # e_hat moves by the friction levels' changes only: (f - 1) l T for each
        assert low.predict(h) - base.predict(h) == pytest.approx(-0.3 * 1.2 * vp
                                                                 - 0.1 * 0.9 * other)
    h_vp, h_other, h_gain = np.eye(6)[0], np.eye(6)[1], np.eye(6)[4]
    assert low.prediction_var(h_vp) == pytest.approx(0.49 * base.prediction_var(h_vp))
    assert low.prediction_var(h_other) == pytest.approx(0.81 * base.prediction_var(h_other))
    assert low.prediction_var(h_gain) == base.prediction_var(h_gain)
    assert low.prediction_var(h_vp + h_other) == pytest.approx(
        0.49 * base.covariance[0, 0] + 0.81 * base.covariance[1, 1]
        + 2 * 0.63 * base.covariance[0, 1])


def test_the_chunk_path_follows_the_oil_as_the_sample_path_does():
    rng = np.random.default_rng(26)
    rows = []
    vp, other, th_s, sign, a_s = operating_points(rng, 720)
    for k in range(vp.size):  # commissioning, then the valve plate falling to 0.6
        h = baseline_regressors(vp[k], other[k], th_s[k], sign[k], a_s[k])
        fall = -0.4 * min(max(k - 240, 0) / 360, 1.0)
        e = float(h @ TRUTH) + rng.normal(0.0, 0.01) + _changed('valve_plate', fall)(
            vp[k], other[k], th_s[k], sign[k], a_s[k])
        rows += [(len(rows) * DT, DT, e, vp[k], other[k], th_s[k] * sign[k], sign[k],
                  a_s[k] * sign[k])] * WINDOW_SAMPLES
    one, many = monitor(viscosity_assumed=True), monitor(viscosity_assumed=True)
    for row in rows:
        one.update(*row)
    columns = [list(c) for c in zip(*rows, strict=True)]
    many.update_many(*(c[:70_000] for c in columns))
    many.update_many(*(c[70_000:] for c in columns))
    assert one.state_dict()['oil_follow']['times'] >= 1
    assert many.state_dict() == one.state_dict()


def _collinear(mon, rng, t, windows, change):
    """Windows where the other friction is always 2x the valve plate's: one signature."""
    for k in range(windows):
        vp = float(rng.uniform(0.1, 0.5))
        sign = 1.0 if k % 2 else -1.0
        th_s = float(rng.uniform(-3.0, 3.0))
        h = baseline_regressors(vp, 2.0 * vp, th_s, sign)
        e = float(h @ TRUTH) + rng.normal(0.0, 0.01) + change * (1 + TRUTH[0]) * vp
        t = feed(mon, t, e, vp, 2.0 * vp, th_s * sign, sign)
    return t


@pytest.mark.parametrize('seed', [31, 32])
def test_a_fall_the_isolation_cannot_give_to_one_friction_is_followed_as_the_oil(seed):
    mon = monitor(viscosity_assumed=True)
    rng = np.random.default_rng(seed)
    t = _collinear(mon, rng, 0.0, 240, 0.0)
    assert not mon.learning and mon.level == OK
    # the valve plate's film shear falls to 0.6 of the learnt: on this duty cycle it reads
    # as either friction's fall (the verdict cannot tell them apart)
    seen, highest = [], OK
    for _ in range(240):
        t = _collinear(mon, rng, t, 1, -0.4)
        highest = max(highest, mon.level)
        if mon.cusum_neg_nm_s > 0.0 and mon.isolation.verdict()[0] == Verdict.CANNOT_TELL:
            seen.append(friction_fall(mon.isolation))
    assert any(j >= 0 for j, _ in seen)  # the cannot-tell verdict did come, and was a fall
    follow = mon.state_dict()['oil_follow']
    assert highest == OK and follow['times'] >= 1
    # the whole fall on one friction (either explains it), as the valve plate's factor: a
    # fall f - 1 of the other friction's level is (f - 1) (1 + b_other) 2 / (1 + b_vp) of
    # the valve plate's, its torque twice the valve plate's shear on this cycle
    vp, other = follow['valve_plate'], follow['other_friction']
    assert min(vp, other) < 1.0 == max(vp, other)
    as_vp = vp if vp < 1.0 else 1.0 + (other - 1.0) * 2.0 * (1 + TRUTH[1]) / (1 + TRUTH[0])
    assert as_vp == pytest.approx(0.6, abs=0.1)


def test_a_rise_the_isolation_cannot_give_to_one_friction_stays_an_alarm():
    mon = monitor(viscosity_assumed=True)
    rng = np.random.default_rng(33)
    t = _collinear(mon, rng, 0.0, 240, 0.0)
    _collinear(mon, rng, t, 240, 0.8)
    assert mon.level >= WARN
    assert mon.verdict(1.0)[0] == Verdict.CANNOT_TELL
    assert friction_fall(mon.isolation) == (-1, pytest.approx(math.nan, nan_ok=True))
    assert mon.state_dict()['oil_follow']['times'] == 0
