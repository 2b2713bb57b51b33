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

"""
The estimator's chunk path: many input messages at once, with the results of `on_input`.

`estimate_chunk` takes a chunk of decoded messages (parallel arrays, in arrival order) and
leaves the estimator exactly as calling ``TorqueEstimator.on_input`` (``on_defect`` for a
defect) message by message would: the same estimates, bit for bit, the same counters, the
same held samples, speed filter, wear monitor and stale reason. The offline replay uses it;
the node keeps the per-message path.

What depends on no state is done on whole arrays: defects, future stamps, non-finite and
implausible values, the sample-and-hold of each input (the latest sample accepted at or
before each speed sample, by position), freshness, the table lookup and the torque
arithmetic. Each operation is the one of the scalar path, element by element and in the same
order (numpy's elementwise arithmetic is IEEE like Python's), so the results are equal, not
close. What is sequential runs in lean loops: the stamp rules of each input (only where its
stamps do not simply increase), the speed filter, the monitor and its attribution, and
``math.tanh`` (not numpy's, which may use other code). A chunk holding what these arrays
cannot represent (stamps beyond int64, a value missing where one is required) goes through
``on_input`` message by message instead.
"""

from __future__ import annotations

import math
from typing import cast, TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .estimate_record import Estimate, EstimateColumns, MONITOR_COLUMNS
from .inputs import (
    Defect,
    DEFECT_COUNTER,
    InputKind,
    MAX_PRESSURE_PA,
    MAX_SPEED_RAD_S,
    MAX_TORQUE_NM,
    TEMPERATURE_RANGE_C,
)
from .monitor import MonitorTrace
from .settled_residual import Released

if TYPE_CHECKING:  # the estimator imports this module
    from .estimator import TorqueEstimator

__all__ = ['estimate_chunk']

_SAFE_NS = 1 << 62
"""Stamps and log times within +-this [ns] (146 years either side of 1970) subtract without
overflow in int64; a chunk holding others takes the per-message path."""
_NO_POSITIONS = np.empty(0, dtype=np.int64)


def _per_message(core: TorqueEstimator, kinds: np.ndarray, stamps: np.ndarray,
                 log_times: np.ndarray, values: np.ndarray, torques: np.ndarray,
                 has_value: np.ndarray, has_torque: np.ndarray, defects: np.ndarray
                 ) -> tuple[np.ndarray, EstimateColumns]:
    """
    Feed a chunk message by message through ``on_input`` (``on_defect`` for a defect).

    What `estimate_chunk` does when the arrays cannot represent the chunk. Arguments and
    result as `estimate_chunk`'s.
    """
    positions: list[int] = []
    estimates: list[Estimate] = []
    monitor = core.monitor
    state: dict[str, list[float]] = {k: [] for k in MONITOR_COLUMNS}
    on_input, on_defect = core.on_input, core.on_defect
    for i, (kind, stamp, log_ns, value, torque, valued, torqued, defect) in enumerate(zip(
            kinds.tolist(), stamps.tolist(), log_times.tolist(), values.tolist(),
            torques.tolist(), has_value.tolist(), has_torque.tolist(), defects.tolist(),
            strict=True)):
        if defect:
            on_defect(defect)
            continue
        est = on_input(kind, stamp, value if valued else None, torque if torqued else None,
                       log_ns)
        if est is not None:
            positions.append(i)
            estimates.append(est)
            for key, x in zip(MONITOR_COLUMNS, (
                    monitor.cusum_pos_nm_s, monitor.cusum_neg_nm_s, monitor.theta_rest,
                    monitor.rest_scale_std), strict=True):
                state[key].append(x)
    return np.array(positions, dtype=np.int64), EstimateColumns.from_rows(estimates, state)


def _nothing() -> tuple[np.ndarray, EstimateColumns]:
    """No estimate."""
    return _NO_POSITIONS, EstimateColumns.from_rows([], {k: [] for k in MONITOR_COLUMNS})


def _integers(values: ArrayLike) -> np.ndarray:
    """Return integers as an array: int64 where they are signed (else as numpy reads them)."""
    array = np.asarray(values)
    return array.astype(np.int64, copy=False) if array.dtype.kind == 'i' else array


def _safe(*arrays: np.ndarray) -> bool:
    """Whether int64 arrays hold only stamps that subtract without overflow."""
    return all(a.dtype == np.int64 and (not a.size or (
        int(a.min()) > -_SAFE_NS and int(a.max()) < _SAFE_NS)) for a in arrays)


