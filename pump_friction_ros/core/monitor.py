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

import math

from .attribution import FrictionAttribution
from .node_parameters import EstimatorConfig

__all__ = ['ERROR', 'LEVEL_NAMES', 'OK', 'STALE', 'WARN', 'WearMonitor']

OK, WARN, ERROR, STALE = 0, 1, 2, 3
CUSUM_CAP_RATIO = 1.2
"""The sums are capped at this times the ERROR threshold, so that after a repair the level
clears in a bounded time (about (1.2 - clear ratio x warn / error) x error / k seconds of
monitored running); the node's ~/reset_monitor service clears it at once."""
LEVEL_NAMES = {OK: 'OK', WARN: 'WARN', ERROR: 'ERROR', STALE: 'STALE'}


class WearMonitor:
    """
    Stateful wear monitor; feed it one friction-direction sample at a time.

    Parameters
    ----------
    config : EstimatorConfig
        Tuning: the ``ewma_*`` and ``cusum_*`` parameters, and the attribution's.

    """

    def __init__(self, config: EstimatorConfig) -> None:
        self.config = config
        self._tau = config.ewma_time_constant_s
        self._k = config.cusum_drift_nm
        self._h_warn = config.cusum_warn_nm_s
        self._h_error = config.cusum_error_nm_s
        self._clear = config.cusum_clear_ratio
        self._cap = CUSUM_CAP_RATIO * config.cusum_error_nm_s
        self._dt = self._a = math.nan
        self.attribution = FrictionAttribution(config)
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

    def _level(self, s: float) -> int:
        if s >= self._h_error or (self.level == ERROR and s > self._clear * self._h_error):
            return ERROR
        if s >= self._h_warn or (self.level >= WARN and s > self._clear * self._h_warn):
            return WARN
        return OK
