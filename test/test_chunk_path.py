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

"""The chunk path (`TorqueEstimator.on_chunk`) gives exactly what `on_input` gives."""

import dataclasses
import itertools
import math

import numpy as np
from pump_friction_ros.core.attribution import AttributionSettings
from pump_friction_ros.core.estimate_record import MONITOR_COLUMNS
from pump_friction_ros.core.estimator import TorqueEstimator
from pump_friction_ros.core.inputs import Defect, InputKind
from pump_friction_ros.core.monitor import MonitorSettings, WearMonitor
from pump_friction_ros.core.node_parameters import (
    EstimatorConfig,
    PressureSource,
    settings_view,
    SpeedSource,
    TorqueSource,
    ViscositySource,
)
from pump_friction_ros.core.speed_filter import SpeedFilter
from pump_friction_ros.sim.duty_cycle import DutyCycle, simulate_duty_cycle
from pump_friction_ros.table.exact_lookup import ExactTableLookup
from pump_friction_ros.table.friction_table import build_table
import pytest

K = InputKind
START_NS = 1_700_000_000 * 1_000_000_000
SOURCE_COMBOS = list(itertools.product(SpeedSource, TorqueSource, PressureSource,
                                       ViscositySource))
LATENCY_NS = {K.JOINT_STATE: 150_001, K.SHAFT_SPEED: 150_003, K.MOTOR_TORQUE: 150_007,
              K.LOAD_PRESSURE: 90_011, K.PRESSURE_A: 90_013, K.PRESSURE_B: 90_017,
              K.OIL_TEMPERATURE: 50_019}


@pytest.fixture(scope='module')
def table(paper_params):
    return build_table(paper_params)


@pytest.fixture(scope='module')
def run(table):
    return simulate_duty_cycle(table, DutyCycle(duration_s=6.0), seed=4)


def _irregular(rng, stamps, values, kind, n_bad):
    """Put every kind of trouble at random places into stamps and values (in place)."""
    n = len(stamps)
    has_value = np.ones(n, dtype=bool)
    defects = np.zeros(n, dtype=np.int64)
    for i in rng.choice(np.arange(30, n - 40), size=n_bad, replace=False).tolist():
        trouble = rng.integers(9)
        if trouble == 0:
            values[i] = math.nan
        elif trouble == 1:
            values[i] = math.inf if rng.random() < 0.5 else 3.0e8  # beyond any limit
        elif trouble == 2:
            stamps[i] = stamps[i - 1]  # duplicate
        elif trouble == 3:
            stamps[i] -= 30_000_000  # out of order
        elif trouble == 4:
            stamps[i] += 5_000_000_000  # far ahead of the receive time
        elif trouble == 5:
            defects[i] = Defect.UNDECODABLE
        elif trouble == 6 and kind == K.JOINT_STATE:
            defects[i] = (Defect.MISSING_JOINT, Defect.MALFORMED)[rng.integers(2)]
        elif trouble == 7 and kind == K.JOINT_STATE:
            has_value[i] = False  # torque only
        elif trouble == 8:
            stamps[i] = -stamps[i]  # before 1970: no clock's time
    if kind == K.JOINT_STATE:
        defects[10], defects[11] = Defect.MISSING_JOINT, Defect.MALFORMED
    return has_value, defects


