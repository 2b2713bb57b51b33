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

"""Which friction changed, each cause's change a line in time: set truths on warming oil."""

import math

import numpy as np
from pump_friction_ros.core.attribution import AttributionSettings, FaultIsolation
from pump_friction_ros.core.friction_choice import choose_friction
from pump_friction_ros.core.node_parameters import EstimatorConfig, settings_view
import pytest

NOISE_NM = 0.01
DURATION_S = 0.25
VP, OTHER = 0, 1
FRICTIONS = ('valve_plate', 'other_friction')


def _windows(seed, truth, ramp, drift_per_k=0.0, windows=1600, onset=400):
    """
    Windows of an EHA cycle as the oil warms from 10 to 40 K above commissioning.

    The speed (100-900 rad/s) and the load (0.5-6 N m, an external force) are independent.
    The valve plate's film shear falls with the viscosity, exp(-0.03 / K) (the temperature
    topic: its signature follows); the other friction, mostly Coulomb, does not. From window
    ``onset`` the friction ``truth`` (0: valve plate, 1: other) is x1.8, or (``ramp``) grows
    along a line to x1.8 at the last window. The torque reads ``drift_per_k`` (T - T_0) of
    itself off throughout. Yields (signatures, drift signature, change, changing).
    """
    rng = np.random.default_rng(seed)
    for k in range(windows):
        warm_k = 10.0 + 30.0 * k / windows
        speed = rng.uniform(100.0, 900.0)
        load = rng.uniform(0.5, 6.0)
        vp = (0.02 + 6e-4 * speed) * math.exp(-0.03 * warm_k)
        s = np.array([vp, 0.05 + 1e-4 * speed, 0.0, -load, 1.0, 1.0])
        s[2] = load + s[VP] + s[OTHER]
        u = warm_k * s[2]
        changing = k >= onset
        wear = 0.8 * ((k - onset + 1) / (windows - onset) if ramp else 1.0) if changing else 0.0
        yield s, u, wear * s[truth] + drift_per_k * u + rng.normal(0.0, NOISE_NM), changing


def _isolation(*args, **kwargs):
    isolation = FaultIsolation(settings_view(EstimatorConfig(), AttributionSettings), False)
    for s, u, d, changing in _windows(*args, **kwargs):
        isolation.add(s, d, NOISE_NM ** -2, DURATION_S, changing, u)
    return isolation


@pytest.mark.parametrize('drift_per_k', [0.0, 0.4e-3])
def test_the_lines_glr_is_its_weighted_least_squares_against_the_drift_alone(drift_per_k):
    # over every window: T = RSS(drift alone) - RSS(now s_j + slope tau s_j on the change's
    # windows, drift c u on all), each window weighted by the memory's keep^age
    keep = math.exp(-DURATION_S / EstimatorConfig().isolation_memory_s)
    windows = list(_windows(3, VP, True, drift_per_k))
    isolation = _isolation(3, VP, True, drift_per_k)
    onset = sum(not changing for *_, changing in windows)
    ages = np.array([len(windows) - 1 - k if changing else onset - 1 - k
                     for k, (*_, changing) in enumerate(windows)], dtype=float)
    w = np.sqrt(NOISE_NM ** -2 * keep ** ages)
    on = np.array([changing for *_, changing in windows], dtype=float)
    u = np.array([u for _, u, _, _ in windows]) * w
    d = np.array([d for _, _, d, _ in windows]) * w

    def rss(columns):
        a = np.column_stack(columns)
        return float(np.sum((d - a @ np.linalg.lstsq(a, d, rcond=None)[0]) ** 2))

    for j in (VP, OTHER):
        s_j = np.array([s[j] for s, *_ in windows]) * on * w
        t = rss([u]) - rss([s_j, ages * DURATION_S * s_j, u])
        assert isolation.stats.line_glr(j, isolation.drift.line_sums(j)) == pytest.approx(
            t, rel=1e-6)
    # without the drift's sums: the line against no change at all (the windows before the
    # change, where s_j is 0, leave the same in both)
    s_vp = np.array([s[VP] for s, *_ in windows]) * on * w
    free = float(d @ d) - rss([s_vp, ages * DURATION_S * s_vp])
    assert isolation.stats.line_glr(VP) == pytest.approx(free, rel=1e-6)


