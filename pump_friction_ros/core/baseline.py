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
The installation's healthy signature, learnt from its own monitored running.

No real pump matches its model and no torque measurement is exact: a torque constant off by
3 % alone puts 0.2-0.45 N m between the measured and the modelled torque at 70-150 bar,
more than the wear monitor's allowance. Condition monitoring therefore compares the pump
with itself. During commissioning (the first ``baseline_learn_s`` of monitored running) the
window means of the monitored residual e (friction direction, ``settled_residual``) are
fitted by a Bayesian linear regression on

    e = b_vp T_vp + b_o T_o + L + c s + g T_th s + noise

with T_vp, T_o the modelled valve-plate and other friction magnitudes, L an extra drive
loss, c a torque offset (s the direction of rotation), g a gain error of the measured
torque against the theoretical one V_g dp / 2 pi (torque constant or pressure sensor). The
priors (``scale_prior_std``, ``offset_prior_std_nm``, ``torque_gain_prior_std``, zero
mean: the pump as modelled) keep terms the duty cycle cannot separate where the prior puts
them; the prediction e_hat = h b, which is all detection needs, is good wherever the
duty cycle has been. The window noise variance is the fit's own residual variance (the
window-to-window scatter, systematic model error included), each window weighted by its
length.

The fit's sufficient statistics are sums (``A = sum w h h^T``, ``sum w h e``, ``sum w e^2``):
they are what the node persists, so learning resumes after a restart where it stopped.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

__all__ = ['BASELINE_TERMS', 'Baseline', 'BaselineLearner', 'Commissioning',
           'baseline_regressors', 'read_sums']

BASELINE_TERMS = ('valve_plate', 'other_friction', 'drive_loss_nm', 'torque_offset_nm',
                  'torque_gain')
"""Coefficients of the healthy signature, in regressor order: relative friction changes
[-], torques [N m], a relative gain error [-]."""
N_TERMS = len(BASELINE_TERMS)


def baseline_regressors(vp_nm: float, other_nm: float, theoretical_s_nm: float,
                        sign: float) -> np.ndarray:
    """
    Return the regressors h of one window (`BASELINE_TERMS` order).

    Parameters
    ----------
    vp_nm, other_nm : float
        Window means of the modelled valve-plate and other friction magnitudes [N m].
    theoretical_s_nm : float
        Window mean of the theoretical torque times the direction of rotation [N m].
    sign : float
        Direction of rotation of the window, +1 or -1.

    Returns
    -------
    ndarray
        h, such that the window's residual is h . b [N m].

    """
    return np.array([vp_nm, other_nm, 1.0, sign, theoretical_s_nm])