def message_stream(run, config, seed):
    """
    Return the input messages of a config, in arrival order, as the chunk arrays.

    Besides the irregularities of `_irregular`: a clock restart (a run of stamps 2 s back,
    longer than ``stamp_resync_samples``) on the speed, gaps in the pressure and the
    temperature (stale skips), JointStates without torque or with neither value, and a
    measured torque far above the model for a while (the monitor raises an alarm).
    """
    rng = np.random.default_rng(seed)
    joint_ns = START_NS + np.round(run.t_s * 1e9).astype(np.int64)
    press_ns = START_NS + np.round(run.pressure_t_s * 1e9).astype(np.int64)
    torque = run.torque_nm + np.where((run.t_s > 1.5) & (run.t_s < 3.5), 3.0, 0.0)
    streams = []  # (kinds, stamps, log times, values, torques, has_value, has_torque, defects)

    def add(kind, stamps, values, torques=None, n_bad=40, arrival=None):
        log = (stamps if arrival is None else arrival) + LATENCY_NS[kind]
        stamps, values = stamps.copy(), values.astype(float).copy()
        has_value, defects = _irregular(rng, stamps, values, kind, n_bad)
        n = stamps.size
        if torques is None:
            torques, has_torque = np.full(n, math.nan), np.zeros(n, dtype=bool)
        else:
            torques = torques.astype(float).copy()
            has_torque = rng.random(n) > 0.02  # a JointState without effort now and then
            torques[rng.choice(n, 20)] = math.nan
            neither = rng.choice(n, 5)
            has_value[neither] = has_torque[neither] = False  # rejected_malformed
        streams.append((np.full(n, int(kind)), stamps, log, values, torques, has_value,
                        has_torque, defects))

    speed_stamps = joint_ns.copy()
    speed_stamps[3000:3030] -= 2_000_000_000  # the clock restarts 2 s back
    if SpeedSource.JOINT_STATE in (config.speed_source, config.torque_source):
        add(K.JOINT_STATE, speed_stamps, run.speed_rad_s, torque, arrival=joint_ns)
    if config.speed_source == SpeedSource.FLOAT64:
        add(K.SHAFT_SPEED, speed_stamps, run.speed_rad_s, arrival=joint_ns)
    if config.torque_source == TorqueSource.FLOAT64:
        add(K.MOTOR_TORQUE, joint_ns, torque)
    keep = (run.pressure_t_s < 2.0) | (run.pressure_t_s > 2.1)  # 100 ms without pressure
    if config.pressure_source == PressureSource.DIFFERENCE:
        add(K.LOAD_PRESSURE, press_ns[keep], run.pressure_diff_pa[keep])
    else:
        for kind, sign in ((K.PRESSURE_A, 1.0), (K.PRESSURE_B, -1.0)):
            add(kind, press_ns[keep], 1.0e5 + np.maximum(sign * run.pressure_diff_pa[keep], 0.0))
    if config.viscosity_source == ViscositySource.TEMPERATURE:
        t_ns = np.arange(joint_ns[0], joint_ns[-1], 50_000_000)
        t_ns = t_ns[(t_ns < joint_ns[0] + 4_000_000_000) | (t_ns > joint_ns[0] + 5_500_000_000)]
        celsius = 45.0 + 0.2 * np.arange(t_ns.size)
        celsius[7] = 300.0  # out of range
        add(K.OIL_TEMPERATURE, t_ns, celsius, n_bad=5)
    arrays = [np.concatenate(parts) for parts in zip(*streams, strict=True)]
    order = np.argsort(arrays[2], kind='stable')
    return [a[order] for a in arrays]


def chunk_bounds(n, rng):
    """Return irregular chunk boundaries: single messages, short and long chunks."""
    bounds = [0]
    while bounds[-1] < n:
        bounds.append(min(n, bounds[-1] + int(rng.choice([1, 2, 17, 400, 1999, 5000]))))
    return list(itertools.pairwise(bounds))


def exact(x):
    """Return a key equal only for identical values (NaN is NaN, -0.0 is not 0.0)."""
    if isinstance(x, float):
        return ('float', x.hex())
    if isinstance(x, tuple | list):
        return tuple(exact(v) for v in x)
    if isinstance(x, np.ndarray):
        return exact(x.tolist())
    if isinstance(x, dict):
        return tuple((k, exact(v)) for k, v in x.items())
    return (type(x).__name__, x)


def state(core):
    """Return everything the estimator carries from one message to the next."""
    slots = [(s.stamp_ns, s.value, s.out_of_order_run) for s in (
        core._speed, core._pressure, core._port_a, core._port_b, core._torque,
        core._temperature)]
    return exact((core.counts, core.last, core.last_stale_reason, core.stale_since_estimate,
                  slots,
                  monitor_state(core.monitor), vars(core.filter), vars(core.settled),
                  core._monitor_stamp_ns))


def monitor_state(monitor):
    """Return everything the wear monitor carries: its own values and its learnt sums."""
    own = {k: v for k, v in vars(monitor).items()
           if isinstance(v, int | float | str | type(None))}
    return (own, monitor.state_dict(), monitor.fit.coefficients, monitor.fit.covariance)


