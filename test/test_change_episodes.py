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

"""A change that comes and goes, named from the windows that show it (core/change_episodes)."""

from dataclasses import replace
import math

import numpy as np
from pump_friction_ros.core.attribution import (
    AttributionSettings,
    FaultIsolation,
    Verdict,
)
from pump_friction_ros.core.change_episodes import ChangeEpisodes
from pump_friction_ros.core.change_stats import ChangeStats
from pump_friction_ros.core.node_parameters import EstimatorConfig, settings_view
from pump_friction_ros.core.oil_follow import friction_fall
import pytest
import yaml

NOISE_NM = 0.01
DURATION_S = 0.25
VP, OTHER = 0, 1
FRICTIONS = (Verdict.VALVE_PLATE, Verdict.OTHER_FRICTION)
KEEP = math.exp(-DURATION_S / EstimatorConfig().isolation_memory_s)


def _windows(seed, truth, intermittent, step=0.8, windows=2400):
    """
    Windows of a load-driven cycle during a friction change, and whether each shows it.

    The speed (100-900 rad/s) and the load (0.5-6 N m) are independent; the two frictions'
    signatures correlate about 0.97 (as the bank's EHAs: 0.97-0.99). The friction ``truth``
    is (1 + ``step``) times healthy throughout, or (``intermittent``) in episodes of 20-90 s
    of running with 20-180 s between them (the bank's intermittent fault), starting on.

    Yields
    ------
    tuple
        (signatures [N m per unit change], change [N m], whether it shows the change).

    """
    rng = np.random.default_rng(seed)
    on, left = True, rng.uniform(80, 360)
    for _ in range(windows):
        speed = rng.uniform(100.0, 900.0)
        load = rng.uniform(0.5, 6.0)
        s = np.array([0.01 + 4e-4 * speed, 0.06 + 2e-4 * speed, 0.0, -load, 1.0, 1.0])
        s[2] = load + s[VP] + s[OTHER]
        shows = on or not intermittent
        d = float(step * s[truth] * shows + rng.normal(0.0, NOISE_NM))  # a float, as the monitor
        yield s, d, shows
        left -= 1
        if left <= 0:
            on = not on
            left = rng.uniform(80, 360) if on else rng.uniform(80, 720)


def _isolation(windows, ratio=None):
    settings = settings_view(EstimatorConfig(), AttributionSettings)
    if ratio is not None:
        settings = replace(settings, isolation_episode_lack_of_fit=ratio)
    isolation = FaultIsolation(settings, False)
    for s, d, _ in windows:
        isolation.add(s, d, NOISE_NM ** -2, DURATION_S, True)
    return isolation


@pytest.mark.parametrize('seed', range(4))
def test_the_windows_taken_as_showing_the_change_are_its_episodes(seed):
    every, episodes = ChangeStats(6), ChangeEpisodes(6, 4.0, 3.0)
    told, truth = [], []
    for s, d, shows in _windows(seed, VP, True):
        every.add(s, d, NOISE_NM ** -2, KEEP, DURATION_S)
        told.append(episodes.add(every, s, d, NOISE_NM ** -2, KEEP, DURATION_S))
        truth.append(shows)
    assert np.mean(np.array(told) == np.array(truth)) >= 0.97
    # their fit: the change while it shows (0.8), within the noise (lack of fit ~1)
    assert episodes.on.b[VP] / episodes.on.g[VP, VP] == pytest.approx(0.8, abs=0.02)
    assert episodes.on.lack_of_fit() < 1.5 < 4.0 * 4.0 < every.lack_of_fit()
    assert episodes.runs_z() < -10.0 and episodes.applies(every)


@pytest.mark.parametrize('seed', range(6))
def test_the_runs_z_score_is_wald_and_wolfowitz_s_on_unforgotten_windows(seed):
    rng = np.random.default_rng(seed)
    blocks = seed % 2 == 1  # runs of 30-60 windows, else independent windows
    shown = (np.repeat(rng.random(40) < 0.4, rng.integers(30, 60, 40)) if blocks
             else rng.random(1500) < 0.3)
    every, episodes = ChangeStats(6), ChangeEpisodes(6, 4.0, 3.0)
    s = np.array([1.0, 0.5, 0.0, 0.0, 0.0, 0.0])
    for on in shown:
        d = 1.0 if on else 0.0
        every.add(s, d, 1.0, 1.0, DURATION_S)  # keep 1: nothing forgotten, plain counts
        episodes.add(every, s, d, 1.0, 1.0, DURATION_S)
    n1, n = shown.sum(), shown.size
    n2, runs = n - n1, 1 + np.count_nonzero(np.diff(shown.astype(int)))
    mean = 2.0 * n1 * n2 / n + 1.0
    var = 2.0 * n1 * n2 * (2.0 * n1 * n2 - n) / (n * n * (n - 1.0))
    assert episodes.on.count == n1
    assert episodes.runs_z() == pytest.approx((runs - mean) / math.sqrt(var), rel=1e-9)
    assert (episodes.runs_z() < -10.0) if blocks else (abs(episodes.runs_z()) < 3.5)


