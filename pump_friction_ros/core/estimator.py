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
Online torque estimator: the ROS-free core of the ``torque_estimator`` node and the replay.

Inputs arrive as timestamped samples (stamps in integer nanoseconds) through `on_input`, one
call per message, whose kinds the table in ``inputs`` lists. Each accepted shaft-speed
sample triggers an estimate from the latest sample of every other input, provided each is
within ``max_input_age_s`` of it (sample-and-hold); otherwise no estimate is made and the
skip is counted. The offline replay hands over many messages at once through `on_chunk`
(``chunk_path``), with exactly the results of `on_input` per message. `estimator_setup`
builds one from the node's parameters (pump file, table).

Expected input torque = theoretical + friction (table) + J * filtered d(omega)/dt
+ drive loss (opposing the motion), by `model.input_torque_nm`. The derivative is that of
the speed through two low-pass stages (``speed_filter``). The residual, measured minus
expected, exists when a fresh measured torque does; the `WearMonitor` takes it aligned in
time and in steady running only (``settled_residual``).

Rejected and counted, never raised: non-finite or implausible values, duplicate or
out-of-order stamps, header stamps more than ``max_stamp_lead_s`` ahead of the receive
time or negative, messages without a usable sample (`inputs.Defect`). After
``stamp_resync_samples`` out-of-order samples of one input in a row its clock is taken as
restarted (counted).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
import math
from typing import Any, TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .attribution import AttributionSettings
from .chunk_path import estimate_chunk
from .diagnostics import DiagnosticSnapshot, snapshot
from .estimate_record import COUNTERS, Estimate, EstimateColumns
from .inputs import (
    Defect,
    DEFECT_COUNTER,
    InputKind,
    MAX_PRESSURE_PA,
    MAX_SPEED_RAD_S,
    MAX_TORQUE_NM,
    TEMPERATURE_RANGE_C,
)
from .monitor import MonitorSettings, WearMonitor
from .node_parameters import (
    EstimatorConfig,
    PressureSource,
    settings_view,
    SpeedSource,
    TorqueSource,
    ViscositySource,
)
from .oil_allowance import oil_allowance
from .oil_range import coverage_warning
from .settled_residual import SettledResidual
from .speed_filter import SpeedFilter
from ..physics.friction import smooth_sign_scalar
from ..physics.model import efficiency_of, input_torque_nm, theoretical_torque_nm
from ..physics.oil import WaltherViscosity
from ..table.exact_lookup import ExactTableLookup
from ..table.friction_table import FrictionTable

if TYPE_CHECKING:
    from .baseline_store import BaselineStore

__all__ = ['COUNTERS', 'Estimate', 'TorqueEstimator']


@dataclass
class _Input:
    """Latest accepted sample of one input."""

    name: str
    stamp_ns: int | None = None
    value: float = math.nan
    out_of_order_run: int = 0


