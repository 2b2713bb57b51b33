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

"""The monitored residual has no inertia leak: closed forms of motion, a pump as modelled."""

import itertools
import math

import numpy as np
from pump_friction_ros.core.estimator import TorqueEstimator
from pump_friction_ros.core.inputs import InputKind as K
from pump_friction_ros.core.node_parameters import EstimatorConfig
from pump_friction_ros.physics.friction import smooth_sign_scalar
from pump_friction_ros.physics.model import input_torque_nm, theoretical_torque_nm
from pump_friction_ros.table.friction_table import build_table
import pytest

J = 1.0e-3  # [kg m^2] the largest EHA rotor of the issue
DT_NS = 1_000_000  # 1 kHz
BINS = (0.0, 10.0, 100.0, 1000.0, math.inf)  # |true acceleration| [rad/s^2]


@pytest.fixture(scope='module')
def table(paper_params):
    return build_table(paper_params)


def trapezoids(n_moves=12):
    """Return speed and acceleration of trapezoid moves at 1e4 rad/s^2 (1 kHz samples)."""
    speed, accel = [], []
    rng = np.random.default_rng(1)
    for _ in range(n_moves):
        target = float(rng.uniform(200.0, 900.0)) * (1 if rng.random() < 0.5 else -1)
        a = 1.0e4 * math.copysign(1.0, target)
        ramp = int(abs(target) / 1.0e4 * 1000)
        for phase in (a, 0.0, -a, 0.0):
            steps = ramp if phase else int(rng.uniform(300, 900))
            for _ in range(steps):
                w = (speed[-1] if speed else 0.0) + phase * 1e-3
                speed.append(w)
                accel.append(phase)
    return np.array(speed), np.array(accel)


def p_loop(time_constants_s=(0.02, 0.05, 0.1)):
    """Return speed and acceleration of a P-loop's exponential approaches (exact samples)."""
    speed, accel = [], []
    w0 = 0.0
    rng = np.random.default_rng(2)
    for tau in time_constants_s * 4:
        target = float(rng.uniform(200.0, 900.0)) * (1 if rng.random() < 0.5 else -1)
        t = np.arange(1, 800) * 1e-3
        w = target + (w0 - target) * np.exp(-t / tau)
        speed.extend(w.tolist())
        accel.extend(((target - w) / tau).tolist())
        w0 = float(w[-1])
    return np.array(speed), np.array(accel)


def feed_modelled_pump(est, table, config, speed, accel):
    """Feed the exact torque of the modelled pump (J = `J`) at 120 bar; return the estimates."""
    out = []
    dp = 120e5
    nu = config.viscosity_m2_s(46e-6)
    for k, (w, a) in enumerate(zip(speed.tolist(), accel.tolist(), strict=True)):
        mags, _ = table.magnitudes(abs(w), dp, nu, w * dp < 0.0)
        direction = smooth_sign_scalar(w, table.zero_speed_threshold_rad_s)
        torque = input_torque_nm(theoretical_torque_nm(table.displacement_m3, dp), sum(mags),
                                 direction, config.drive_loss_torque_nm) + J * a
        stamp = (k + 1) * DT_NS
        est.on_input(K.LOAD_PRESSURE, stamp, dp)
        out.append(est.on_input(K.JOINT_STATE, stamp, w, torque))
    return out


def monitored_residuals(table, speed, accel, config):
    """Feed the exact torque of the modelled pump; return (residual, |a|) of monitored samples."""
    est = TorqueEstimator(config, table, 46e-6)
    got = []
    update = est.monitor.update

    stamps = []

    def record(t_s, dt_s, residual_nm, *rest):
        got.append(residual_nm)
        stamps.append(t_s)
        return update(t_s, dt_s, residual_nm, *rest)

    est.monitor.update = record
    estimates = feed_modelled_pump(est, table, config, speed, accel)
    raw = [e.residual_nm * math.copysign(1.0, w)
           for e, w in zip(estimates, speed.tolist(), strict=True)]
    at = np.array([round(t * 1e9 / DT_NS) - 1 for t in stamps])
    return np.array(got), np.abs(accel[at]), np.array(raw)[at]


@pytest.mark.parametrize('motion', [trapezoids, p_loop])
def test_monitored_residual_has_no_inertia_leak_in_any_acceleration_bin(table, motion):
    speed, accel = motion()
    config = EstimatorConfig(rotor_inertia_kg_m2=J, drive_loss_torque_nm=0.03)
    residual, a, raw = monitored_residuals(table, speed, accel, config)
    assert residual.size > 2000
    populated = 0
    for low, high in itertools.pairwise(BINS):
        inside = (a >= low) & (a < high)
        if inside.sum() >= 20:
            populated += 1
            assert abs(residual[inside].mean()) < 0.01, (low, residual[inside].mean())
            assert np.abs(residual[inside]).max() < 0.03, (low, np.abs(residual[inside]).max())
    assert populated >= (3 if motion is p_loop else 1)
    if motion is p_loop:  # the leak the aligned residual removes: J a - J a_filtered
        assert np.abs(raw[a >= 100.0]).mean() > 0.02  # twice the bound, up to 0.07 N m


def test_a_settle_time_of_zero_lets_the_trapezoid_corners_in(table):
    speed, accel = trapezoids()
    config = EstimatorConfig(rotor_inertia_kg_m2=J, monitor_settle_s=0.0,
                             monitor_max_accel_rad_s2=5000.0)
    residual, _, _ = monitored_residuals(table, speed, accel, config)
    assert np.abs(residual).max() > 0.05  # the settle time is what keeps them out


def test_the_baseline_learns_a_misconfigured_rotor_inertia(table):
    # the node is told 0.8 J: 0.2 J a (up to 0.2 N m where the monitor takes samples) is
    # the installation's, not a fault; the baseline's inertia term takes it, the window
    # scatter about the fit falls to the sampling's, and no alarm follows
    speed, accel = p_loop((0.02, 0.05, 0.1) * 3)
    config = EstimatorConfig(rotor_inertia_kg_m2=0.8 * J, drive_loss_torque_nm=0.03,
                             baseline_learn_s=4.0)
    est = TorqueEstimator(config, table, 46e-6)
    feed_modelled_pump(est, table, config, speed, accel)
    baseline = est.monitor.baseline
    assert baseline is not None
    learnt, std = baseline.coefficients[5], baseline.std()[5]
    assert abs(learnt - 0.2 * J) < max(3.0 * std, 0.02 * J), (learnt, std)
    assert std < 0.1 * J
    assert math.sqrt(baseline.window_var_nm2) < 0.01
    assert est.monitor.level == 0 and est.monitor.cusum_pos_nm_s < 0.1
