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

"""Without the temperature, a wear's interval holds it wherever in its band the oil sits."""

import math

import numpy as np
from pump_friction_ros.core.attribution import FaultIsolation, Verdict
from pump_friction_ros.core.change_stats import ChangeStats
from pump_friction_ros.core.monitor import OK
import pytest

from .test_oil_allowance import _monitor, BAND, DT, oil_window, SLOPE, TRUTH, WINDOW_SAMPLES

Z95 = 1.959963984540054


def _windows(seed, n=400):
    rng = np.random.default_rng(seed)
    s = rng.uniform(0.05, 0.6, size=(n, 6)) * rng.choice([-1.0, 1.0], size=(n, 6))
    s[:, 0] = np.abs(s[:, 0])  # a friction's signature does not change sign
    v = SLOPE * rng.uniform(50.0, 900.0, size=n)  # the band's friction change per window
    w = rng.uniform(50.0, 200.0, size=n)
    age = rng.uniform(0.1, 0.3, size=n)
    return s, v, w, age


def _stats(s, d, v, w, age, memory_s):
    st = ChangeStats(6)
    for row, dk, vk, wk, ak in zip(s, d, v, w, age, strict=True):
        st.add(row, float(dk), float(wk), math.exp(-ak / memory_s), float(ak), float(vk))
    return st


@pytest.mark.parametrize('memory_s', [math.inf, 30.0])
def test_an_oil_offset_moves_the_change_and_its_line_by_the_bias_bound_and_no_more(memory_s):
    s, v, w, age = _windows(1)
    # windows' ages now (monitored running since each), to build a line through the change
    tau = np.cumsum(age[::-1])[::-1] - age
    line = 0.4 - 2e-3 * tau  # a wear still rising: 0.4 now
    for e in (-1.0, -0.5, 0.0, 1.0):
        d = line * s[:, 0] + e * v
        st = _stats(s, d, v, w, age, memory_s)
        mean, now = st.oil_bias(0)
        base = _stats(s, line * s[:, 0], v, w, age, memory_s)
        # least squares is linear in d: the oil's e v moves the fits by e times the bounds
        moved = st.b[0] / st.g[0, 0] - base.b[0] / base.g[0, 0]
        assert moved == pytest.approx(e * mean, abs=1e-12)
        moved_now = st.trend(0)[0] - base.trend(0)[0]
        assert abs(moved_now) == pytest.approx(abs(e) * now, abs=1e-9)
    # against weighted least squares of v alone, with the memory's weights
    keep = np.exp(-np.cumsum(age[::-1])[::-1] / memory_s) / np.exp(-age / memory_s)
    weight = w * keep
    x = s[:, 0]
    assert mean == pytest.approx(abs(np.sum(weight * x * v) / np.sum(weight * x * x)), rel=1e-9)
    design = np.column_stack([x, x * tau]) * np.sqrt(weight)[:, None]
    coef = np.linalg.lstsq(design, v * np.sqrt(weight), rcond=None)[0]
    assert now == pytest.approx(abs(coef[0]), rel=1e-9)


def test_without_a_band_nothing_moves():
    s, v, w, age = _windows(2)
    st = _stats(s, 0.3 * s[:, 0], v * 0.0, w, age, 30.0)
    assert st.oil_bias(0) == (0.0, 0.0)


def _wear_in_other_oil(oil, delta, offset, seed, windows=3000):
    """
    Run a pump as learnt at commissioning, then worn with the oil off commissioning's.

    From 60 s of running on (commissioning learns in the first 30 s), the valve plate's
    friction is 1 + delta of its healthy level and the oil sits ``offset`` of the band
    away (its viscous friction offset x SLOPE x |speed| above commissioning's). Returns the
    monitor.
    """
    rng = np.random.default_rng(seed)
    # the synthetic pump has the model's shapes, its levels learnt without systematic error:
    # no floor on them, so that the oil's part of the interval is seen alone
    mon = _monitor(oil, level_systematic_std=0.0)
    t, n = 0.0, WINDOW_SAMPLES
    for _ in range(windows):
        speed, vp, other, sign, th, h = oil_window(rng)
        worn = t > 60.0
        e = float(h @ TRUTH) + rng.normal(0.0, 0.01) + (
            delta * (1.0 + TRUTH[0]) * vp + offset * SLOPE * speed if worn else 0.0)
        mon.update_many([t + i * DT for i in range(n)], [DT] * n, [e] * n, [vp] * n,
                        [other] * n, [th] * n, [sign] * n, None, [speed] * n)
        t += n * DT
    return mon


@pytest.mark.parametrize('seed', [4, 5, 6])
@pytest.mark.parametrize('offset', [-0.9, 0.9])
def test_a_wear_read_where_the_oil_is_off_commissioning_is_held_by_its_interval(seed, offset):
    delta = 0.8  # valve plate x1.8
    mon = _wear_in_other_oil(BAND, delta, offset, seed)
    assert mon.level > OK and mon.verdict(1.0)[0] == Verdict.VALVE_PLATE
    assert 'oil viscosity' in mon.verdict(1.0)[1]  # the scale is the valve plate's or the oil's
    assert abs(mon.theta_vp - (1.0 + delta)) <= Z95 * mon.valve_plate_scale_std
    # the oil moved the reading, by more than half what it can
    bias, _ = mon.isolation.stats.oil_bias(0)
    assert abs(mon.theta_vp - (1.0 + delta)) > 0.5 * bias > 0.0
    # without the band (none configured) the same oil is read as wear, its interval missing
    # the valve plate's change: the band, where the installation knows it, is what holds it
    blind = _wear_in_other_oil(None, delta, offset, seed)
    assert blind.isolation.stats.oil_bias(0) == (0.0, 0.0)
    assert abs(blind.theta_vp - (1.0 + delta)) > Z95 * blind.valve_plate_scale_std


def test_with_the_oil_where_it_was_the_interval_is_wider_by_the_bias_alone():
    mon = _wear_in_other_oil(BAND, 0.8, 0.0, 4)
    blind = _wear_in_other_oil(None, 0.8, 0.0, 4)
    assert mon.verdict(1.0)[0] == blind.verdict(1.0)[0] == Verdict.VALVE_PLATE
    bias, _ = mon.isolation.stats.oil_bias(0)
    grown = Z95 * (mon.valve_plate_scale_std - blind.valve_plate_scale_std)
    assert grown == pytest.approx(bias, rel=0.05)


def test_the_band_sums_survive_a_restart_and_an_older_state_loads_without_them():
    mon = _wear_in_other_oil(BAND, 0.8, 0.9, 4, windows=800)
    state = mon.isolation.state()
    assert any(state['bv'])
    again = FaultIsolation(mon.isolation.settings, True)
    again.load(state)
    assert again.stats.oil_bias(0) == mon.isolation.stats.oil_bias(0)
    older = {key: value for key, value in state.items() if key not in ('bv', 'bv1')}
    again.load(older)
    assert again.stats.oil_bias(0) == (0.0, 0.0)
    sums = again.stats.g.copy()
    with pytest.raises(ValueError):
        again.load({**state, 'bv': [1.0, 2.0]})
    # refused before any sum is replaced: the isolation is as it was
    assert np.array_equal(again.stats.g, sums) and again.stats.oil_bias(0) == (0.0, 0.0)
