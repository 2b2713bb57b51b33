"""Valve-plate wear monitor: EWMA, two-sided CUSUM with hysteresis, and RLS attribution.

Everything runs on the *friction-direction residual*: measured minus expected torque times
the sign of the speed, so that "more friction than modelled" is positive in both directions
of rotation.

* EWMA of the residual (time constant ``ewma_time_constant_s``), and of its square for a
  running standard deviation.
* Two-sided CUSUM weighted by time, so its thresholds do not depend on the sample rate:
  S+ = max(0, S+ + (r - k) dt) and S- = max(0, S- + (-r - k) dt), in N m s. WARN when
  max(S+, S-) reaches ``cusum_warn_nm_s``, ERROR at ``cusum_error_nm_s``; a level clears
  only when the sum falls below ``cusum_clear_ratio`` times its threshold (hysteresis).
  The sums are capped at ``CUSUM_CAP_RATIO`` times the ERROR threshold.
* Attribution: recursive least squares with exponential forgetting (time constant
  ``rls_forgetting_time_s``) of y = theta_vp T_vp + theta_rest T_rest, where y is the
  friction part of the measured torque (measured - theoretical - inertia - drive loss, in the
  friction direction) and T_vp, T_rest the modelled valve-plate and other friction
  magnitudes. theta = (1, 1) is the pump as modelled; a rising theta_vp with theta_rest ~ 1
  says the valve plate. The regression is weighted by the running residual variance, so P is
  the covariance of theta: the reported std is sqrt(P_vp,vp). It assumes white residuals;
  real residuals are correlated over a move, so read it as a lower bound (on the sample duty
  cycle the estimate wanders by ~10x the reported std). P is capped at the prior so that it
  cannot wind up while the pump idles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ['ERROR', 'LEVEL_NAMES', 'OK', 'STALE', 'WARN', 'MonitorConfig', 'WearMonitor']

OK, WARN, ERROR, STALE = 0, 1, 2, 3
CUSUM_CAP_RATIO = 1.2
"""The sums are capped at this times the ERROR threshold, so that after a repair the level
clears in a bounded time (about (1.2 - clear ratio x warn / error) x error / k seconds of
monitored running); the node's ~/reset_monitor service clears it at once."""
LEVEL_NAMES = {OK: 'OK', WARN: 'WARN', ERROR: 'ERROR', STALE: 'STALE'}


@dataclass(frozen=True)
class MonitorConfig:
    """Monitor tuning (see the module docstring); SI units. Defaults live in ``config``."""

    ewma_time_constant_s: float
    cusum_drift_nm: float
    cusum_warn_nm_s: float
    cusum_error_nm_s: float
    cusum_clear_ratio: float
    rls_forgetting_time_s: float
    rls_initial_std: float


class WearMonitor:
    """Stateful wear monitor; feed it one friction-direction sample at a time.

    Parameters
    ----------
    config : MonitorConfig
        Tuning.
    """

    def __init__(self, config: MonitorConfig) -> None:
        self.config = config
        self._tau = config.ewma_time_constant_s
        self._k = config.cusum_drift_nm
        self._h_warn = config.cusum_warn_nm_s
        self._h_error = config.cusum_error_nm_s
        self._clear = config.cusum_clear_ratio
        self._cap = CUSUM_CAP_RATIO * config.cusum_error_nm_s
        self._t_forget = config.rls_forgetting_time_s
        self._p_max = config.rls_initial_std**2
        self._dt = self._a = self._lam = math.nan
        self.reset()

    def reset(self) -> None:
        """Forget everything: the pump as modelled, no alarm."""
        self.samples = 0
        self.ewma_nm = 0.0
        self._var = 0.0
        self.cusum_pos_nm_s = 0.0
        self.cusum_neg_nm_s = 0.0
        self.level = OK
        self.theta_vp = 1.0
        self.theta_rest = 1.0
        p0 = self._p_max
        self._p00, self._p01, self._p11 = p0, 0.0, p0
        self._noise_var = max(self._k, 1e-3) ** 2

    @property
    def residual_std_nm(self) -> float:
        """Running standard deviation of the residual [N m]."""
        return math.sqrt(self._var)

    @property
    def valve_plate_scale_std(self) -> float:
        """Standard deviation of the valve-plate friction scale estimate [-]."""
        return math.sqrt(self._p00)

    @property
    def rest_scale_std(self) -> float:
        """Standard deviation of the other components' friction scale estimate [-]."""
        return math.sqrt(self._p11)

    def update(self, dt_s: float, residual_nm: float, friction_nm: float,
               valve_plate_nm: float, rest_nm: float) -> int:
        """Take one sample.

        Parameters
        ----------
        dt_s : float
            Time since the previous sample the monitor took [s].
        residual_nm : float
            Friction-direction residual, measured - expected [N m].
        friction_nm : float
            Friction part of the measured torque, friction direction [N m].
        valve_plate_nm : float
            Modelled valve-plate friction magnitude [N m].
        rest_nm : float
            Modelled friction magnitude of the other components [N m].

        Returns
        -------
        int
            The level after this sample (OK, WARN or ERROR).
        """
        self.samples += 1
        r = residual_nm
        if dt_s != self._dt:  # samples usually come evenly spaced: compute the factors once
            self._dt = dt_s
            self._a = 1.0 - math.exp(-dt_s / self._tau)
            self._lam = math.exp(-dt_s / self._t_forget)
        a, lam = self._a, self._lam
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
        self.level = self._level(max(self.cusum_pos_nm_s, self.cusum_neg_nm_s))
        # weighted RLS with forgetting on (theta_vp, theta_rest)
        f1, f2 = valve_plate_nm, rest_nm
        p00, p01, p11 = self._p00, self._p01, self._p11
        pf1 = p00 * f1 + p01 * f2
        pf2 = p01 * f1 + p11 * f2
        err = friction_nm - (self.theta_vp * f1 + self.theta_rest * f2)
        self._noise_var += a * (err * err - self._noise_var)
        den = lam * self._noise_var + f1 * pf1 + f2 * pf2
        if den > 0.0:
            k1, k2 = pf1 / den, pf2 / den
            self.theta_vp += k1 * err
            self.theta_rest += k2 * err
            p00 = (p00 - k1 * pf1) / lam
            p01 = (p01 - k1 * pf2) / lam
            p11 = (p11 - k2 * pf2) / lam
            largest = p00 if p00 > p11 else p11
            if largest > self._p_max:  # no wind-up without excitation
                scale = self._p_max / largest
                p00, p01, p11 = p00 * scale, p01 * scale, p11 * scale
            self._p00, self._p01, self._p11 = p00, p01, p11
        return self.level

    def _level(self, s: float) -> int:
        if s >= self._h_error or (self.level == ERROR and s > self._clear * self._h_error):
            return ERROR
        if s >= self._h_warn or (self.level >= WARN and s > self._clear * self._h_warn):
            return WARN
        return OK