def feed_one_by_one(core, arrays):
    """Feed as the node does, ``on_input`` per message; note the monitor after each estimate."""
    positions, estimates, monitor_after = [], [], []
    for i, (kind, stamp, log_ns, value, torque, has_value, has_torque, defect) in enumerate(
            zip(*(a.tolist() for a in arrays), strict=True)):
        if defect:
            core.on_defect(defect)
            continue
        est = core.on_input(kind, stamp, value if has_value else None,
                            torque if has_torque else None, log_ns)
        if est is not None:
            positions.append(i)
            estimates.append(est)
            mon = core.monitor
            monitor_after.append((mon.cusum_pos_nm_s, mon.cusum_neg_nm_s, mon.theta_rest,
                                  mon.rest_scale_std))
    return positions, estimates, monitor_after


@pytest.mark.parametrize(('speed', 'torque', 'pressure', 'viscosity'), SOURCE_COMBOS,
                         ids=['-'.join(c.value for c in combo) for combo in SOURCE_COMBOS])
def test_irregular_chunks_give_exactly_what_on_input_gives(table, run, speed, torque,
                                                           pressure, viscosity):
    index = SOURCE_COMBOS.index((speed, torque, pressure, viscosity))
    oil = index % 2  # every other combination with the oil allowances (oil_allowance) on
    config = dataclasses.replace(EstimatorConfig(), speed_source=speed, torque_source=torque,
                                 pressure_source=pressure, viscosity_source=viscosity,
                                 drive_loss_torque_nm=0.05, baseline_learn_s=0.3,
                                 cusum_drift_nm=1.0, oil_temperature_band_c=3.0 * oil,
                                 torque_constant_drift_per_k=1.2e-3 * oil)
    arrays = message_stream(run, config, seed=index)
    rng = np.random.default_rng(100 + index)
    node = TorqueEstimator(config, table, 46e-6)
    replay = TorqueEstimator(config, table, 46e-6)
    made = 0
    levels = set()
    for start, end in chunk_bounds(arrays[0].size, rng):
        part = [a[start:end] for a in arrays]
        positions, estimates, monitor_after = feed_one_by_one(node, part)
        got_positions, columns = replay.on_chunk(*part)
        assert got_positions.tolist() == positions
        assert exact(columns.rows()) == exact(estimates)
        assert exact(list(zip(*(columns.monitor[k].tolist() for k in MONITOR_COLUMNS),
                              strict=True))) == exact(monitor_after)
        assert state(replay) == state(node)  # the node's state at every chunk boundary
        made += len(estimates)
        levels.update(e.level for e in estimates)
    counts = node.counts
    assert made == counts['estimates'] > 2000
    assert levels >= {0, 1}  # the monitor raised an alarm
    for name in ('rejected_non_finite', 'rejected_out_of_range', 'rejected_out_of_order',
                 'rejected_duplicate', 'rejected_future_stamp', 'rejected_negative_stamp',
                 'rejected_undecodable',
                 'stamp_resyncs', 'stale_skips', 'residuals', 'monitor_samples'):
        assert counts[name], name
    joint = SpeedSource.JOINT_STATE in (speed, torque)
    for name in ('rejected_missing_joint', 'rejected_malformed'):
        assert bool(counts[name]) == joint, name
    # and the two go on alike, message by message
    tail = [a[-500:] for a in arrays]
    assert exact(feed_one_by_one(replay, tail)) == exact(feed_one_by_one(node, tail))
    assert state(replay) == state(node)


def test_stamps_beyond_int64_take_the_per_message_path(table):
    config = EstimatorConfig()
    node = TorqueEstimator(config, table, 46e-6)
    replay = TorqueEstimator(config, table, 46e-6)
    base = 2 ** 63 - 10_000_000  # subtracting two of these overflows int64
    kinds = [K.LOAD_PRESSURE, K.JOINT_STATE, K.JOINT_STATE, K.LOAD_PRESSURE, K.JOINT_STATE]
    stamps = [base, base + 1_000_000, base + 2_000_000, base + 2_500_000, base + 3_000_000]
    log_times = [s + 2 ** 20 for s in stamps]  # beyond int64 too
    values = [100e5, 300.0, 310.0, 101e5, 320.0]
    torques = [math.nan, 20.0, 20.5, math.nan, 21.0]
    has_value = [True] * 5
    has_torque = [False, True, True, False, True]
    defects = [0] * 5
    arrays = [np.asarray(a) for a in (kinds, stamps, log_times, values, torques, has_value,
                                      has_torque, defects)]
    positions, estimates, _ = feed_one_by_one(node, arrays)
    got_positions, columns = replay.on_chunk(kinds, stamps, log_times, values, torques,
                                             has_value, has_torque, defects)
    assert len(estimates) == 3
    assert got_positions.tolist() == positions
    assert exact(columns.rows()) == exact(estimates)
    assert state(replay) == state(node)


