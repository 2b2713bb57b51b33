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
Valve-plate wear monitor: EWMA, two-sided CUSUM with hysteresis, and attribution.

Detection runs on the *friction-direction residual*: measured minus expected torque times
the sign of the speed, so that "more friction than modelled" is positive in both directions
of rotation.

* EWMA of the residual (time constant ``ewma_time_constant_s``), and of its square for a
  running standard deviation.
* Two-sided CUSUM weighted by time, so its thresholds do not depend on the sample rate:
  S+ = max(0, S+ + (r - k) dt) and S- = max(0, S- + (-r - k) dt), in N m s. WARN when
  max(S+, S-) reaches ``cusum_warn_nm_s``, ERROR at ``cusum_error_nm_s``; a level clears
  only when the sum falls below ``cusum_clear_ratio`` times its threshold (hysteresis).
  The sums are capped at ``CUSUM_CAP_RATIO`` times the ERROR threshold.
* Attribution (``attribution.FrictionAttribution``): which term explains the residual
  (valve plate, other friction, or a term that does not scale with friction), with honest
  uncertainties and an identifiability check.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import NamedTuple

from .attribution import AttributionSettings, FrictionAttribution

__all__ = ['ERROR', 'LEVEL_NAMES', 'OK', 'STALE', 'WARN', 'MonitorSettings', 'MonitorTrace',
           'WearMonitor']

OK, WARN, ERROR, STALE = 0, 1, 2, 3
CUSUM_CAP_RATIO = 1.2
"""The sums are capped at this times the ERROR threshold, so that after a repair the level
clears in a bounded time (about (1.2 - clear ratio x warn / error) x error / k seconds of
monitored running); the node's ~/reset_monitor service clears it at once."""
LEVEL_NAMES = {OK: 'OK', WARN: 'WARN', ERROR: 'ERROR', STALE: 'STALE'}


class MonitorTrace(NamedTuple):
    """The monitor's state after each of many samples (`WearMonitor.update_many`)."""

    level: list[int]
    cusum_pos_nm_s: list[float]
    cusum_neg_nm_s: list[float]
    valve_plate_scale: list[float]  # `WearMonitor.theta_vp`
    other_scale: list[float]  # `WearMonitor.theta_rest`
    valve_plate_scale_std: list[float]
    other_scale_std: list[float]


@dataclass(frozen=True)
class MonitorSettings:
    """The node parameters of the detection (declared in ``node_parameters``)."""

    ewma_time_constant_s: float
    cusum_drift_nm: float
    cusum_warn_nm_s: float
    cusum_error_nm_s: float
    cusum_clear_ratio: float


