"""Online torque estimator: the ROS-free core of the ``torque_estimator`` node and the replay.

Inputs arrive as timestamped samples (stamps in integer nanoseconds) through the ``on_*``
methods, one per message kind the node subscribes. Each accepted shaft-speed sample triggers
an estimate from the latest sample of every other input, provided each is younger than
``max_input_age_s`` (sample-and-hold); otherwise no estimate is made and the skip is counted.

Expected input torque = theoretical + friction (table) + J * filtered d(omega)/dt
+ drive loss (opposing the motion). The derivative is that of the speed through two
first-order low-pass stages (time constant ``accel_filter_time_constant_s`` each), exact
for any sample spacing, so noisy speed does not make it explode. The residual, measured
minus expected, exists when a fresh measured torque does; it feeds the `WearMonitor`.

Rejected and counted, never raised: non-finite values, stamps older than (out of order) or
equal to (duplicate) the input's last accepted stamp, values beyond physical plausibility.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

from .config import EstimatorConfig
from .model import COMPONENTS, efficiency_of
from .monitor import LEVEL_NAMES, OK, STALE, MonitorConfig, WearMonitor
from .oil import WaltherViscosity
from .params import load_pump
from .table import NOT_FINITE, FrictionTable, cached_table, describe_flags, load_table

__all__ = ['COUNTERS', 'DiagnosticSnapshot', 'Estimate', 'TorqueEstimator',
           'estimator_from_config']

MAX_SPEED_RAD_S = 1.0e4
"""|speed| above this (95,000 rpm) is not a plausible measurement: rejected."""
MAX_PRESSURE_PA = 2.0e8
"""|pressure| above this (2,000 bar) is rejected."""
MAX_TORQUE_NM = 1.0e4
"""|torque| above this is rejected."""
TEMPERATURE_RANGE_C = (-60.0, 250.0)
"""Oil temperatures outside this range are rejected."""

COUNTERS = ('estimates', 'stale_skips', 'rejected_non_finite', 'rejected_out_of_order',
            'rejected_duplicate', 'rejected_out_of_range', 'clamped_to_table',
            'residuals', 'monitor_samples')


@dataclass
class _Input:
    """Latest accepted sample of one input."""

    name: str
    stamp_ns: int | None = None
    value: float = math.nan


class Estimate(NamedTuple):
    """One estimate (what the node publishes), SI units; NaN where not available.

    A NamedTuple: made a thousand times a second, it must be cheap to build.
    """

    stamp_ns: int
    speed_rad_s: float
    pressure_diff_pa: float
    viscosity_m2_s: float
    theoretical_nm: float
    components_nm: tuple[float, float, float, float]  # COMPONENTS order, signed
    friction_nm: float
    inertia_nm: float
    accel_rad_s2: float  # filtered shaft acceleration
    drive_loss_nm: float
    expected_nm: float
    efficiency: float  # NaN where undefined (near zero speed or pressure)
    measured_nm: float  # NaN without a fresh measured torque
    residual_nm: float  # NaN without a fresh measured torque
    valve_plate_scale: float
    valve_plate_scale_std: float
    level: int
    table_flags: int
    publish: bool  # output decimation: publish this one


@dataclass(frozen=True)
class DiagnosticSnapshot:
    """What /diagnostics reports: level, message and key-values with units in the keys."""

    level: int
    message: str
    values: list[tuple[str, str]] = field(default_factory=list)


class TorqueEstimator:
    """ROS-free core of the torque estimator.

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
        self._viscosity_m2_s = config.oil_viscosity_m2_s or default_viscosity_m2_s
        self._walther = WaltherViscosity(config.oil_viscosity_40c_m2_s,
                                         config.oil_viscosity_100c_m2_s)
        self._max_age_ns = round(config.max_input_age_s * 1e9)
        self._max_temp_age_ns = round(config.max_temperature_age_s * 1e9)
        self._ports = config.pressure_source == 'ports'
        self._use_temperature = config.viscosity_source == 'temperature'
        # constants of the per-sample path, read once
        self._inertia = config.rotor_inertia_kg_m2
        self._drive_loss = config.drive_loss_torque_nm
        self._monitor_min_speed = config.monitor_min_speed_rad_s
        self._monitor_max_accel = config.monitor_max_accel_rad_s2
        self._monitor_max_dt = config.max_input_age_s
        self._decimation = config.output_decimation
        self._torque_per_pa = table.displacement_m3 / (2.0 * math.pi)
        self._inv_zero_speed = 1.0 / table.zero_speed_threshold_rad_s
        self._eff_min_speed = table.efficiency_min_speed_rad_s
        self._eff_min_pressure = table.efficiency_min_pressure_pa
        self.monitor = WearMonitor(MonitorConfig(
            ewma_time_constant_s=config.ewma_time_constant_s,
            cusum_drift_nm=config.cusum_drift_nm, cusum_warn_nm_s=config.cusum_warn_nm_s,
            cusum_error_nm_s=config.cusum_error_nm_s,
            cusum_clear_ratio=config.cusum_clear_ratio,
            rls_forgetting_time_s=config.rls_forgetting_time_s,
            rls_initial_std=config.rls_initial_std))
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
        self._lp1 = self._lp2 = self._speed_prev = 0.0  # speed filter state
        self._filter_step_ns = -1
        self._filter_coefficients = (0.0, 0.0, 0.0)
        self._accel = 0.0
        self._monitor_stamp_ns: int | None = None
        self.last: Estimate | None = None
        self.last_stale_reason = 'no input yet'
        self.monitor.reset()

    # -- inputs ---------------------------------------------------------------------------

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
            counts['rejected_duplicate' if stamp_ns == last else 'rejected_out_of_order'] += 1
            return False
        slot.stamp_ns = stamp_ns
        slot.value = value
        return True

    def on_joint_state(self, stamp_ns: int, speed_rad_s: float | None,
                       torque_nm: float | None) -> Estimate | None:
        """Take a JointState sample: speed (velocity) and/or torque (effort).

        The torque is taken first so that the estimate the speed triggers uses it.

        Parameters
        ----------
        stamp_ns : int
            Sample time [ns].
        speed_rad_s : float or None
            Shaft speed [rad/s], None when the message carries none.
        torque_nm : float or None
            Measured motor torque [N m], None when the message carries none.

        Returns
        -------
        Estimate or None
            The estimate made, if any.
        """
        if torque_nm is not None and self.config.torque_source == 'joint_state':
            self.on_torque(stamp_ns, torque_nm)
        if speed_rad_s is not None and self.config.speed_source == 'joint_state':
            return self.on_speed(stamp_ns, speed_rad_s)
        return None

    def on_torque(self, stamp_ns: int, torque_nm: float) -> bool:
        """Take a measured motor torque sample [N m]; False if rejected."""
        return self._accept(self._torque, stamp_ns, torque_nm, MAX_TORQUE_NM)

    def on_pressure(self, stamp_ns: int, pressure_diff_pa: float) -> bool:
        """Take a pressure difference p_A - p_B sample [Pa]; False if rejected."""
        return self._accept(self._pressure, stamp_ns, pressure_diff_pa, MAX_PRESSURE_PA)

    def on_port_pressure(self, port: str, stamp_ns: int, pressure_pa: float) -> bool:
        """Take a port pressure sample, ``port`` 'a' or 'b' [Pa]; False if rejected."""
        slot = self._port_a if port == 'a' else self._port_b
        return self._accept(slot, stamp_ns, pressure_pa, MAX_PRESSURE_PA)

    def on_temperature(self, stamp_ns: int, temperature_c: float) -> bool:
        """Take an oil temperature sample [degC]; False if rejected."""
        if math.isfinite(temperature_c) and not (
                TEMPERATURE_RANGE_C[0] <= temperature_c <= TEMPERATURE_RANGE_C[1]):
            self.counts['rejected_out_of_range'] += 1
            return False
        return self._accept(self._temperature, stamp_ns, temperature_c, math.inf)

    def on_speed(self, stamp_ns: int, speed_rad_s: float) -> Estimate | None:
        """Take a shaft speed sample [rad/s] and make an estimate if the inputs are fresh.

        Parameters
        ----------
        stamp_ns : int
            Sample time [ns].
        speed_rad_s : float
            Shaft speed [rad/s].

        Returns
        -------
        Estimate or None
            None when the sample is rejected or another input is stale.
        """
        previous = self._speed.stamp_ns
        if not self._accept(self._speed, stamp_ns, speed_rad_s, MAX_SPEED_RAD_S):
            return None
        self._filter_speed(stamp_ns, previous, speed_rad_s)
        p = self._pressure
        if not self._ports and p.stamp_ns is not None and \
                -self._max_age_ns <= stamp_ns - p.stamp_ns <= self._max_age_ns:
            dp = p.value  # the common case, inline
        else:
            dp = self._pressure_at(stamp_ns)
        if dp is None:
            return self._stale(f'no fresh {"port pressures" if self._ports else "pressure"}')
        viscosity = self._viscosity_at(stamp_ns) if self._use_temperature \
            else self._viscosity_m2_s
        if viscosity is None:
            return self._stale('no fresh oil temperature')
        return self._estimate(stamp_ns, speed_rad_s, dp, viscosity)

    # -- internals ------------------------------------------------------------------------

    def _filter_speed(self, stamp_ns: int, previous_ns: int | None, speed: float) -> None:
        """Two first-order low-pass stages and the derivative of the second.

        Each stage is the exact discretisation of tau y' = x - y for an input linear between
        samples (first-order hold): y_k = b y_k-1 + a x_k-1 + c (x_k - x_k-1), with
        b = exp(-dt/tau), a = 1 - b, c = 1 - tau a / dt. A ramp then lags by exactly tau per
        stage at any sample spacing, and (lp1 - lp2) / tau is the slope of lp2.
        """
        if previous_ns is None or stamp_ns - previous_ns > self._max_age_ns:
            self._lp1 = self._lp2 = self._speed_prev = speed  # (re)start: no derivative
            self._accel = 0.0  # across a gap
            return
        step_ns = stamp_ns - previous_ns
        if step_ns != self._filter_step_ns:  # evenly spaced samples: coefficients once
            dt = step_ns * 1e-9
            tau = self.config.accel_filter_time_constant_s
            b = math.exp(-dt / tau)
            self._filter_coefficients = (b, 1.0 - b, 1.0 - tau * (1.0 - b) / dt)
            self._filter_step_ns = step_ns
        b, a, c = self._filter_coefficients
        tau = self.config.accel_filter_time_constant_s
        lp1_old = self._lp1
        self._lp1 = b * lp1_old + a * self._speed_prev + c * (speed - self._speed_prev)
        self._lp2 = b * self._lp2 + a * lp1_old + c * (self._lp1 - lp1_old)
        self._speed_prev = speed
        self._accel = (self._lp1 - self._lp2) / tau

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
        if not self._use_temperature:
            return self._viscosity_m2_s
        t = self._temperature
        return self._walther(t.value) if self._fresh(t, stamp_ns, self._max_temp_age_ns) \
            else None

    def _stale(self, reason: str) -> None:
        self.counts['stale_skips'] += 1
        self.last_stale_reason = reason
        return None

    def _estimate(self, stamp_ns: int, speed: float, dp: float, viscosity: float) -> Estimate:
        counts = self.counts
        mags, flags = self.table.magnitudes(abs(speed), abs(dp), viscosity, speed * dp < 0.0)
        if flags:
            counts['clamped_to_table'] += 1
        direction = math.tanh(speed * self._inv_zero_speed)
        vp, bearing, joints, heads = mags
        comps = (direction * vp, direction * bearing, direction * joints, direction * heads)
        friction = comps[0] + comps[1] + comps[2] + comps[3]
        theoretical = self._torque_per_pa * dp
        inertia = self._inertia * self._accel
        drive_loss = direction * self._drive_loss
        expected = theoretical + friction + inertia + drive_loss
        efficiency = efficiency_of(theoretical, theoretical + friction + drive_loss, speed, dp,
                                   self._eff_min_speed, self._eff_min_pressure)
        measured = residual = math.nan
        monitor = self.monitor
        torque = self._torque
        if torque.stamp_ns is not None and abs(stamp_ns - torque.stamp_ns) <= self._max_age_ns:
            measured = torque.value
            residual = measured - expected
            counts['residuals'] += 1
            if abs(speed) >= self._monitor_min_speed and \
                    abs(self._accel) <= self._monitor_max_accel:
                sign = 1.0 if speed > 0.0 else -1.0
                last = self._monitor_stamp_ns
                dt = 0.0 if last is None else min((stamp_ns - last) * 1e-9, self._monitor_max_dt)
                self._monitor_stamp_ns = stamp_ns
                friction_part = (measured - theoretical - inertia) * sign - self._drive_loss
                monitor.update(dt, residual * sign, friction_part, vp, bearing + joints + heads)
                counts['monitor_samples'] += 1
        n = counts['estimates'] = counts['estimates'] + 1
        estimate = Estimate(stamp_ns, speed, dp, viscosity, theoretical, comps, friction, inertia,
                            self._accel, drive_loss, expected, efficiency, measured, residual,
                            monitor.theta_vp, monitor.valve_plate_scale_std, monitor.level,
                            flags, (n - 1) % self._decimation == 0)
        self.last = estimate
        return estimate

    # -- diagnostics ----------------------------------------------------------------------

    def diagnostics(self, now_ns: int) -> DiagnosticSnapshot:
        """Status for /diagnostics at time ``now_ns``.

        Parameters
        ----------
        now_ns : int
            Current time of the node's clock (or of the replay) [ns].

        Returns
        -------
        DiagnosticSnapshot
            Level (STALE when no estimate for ``stale_timeout_s``), message, key-values.
        """
        est = self.last
        mon = self.monitor
        age_s = math.inf if est is None else (now_ns - est.stamp_ns) * 1e-9
        if est is None or age_s > self.config.stale_timeout_s:
            level = STALE
            message = f'stale: {self.last_stale_reason}' if est is None or \
                self.counts['stale_skips'] else 'stale: no shaft speed'
        else:
            level = mon.level
            message = _level_message(level, mon)
        if est is not None and est.table_flags & ~NOT_FINITE:
            message += f'; outside the table: {describe_flags(est.table_flags)}'
        nan = math.nan
        values = [
            ('level', level),
            ('level_name', LEVEL_NAMES[level]),
            ('seconds_since_estimate_s', age_s),
            ('speed_rad_s', est.speed_rad_s if est else nan),
            ('pressure_diff_pa', est.pressure_diff_pa if est else nan),
            ('viscosity_m2_s', est.viscosity_m2_s if est else nan),
            ('expected_torque_nm', est.expected_nm if est else nan),
            ('theoretical_torque_nm', est.theoretical_nm if est else nan),
            ('friction_torque_nm', est.friction_nm if est else nan),
        ]
        for name, value in zip(COMPONENTS, est.components_nm if est else (nan,) * 4,
                               strict=True):
            values.append((f'{name}_torque_nm', value))
        values += [
            ('inertia_torque_nm', est.inertia_nm if est else nan),
            ('efficiency', est.efficiency if est else nan),
            ('measured_torque_nm', est.measured_nm if est else nan),
            ('residual_nm', est.residual_nm if est else nan),
            ('residual_ewma_nm', mon.ewma_nm),
            ('residual_std_nm', mon.residual_std_nm),
            ('cusum_pos_nm_s', mon.cusum_pos_nm_s),
            ('cusum_neg_nm_s', mon.cusum_neg_nm_s),
            ('cusum_warn_nm_s', self.config.cusum_warn_nm_s),
            ('cusum_error_nm_s', self.config.cusum_error_nm_s),
            ('valve_plate_friction_scale', mon.theta_vp),
            ('valve_plate_friction_scale_std', mon.valve_plate_scale_std),
            ('other_friction_scale', mon.theta_rest),
            ('other_friction_scale_std', mon.rest_scale_std),
        ]
        values += [(name, self.counts[name]) for name in COUNTERS]
        return DiagnosticSnapshot(level, message, [(k, _format(v)) for k, v in values])


