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

"""The /diagnostics status of the estimator: level, message and key-values (units in keys)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
import math

from .baseline import BASELINE_TERMS
from .estimate_record import COUNTERS, Estimate
from .monitor import LEVEL_NAMES, OK, STALE, WearMonitor
from ..physics.model import COMPONENTS
from ..physics.units import m2_s_to_cst
from ..table.friction_table import describe_flags, NOT_FINITE, VISCOSITY_CLAMPED

__all__ = ['DiagnosticSnapshot', 'format_value', 'level_message',
           'snapshot']

_REJECTIONS = tuple(name for name in COUNTERS if name.startswith('rejected_'))
"""Counters of samples refused (each makes no estimate), as /diagnostics names them."""

_RELATIVE = ('valve_plate', 'other_friction', 'torque_gain')
"""Baseline terms that are relative changes, reported as factors (1: as modelled)."""


@dataclass(frozen=True)
class DiagnosticSnapshot:
    """What /diagnostics reports: level, message and key-values with units in the keys."""

    level: int
    message: str
    values: list[tuple[str, str]] = field(default_factory=list)


def snapshot(last: Estimate | None, monitor: WearMonitor, counts: dict[str, int],
             stale_timeout_s: float, stale_reason: str, now_ns: int,
             table_viscosity_m2_s: tuple[float, float] | None = None,
             extra: Sequence[tuple[str, float | int | str]] = (), note: str = '',
             at_last_status: tuple[int, Mapping[str, int]] | None = None,
             max_stamp_lead_s: float = math.inf, clock_stopped: str = ''
             ) -> DiagnosticSnapshot:
    """
    Status at time ``now_ns``.

    Parameters
    ----------
    last : Estimate or None
        The latest estimate.
    monitor : WearMonitor
        The wear monitor.
    counts : dict
        The estimator's counters (`COUNTERS`).
    stale_timeout_s : float
        The ``stale_timeout_s`` parameter [s] (the CUSUM thresholds are the monitor's).
    stale_reason : str
        Why the latest speed sample skipped made no estimate; '' when an estimate came after
        it (inputs that stop then are 'no shaft speed', not a skip of long ago).
    now_ns : int
        Current time of the node's clock (or of the replay) [ns].
    table_viscosity_m2_s : tuple of float, optional
        Ends of the table's viscosity axis [m^2/s]: while the latest estimate's oil is
        outside them, the message says so with the viscosity and the range (once, in the
        status, for as long as it lasts; each sample is counted in ``clamped_to_table``).
    extra : sequence of (str, value)
        More key-values, after the counters (the baseline file's, `BaselineStore.diagnostics`).
    note : str
        Appended to the message after ``; `` when not empty (e.g. the baseline file not used).
    at_last_status : tuple of (int, mapping of str to int), optional
        The time [ns] and the counters of the previous status (None: there was none). While
        STALE, the message says why from what grew since: the stale skips' reason if they
        grew, the rejections that grew (non-finite, out-of-order samples...), so a reason of
        long ago is not repeated while the samples are now rejected for another; or, when
        estimates were made since but stamped older than the previous status by more than
        ``stale_timeout_s``, that their stamps are of another clock.
    max_stamp_lead_s : float
        The ``max_stamp_lead_s`` parameter [s]: an input stamped further ahead of its receipt
        is rejected, so a latest estimate stamped further ahead of ``now_ns`` means the
        clock went back (a simulation or a bag restarted): STALE, not its old level.
    clock_stopped : str
        Why the node's clock does not advance (simulated time without /clock, or paused);
        '' when it does. STALE with it, whatever the latest estimate.

    Returns
    -------
    DiagnosticSnapshot
        Level (STALE when no estimate for ``stale_timeout_s``, or the latest stamped more
        than ``max_stamp_lead_s`` after ``now_ns``: the clock went back), message,
        key-values.

    """
    est = last
    mon = monitor
    age_s = math.inf if est is None else (now_ns - est.stamp_ns) * 1e-9
    if clock_stopped:
        level = STALE
        message = f'stale: {clock_stopped}'
    elif est is not None and now_ns != 0 and age_s < -max_stamp_lead_s:  # (0: no clock yet)
        level = STALE
        message = (f'stale: the latest estimate is stamped {-age_s:.4g} s after this clock: '
                   'the clock went back (a simulation or a bag restarted), or the stamps of '
                   'the inputs are of another clock')
    elif est is None or age_s > stale_timeout_s:
        level = STALE
        message = 'stale: ' + _stale_why(est, counts, at_last_status, stale_reason, age_s,
                                         round(stale_timeout_s * 1e9))
    else:
        level = mon.level
        message = level_message(level, mon)
    # the table flags are the latest estimate's: not said of an estimate gone stale
    flags = 0 if est is None or level == STALE else est.table_flags & ~NOT_FINITE
    if est is not None and flags & VISCOSITY_CLAMPED and table_viscosity_m2_s is not None:
        low, high = (m2_s_to_cst(v) for v in table_viscosity_m2_s)
        message += (f'; oil viscosity {m2_s_to_cst(est.viscosity_m2_s):.4g} cSt outside the '
                    f'table ({low:.4g}-{high:.4g} cSt): torque taken at the edge')
        flags &= ~VISCOSITY_CLAMPED
    if flags:
        message += f'; outside the table: {describe_flags(flags)}'
    if note:
        message += f'; {note}'
    nan = math.nan
    values: list[tuple[str, float | int | str]] = [
        ('level', level),
        ('level_name', LEVEL_NAMES[level]),
        ('seconds_since_estimate_s', age_s),
        ('speed_rad_s', est.speed_rad_s if est else nan),
        ('pressure_diff_pa', est.pressure_diff_pa if est else nan),
        ('viscosity_m2_s', est.viscosity_m2_s if est else nan),
        # the temperature topic's, through the oil's law (NaN: the viscosity is assumed)
        ('oil_temperature_c', mon.oil_temperature_c(est.viscosity_m2_s) if est else nan),
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
        ('cusum_warn_nm_s', mon.settings.cusum_warn_nm_s),
        ('cusum_error_nm_s', mon.settings.cusum_error_nm_s),
    ]
    values += [
        ('valve_plate_scale', mon.theta_vp),
        ('valve_plate_scale_std', mon.valve_plate_scale_std),
        ('other_friction_scale', mon.theta_rest),
        ('other_friction_scale_std', mon.rest_scale_std),
        # a change up to this scale goes unseen on this duty cycle (1: not yet learnt)
        ('valve_plate_undetectable_scale', 1.0 + mon.undetectable_change['valve_plate']),
        ('other_friction_undetectable_scale', 1.0 + mon.undetectable_change['other_friction']),
        ('baseline_learnt_s', mon.learner.learnt_s),
        ('baseline_learn_s', mon.settings.baseline_learn_s),
        ('baseline_complete', int(not mon.learning)),
        ('detection_held', int(bool(mon.held))),  # waiting for the oil to settle
    ]
    fit = mon.baseline if mon.baseline is not None else mon.fit
    for name, value, std in zip(BASELINE_TERMS, fit.coefficients, fit.std(), strict=True):
        relative = name in _RELATIVE  # a relative change, shown as a factor
        key = f'baseline_{name}_scale' if relative else f'baseline_{name}'
        values += [(key, float(value) + (1.0 if relative else 0.0)), (f'{key}_std', float(std))]
    values.append(('baseline_window_std_nm', math.sqrt(fit.window_var_nm2)))
    # the oil it was learnt on: the farther the oil runs from it, the more the healthy level
    # now is the model's extrapolation (docs/monitor.md)
    values.append(('baseline_oil_temperature_c', mon.baseline_temperature_c))
    # the torque reads this times the oil's warming since commissioning high: learnt drift
    values.append(('baseline_torque_drift_per_k', mon.measurement_drift_per_k))
    values.append(('alarm_onset_s', mon.alarm_onset_s))
    values.append(('change_start_s', mon.change_start_s))  # the scales' change began
    alarm = mon.last_alarm  # kept after it clears (``last_alarm``)
    values += [('last_alarm_onset_s', alarm.onset_s), ('last_alarm_cleared_s', alarm.cleared_s),
               ('last_alarm_level', alarm.level),  # its verdict: in the message at OK
               ('last_alarm_valve_plate_scale', alarm.valve_plate_scale),
               ('last_alarm_valve_plate_scale_std', alarm.valve_plate_scale_std)]
    values += [(name, counts[name]) for name in COUNTERS]
    values += extra
    return DiagnosticSnapshot(level, message, [(k, format_value(v)) for k, v in values])


def _stale_why(last: Estimate | None, counts: Mapping[str, int],
               at_last_status: tuple[int, Mapping[str, int]] | None, stale_reason: str,
               age_s: float, timeout_ns: int) -> str:
    """Say why no estimate came lately: what the samples since the last status met."""
    before = at_last_status[1] if at_last_status is not None else {}
    grown = {name: counts[name] - before.get(name, 0) for name in COUNTERS}
    if grown['estimates'] and last is not None and at_last_status is not None and \
            last.stamp_ns + timeout_ns < at_last_status[0]:
        # made since the last status, yet stamped stale already then: not a dropout
        return (f'the latest estimate is stamped {age_s:.4g} s before this clock: the header '
                'stamps of the inputs are of another clock')
    parts = [stale_reason] if grown['stale_skips'] and stale_reason else []
    rejected = [f'{name} {grown[name]}' for name in _REJECTIONS if grown[name]]
    if rejected:
        parts.append(f'samples rejected since the last status ({", ".join(rejected)})')
    if parts:
        return '; '.join(parts)
    # nothing came since the last status: as of the last skip if it came after the latest
    # estimate, else the speed stopped (nothing triggers a skip)
    return stale_reason or 'no shaft speed'


def level_message(level: int, mon: WearMonitor) -> str:
    """
    Return the status message for a level: what is above or below the model, and why.

    Parameters
    ----------
    level : int
        OK, WARN or ERROR.
    mon : WearMonitor
        The monitor (its sums and the attribution's verdict).

    Returns
    -------
    str
        The message.

    """
    if level == OK:
        if mon.learning:
            return mon.baseline_status()
        if mon.held:  # after a start or a pause without temperature topic
            return mon.held
        note = mon.last_alarm.note()
        return 'torque as the healthy baseline' + (f'; {note}' if note else '')
    verdict, words = mon.verdict(1.0)
    side = 'differs from' if verdict == 'not_friction' else (
        'above' if mon.cusum_pos_nm_s >= mon.cusum_neg_nm_s else 'below')
    return f'{LEVEL_NAMES[level]}: torque {side} the healthy baseline: {words}'


def format_value(value: float | int | str) -> str:
    """
    Return a key-value's value as plain text that plotting tools parse as a number.

    Parameters
    ----------
    value : float, int or str
        The value.

    Returns
    -------
    str
        ``repr`` of a finite float, ``nan`` / ``inf`` / ``-inf`` spelled so.

    """
    if isinstance(value, str):
        return value
    if isinstance(value, int):
        return str(value)
    if math.isfinite(value):
        return repr(float(value))
    return 'nan' if math.isnan(value) else ('inf' if value > 0 else '-inf')
