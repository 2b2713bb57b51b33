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

"""The speed filter: scalar and array forms agree; a ramp lags by tau per stage, exactly."""

import numpy as np
from pump_friction_ros.core.speed_filter import filter_two_stage, SpeedFilter
import pytest

NS = 1_000_000_000


def scalar_run(stamps_ns, x, tau_s):
    """Feed the scalar form sample by sample; its second-stage output and acceleration."""
    filt = SpeedFilter(tau_s, max_gap_ns=10 * NS)
    lp2, accel = [], []
    for stamp, value in zip(stamps_ns, x, strict=True):
        accel.append(filt.update(int(stamp), float(value)))
        lp2.append(filt._lp2)  # white box: the second stage, which filter_two_stage gives
    return np.array(lp2), np.array(accel)


@pytest.mark.parametrize(('dt_ns', 'tau_s'), [(1_000_000, 0.01), (250_000, 0.002),
                                              (7_000_000, 0.003)])
def test_scalar_update_equals_the_array_form_on_a_noisy_record(dt_ns, tau_s):
    rng = np.random.default_rng(5)
    n = 5000
    t = np.arange(n) * dt_ns * 1e-9
    x = 400.0 * np.sin(2 * np.pi * 1.3 * t) + 50.0 + rng.normal(0.0, 2.0, n)
    lp2, _ = scalar_run(np.arange(n) * dt_ns, x, tau_s)
    array = filter_two_stage(x, dt_ns * 1e-9, tau_s)
    np.testing.assert_allclose(lp2, array, rtol=1e-12, atol=1e-12 * np.abs(x).max())


@pytest.mark.parametrize('dt_over_tau', [0.01, 0.1, 1.0, 3.7])
def test_ramp_gives_its_slope_exactly_with_a_lag_of_tau_per_stage(dt_over_tau):
    tau_s, slope = 0.02, 1234.5  # [s], [rad/s^2]
    dt_ns = round(dt_over_tau * tau_s * NS)
    n = int(60 * tau_s * NS / dt_ns) + 2  # 60 tau: the start-up transient is gone
    t = np.arange(n) * dt_ns * 1e-9
    x = slope * t
    lp2, accel = scalar_run(np.arange(n) * dt_ns, x, tau_s)
    array = filter_two_stage(x, dt_ns * 1e-9, tau_s)
    assert accel[-1] == pytest.approx(slope, rel=1e-10)
    # second stage lags by 2 tau, so (lp1 - lp2) / tau = slope puts the first at one tau
    assert lp2[-1] == pytest.approx(slope * (t[-1] - 2 * tau_s), abs=1e-9 * slope * tau_s)
    assert array[-1] == pytest.approx(slope * (t[-1] - 2 * tau_s), abs=1e-9 * slope * tau_s)


def test_ramp_slope_is_exact_at_uneven_sample_spacing_too():
    tau_s, slope = 0.01, -800.0
    rng = np.random.default_rng(2)
    stamps = np.cumsum(rng.integers(200_000, 3_000_000, 2000))  # 0.2 to 3 ms apart
    t = stamps * 1e-9
    lp2, accel = scalar_run(stamps, slope * t, tau_s)
    np.testing.assert_allclose(accel[-500:], slope, rtol=1e-9)
    np.testing.assert_allclose(lp2[-500:], slope * (t[-500:] - 2 * tau_s),
                               atol=1e-9 * abs(slope) * tau_s)