def test_the_exact_lookup_equals_the_scalar_path_bit_for_bit(table):
    rng = np.random.default_rng(3)
    n = 20000
    speed = np.abs(rng.normal(0.0, 1.2 * table.speed_axis_rad_s[-1], n))
    pressure = np.abs(rng.normal(0.0, 1.2 * table.pressure_axis_pa[-1], n))
    v_axis = table.viscosity_axis_m2_s
    viscosity = rng.uniform(0.5 * v_axis[0], 1.5 * v_axis[-1], n)
    for axis, values in ((table.speed_axis_rad_s, speed), (table.pressure_axis_pa, pressure),
                         (v_axis, viscosity)):
        values[:axis.size] = axis  # the nodes themselves
    speed[5], pressure[6], viscosity[7], viscosity[8] = math.nan, math.inf, math.nan, 0.0
    motoring = rng.random(n) < 0.5
    mags, flags = ExactTableLookup(table).magnitudes(speed, pressure, viscosity, motoring)
    for i in range(n):
        ref, ref_flags = table.magnitudes(float(speed[i]), float(pressure[i]),
                                          float(viscosity[i]), bool(motoring[i]))
        assert exact([float(m[i]) for m in mags]) == exact(list(ref)), i
        assert int(flags[i]) == ref_flags, i


def test_speed_filter_update_many_equals_update():
    rng = np.random.default_rng(8)
    stamps = np.cumsum(rng.choice([1_000_000, 1_000_000, 2_000_000, 90_000_000, -5_000_000],
                                  3000)).tolist()  # gaps and steps back restart it
    speeds = rng.normal(100.0, 50.0, 3000).tolist()
    one, many = SpeedFilter(0.01, 50_000_000), SpeedFilter(0.01, 50_000_000)
    expected = [one.update(s, x) for s, x in zip(stamps, speeds, strict=True)]
    first, second = many.update_many(stamps[:1234], speeds[:1234]), \
        many.update_many(stamps[1234:], speeds[1234:])
    assert exact(np.concatenate((first[0], second[0]))) == exact(expected)
    assert first[1][-1] < second[1][-1] == one.restarts > 10  # the gaps restarted it
    assert exact(vars(many)) == exact(vars(one))


def test_monitor_update_many_equals_update():
    config = EstimatorConfig(baseline_learn_s=1.0)
    rng = np.random.default_rng(9)
    n = 8000
    t = (np.arange(n) * 1e-3).tolist()
    dt = np.where(rng.random(n) < 0.01, 0.0, 1e-3).tolist()  # gaps restart the windows
    sign = np.where(np.arange(n) % 1500 < 700, 1.0, -1.0).tolist()  # reversals
    vp, other, theoretical = (rng.uniform(0.1, 2.0, n).tolist() for _ in range(3))
    accel = rng.uniform(-800.0, 800.0, n).tolist()  # the baseline's inertia regressor
    residual = (rng.normal(0.0, 0.1, n)  # above the baseline after 5 s
                + np.where(np.arange(n) > 5000, 2.5, 0.0)).tolist()
    one, many = (WearMonitor(settings_view(config, MonitorSettings),
                             settings_view(config, AttributionSettings)) for _ in range(2))
    expected = []
    for row in zip(t, dt, residual, vp, other, theoretical, sign, accel, strict=True):
        one.update(*row)
        expected.append((one.level, one.cusum_pos_nm_s, one.cusum_neg_nm_s, one.theta_vp,
                         one.theta_rest, one.valve_plate_scale_std, one.rest_scale_std))
    columns = (t, dt, residual, vp, other, theoretical, sign, accel)
    traces = [many.update_many(*(c[a:b] for c in columns))
              for a, b in ((0, 1), (1, 2500), (2500, n))]
    got = [row for trace in traces for row in zip(*trace, strict=True)]
    assert {row[0] for row in expected} == {0, 1, 2}
    assert exact(got) == exact(expected)
    assert exact(monitor_state(many)) == exact(monitor_state(one))
