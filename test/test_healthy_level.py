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

"""Without the temperature, the healthy level now is known within the unseen change."""

import math

import numpy as np
from pump_friction_ros.core.attribution import Verdict
from pump_friction_ros.core.baseline import baseline_regressors
from pump_friction_ros.core.friction_bias import Z95
from pump_friction_ros.core.healthy_level import oil_seen_moving, with_unseen_level
from pump_friction_ros.core.monitor import OK, WARN
import pytest

from .test_baseline_monitor import _changed, feed, monitor, run, TRUTH
from .test_oil_follow import commissioned, thinning


@pytest.mark.parametrize(('low', 'high', 'unseen'), [
    (-0.1, 0.1, 0.2), (0.3, 0.5, 0.25), (-0.4, -0.2, 0.1), (0.0, 0.0, 0.3), (-0.5, 1.5, 0.6)])
def test_the_interval_over_an_unseen_healthy_level_holds_every_ratio_and_no_more(
        low, high, unseen):
    # every reading c in [low, high] over every healthy level 1 + b, |b| <= unseen: the
    # wear (1 + c) / (1 + b) - 1; the interval is exactly their range (closed form: the
    # ratio is monotone in each, its extremes at the corners)
    c, b = np.meshgrid(np.linspace(low, high, 201), np.linspace(-unseen, unseen, 201))
    wear = (1.0 + c) / (1.0 + b) - 1.0
    lo, hi = with_unseen_level(low, high, unseen)
    assert lo == pytest.approx(wear.min(), abs=1e-12)
    assert hi == pytest.approx(wear.max(), abs=1e-12)
    assert with_unseen_level(low, high, 0.0) == (low, high)


@pytest.mark.parametrize('unseen', [1.0, 1.3])
def test_an_unseen_change_of_the_whole_level_leaves_the_scale_unbounded_above(unseen):
    # a healthy level that may be nothing: no upper end (not a reading over almost zero)
    lo, hi = with_unseen_level(-0.1, 0.1, unseen)
    assert lo == pytest.approx(0.9 / (1.0 + unseen) - 1.0) and hi == math.inf


@pytest.mark.parametrize('case', ['no change', 'valve_plate'])
def test_a_scale_whose_healthy_level_may_be_nothing_reads_as_read_with_an_infinite_std(case):
    # seen on the bank's cold start without topic, seed 3: the valve plate's undetectable
    # change above 1 on thin oil was published as 1 +- 1e6 (and a named one would have read
    # the middle of [c, 1e6 c]: some 5e5)
    mon = _state(case)
    confirmed = mon.level != OK
    assert confirmed == (case == 'valve_plate')
    unseen = mon._undetectable.copy()
    unseen[0] = 1.2
    vp, vp_std, other, other_std = mon.isolation.scales(mon.baseline, unseen, confirmed, True)
    assert vp_std == math.inf
    if confirmed:  # the change as read (a valve plate x1.8)
        assert vp == pytest.approx(1.0 + mon.isolation.friction_change(0)[0], rel=1e-12)
        assert 1.5 < vp < 2.2
    else:
        assert vp == 1.0
    assert math.isfinite(other) and math.isfinite(other_std)  # its own level is known


@pytest.mark.parametrize(('assumed', 'band', 'restarts', 'follows', 'expected'), [
    (True, 0.0, 1, 0, True), (True, 0.0, 0, 2, True), (True, 0.0, 0, 0, False),
    (False, 0.0, 3, 0, False), (True, 3.0, 1, 1, False)])
def test_the_healthy_level_is_uncertain_without_topic_or_band_once_the_oil_was_seen_moving(
        assumed, band, restarts, follows, expected):
    assert oil_seen_moving(assumed, band, restarts, follows) is expected


def test_a_steady_installation_without_topic_keeps_its_intervals():
    mon, rng, t = commissioned(True, 31)
    run(mon, rng, 480, TRUTH, t0=t)
    assert mon.commissioning.restarts == 0 and mon.state_dict()['oil_follow']['times'] == 0
    assert not mon.oil_moved and 'seen moving' not in mon.oil_note


def _collinear(mon, rng):
    """Commission on one friction shape (other = 2 x valve plate), then a valve plate x1.8."""
    t = 0.0
    for k in range(480):
        vp = float(rng.uniform(0.1, 0.5))
        sign = 1.0 if k % 2 else -1.0
        th_s = float(rng.uniform(-3.0, 3.0))
        e = float(baseline_regressors(vp, 2.0 * vp, th_s, sign) @ TRUTH) + \
            rng.normal(0.0, 0.01) + (0.8 * (1 + TRUTH[0]) * vp if k >= 240 else 0.0)
        t = feed(mon, t, e, vp, 2.0 * vp, th_s * sign, sign)


def _state(case):
    """Return a no-topic monitor in one of `scales`' cases."""
    mon, rng, t = commissioned(True, 51)
    if case == 'no windows':
        mon.isolation.reset()
    elif case == 'no change':
        run(mon, rng, 120, TRUTH, t0=t)
        assert mon.cusum_pos_nm_s == mon.cusum_neg_nm_s == 0.0
    elif case == 'not confirmed':  # a change under way, below the threshold
        run(mon, rng, 12, TRUTH, change=_changed('valve_plate', 0.3), t0=t)
        assert mon.cusum_pos_nm_s > 0.0 and mon.isolation.stats.windows
    elif case in ('valve_plate', 'torque_offset'):
        run(mon, rng, 240, TRUTH, change=_changed(case, 0.8 if case == 'valve_plate' else 0.1),
            t0=t)
    else:  # cannot tell
        mon = monitor(viscosity_assumed=True)
        _collinear(mon, np.random.default_rng(6))
    return mon