class _Accepted:
    """The samples of one input accepted in a chunk, and its held sample before it."""

    def __init__(self, prev_stamp_ns: int | None, prev_value: float) -> None:
        self.prev_stamp_ns = prev_stamp_ns
        self.prev_value = prev_value
        self.positions = np.empty(0, dtype=np.int64)
        self.stamps = np.empty(0, dtype=np.int64)
        self.values = np.empty(0)

    def held(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Stamp, value and presence of the latest sample accepted at or before each position."""
        k = np.searchsorted(self.positions, positions, side='right')
        prev = self.prev_stamp_ns
        stamps = np.concatenate(([0 if prev is None else prev], self.stamps))
        values = np.concatenate(([self.prev_value], self.values))
        present = np.ones(self.stamps.size + 1, dtype=bool)
        present[0] = prev is not None
        return stamps[k], values[k], present[k]


def _accept(core: TorqueEstimator, slot_name: str,
            candidates: tuple[np.ndarray, np.ndarray, np.ndarray], limit: float,
            value_range: tuple[float, float] | None = None) -> _Accepted:
    """
    Apply ``TorqueEstimator._accept`` to the samples of one input, in order.

    ``candidates``: their positions in the chunk, stamps and values. Returns what was
    accepted, with the input's held sample before the chunk; the input's slot is left as
    the per-message path leaves it.
    """
    positions, stamps, values = candidates
    slot = getattr(core, slot_name)
    result = _Accepted(slot.stamp_ns, slot.value)
    if not positions.size:
        return result
    counts = core.counts
    finite = np.isfinite(values)
    if value_range is None:
        implausible = finite & (np.abs(values) > limit)
    else:  # the temperature: its range, checked before the finite test counts
        implausible = finite & ((values < value_range[0]) | (values > value_range[1]))
    counts['rejected_non_finite'] += int(finite.size - np.count_nonzero(finite))
    counts['rejected_out_of_range'] += int(np.count_nonzero(implausible))
    ok = finite & ~implausible
    positions, stamps, values = positions[ok], stamps[ok], values[ok]
    if not positions.size:
        return result
    last = slot.stamp_ns
    if (last is None or int(stamps[0]) > last) and bool(np.all(stamps[1:] > stamps[:-1])):
        keep = None  # the usual case: every stamp after the one before
        slot.out_of_order_run = 0
    else:
        keep_list = []
        run, resync = slot.out_of_order_run, core.config.stamp_resync_samples
        for stamp in stamps.tolist():  # `TorqueEstimator._accept`'s stamp rules
            if last is not None and stamp <= last:
                if stamp == last:
                    counts['rejected_duplicate'] += 1
                    keep_list.append(False)
                    continue
                run += 1
                if run < resync:
                    counts['rejected_out_of_order'] += 1
                    keep_list.append(False)
                    continue
                counts['stamp_resyncs'] += 1
            run = 0
            last = stamp
            keep_list.append(True)
        slot.out_of_order_run = run
        keep = np.array(keep_list, dtype=bool)
    if keep is not None:
        positions, stamps, values = positions[keep], stamps[keep], values[keep]
    if positions.size:
        slot.stamp_ns = int(stamps[-1])
        slot.value = float(values[-1])
    result.positions, result.stamps, result.values = positions, stamps, values
    return result


def estimate_chunk(core: TorqueEstimator, kinds: ArrayLike, stamps: ArrayLike,
                   log_times: ArrayLike, values: ArrayLike, torques: ArrayLike,
                   has_value: ArrayLike, has_torque: ArrayLike, defects: ArrayLike
                   ) -> tuple[np.ndarray, EstimateColumns]:
    """
    Feed a chunk of input messages to the estimator: ``on_input`` for each, all at once.

    Parameters
    ----------
    core : TorqueEstimator
        The estimator; left as the per-message path would leave it.
    kinds : array_like of int
        `InputKind` of each message.
    stamps : array_like of int
        Sample times [ns] (``on_input``'s ``stamp_ns``).
    log_times : array_like of int
        Receive times [ns] (``on_input``'s ``receive_ns``).
    values : array_like of float
        The value in SI (JointState: the speed, where ``has_value``).
    torques : array_like of float
        JointState only: the measured torque [N m], where ``has_torque``.
    has_value, has_torque : array_like of bool
        Whether the message carries a value, a torque (JointState).
    defects : array_like of int
        `Defect` of each message; 0 for a sample (``on_defect`` for the others).

    Returns
    -------
    tuple
        The positions in the chunk of the messages that made an estimate (int64 array),
        and the estimates, in order.

    """
    return _estimate_arrays(
        core, np.asarray(kinds).astype(np.int64, copy=False), _integers(stamps),
        _integers(log_times), np.asarray(values, dtype=np.float64),
        np.asarray(torques, dtype=np.float64), np.asarray(has_value).astype(bool, copy=False),
        np.asarray(has_torque).astype(bool, copy=False),
        np.asarray(defects).astype(np.int64, copy=False))


def _estimate_arrays(core: TorqueEstimator, kinds: np.ndarray, stamps: np.ndarray,
                     log_times: np.ndarray, values: np.ndarray, torques: np.ndarray,
                     has_value: np.ndarray, has_torque: np.ndarray, defects: np.ndarray
                     ) -> tuple[np.ndarray, EstimateColumns]:
    """`estimate_chunk` once its arguments are arrays of the right types."""
    n = kinds.size
    if not n:
        return _nothing()
    slots = [getattr(core, name).stamp_ns for name in
             ('_speed', '_pressure', '_port_a', '_port_b', '_torque', '_temperature')]
    defective = defects != 0
    kind = np.where(defective, -1, kinds)
    unknown = ~defective & ((kinds < 0) | (kinds > max(InputKind)))
    if not _safe(stamps, log_times, np.array([s for s in slots if s is not None],
                                             dtype=np.int64)) \
            or bool(np.any(unknown | ((kind > InputKind.JOINT_STATE) & ~has_value))):
        return _per_message(core, kinds, stamps, log_times, values, torques, has_value,
                            has_torque, defects)
    counts = core.counts
    # defects, then stamps too far ahead of their receive time, then stamps before 1970
    if defective.any():
        found, number = np.unique(defects[defective], return_counts=True)
        for defect, count in zip(found.tolist(), number.tolist(), strict=True):
            counts[DEFECT_COUNTER[Defect(defect)]] += count
    future = ~defective & (stamps - log_times > core._max_lead_ns)
    if future.any():
        counts['rejected_future_stamp'] += int(np.count_nonzero(future))
        kind = np.where(future, -1, kind)
    negative = ~defective & ~future & (stamps < 0)
    if negative.any():
        counts['rejected_negative_stamp'] += int(np.count_nonzero(negative))
        kind = np.where(negative, -1, kind)
    joint = kind == InputKind.JOINT_STATE
    counts['rejected_malformed'] += int(np.count_nonzero(joint & ~has_value & ~has_torque))

    def pick(mask: np.ndarray, source: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        where = np.flatnonzero(mask)
        return where, stamps[where], source[where]

    torque_mask = kind == InputKind.MOTOR_TORQUE
    speed_mask = kind == InputKind.SHAFT_SPEED
    if core._joint_torque:
        torque_mask |= joint & has_torque
    if core._joint_speed:
        speed_mask |= joint & has_value
    torque_source = np.where(joint, torques, values)
    torque = _accept(core, '_torque', pick(torque_mask, torque_source), MAX_TORQUE_NM)
    pressure = _accept(core, '_pressure', pick(kind == InputKind.LOAD_PRESSURE, values),
                       MAX_PRESSURE_PA)
    port_a = _accept(core, '_port_a', pick(kind == InputKind.PRESSURE_A, values),
                     MAX_PRESSURE_PA)
    port_b = _accept(core, '_port_b', pick(kind == InputKind.PRESSURE_B, values),
                     MAX_PRESSURE_PA)
    temperature = _accept(core, '_temperature', pick(kind == InputKind.OIL_TEMPERATURE, values),
                          math.inf, TEMPERATURE_RANGE_C)
    speed = _accept(core, '_speed', pick(speed_mask, values), MAX_SPEED_RAD_S)
    if not speed.positions.size:
        return _nothing()
    accel, restarts = core.filter.update_many(speed.stamps, speed.values)
    return _estimates(core, speed, accel, restarts, torque, pressure, port_a, port_b,
                      temperature)


def _estimates(core: TorqueEstimator, speed: _Accepted, accel: np.ndarray,
               restarts: np.ndarray, torque: _Accepted,
               pressure: _Accepted, port_a: _Accepted, port_b: _Accepted,
               temperature: _Accepted) -> tuple[np.ndarray, EstimateColumns]:
    """Sample-and-hold, stale skips, and the estimates of the accepted speed samples."""
    counts = core.counts
    q, stamp = speed.positions, speed.stamps
    max_age = core._max_age_ns
    if core._ports:
        fresh_a, value_a = _fresh(port_a, q, stamp, max_age)
        fresh_b, value_b = _fresh(port_b, q, stamp, max_age)
        has_dp, dp = fresh_a & fresh_b, value_a - value_b
        pressure_reason = 'no fresh port pressures'
    else:
        has_dp, dp = _fresh(pressure, q, stamp, max_age)
        pressure_reason = 'no fresh pressure'
    made = has_dp
    if core._use_temperature:
        has_temperature, celsius = _fresh(temperature, q, stamp, core._max_temp_age_ns)
        made = has_dp & has_temperature
    speed_rad_s = speed.values
    if made.size:  # whether the last speed sample that judged freshness made an estimate
        core.stale_since_estimate = not made[-1]
    if not made.all():
        stale = np.flatnonzero(~made)
        counts['stale_skips'] += int(stale.size)
        core.last_stale_reason = pressure_reason if not has_dp[stale[-1]] \
            else 'no fresh oil temperature'
        keep = np.flatnonzero(made)
        q, stamp, dp, accel = q[keep], stamp[keep], dp[keep], accel[keep]
        restarts = restarts[keep]
        speed_rad_s = speed_rad_s[keep]
        if core._use_temperature:
            celsius = celsius[keep]
        if not q.size:
            return _nothing()
    if core._use_temperature:
        unique, inverse = np.unique(celsius, return_inverse=True)
        walther = core._walther
        viscosity = np.array([walther(t) for t in unique.tolist()])[inverse.ravel()]
    else:
        viscosity = np.full(q.size, core._viscosity_m2_s)
    has_torque, torque_nm = _fresh(torque, q, stamp, max_age)
    measured = np.where(has_torque, torque_nm, math.nan)
    return q, _build(core, stamp, speed_rad_s, dp, viscosity, accel, restarts, measured,
                     has_torque)


def _fresh(held: _Accepted, positions: np.ndarray, stamps: np.ndarray, max_age_ns: int
           ) -> tuple[np.ndarray, np.ndarray]:
    """Whether each position holds a sample of the input within the age, and its value."""
    held_stamps, values, present = held.held(positions)
    return present & (np.abs(stamps - held_stamps) <= max_age_ns), values


def _build(core: TorqueEstimator, stamp: np.ndarray, speed: np.ndarray, dp: np.ndarray,
           viscosity: np.ndarray, accel: np.ndarray, restarts: np.ndarray,
           measured: np.ndarray, has_torque: np.ndarray) -> EstimateColumns:
    """``TorqueEstimator._estimate`` over arrays: the torques, the monitor, the estimates."""
    counts = core.counts
    lookup = core._chunk_lookup()
    (vp, bearing, joints, heads), flags = lookup.magnitudes(np.abs(speed), np.abs(dp),
                                                            viscosity, speed * dp < 0.0)
    counts['clamped_to_table'] += int(np.count_nonzero(flags))
    zero = core._zero_speed
    direction = np.array([math.tanh(x / zero) for x in speed.tolist()])
    comps = [direction * vp, direction * bearing, direction * joints, direction * heads]
    friction_mag = vp + bearing + joints + heads
    theoretical = core._displacement_m3 / (2.0 * math.pi) * dp  # `theoretical_torque_nm`
    inertia = core._inertia * accel
    steady = theoretical + direction * (friction_mag + core._drive_loss)  # `input_torque_nm`
    expected = steady + inertia
    efficiency = _efficiency(core, theoretical, steady, speed, dp)
    residual = measured - expected  # NaN without a fresh torque
    counts['residuals'] += int(np.count_nonzero(has_torque))
    steady_now = (np.abs(speed) >= core._monitor_min_speed) & \
        (np.abs(accel) <= core._monitor_max_accel)
    other = (bearing + joints) + heads
    released = core.settled.update_many(
        stamp, restarts, np.where(has_torque, measured - steady, math.nan), steady_now,
        (inertia, vp, other, theoretical, speed, accel, viscosity, joints))
    monitored = np.zeros(stamp.size, dtype=bool)
    monitored[released.positions] = True
    monitor = core.monitor
    before: list[list[float]] = [[x] for x in (
        monitor.level, monitor.cusum_pos_nm_s, monitor.cusum_neg_nm_s, monitor.theta_vp,
        monitor.theta_rest, monitor.valve_plate_scale_std, monitor.rest_scale_std)]
    if released.positions.size:
        trace = _monitor(core, released, (inertia, vp, other, theoretical, speed, accel,
                                          viscosity, joints))
        counts['monitor_samples'] += released.positions.size
        # each estimate carries the monitor's state after the latest monitored sample
        latest = np.cumsum(monitored)
        state = [np.array(first + after)[latest]
                 for first, after in zip(before, cast(list[list[float]], list(trace)),
                                         strict=True)]
    else:
        state = [np.repeat(np.array(first), stamp.size) for first in before]
    n0 = counts['estimates']
    counts['estimates'] = n0 + stamp.size
    publish = (np.arange(stamp.size) + n0) % core._decimation == 0
    level, cusum_pos, cusum_neg, vp_scale, other_scale, vp_std, other_std = state
    columns = EstimateColumns(
        [stamp, speed, dp, viscosity, theoretical, *comps,
         ((comps[0] + comps[1]) + comps[2]) + comps[3], inertia, accel,
         direction * core._drive_loss, expected, efficiency, measured, residual, vp_scale,
         vp_std, level, flags, publish],
        dict(zip(MONITOR_COLUMNS, (cusum_pos, cusum_neg, other_scale, other_std),
                 strict=True)))
    core.last = columns.rows(slice(-1, None))[0]
    return columns


def _efficiency(core: TorqueEstimator, theoretical: np.ndarray, steady: np.ndarray,
                speed: np.ndarray, dp: np.ndarray) -> np.ndarray:
    """`model.efficiency_of` over arrays, with its branches as masks."""
    undefined = (np.abs(speed) < core._eff_min_speed) | (np.abs(dp) < core._eff_min_pressure) \
        | (steady == 0.0) | (theoretical == 0.0)
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        pumping = theoretical / steady
        motoring = steady / theoretical
    motoring = np.where(motoring < 0.0, 0.0, motoring)  # max(x, 0.0): x unless x < 0
    return np.where(undefined, math.nan, np.where(theoretical * speed > 0.0, pumping, motoring))


def _monitor(core: TorqueEstimator, released: Released,
             columns: tuple[np.ndarray, ...]) -> MonitorTrace:
    """
    Feed the released settled samples to the wear monitor: `TorqueEstimator._monitor`.

    ``released``: `SettledResidual.update_many`'s, payloads by position in ``columns``
    (inertia, valve plate, other friction, theoretical torque, speed, acceleration,
    viscosity, spherical joints) or, for
    samples of an earlier chunk, as tuples. The arithmetic is `_monitor`'s, element by
    element.
    """
    old = released.carried
    at = released.sources[len(old):]
    fields = [np.concatenate((np.array([cast(tuple, e)[j] for e in old], dtype=float),
                              column[at])) for j, column in enumerate(columns)]
    inertia, vp, other, theoretical, speed, accel, viscosity, joints = fields
    stamps, filtered = released.stamps_ns, released.filtered_nm
    sign = np.where(speed > 0.0, 1.0, -1.0)
    last = core._monitor_stamp_ns
    if last is None and core._learnt_first_ns is None:
        core._learnt_first_ns = int(stamps[0])
    # the gap rule: a clock restart (stamp resync) steps back, a new run for the monitor
    before = np.concatenate(([stamps[0] if last is None else last], stamps[:-1]))
    step = stamps - before
    gaps = np.where(step > 0, step * 1e-9, math.inf)
    if last is None:
        gaps[0] = math.inf
    gaps = np.where(gaps <= core._monitor_max_dt, gaps, 0.0)
    core._monitor_stamp_ns = int(stamps[-1])
    return core.monitor.update_many((stamps * 1e-9).tolist(), gaps.tolist(),
                                    ((filtered - inertia) * sign).tolist(), vp.tolist(),
                                    other.tolist(), theoretical.tolist(), sign.tolist(),
                                    accel.tolist(), np.abs(speed).tolist(),
                                    viscosity.tolist(), joints.tolist())
