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

"""The spherical joints as a cause of the isolation: set truths and closed forms."""

import numpy as np
from pump_friction_ros.core.attribution import AttributionSettings, CAUSES, FaultIsolation, Verdict
from pump_friction_ros.core.change_stats import ChangeStats
from pump_friction_ros.core.node_parameters import EstimatorConfig, settings_view
import pytest

NOISE_NM = 0.01
DURATION_S = 0.25
JOINTS = CAUSES.index('spherical_joints')
KAPPA = 0.005  # the joints' friction over the theoretical torque (Hong & Doh 2004: ~0.5 %)


def test_a_bounded_cause_s_glr_is_the_likelihood_maximised_over_its_admissible_changes():
    rng = np.random.default_rng(3)
    s = rng.uniform(0.5, 1.5, size=(200, 2))
    for true in (-3.0, -0.5, 2.0):  # below the bound, above it, well above
        d = true * s[:, 0] + rng.normal(0.0, 0.05, 200)
        stats = ChangeStats(2, np.array([-1.0, -np.inf]))
        for row, x in zip(s, d, strict=True):
            stats.add(row, float(x), 1.0, 1.0, 0.0)
        grid = np.linspace(-1.0, 5.0, 60001)  # the first cause's admissible changes
        best = max(float(np.sum(d * d) - np.sum((d[:, None] - s[:, [0]] * grid) ** 2, axis=0)
                         .min()), 0.0)
        assert stats.glr()[0] == pytest.approx(best, rel=1e-6, abs=1e-6)
        assert stats.glr()[1] == pytest.approx(stats.b[1] ** 2 / stats.g[1, 1], rel=1e-12)


def _isolation(change, motoring_share, seed=0, windows=400):
    """
    Windows of a pump at 20-150 bar, a share of them overrunning the load (motoring).

    Signatures in `DETECTED_CAUSES` order and the joints' KAPPA |T_th|; ``change(s, joints)``
    is the change of a window [N m]. Every window belongs to the change.
    """
    isolation = FaultIsolation(settings_view(EstimatorConfig(), AttributionSettings), False)
    rng = np.random.default_rng(seed)
    for _ in range(windows):
        load = rng.uniform(1.6, 12.0)  # |T_th| [N m]
        ts = -load if rng.random() < motoring_share else load  # T_th times the direction
        speed = rng.uniform(50.0, 900.0)
        vp, other = 0.05 + 4e-4 * speed, 0.1 + 3e-4 * speed + KAPPA * load
        s = np.array([vp, other, ts + vp + other, -ts, 1.0, 1.0])
        joints = KAPPA * load
        d = change(s, joints) + rng.normal(0.0, NOISE_NM)
        isolation.add(s, d, NOISE_NM ** -2, DURATION_S, True, joints_nm=joints)
    return isolation


def test_the_joints_tripled_are_named_other_friction_where_the_pump_overruns_its_load():
    verdict, words, named = _isolation(lambda s, joints: 2.0 * joints, 0.3).verdict()
    assert (verdict, named) == (Verdict.OTHER_FRICTION, JOINTS)
    assert 'spherical joints' in words and 'scale 3.0' in words


def test_the_joints_and_a_pressure_gain_cannot_be_told_where_the_pump_only_drives_its_load():
    isolation = _isolation(lambda s, joints: 2.0 * joints, 0.0)
    verdict, words, named = isolation.verdict()
    assert (verdict, named) == (Verdict.CANNOT_TELL, -1)
    assert 'spherical joints' in words and 'pressure-sensor gain' in words
    assert 'both drives and overruns the load' in words
    assert isolation.may_be_measurement()  # a gain's drift with temperature may explain it


def test_a_pressure_reading_high_where_the_load_only_drives_the_pump_may_be_the_joints():
    # motoring: the theoretical torque opposes the friction, so a pressure read 5 % high
    # adds what 9.4 times the joints' friction adds (the bank's cruise family)
    verdict, words, _ = _isolation(lambda s, joints: 0.05 * s[3], 1.0).verdict()
    assert verdict == Verdict.CANNOT_TELL
    assert 'pressure-sensor gain' in words and 'spherical joints' in words


def test_a_pressure_reading_high_is_not_the_joints_falling_below_none():
    # read 3 % high where the pump only drives the load: one signature with a joints'
    # change of -6, which a friction cannot have
    verdict, words, _ = _isolation(lambda s, joints: 0.03 * s[3], 0.0).verdict()
    assert verdict == Verdict.NOT_FRICTION and 'pressure-sensor gain' in words


def test_a_pressure_gain_where_the_pump_overruns_its_load_is_not_the_joints():
    verdict, words, _ = _isolation(lambda s, joints: 0.01 * s[3], 0.3).verdict()
    assert verdict == Verdict.NOT_FRICTION and 'pressure-sensor gain' in words


def test_an_isolation_state_from_before_the_joints_loads_with_their_sums_zero():
    isolation = _isolation(lambda s, joints: 2.0 * joints, 0.3)
    state = isolation.state()
    n = len(CAUSES) - 1
    old = dict(state, g=[row[:n] for row in state['g'][:n]],
               **{key: state[key][:n] for key in ('b', 'g1', 'g2', 'b1', 'bv', 'bv1')})
    old['drift'] = dict(state['drift'], x=state['drift']['x'][:n], x1=state['drift']['x1'][:n])
    episodes = state['episodes']
    old['episodes'] = dict(episodes, g=[row[:n] for row in episodes['g'][:n]],
                           **{key: episodes[key][:n] for key in ('b', 'g1', 'g2', 'b1')})
    again = FaultIsolation(isolation.settings, False)
    again.load(old)
    np.testing.assert_array_equal(again.stats.g[:n, :n], isolation.stats.g[:n, :n])
    assert not again.stats.g[JOINTS].any() and not again.stats.g[:, JOINTS].any()
    np.testing.assert_array_equal(again.stats.b[:n], isolation.stats.b[:n])
    assert again.stats.b[JOINTS] == 0.0
    # the joints still cannot fall below none, on all the windows and on the episodes'
    np.testing.assert_array_equal(again.stats.lowest, isolation.stats.lowest)
    np.testing.assert_array_equal(again.episodes.lowest, isolation.episodes.lowest)