def _ends(scale, std):
    return scale - 1.0 - Z95 * std, scale - 1.0 + Z95 * std


@pytest.mark.parametrize(('case', 'verdict'), [
    ('no windows', Verdict.NONE), ('no change', Verdict.NONE), ('not confirmed', Verdict.NONE),
    ('valve_plate', Verdict.VALVE_PLATE), ('torque_offset', Verdict.NOT_FRICTION),
    ('cannot tell', Verdict.CANNOT_TELL)])
def test_every_case_of_the_scales_carries_the_interval_over_the_unseen_healthy_level(
        case, verdict):
    mon = _state(case)
    confirmed = mon.level != OK
    assert confirmed == (verdict != Verdict.NONE)
    if confirmed:
        assert mon.verdict(1.0)[0] == verdict
    before = mon.isolation.scales(mon.baseline, mon._undetectable, confirmed, False)
    after = mon.isolation.scales(mon.baseline, mon._undetectable, confirmed, True)
    for k, cause in ((0, 'valve_plate'), (2, 'other_friction')):
        unseen = mon.undetectable_change[cause]
        old, new = _ends(*before[k:k + 2]), _ends(*after[k:k + 2])
        named = {Verdict.VALVE_PLATE: 'valve_plate', Verdict.NOT_FRICTION: 'torque_offset'}
        if not confirmed or (verdict != Verdict.CANNOT_TELL and named[verdict] != cause):
            # no change confirmed, or another cause named: still 1, the larger half either side
            assert after[k] == 1.0
            assert new[1] == pytest.approx(with_unseen_level(*old, unseen)[1], rel=1e-12)
            assert new[0] == pytest.approx(-new[1], rel=1e-12)
        else:  # the change as read, +- what holds its interval over every healthy level
            middle, ends = before[k] - 1.0, with_unseen_level(*old, unseen)
            assert after[k] == pytest.approx(before[k], rel=1e-12)
            half = max(ends[1] - middle, middle - ends[0])
            assert new == pytest.approx((middle - half, middle + half), rel=1e-12)
            assert new[0] <= ends[0] + 1e-12 and new[1] >= ends[1] - 1e-12
        assert new[0] <= old[0] and new[1] >= old[1]  # it holds the interval over the baseline
        assert unseen == 0.0 or new[1] - new[0] > old[1] - old[0] or new == old


def _wear_on_an_oil_thinned_unseen(seed):
    """
    Return the monitor after a valve plate x1.6 on an oil that thinned past its follow.

    The oil thins to 0.7, the baseline follows it down (the oil seen moving), the oil goes
    on thinning by 0.8 times the change the detection does not see, then the valve plate
    wears to 1.6 times its friction on that oil: the truth, over the healthy pump now.
    """
    # the pump has the model's shapes: its levels carry no model error
    # (`test_level_systematic` pins that floor)
    mon, rng, t = commissioned(True, seed, level_systematic_std=0.0)
    t, highest = thinning(mon, rng, t, 0.7)
    assert highest == OK and mon.oil_moved
    followed = mon.state_dict()['oil_follow']['valve_plate']
    # the level now over the learnt one: the followed level, thinned within the unseen
    oil = followed * (1.0 - 0.8 * mon.undetectable_change['valve_plate'])
    t = run(mon, rng, 240, TRUTH, change=_changed('valve_plate', oil - 1.0), t0=t)
    assert mon.level == OK and mon.state_dict()['oil_follow']['valve_plate'] == followed
    run(mon, rng, 240, TRUTH, change=_changed('valve_plate', oil * 1.6 - 1.0), t0=t)
    assert mon.level >= WARN
    return mon


def test_wear_read_on_an_oil_thinned_unseen_is_inside_the_interval_once_the_oil_moved():
    named = old_misses = 0
    for seed in range(41, 53):
        mon = _wear_on_an_oil_thinned_unseen(seed)
        if mon.verdict(1.0)[0] != Verdict.VALVE_PLATE:
            continue
        named += 1
        assert abs(mon.theta_vp - 1.6) <= Z95 * mon.valve_plate_scale_std, seed
        # over the followed level as if it were the healthy one now
        vp, vp_std, _, _ = mon.isolation.scales(mon.baseline, mon._undetectable, True, False)
        old_misses += abs(vp - 1.6) > Z95 * vp_std
    assert named >= 10
    assert old_misses >= named // 3  # (the reading is 1.6 x the unseen thinning)


@pytest.mark.parametrize('assumed', [True, False])
def test_with_the_temperature_topic_the_healthy_level_is_the_baselines(assumed):
    # commissioning restarted (a pump still changing): the oil seen moving only without topic
    mon = monitor(viscosity_assumed=assumed)
    rng = np.random.default_rng(3)
    t = 0.0
    for step in range(10):  # settling, then steady
        t = run(mon, rng, 60 if step < 8 else 240,
                TRUTH + np.array([0.6 * 0.8 ** min(step, 7), 0, 0, 0, 0, 0]), t0=t)
    assert mon.commissioning.restarts >= 1 and not mon.learning
    assert mon.oil_moved == assumed


def test_the_diagnostics_say_why_the_intervals_hold_an_unseen_oil():
    mon, rng, t = commissioned(True, 46)
    assert 'seen moving' not in mon.oil_note
    thinning(mon, rng, t, 0.7)
    assert 'seen moving without temperature topic' in mon.oil_note