class TorqueEstimator:
    """
    Expected torque, residual and wear monitoring from timestamped samples.

    Parameters
    ----------
    config : EstimatorConfig
        Validated parameters.
    table : FrictionTable
        Friction table of the pump in use (its provenance already checked).
    default_viscosity_m2_s : float
        Viscosity when the config gives none (the pump file's) [m^2/s].
    pump_name : str
        Name used in the diagnostics.

    """

    def __init__(self, config: EstimatorConfig, table: FrictionTable,
                 default_viscosity_m2_s: float, pump_name: str = 'pump') -> None:
        self.config = config
        self.table = table
        self.pump_name = pump_name
        self._viscosity_m2_s = config.viscosity_m2_s(default_viscosity_m2_s)
        # one line where the table's viscosity axis falls short of the oil; '' if it covers
        self.table_coverage = coverage_warning(table, config, default_viscosity_m2_s)
        self._walther = WaltherViscosity(config.oil_viscosity_40c_m2_s,
                                         config.oil_viscosity_100c_m2_s)
        self._max_age_ns = round(config.max_input_age_s * 1e9)
        self._max_temp_age_ns = round(config.max_temperature_age_s * 1e9)
        self._max_lead_ns = round(config.max_stamp_lead_s * 1e9)
        self._ports = config.pressure_source == PressureSource.PORTS
        self._use_temperature = config.viscosity_source == ViscositySource.TEMPERATURE
        self._joint_speed = config.speed_source == SpeedSource.JOINT_STATE
        self._joint_torque = config.torque_source == TorqueSource.JOINT_STATE
        # constants of the per-sample path, read once
        self._inertia = config.rotor_inertia_kg_m2
        self._drive_loss = config.drive_loss_torque_nm
        self._monitor_min_speed = config.monitor_min_speed_rad_s
        self._monitor_max_accel = config.monitor_max_accel_rad_s2
        self._monitor_max_dt = config.max_input_age_s
        self._decimation = config.output_decimation
        self._displacement_m3 = table.displacement_m3
        self._zero_speed = table.zero_speed_threshold_rad_s
        self._eff_min_speed = table.efficiency_min_speed_rad_s
        self._eff_min_pressure = table.efficiency_min_pressure_pa
        assumed = not self._use_temperature
        oil = oil_allowance(table, self._viscosity_m2_s, self._walther, assumed,
                            config.oil_temperature_band_c, config.torque_constant_drift_per_k)
        self.monitor = WearMonitor(settings_view(config, MonitorSettings),
                                   settings_view(config, AttributionSettings),
                                   config.drive_loss_torque_nm, assumed,
                                   config.rotor_inertia_kg_m2, oil)
        self._lookup: ExactTableLookup | None = None
        self.filter = SpeedFilter(config.accel_filter_time_constant_s, self._max_age_ns)
        self.settled = SettledResidual(config.accel_filter_time_constant_s, self._max_age_ns,
                                       config.monitor_settle_s, config.monitor_lookahead_s)
        self.baseline: BaselineStore | None = None  # its status goes into the diagnostics
        # indexed by InputKind; the value is a float for every kind but JOINT_STATE's
        handlers = {InputKind.JOINT_STATE: self._on_joint_state,
                    InputKind.SHAFT_SPEED: self._on_speed,
                    InputKind.MOTOR_TORQUE: self._on_torque,
                    InputKind.LOAD_PRESSURE: self._on_pressure,
                    InputKind.PRESSURE_A: self._on_pressure_a,
                    InputKind.PRESSURE_B: self._on_pressure_b,
                    InputKind.OIL_TEMPERATURE: self._on_temperature}
        # indexed by InputKind (an int) for the per-message path; every kind has one
        self._handlers: tuple[Callable[[int, Any, float | None], Estimate | None], ...] = \
            tuple(handlers[kind] for kind in InputKind)
        self.reset()

    def reset(self) -> None:
        """Forget all inputs, filters, counters and the monitor's state."""
        self.counts = dict.fromkeys(COUNTERS, 0)
        self._speed = _Input('speed')
        self._pressure = _Input('pressure')
        self._port_a = _Input('pressure_a')
        self._port_b = _Input('pressure_b')
        self._torque = _Input('torque')
        self._temperature = _Input('temperature')
        self.filter.reset()
        self.settled.reset()
        self.last: Estimate | None = None
        self.last_stale_reason = 'no input yet'
        self.stale_since_estimate = False  # a speed sample skipped stale after the latest
        self._at_status: tuple[int, dict[str, int]] | None = None  # last diagnostics()'s
        self.reset_monitor()

    def reset_monitor(self) -> None:
        """Forget the wear monitor's state, its baseline included (after a repair): re-learn."""
        self.monitor.reset()
        self._monitor_stamp_ns: int | None = None
        # what the monitor learnt from since this reset, across restarts (`learnt`)
        self._learnt_first_ns: int | None = None
        self._learnt_last_ns: int | None = None  # before the restart (a baseline file)
        self._learnt_offset = -self.counts['monitor_samples']

    @property
    def learnt(self) -> tuple[int, int | None, int | None]:
        """Return samples learnt since the monitor's reset (restarts too), first, last [ns]."""
        last = self._monitor_stamp_ns
        return (self._learnt_offset + self.counts['monitor_samples'], self._learnt_first_ns,
                self._learnt_last_ns if last is None else last)

    def restore_monitor(self, state: dict[str, object], samples: int, first_ns: int | None,
                        last_ns: int | None) -> None:
        """
        Restore the monitor's state and `learnt` as saved before a restart (a baseline file).

        A state the monitor refuses raises its ValueError, the monitor reset, never half loaded.
        """
        self.reset_monitor()
        try:
            self.monitor.load_state_dict(state)
        except ValueError:
            self.reset_monitor()
            raise
        self._learnt_offset += samples
        self._learnt_first_ns, self._learnt_last_ns = first_ns, last_ns

    # -- inputs ---------------------------------------------------------------------------

    def on_input(self, kind: InputKind, stamp_ns: int, value: float | None,
                 torque_nm: float | None = None, receive_ns: int | None = None
                 ) -> Estimate | None:
        """
        Take one input message's sample: the one entry point of the node and the replay.

        Parameters
        ----------
        kind : InputKind
            What the message carries (``inputs.INPUTS``).
        stamp_ns : int
            Sample time [ns]: the header stamp, or the receive time (see ``inputs``).
        value : float or None
            The value in SI (JointState: the speed, None when the message has none).
        torque_nm : float or None
            JointState only: the measured torque (effort) [N m], None when absent.
        receive_ns : int, optional
            When the message was received (the replay: its log time) [ns]; a stamp more
            than ``max_stamp_lead_s`` ahead of it is rejected.

        Returns
        -------
        Estimate or None
            The estimate a shaft-speed sample made, if any.

        """
        if receive_ns is not None and stamp_ns - receive_ns > self._max_lead_ns:
            self.counts['rejected_future_stamp'] += 1
            return None
        if stamp_ns < 0:  # before 1970: no ROS clock reads it (a baseline could not hold it)
            self.counts['rejected_negative_stamp'] += 1
            return None
        return self._handlers[kind](stamp_ns, value, torque_nm)

    def on_chunk(self, kinds: ArrayLike, stamps: ArrayLike, log_times: ArrayLike,
                 values: ArrayLike, torques: ArrayLike, has_value: ArrayLike,
                 has_torque: ArrayLike, defects: ArrayLike
                 ) -> tuple[np.ndarray, EstimateColumns]:
        """
        Take many input messages at once: exactly `on_input` (or `on_defect`) for each.

        The replay's path (``chunk_path.estimate_chunk``): the per-message calls' estimates,
        counters and state, in whole-array arithmetic where nothing depends on the order.

        Parameters
        ----------
        kinds, stamps, log_times, values, torques, has_value, has_torque, defects : array_like
            The messages, as ``chunk_path.estimate_chunk`` takes them.

        Returns
        -------
        tuple
            Positions in the chunk of the messages that made an estimate (int64 array), and
            the estimates (`EstimateColumns`: ``rows()`` gives the `Estimate` objects).

        """
        return estimate_chunk(self, kinds, stamps, log_times, values, torques, has_value,
                              has_torque, defects)

    def _chunk_lookup(self) -> ExactTableLookup:
        """Return the chunk path's table lookup, made on first use."""
        if self._lookup is None:
            self._lookup = ExactTableLookup(self.table)
        return self._lookup

    def on_defect(self, defect: Defect) -> None:
        """
        Count a message that carried no usable sample.

        Parameters
        ----------
        defect : Defect
            Why (a missing joint, malformed arrays, an undecodable bag message).

        """
        self.counts[DEFECT_COUNTER[Defect(defect)]] += 1

    def _on_joint_state(self, stamp_ns: int, speed: float | None,
                        torque: float | None) -> Estimate | None:
        if speed is None and torque is None:
            self.counts['rejected_malformed'] += 1  # a JointState with neither for the joint
            return None
        if torque is not None and self._joint_torque:
            self._accept(self._torque, stamp_ns, torque, MAX_TORQUE_NM)
        if speed is not None and self._joint_speed:
            return self._on_speed(stamp_ns, speed, None)
        return None

    def _on_torque(self, stamp_ns: int, value: float, _: object) -> None:
        self._accept(self._torque, stamp_ns, value, MAX_TORQUE_NM)

    def _on_pressure(self, stamp_ns: int, value: float, _: object) -> None:
        self._accept(self._pressure, stamp_ns, value, MAX_PRESSURE_PA)

    def _on_pressure_a(self, stamp_ns: int, value: float, _: object) -> None:
        self._accept(self._port_a, stamp_ns, value, MAX_PRESSURE_PA)

    def _on_pressure_b(self, stamp_ns: int, value: float, _: object) -> None:
        self._accept(self._port_b, stamp_ns, value, MAX_PRESSURE_PA)

    def _on_temperature(self, stamp_ns: int, value: float, _: object) -> None:
        if math.isfinite(value) and not TEMPERATURE_RANGE_C[0] <= value <= TEMPERATURE_RANGE_C[1]:
            self.counts['rejected_out_of_range'] += 1
            return
        self._accept(self._temperature, stamp_ns, value, math.inf)

    def _accept(self, slot: _Input, stamp_ns: int, value: float, limit: float) -> bool:
        counts = self.counts
        if not math.isfinite(value):
            counts['rejected_non_finite'] += 1
            return False
        if abs(value) > limit:
            counts['rejected_out_of_range'] += 1
            return False
        last = slot.stamp_ns
        if last is not None and stamp_ns <= last:
            if stamp_ns == last:
                counts['rejected_duplicate'] += 1
                return False
            slot.out_of_order_run += 1
            if slot.out_of_order_run < self.config.stamp_resync_samples:
                counts['rejected_out_of_order'] += 1
                return False
            counts['stamp_resyncs'] += 1  # the source's clock restarted: follow it
        slot.out_of_order_run = 0
        slot.stamp_ns = stamp_ns
        slot.value = value
        return True

    def _on_speed(self, stamp_ns: int, speed: float, _: object) -> Estimate | None:
        if not self._accept(self._speed, stamp_ns, speed, MAX_SPEED_RAD_S):
            return None
        accel = self.filter.update(stamp_ns, speed)
        p = self._pressure
        if not self._ports and p.stamp_ns is not None and \
                -self._max_age_ns <= stamp_ns - p.stamp_ns <= self._max_age_ns:
            dp: float | None = p.value  # the common case, inline
        else:
            dp = self._pressure_at(stamp_ns)
        if dp is None:
            self._stale(f'no fresh {"port pressures" if self._ports else "pressure"}')
            return None
        viscosity = self._viscosity_at(stamp_ns) if self._use_temperature \
            else self._viscosity_m2_s
        if viscosity is None:
            self._stale('no fresh oil temperature')
            return None
        self.stale_since_estimate = False
        return self._estimate(stamp_ns, speed, dp, viscosity, accel)

    # -- internals ------------------------------------------------------------------------

    def _fresh(self, slot: _Input, stamp_ns: int, max_age_ns: int) -> bool:
        return slot.stamp_ns is not None and abs(stamp_ns - slot.stamp_ns) <= max_age_ns

    def _pressure_at(self, stamp_ns: int) -> float | None:
        if self._ports:
            a, b = self._port_a, self._port_b
            if self._fresh(a, stamp_ns, self._max_age_ns) and \
                    self._fresh(b, stamp_ns, self._max_age_ns):
                return a.value - b.value
            return None
        p = self._pressure
        return p.value if self._fresh(p, stamp_ns, self._max_age_ns) else None

    def _viscosity_at(self, stamp_ns: int) -> float | None:
        t = self._temperature
        return self._walther(t.value) if self._fresh(t, stamp_ns, self._max_temp_age_ns) \
            else None

    def _stale(self, reason: str) -> None:
        self.counts['stale_skips'] += 1
        self.last_stale_reason = reason
        self.stale_since_estimate = True

    def _estimate(self, stamp_ns: int, speed: float, dp: float, viscosity: float,
                  accel: float) -> Estimate:
        counts = self.counts
        mags, flags = self.table.magnitudes(abs(speed), abs(dp), viscosity, speed * dp < 0.0)
        if flags:
            counts['clamped_to_table'] += 1
        direction = smooth_sign_scalar(speed, self._zero_speed)
        vp, bearing, joints, heads = mags
        comps = (direction * vp, direction * bearing, direction * joints, direction * heads)
        friction_mag = vp + bearing + joints + heads
        theoretical = theoretical_torque_nm(self._displacement_m3, dp)
        inertia = self._inertia * accel
        steady = input_torque_nm(theoretical, friction_mag, direction, self._drive_loss)
        expected = steady + inertia
        efficiency = efficiency_of(theoretical, steady, speed, dp, self._eff_min_speed,
                                   self._eff_min_pressure)
        measured = residual = math.nan
        monitor = self.monitor
        torque = self._torque
        if torque.stamp_ns is not None and abs(stamp_ns - torque.stamp_ns) <= self._max_age_ns:
            measured = torque.value
            residual = measured - expected
            counts['residuals'] += 1
            released = self.settled.update(
                stamp_ns, self.filter.restarts, measured - steady,
                abs(speed) >= self._monitor_min_speed and abs(accel) <= self._monitor_max_accel,
                (inertia, vp, bearing + joints + heads, theoretical, speed, accel, viscosity,
                 joints))
            if released is not None:
                self._monitor(*released)
        else:
            self.settled.update(stamp_ns, self.filter.restarts, math.nan, False, None)
        n = counts['estimates'] = counts['estimates'] + 1
        estimate = Estimate(stamp_ns, speed, dp, viscosity, theoretical, comps,
                            comps[0] + comps[1] + comps[2] + comps[3], inertia, accel,
                            direction * self._drive_loss, expected, efficiency, measured,
                            residual, monitor.theta_vp, monitor.valve_plate_scale_std,
                            monitor.level, flags, (n - 1) % self._decimation == 0)
        self.last = estimate
        return estimate

    def _monitor(self, stamp_ns: int, filtered_nm: float,
                 payload: tuple[float, ...]) -> None:
        """Feed one settled sample (released by `SettledResidual`: eight floats) to the monitor."""
        inertia, vp, other, theoretical, speed, accel, viscosity, joints = payload
        sign = 1.0 if speed > 0.0 else -1.0
        last = self._monitor_stamp_ns
        if last is None and self._learnt_first_ns is None:
            self._learnt_first_ns = stamp_ns
        # a clock restart (stamp resync) steps back: a new run for the monitor
        gap = math.inf if last is None or stamp_ns <= last else (stamp_ns - last) * 1e-9
        self._monitor_stamp_ns = stamp_ns
        self.monitor.update(stamp_ns * 1e-9, gap if gap <= self._monitor_max_dt else 0.0,
                            (filtered_nm - inertia) * sign, vp, other, theoretical, sign,
                            accel, abs(speed), viscosity, joints)
        self.counts['monitor_samples'] += 1

    # -- diagnostics ----------------------------------------------------------------------

    def diagnostics(self, now_ns: int, clock_stopped: str = '') -> DiagnosticSnapshot:
        """
        Status for /diagnostics at ``now_ns``; keeps the counters for the next one's message.

        Parameters
        ----------
        now_ns : int
            Current time of the node's clock (or of the replay) [ns].
        clock_stopped : str
            Why the node's clock does not advance ('' when it does): the status is STALE
            with it, whatever the latest estimate.

        Returns
        -------
        DiagnosticSnapshot
            Level, message and key-values (see ``diagnostics.snapshot``).

        """
        axis = self.table.viscosity_axis_m2_s
        extra, note = self.baseline.diagnostics() if self.baseline is not None else ([], '')
        note = '; '.join(x for x in (note, self.monitor.oil_note) if x)
        previous, self._at_status = self._at_status, (now_ns, dict(self.counts))
        return snapshot(self.last, self.monitor, self.counts, self.config.stale_timeout_s,
                        self.last_stale_reason if self.stale_since_estimate or
                        self.last is None else '', now_ns, (float(axis[0]), float(axis[-1])),
                        extra, note, previous, self.config.max_stamp_lead_s, clock_stopped)
