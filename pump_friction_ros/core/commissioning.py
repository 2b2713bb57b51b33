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
Commissioning: learn the healthy baseline until the pump agrees with itself.

The baseline (``baseline``) is the fit of ``baseline_learn_s`` of monitored running; it is
complete only once the fits of two halves of it agree, so that a pump still settling (the
oil warming up without a temperature input, running in) is not taken as healthy. The check
and its extrapolation are `Commissioning`'s; docs/monitor.md gives the figures.

A settling pump's friction moves one way; an oil temperature that swings, with the
viscosity a parameter, moves it up and down, and commissioning then restarts for as long
as it swings (the bank's steps without temperature topic, seed 4, installation 1: +-2.5 K
every 25 min, never complete in 30 min with a fault; where the halves straddle a crest they
agree, and the baseline completes at the top of the swing). Each failed check whose change
of the mean prediction went against the one before is counted, and the status says so
with the remedy, the temperature topic.
"""

from __future__ import annotations

import math

import numpy as np

from .baseline import BaselineLearner, read_count

__all__ = ['DRIFT_NOISE_SIGMAS', 'Commissioning']

DRIFT_NOISE_SIGMAS = 1.0
"""The drift between the commissioning's halves is taken less this many standard deviations
of its noise (the fits' own uncertainty) before it is extrapolated. Measured on simulated
commissionings (test_baseline_monitor, the shipped tolerance 0.0125 N m, 10 % of the time
monitored): at 1, no steady pump of 20 restarts and a pump settling with a time constant up
to ``baseline_settle_time_constant_s`` completes with at most 0.029 N m still to come. At
a tolerance of 0.025: at 2, 0.057 N m were left; at 0.5, steady pumps restarted up to 7
times."""


class Commissioning:
    """
    Learn the baseline until ``learn_s`` of monitored running agree with themselves.

    The windows fill two halves of ``learn_s / 2`` each. When both are full, the fits of
    each half are compared over the operating points of the second: the RMS difference of
    their predictions, less `DRIFT_NOISE_SIGMAS` of its standard deviation from the fits'
    own uncertainty, is the drift the pump made between the halves' mean times, Delta apart.
    Where it exceeds ``tolerance_nm`` the first half is dropped and learning goes on with
    the second; otherwise the baseline is the fit of both. Once a check has failed, the pump
    has been seen changing (oil warming up without a temperature input, running in), and
    such a change settles like exp(-t / tau): from then on a drift D over Delta counts as
    the D / (1 - exp(-Delta / tau)) still to come. (Without this extrapolation a warm-up
    whose drift per half had just fallen below the tolerance went on drifting by several
    times it after commissioning, and raised alarms: the bank's cold start without
    temperature topic, docs/monitor.md. Thirty seconds of steady running cannot show that
    nothing moves over minutes, so the first check takes the drift as it is.)

    Parameters
    ----------
    prior_std : tuple of float
        Prior standard deviation of each coefficient (`BASELINE_TERMS` order).
    learn_s : float
        Monitored running to learn from [s].
    tolerance_nm : float
        Largest drift still to come of a pump taken as stationary [N m].
    settle_time_constant_s : float
        tau: the slowest settling commissioning waits for once it has seen the pump change
        [s] (0: the drift between the halves alone).

    """

    def __init__(self, prior_std: tuple[float, ...], learn_s: float,
                 tolerance_nm: float, settle_time_constant_s: float = 0.0) -> None:
        self.learn_s = learn_s
        self.tolerance_nm = tolerance_nm
        self.settle_time_constant_s = settle_time_constant_s
        self.learner = BaselineLearner(prior_std)
        self.older = BaselineLearner(prior_std)
        self.recent = BaselineLearner(prior_std)
        self.reset()

    def reset(self) -> None:
        """Forget every window: learn afresh."""
        for learner in (self.learner, self.older, self.recent):
            learner.reset()
        self.restarts = 0
        """Times the older half was dropped: the pump was still changing."""
        self.drift_nm = math.nan
        """Drift still to come at the last check (beyond the fits' noise) [N m]."""
        self.direction = 0.0
        """Sign of the last failed check's change of the mean prediction (0: none yet)."""
        self.reversals = 0
        """Failed checks whose change went the other way from the one before: a pump
        that settles moves one way; one that swings (an oil temperature that comes and
        goes with the viscosity a parameter) turns."""
        self.fit = self.learner.fit()

    def remaining_drift_nm(self) -> float:
        """
        Return the drift still to come from the two full halves' fits [N m].

        Counted from the older half's mean time (conservative by the drift between the
        halves). Before the first restart tau is not applied: the drift as it is.

        Returns
        -------
        float
            (RMS prediction difference - `DRIFT_NOISE_SIGMAS` std) / (1 - exp(-Delta / tau)),
            >= 0.

        """
        old, new = self.older.fit(), self.recent.fit()
        change = old.coefficients - new.coefficients
        moments = self.recent.a / max(self.recent.weight, 1e-300)
        drift = math.sqrt(max(float(change @ moments @ change), 0.0))
        noise = math.sqrt(max(float(np.sum(moments * (old.covariance + new.covariance))),
                              0.0))
        excess = max(drift - DRIFT_NOISE_SIGMAS * noise, 0.0)
        tau = self.settle_time_constant_s if self.restarts else 0.0  # seen changing
        if not excess > 0.0 or not tau > 0.0:
            return excess
        # wall time between the halves: at least their monitored running (a clock that
        # stepped back must not make it zero)
        apart = self.recent.mean_time_s - self.older.mean_time_s
        apart = max(apart, 0.5 * self.learn_s) if math.isfinite(apart) else 0.5 * self.learn_s
        return excess / -math.expm1(-apart / tau)

    def add(self, h: np.ndarray, e_nm: float, weight: float, duration_s: float,
            t_s: float = 0.0, temperature_c: float = math.nan) -> bool:
        """
        Add a window; return whether the baseline is now complete (`fit` is it).

        Parameters
        ----------
        h : ndarray
            The window's regressors.
        e_nm : float
            Its mean residual [N m].
        weight : float
            Its length over the nominal window length [-].
        duration_s : float
            Its monitored running [s].
        t_s : float
            Its time [s].
        temperature_c : float
            Its oil temperature [degC] (NaN: not known).

        Returns
        -------
        bool
            True once ``learn_s`` of stationary running are learnt.

        """
        half = 0.5 * self.learn_s
        self.recent.add(h, e_nm, weight, duration_s, t_s, temperature_c)
        self.learner.add(h, e_nm, weight, duration_s, t_s, temperature_c)
        self.fit = self.learner.fit()
        if self.recent.learnt_s < half:
            return False
        if self.learner.learnt_s - self.recent.learnt_s < half:
            self.older.load(self.recent.state())  # the first half is full
            self.recent.reset()
            return False
        self.drift_nm = self.remaining_drift_nm()
        if self.drift_nm <= self.tolerance_nm:
            return True
        self._turned()
        self.learner.load(self.recent.state())  # still changing: keep the second half
        self.older.load(self.recent.state())
        self.recent.reset()
        self.restarts += 1
        self.fit = self.learner.fit()
        return False

    def _turned(self) -> None:
        """Count a failed check whose mean prediction moved against the one before."""
        old, new = self.older.fit(), self.recent.fit()
        mean_h = self.recent.a[:, 2] / max(self.recent.weight, 1e-300)  # (h[2] is 1)
        change = float((new.coefficients - old.coefficients) @ mean_h)
        direction = math.copysign(1.0, change) if change else 0.0
        if direction and self.direction and direction != self.direction:
            self.reversals += 1
        self.direction = direction or self.direction

    def status(self) -> str:
        """Return the learning's progress in words."""
        turned = f'; it rose and fell: turned {self.reversals} times, as an oil ' \
            'temperature swinging with the viscosity a parameter does (give the node the ' \
            'temperature topic)' if self.reversals else ''
        still = f' (still changing: restarted {self.restarts} times, drift still to come ' \
            f'{self.drift_nm:.3f} N m{turned})' if self.restarts else ''
        return (f'learning the healthy baseline: {self.learner.learnt_s:.0f} of '
                f'{self.learn_s:.0f} s of monitored running{still}')

    def state(self) -> dict[str, object]:
        """Return the sums as plain values."""
        return {'learner': self.learner.state(), 'older': self.older.state(),
                'recent': self.recent.state(), 'restarts': self.restarts,
                'drift_nm': float(self.drift_nm), 'direction': float(self.direction),
                'reversals': self.reversals}

    def load(self, state: dict[str, object]) -> None:
        """
        Restore `state`'s sums.

        Parameters
        ----------
        state : dict
            A `state` result.

        Raises
        ------
        ValueError
            Missing or malformed sums.

        """
        for name in ('learner', 'older', 'recent'):
            getattr(self, name).load(state[name])
        self.restarts = read_count(state, 'restarts', 'commissioning')
        self.drift_nm = float(state['drift_nm'])  # type: ignore[arg-type]
        # (came later: a state without them has seen no turn)
        self.direction = float(state.get('direction', 0.0))  # type: ignore[arg-type]
        self.reversals = read_count({'reversals': 0, **state}, 'reversals', 'commissioning')
        self.fit = self.learner.fit()