def test_too_few_windows_or_no_spread_of_age_fit_no_line():
    isolation = FaultIsolation(settings_view(EstimatorConfig(), AttributionSettings), False)
    s = np.array([0.2, 0.3, 7.0, -6.5, 1.0, 1.0])
    isolation.add(s, 0.1, 1e4, 0.0, True)  # no running between the windows: one age
    isolation.add(s, 0.1, 1e4, 0.0, True)
    assert isolation.stats.line_glr(VP) is None
    isolation.add(s, 0.1, 1e4, 1.0, True)  # ages, but one degree of freedom short
    assert isolation.stats.line_glr(VP) is None
    isolation.add(s, 0.1, 1e4, 1.0, True)
    assert isolation.stats.line_glr(VP) is not None


@pytest.mark.parametrize('seed', range(6))
def test_a_valve_plate_wear_growing_on_warming_oil_is_named_the_valve_plate(seed):
    # the valve plate's signature falls as the oil warms while its wear grows: the change
    # in N m stays level, which the other friction's steady signature fits better than the
    # valve plate's own step does. A line per cause reads it right
    isolation = _isolation(seed, VP, True, 0.3e-3)
    assert isolation.verdict()[0] == 'valve_plate'
    st = isolation.stats
    g, b, _ = isolation.drift.profile(st.g, st.b)
    steps = b * b / np.diag(g)  # the step per cause (the drift profiled), as before the line
    z2 = EstimatorConfig().attribution_z ** 2
    assert steps[OTHER] - steps[VP] > z2  # a step per cause names the other friction
    now = isolation.moving(VP)
    assert now is not None and now[2] < 0.0 and abs(now[0] - 0.8) < 3.0 * math.sqrt(now[1])


@pytest.mark.parametrize('seed', range(4))
@pytest.mark.parametrize('truth', [VP, OTHER])
@pytest.mark.parametrize('ramp', [False, True])
def test_steps_and_ramps_of_either_friction_are_named_right(seed, truth, ramp):
    assert _isolation(10 + seed, truth, ramp, -0.3e-3).verdict()[0] == FRICTIONS[truth]


def test_with_one_age_for_every_window_the_choice_is_a_step_per_cause():
    # no running between the windows: no line can be fitted, and both causes fall back to
    # a step, against the drift alone and against the bias and the drift (`friction_bias`),
    # neither fitted with more; the evidence is the fit with the smaller lead
    isolation = FaultIsolation(settings_view(EstimatorConfig(), AttributionSettings), False)
    for s, u, d, changing in _windows(4, VP, False, 0.3e-3):
        isolation.add(s, d, NOISE_NM ** -2, 0.0, changing, u)
    st = isolation.stats
    assert st.line_glr(VP, isolation.drift.line_sums(VP)) is None
    with_bias = [isolation.bias.glr(i, False) / st.lack_of_fit() for i in (VP, OTHER)]
    g, b, _ = isolation.drift.profile(st.g, st.b)
    without = [b[i] ** 2 / g[i, i] / st.lack_of_fit() for i in (VP, OTHER)]
    assert min(with_bias[VP] - with_bias[OTHER], without[VP] - without[OTHER]) > 9.0
    lead = min(with_bias, without, key=lambda x: x[VP] - x[OTHER])
    choice = choose_friction(st, isolation.drift, isolation.bias, isolation.evidence()[0])
    assert (choice.first, choice.second, choice.split) == (VP, OTHER, None)
    assert (choice.t[VP], choice.t[OTHER]) == pytest.approx(lead, rel=1e-12)


@pytest.mark.parametrize('seed', range(6))
def test_a_state_saved_before_the_drifts_age_weighted_sum_loads_without_a_line_that_misleads(
        seed):
    # a state written between the line's sums (g1, g2, b1) and the drift's cross sum x1: the
    # line would be fitted with x1 = 0 against g1 != 0 and could name the valve plate for an
    # other friction's step. Loaded, the windows count as of one age, as x1's zeros say
    isolation = _isolation(seed, OTHER, False, 0.3e-3, windows=1000)
    state = isolation.state()
    state['drift'] = {key: value for key, value in state['drift'].items() if key != 'x1'}
    again = FaultIsolation(settings_view(EstimatorConfig(), AttributionSettings), False)
    again.load(state)
    assert not (again.stats.g1.any() or again.stats.g2.any() or again.stats.b1.any())
    for s, u, d, changing in list(_windows(seed, OTHER, False, 0.3e-3))[1000:1200]:
        again.add(s, d, NOISE_NM ** -2, DURATION_S, changing, u)
    assert again.verdict()[0] == 'other_friction'