def _level_message(level: int, mon: WearMonitor) -> str:
    if level == OK:
        return 'friction as modelled'
    side = 'above' if mon.cusum_pos_nm_s >= mon.cusum_neg_nm_s else 'below'
    cause = ''
    if side == 'above':
        more_vp = mon.theta_vp - 1.0 > 2.0 * mon.valve_plate_scale_std and \
            mon.theta_vp - 1.0 > mon.theta_rest - 1.0
        cause = (f': valve plate (scale {mon.theta_vp:.2f})' if more_vp
                 else f': not the valve plate (scale {mon.theta_vp:.2f}, others '
                 f'{mon.theta_rest:.2f})')
    return f'{LEVEL_NAMES[level]}: friction {side} model{cause}'


def _format(value: float | int | str) -> str:
    """Plain numbers, parseable by plotting tools (``nan`` / ``inf`` spelled so)."""
    if isinstance(value, str):
        return value
    if isinstance(value, int):
        return str(value)
    return repr(float(value)) if math.isfinite(value) else ('nan' if math.isnan(value)
                                                             else ('inf' if value > 0
                                                                   else '-inf'))


def estimator_from_config(config: EstimatorConfig) -> TorqueEstimator:
    """Build the estimator a config describes: pump file, table (given or cached), tuning.

    Parameters
    ----------
    config : EstimatorConfig
        Validated parameters.

    Returns
    -------
    TorqueEstimator
        Ready to take samples.

    Raises
    ------
    ConfigError
        Invalid pump file.
    TableError
        Unreadable table, or a table built for another pump or model version.
    """
    params = load_pump(config.pump_file or None)
    table = load_table(config.table_file, params) if config.table_file else cached_table(params)
    return TorqueEstimator(config, table, params.oil.viscosity_m2_s, params.name)