class WearMonitor:
    """
    Stateful wear monitor; feed it one friction-direction sample at a time.

    Parameters
    ----------
    config : MonitorSettings
        Tuning of the detection: the ``ewma_*`` and ``cusum_*`` parameters.
    attribution : AttributionSettings
        Tuning of the attribution.

    """

    def __init__(self, config: MonitorSettings, attribution: AttributionSettings) -> None:
        self.settings = config
        self._tau = config.ewma_time_constant_s
        self._k = config.cusum_drift_nm
        self._h_warn = config.cusum_warn_nm_s
        self._h_error = config.cusum_error_nm_s
        self._clear = config.cusum_clear_ratio
        self._cap = CUSUM_CAP_RATIO * config.cusum_error_nm_s
        self._dt = self._a = math.nan
        self.attribution = FrictionAttribution(attribution)
        self.reset()

    def reset(self) -> None:
        """Forget everything: the pump as modelled, no alarm."""
        self.samples = 0
        self.ewma_nm = 0.0
        self._var = 0.0
        self.cusum_pos_nm_s = 0.0
        self.cusum_neg_nm_s = 0.0
        self.level = OK
        self.alarm_onset_s = math.nan
        self.attribution.reset()

    @property
    def residual_std_nm(self) -> float:
        """Return the running standard deviation of the residual [N m]."""
        return math.sqrt(self._var)

    @property
    def theta_vp(self) -> float:
        """Valve-plate friction scale estimate [-] (1: as modelled)."""
        return self.attribution.values[0]

    @property
    def theta_rest(self) -> float:
        """Friction scale estimate of the other components [-]."""
        return self.attribution.values[1]

    @property
    def valve_plate_scale_std(self) -> float:
        """Return the standard deviation of the valve-plate friction scale estimate [-]."""
        return self.attribution.stds[0]

    @property
    def rest_scale_std(self) -> float:
        """Return the standard deviation of the other components' friction scale estimate [-]."""
        return self.attribution.stds[1]

    def update(self, t_s: float, dt_s: float, residual_nm: float, friction_nm: float,
               valve_plate_nm: float, bearing_nm: float, pistons_nm: float,
               theoretical_nm: float, sign: float) -> int:
        """
        Take one sample.

        Parameters
        ----------
        t_s : float
            Sample time [s].
        dt_s : float
            Time since the previous sample the monitor took [s] (0 after a gap).
        residual_nm : float
            Measured - expected torque [N m] (not yet in the friction direction).
        friction_nm : float
            Friction part of the measured torque, friction direction [N m].
        valve_plate_nm : float
            Modelled valve-plate friction magnitude [N m].
        bearing_nm : float
            Modelled shaft-bearing friction magnitude [N m].
        pistons_nm : float
            Modelled friction magnitude of the spherical joints and piston heads [N m].
        theoretical_nm : float
            Theoretical torque from the measured pressure [N m].
        sign : float
            Direction of rotation, +1 or -1.

        Returns
        -------
        int
            The level after this sample (OK, WARN or ERROR).

        """
        self.samples += 1
        r = residual_nm * sign
        if dt_s != self._dt:  # samples usually come evenly spaced: compute the factor once
            self._dt = dt_s
            self._a = 1.0 - math.exp(-dt_s / self._tau)
        a = self._a
        # EWMA of the residual and of its variance
        dev = r - self.ewma_nm
        self.ewma_nm += a * dev
        self._var += a * (dev * dev - self._var)
        # time-weighted two-sided CUSUM
        k = self._k
        pos = self.cusum_pos_nm_s + (r - k) * dt_s
        neg = self.cusum_neg_nm_s + (-r - k) * dt_s
        cap = self._cap
        self.cusum_pos_nm_s = 0.0 if pos < 0.0 else (cap if pos > cap else pos)
        self.cusum_neg_nm_s = 0.0 if neg < 0.0 else (cap if neg > cap else neg)
        level = self._level(max(self.cusum_pos_nm_s, self.cusum_neg_nm_s))
        if level != self.level:
            if self.level == OK:
                self.alarm_onset_s = t_s
            elif level == OK:
                self.alarm_onset_s = math.nan
            self.level = level
        self.attribution.add(t_s, dt_s, residual_nm, friction_nm, valve_plate_nm, bearing_nm,
                             pistons_nm, theoretical_nm, sign)
        return level

    def update_many(self, t_s: list[float], dt_s: list[float], residual_nm: list[float],
                    friction_nm: list[float], valve_plate_nm: list[float],
                    bearing_nm: list[float], pistons_nm: list[float],
                    theoretical_nm: list[float], sign: list[float]) -> MonitorTrace:
        """
        Take many samples in order: `update` for each, in lean loops (the chunk path).

        The same operations in the same order as `update`; the EWMA, CUSUM and level do not
        depend on the attribution nor it on them, so each runs over all the samples in one
        loop. Results and state are identical to calling `update` sample by sample.

        Parameters
        ----------
        t_s, dt_s, residual_nm, friction_nm : list of float
            Per sample, as `update` takes them [s, s, N m, N m].
        valve_plate_nm, bearing_nm, pistons_nm, theoretical_nm : list of float
            Per sample, as `update` takes them [N m].
        sign : list of float
            Direction of rotation per sample, +1 or -1.

        Returns
        -------
        MonitorTrace
            The monitor's state after each sample.

        """
        tau, k, cap = self._tau, self._k, self._cap
        last_dt, a = self._dt, self._a
        ewma, var = self.ewma_nm, self._var
        pos_sum, neg_sum = self.cusum_pos_nm_s, self.cusum_neg_nm_s
        level, onset = self.level, self.alarm_onset_s
        h_warn, h_error = self._h_warn, self._h_error
        clear_warn, clear_error = self._clear * h_warn, self._clear * h_error
        levels: list[int] = []
        positive: list[float] = []
        negative: list[float] = []
        for t, dt, residual, sgn in zip(t_s, dt_s, residual_nm, sign, strict=True):
            r = residual * sgn
            if dt != last_dt:
                last_dt = dt
                a = 1.0 - math.exp(-dt / tau)
            dev = r - ewma
            ewma += a * dev
            var += a * (dev * dev - var)
            pos = pos_sum + (r - k) * dt
            neg = neg_sum + (-r - k) * dt
            pos_sum = 0.0 if pos < 0.0 else (cap if pos > cap else pos)
            neg_sum = 0.0 if neg < 0.0 else (cap if neg > cap else neg)
            s = max(pos_sum, neg_sum)  # `_level`, inline
            if s >= h_error or (level == ERROR and s > clear_error):
                new = ERROR
            elif s >= h_warn or (level >= WARN and s > clear_warn):
                new = WARN
            else:
                new = OK
            if new != level:
                if level == OK:
                    onset = t
                elif new == OK:
                    onset = math.nan
                level = new
            levels.append(level)
            positive.append(pos_sum)
            negative.append(neg_sum)
        self.samples += len(levels)
        self._dt, self._a = last_dt, a
        self.ewma_nm, self._var = ewma, var
        self.cusum_pos_nm_s, self.cusum_neg_nm_s = pos_sum, neg_sum
        self.level, self.alarm_onset_s = level, onset
        scales, stds = self.attribution.add_many(t_s, dt_s, residual_nm, friction_nm,
                                                 valve_plate_nm, bearing_nm, pistons_nm,
                                                 theoretical_nm, sign)
        return MonitorTrace(levels, positive, negative, *scales, *stds)

    STATE_VERSION = 1
    """Version of `state_dict`'s layout; `load_state_dict` refuses others."""

    def state_dict(self) -> dict[str, object]:
        """
        Return what the monitor has learnt, as plain JSON-able values (persisted by the node).

        Returns
        -------
        dict
            ``version`` and the learnt state; `load_state_dict` restores it exactly.

        """
        return {'version': self.STATE_VERSION, 'samples': self.samples,
                'cusum_pos_nm_s': self.cusum_pos_nm_s, 'cusum_neg_nm_s': self.cusum_neg_nm_s}

    def load_state_dict(self, state: dict[str, object]) -> None:
        """
        Restore what `state_dict` returned.

        Parameters
        ----------
        state : dict
            A `state_dict` result (e.g. read back from the node's baseline file).

        Raises
        ------
        ValueError
            A state of another version, or missing or malformed entries.

        """
        if state.get('version') != self.STATE_VERSION:
            raise ValueError(f'monitor state version {state.get("version")!r}, '
                             f'expected {self.STATE_VERSION}')
        try:
            self.samples = int(state['samples'])  # type: ignore[call-overload]
            self.cusum_pos_nm_s = float(state['cusum_pos_nm_s'])  # type: ignore[arg-type]
            self.cusum_neg_nm_s = float(state['cusum_neg_nm_s'])  # type: ignore[arg-type]
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f'malformed monitor state: {exc}') from None

    def _level(self, s: float) -> int:
        if s >= self._h_error or (self.level == ERROR and s > self._clear * self._h_error):
            return ERROR
        if s >= self._h_warn or (self.level >= WARN and s > self._clear * self._h_warn):
            return WARN
        return OK