@dataclass(frozen=True)
class Baseline:
    """
    A learnt healthy signature: coefficients, their covariance, and the window noise.

    Attributes
    ----------
    coefficients : ndarray
        b in `BASELINE_TERMS` order.
    covariance : ndarray
        Posterior covariance of b.
    window_var_nm2 : float
        Residual variance of a window of the nominal length about the fit [N m^2].
    learnt_s : float
        Monitored running the fit is made of [s].

    """

    coefficients: np.ndarray
    covariance: np.ndarray
    window_var_nm2: float
    learnt_s: float

    def predict(self, h: np.ndarray) -> float:
        """Return the healthy residual e_hat = h . b of a window with regressors ``h`` [N m]."""
        return float(h @ self.coefficients)

    def prediction_var(self, h: np.ndarray) -> float:
        """Return the variance of `predict` from the uncertainty of b [N m^2]."""
        return float(h @ self.covariance @ h)

    def std(self) -> np.ndarray:
        """Return the posterior standard deviations of b (`BASELINE_TERMS` order)."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))


def read_sums(state: dict[str, object], arrays: dict[str, tuple[int, ...]],
              scalars: tuple[str, ...], what: str
              ) -> tuple[list[np.ndarray], list[float]]:
    """
    Read persisted weighted sums back: arrays of known shape and non-negative scalars.

    Parameters
    ----------
    state : dict
        The saved sums (plain values).
    arrays : dict
        Name and shape of each array.
    scalars : tuple of str
        Names of the scalar sums (weights, counts, sums of squares: >= 0).
    what : str
        Whose sums, for the message.

    Returns
    -------
    tuple of list
        The arrays, the scalars, in the order asked.

    Raises
    ------
    ValueError
        A missing entry, a wrong shape, a non-finite or negative value.

    """
    out = [np.asarray(state[name], dtype=float) for name in arrays]
    if any(x.shape != shape or not np.all(np.isfinite(x))
           for x, shape in zip(out, arrays.values(), strict=True)):
        raise ValueError(f'{what} sums of the wrong shape or not finite')
    values = [float(state[name]) for name in scalars]  # type: ignore[arg-type]
    if not all(math.isfinite(x) and x >= 0.0 for x in values):
        raise ValueError(f'{what} sums negative or not finite')
    return out, values


class BaselineLearner:
    """
    Sufficient statistics of the baseline fit, window by window.

    Parameters
    ----------
    prior_std : sequence of float
        Prior standard deviation of each coefficient (`BASELINE_TERMS` order).

    """

    def __init__(self, prior_std: tuple[float, ...]) -> None:
        self.prior_precision = np.diag(1.0 / np.asarray(prior_std, dtype=float) ** 2)
        self.reset()

    def reset(self) -> None:
        """Forget every window."""
        self.a = np.zeros((N_TERMS, N_TERMS))
        self.b = np.zeros(N_TERMS)
        self.c = 0.0
        self.weight = 0.0
        self.windows = 0
        self.learnt_s = 0.0

    def add(self, h: np.ndarray, e_nm: float, weight: float, duration_s: float) -> None:
        """
        Add one window.

        Parameters
        ----------
        h : ndarray
            Its regressors (`baseline_regressors`).
        e_nm : float
            Its mean residual [N m].
        weight : float
            Its length over the nominal window length [-].
        duration_s : float
            Its monitored running [s].

        """
        self.a += weight * np.outer(h, h)
        self.b += weight * e_nm * h
        self.c += weight * e_nm * e_nm
        self.weight += weight
        self.windows += 1
        self.learnt_s += duration_s

    def fit(self) -> Baseline:
        """
        Return the posterior of the coefficients, the noise variance estimated from the fit.

        Returns
        -------
        Baseline
            The fit of the windows so far (the prior's mean where none).

        """
        var = 0.01  # [N m^2] a first guess; two passes settle it
        coef: np.ndarray = np.zeros(N_TERMS)
        cov: np.ndarray = np.diag(1.0 / np.diag(self.prior_precision))
        for _ in range(3):
            precision = self.a / var + self.prior_precision
            cov = np.linalg.inv(precision)
            coef = cov @ (self.b / var)
            sse = self.c - 2.0 * float(coef @ self.b) + float(coef @ self.a @ coef)
            dof = self.weight - float(np.trace(cov @ self.a) / var)
            if dof <= 1.0:
                break
            var = max(sse / dof, 1e-12)
        return Baseline(coef, 0.5 * (cov + cov.T), var, self.learnt_s)

    def state(self) -> dict[str, object]:
        """Return the sums as plain values (for the baseline file)."""
        return {'a': self.a.tolist(), 'b': self.b.tolist(), 'c': self.c,
                'weight': self.weight, 'windows': self.windows, 'learnt_s': self.learnt_s}

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
            Missing, malformed or non-finite sums.

        """
        (a, b), (c, weight, learnt) = read_sums(
            state, {'a': (N_TERMS, N_TERMS), 'b': (N_TERMS,)}, ('c', 'weight', 'learnt_s'),
            'baseline')
        self.a, self.b, self.c, self.weight, self.learnt_s = a, b, c, weight, learnt
        self.windows = int(state['windows'])  # type: ignore[call-overload]


class Commissioning:
    """
    Learn the baseline until ``learn_s`` of monitored running agree with themselves.

    The windows fill two halves of ``learn_s / 2`` each. When both are full, the fits of
    each half are compared over the operating points of the second: where their
    predictions differ by more than ``tolerance_nm`` (RMS), the pump was still changing (oil
    warming up, running in) and the first half is dropped: learning goes on with the
    second. Otherwise the baseline is the fit of both.

    Parameters
    ----------
    prior_std : tuple of float
        Prior standard deviation of each coefficient (`BASELINE_TERMS` order).
    learn_s : float
        Monitored running to learn from [s].
    tolerance_nm : float
        Largest RMS difference of the two halves' predictions of a stationary pump [N m].

    """

    def __init__(self, prior_std: tuple[float, ...], learn_s: float,
                 tolerance_nm: float) -> None:
        self.learn_s = learn_s
        self.tolerance_nm = tolerance_nm
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
        """RMS difference of the two halves' predictions at the last check [N m]."""
        self.fit = self.learner.fit()

    def add(self, h: np.ndarray, e_nm: float, weight: float, duration_s: float) -> bool:
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

        Returns
        -------
        bool
            True once ``learn_s`` of stationary running are learnt.

        """
        half = 0.5 * self.learn_s
        self.recent.add(h, e_nm, weight, duration_s)
        self.learner.add(h, e_nm, weight, duration_s)
        self.fit = self.learner.fit()
        if self.recent.learnt_s < half:
            return False
        if self.learner.learnt_s - self.recent.learnt_s < half:
            self.older.load(self.recent.state())  # the first half is full
            self.recent.reset()
            return False
        change = self.older.fit().coefficients - self.recent.fit().coefficients
        moments = self.recent.a / max(self.recent.weight, 1e-300)
        self.drift_nm = math.sqrt(max(float(change @ moments @ change), 0.0))
        if self.drift_nm <= self.tolerance_nm:
            return True
        self.learner.load(self.recent.state())  # still changing: keep the second half
        self.older.load(self.recent.state())
        self.recent.reset()
        self.restarts += 1
        self.fit = self.learner.fit()
        return False

    def status(self) -> str:
        """Return the learning's progress in words."""
        still = f' (still changing: restarted {self.restarts} times, last drift ' \
            f'{self.drift_nm:.3f} N m)' if self.restarts else ''
        return (f'learning the healthy baseline: {self.learner.learnt_s:.0f} of '
                f'{self.learn_s:.0f} s of monitored running{still}')

    def state(self) -> dict[str, object]:
        """Return the sums as plain values."""
        return {'learner': self.learner.state(), 'older': self.older.state(),
                'recent': self.recent.state(), 'restarts': self.restarts,
                'drift_nm': self.drift_nm}

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
        self.restarts = int(state['restarts'])  # type: ignore[call-overload]
        self.drift_nm = float(state['drift_nm'])  # type: ignore[arg-type]
        self.fit = self.learner.fit()