@pytest.mark.parametrize('seed', range(4))
@pytest.mark.parametrize('truth', [VP, OTHER])
def test_a_friction_that_comes_and_goes_is_named_on_the_windows_that_show_it(seed, truth):
    windows = list(_windows(10 + seed, truth, True))
    isolation = _isolation(windows)
    verdict, phrase, named = isolation.verdict()
    assert isolation.comes_and_goes()
    assert (verdict, named) == (FRICTIONS[truth], truth)
    assert 'comes and goes' in phrase and '1.80 while it shows' in phrase
    # an oil thins, it does not come and go: a friction that comes and goes is not followed
    assert friction_fall(isolation) == (-1, pytest.approx(math.nan, nan_ok=True))
    # on every window one change fits neither state: the lack of fit divides the lead
    t_every = isolation.evidence()[0]
    t_shown = isolation.evidence(shown=True)[0]
    lead_every, lead_shown = (t[truth] - t[1 - truth] for t in (t_every, t_shown))
    assert lead_shown > 10.0 * max(lead_every, 1.0)
    assert not _isolation(windows, ratio=1e6).comes_and_goes()


@pytest.mark.parametrize('seed', range(4))
@pytest.mark.parametrize('truth', [VP, OTHER])
def test_a_step_change_is_read_on_every_window_as_before(seed, truth):
    windows = list(_windows(20 + seed, truth, False))
    isolation = _isolation(windows)
    assert not isolation.comes_and_goes()
    assert isolation.episodes.on.lack_of_fit() < 1.5 and isolation.stats.lack_of_fit() < 1.5
    assert isolation.verdict() == _isolation(windows, ratio=1e6).verdict()
    assert isolation.verdict()[0] == FRICTIONS[truth]


def test_ageing_adds_the_running_but_not_a_window():
    rng = np.random.default_rng(3)
    s1, s2, s3 = (rng.uniform(0.1, 1.0, 6) for _ in range(3))
    aged, padded = ChangeStats(6), ChangeStats(6)
    aged.add(s1, 0.3, 4.0, KEEP, 0.25)
    aged.age(KEEP, 0.5)
    aged.add(s3, -0.2, 9.0, KEEP, 0.25)
    padded.add(s1, 0.3, 4.0, KEEP, 0.25)
    padded.add(s2, 7.0, 0.0, KEEP, 0.5)  # a window of no weight: only its running counts
    padded.add(s3, -0.2, 9.0, KEEP, 0.25)
    for name in ('g', 'b', 'c', 'g1', 'g2', 'b1'):
        np.testing.assert_allclose(getattr(aged, name), getattr(padded, name), rtol=1e-12)
    assert aged.count == pytest.approx(padded.count - KEEP)  # the padding, aged by one window
    assert (aged.windows, padded.windows) == (2, 3)


@pytest.mark.parametrize('seed', range(4))
@pytest.mark.parametrize('truth', [VP, OTHER])
def test_windows_a_drift_picks_one_by_one_are_not_a_change_that_comes_and_goes(seed, truth):
    # a step with a torque-constant drift the single causes do not fit (lack of fit 4-7):
    # some windows fit one cause alone, scattered (test_friction_bias's windows)
    from test.test_friction_bias import _windows as drifting

    isolation = _isolation([(s, d, changing) for s, _, d, changing in
                            drifting(20 + seed, truth, (0.0, 0.0), drift_per_k=-0.3e-3)
                            if changing])
    assert isolation.stats.lack_of_fit() > 4.0
    assert abs(isolation.episodes.runs_z()) < 3.0
    assert not isolation.comes_and_goes()


def test_the_episodes_survive_a_restart_through_a_yaml_file():
    windows = list(_windows(5, VP, True, windows=1600))
    isolation = _isolation(windows)
    assert isolation.comes_and_goes()
    again = _isolation(list(_windows(6, OTHER, False, windows=50)))
    again.load(yaml.safe_load(yaml.safe_dump(isolation.state())))  # the state file's format
    assert again.verdict() == isolation.verdict()
    assert again.episodes.state() == isolation.episodes.state()


@pytest.mark.parametrize('seed', range(4))
def test_an_older_state_without_them_counts_only_the_windows_classified_since(seed):
    # a change under way when the older state was written: its every-window sums hold ~500
    # windows the episodes never saw; they must not pass for one long run of 'not shown'
    from test.test_friction_bias import _windows as drifting

    windows = [(s, d, changing) for s, _, d, changing in
               drifting(20 + seed, OTHER, (0.0, 0.0), drift_per_k=-0.3e-3, windows=1800)
               if changing]
    before = _isolation(windows[:600])
    older = {key: value for key, value in before.state().items() if key != 'episodes'}
    again = _isolation([])
    again.load(older)
    assert again.episodes.on.windows == 0 and not again.comes_and_goes()
    for s, d, _ in windows[600:]:
        again.add(s, d, NOISE_NM ** -2, DURATION_S, True)
        assert not again.comes_and_goes()
    assert abs(again.episodes.runs_z()) < 3.0
    assert again.episodes.seen < again.stats.count


@pytest.mark.parametrize('bad', [{'g': [[0.0]]}, {'c': -1.0}, {'b1': [math.nan] * 6},
                                 {'switches': -2.0}, {'last': 'yes'}, {'last': 1},
                                 {'windows': -3}, {'windows': 2.5}, {'seen': 0.5},
                                 {'last': KeyError}])
def test_malformed_episode_sums_are_refused(bad):
    isolation = _isolation(list(_windows(5, VP, True, windows=600)))
    state = isolation.state()
    episodes = {**state['episodes'], **bad}  # type: ignore[dict-item]
    if bad.get('last') is KeyError:  # missing
        del episodes['last']
    state['episodes'] = episodes
    with pytest.raises(ValueError):
        isolation.load(state)
