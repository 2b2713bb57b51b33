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

    e = b_vp T_vp + b_o T_o + L + c s + g T_th s + dJ a s + noise

with T_vp, T_o the modelled valve-plate and other friction magnitudes, L an extra drive
loss, c a torque offset (s the direction of rotation), g a gain error of the measured
torque against the theoretical one V_g dp / 2 pi (torque constant or pressure sensor), and
dJ an error of the effective rotor inertia (a the filtered acceleration). The monitor takes
samples up to ``monitor_max_accel_rad_s2``, where J a is 0.5-1 N m on an EHA rotor: a
data-sheet J off by 10 %, or a drive whose torque sample and encoder difference are not
taken at the same instant while the speed loop moves the acceleration within a sample,
leaves 0.05-0.2 N m of it in every window that accelerates. On the bank's pick-and-place
family with perfect sensors and the true J configured, the windows scatter 0.070 N m about
the fit without this term and 0.002 N m with it (docs/monitor.md). The priors
(``scale_prior_std``, ``offset_prior_std_nm``, ``torque_gain_prior_std``,
``inertia_prior_std_kg_m2``, zero mean: the pump as modelled) keep terms the duty cycle
cannot separate where the prior puts them; the prediction e_hat = h b, which is all
detection needs, is good wherever the duty cycle has been. The window noise variance is the
fit's own residual variance (the window-to-window scatter, systematic model error
included), each window weighted by its length.

The fit's sufficient statistics are sums (``A = sum w h h^T``, ``sum w h e``, ``sum w e^2``):
they are what the node persists, so learning resumes after a restart where it stopped.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

__all__ = ['BASELINE_TERMS', 'Baseline', 'BaselineLearner', 'baseline_regressors',
           'is_gram', 'read_count', 'read_sums', 'spd_inverse']

BASELINE_TERMS = ('valve_plate', 'other_friction', 'drive_loss_nm', 'torque_offset_nm',
                  'torque_gain', 'rotor_inertia_kg_m2')
"""Coefficients of the healthy signature, in regressor order: relative friction changes
[-], torques [N m], a relative gain error [-], an inertia error [kg m^2]."""
N_TERMS = len(BASELINE_TERMS)


def baseline_regressors(vp_nm: float, other_nm: float, theoretical_s_nm: float,
                        sign: float, accel_s_rad_s2: float = 0.0) -> np.ndarray:
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
    accel_s_rad_s2 : float
        Window mean of the filtered acceleration times the direction of rotation
        [rad/s^2].

    Returns
    -------
    ndarray
        h, such that the window's residual is h . b [N m].

    """
    return np.array([vp_nm, other_nm, 1.0, sign, theoretical_s_nm, accel_s_rad_s2])


def spd_inverse(matrix: np.ndarray) -> np.ndarray:
    """
    Return the inverse of a small symmetric positive definite matrix, by Cholesky.

    In plain floats, one order of operations: the same bits whatever the BLAS thread count.
    (LAPACK's inverse of a 6 x 6 matrix differs in the last bits between one and two
    OpenBLAS threads, and between numpy releases; a replay on a Dask worker must give the
    local replay's answer.) The baseline's is 6 x 6, three times per commissioning window.

    Parameters
    ----------
    matrix : ndarray, shape (n, n)
        Symmetric positive definite (a posterior precision: the prior's is positive).

    Returns
    -------
    ndarray, shape (n, n)
        Its inverse.

    Raises
    ------
    ValueError
        The matrix is not positive definite.

    """
    a = matrix.tolist()
    n = len(a)
    low = [[0.0] * n for _ in range(n)]  # a = low low^T
    for j in range(n):
        pivot = a[j][j] - math.fsum(low[j][k] * low[j][k] for k in range(j))
        if not pivot > 0.0:
            raise ValueError('matrix not positive definite')
        low[j][j] = math.sqrt(pivot)
        for i in range(j + 1, n):
            low[i][j] = (a[i][j] - math.fsum(low[i][k] * low[j][k] for k in range(j))) \
                / low[j][j]
    inv_low = [[0.0] * n for _ in range(n)]
    for i in range(n):
        inv_low[i][i] = 1.0 / low[i][i]
        for j in range(i):
            inv_low[i][j] = -math.fsum(low[i][k] * inv_low[k][j] for k in range(j, i)) \
                / low[i][i]
    return np.array([[math.fsum(inv_low[k][i] * inv_low[k][j] for k in range(max(i, j), n))
                      for j in range(n)] for i in range(n)])


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
    temperature_c : float
        Mean oil temperature of its windows [degC] (NaN: not known; ``oil_allowance``).

    """

    coefficients: np.ndarray
    covariance: np.ndarray
    window_var_nm2: float
    learnt_s: float
    temperature_c: float = math.nan

    def predict(self, h: np.ndarray) -> float:
        """Return the healthy residual e_hat = h . b of a window with regressors ``h`` [N m]."""
        return float(h @ self.coefficients)

    def prediction_var(self, h: np.ndarray) -> float:
        """Return the variance of `predict` from the uncertainty of b [N m^2]."""
        return float(h @ self.covariance @ h)

    def std(self) -> np.ndarray:
        """Return the posterior standard deviations of b (`BASELINE_TERMS` order)."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))


def is_gram(x: np.ndarray) -> bool:
    """
    Tell whether a square array can be a sum of weighted outer products w s s^T (w >= 0).

    Such a sum is symmetric and positive semi-definite; a saved one that is not was not
    written by this package, and would put a negative variance under a square root.

    Parameters
    ----------
    x : ndarray
        Square array.

    Returns
    -------
    bool
        Symmetric and no eigenvalue below -1e-6 of its largest diagonal entry (rounding).

    """
    scale = float(np.max(np.abs(np.diag(x)), initial=0.0))
    if not np.allclose(x, x.T, rtol=0.0, atol=1e-9 * scale):
        return False
    return x.size == 0 or float(np.linalg.eigvalsh(0.5 * (x + x.T))[0]) >= -1e-6 * scale


def read_count(state: dict[str, object], key: str, what: str) -> int:
    """
    Read a persisted count: an integer >= 0 (not a bool, not 2.5).

    Parameters
    ----------
    state : dict
        The saved values.
    key : str
        The count's name.
    what : str
        Whose count, for the message.

    Returns
    -------
    int
        The count.

    Raises
    ------
    ValueError
        Missing, or not a count.

    """
    value = state[key]
    if type(value) is not int or value < 0:
        raise ValueError(f'{what} {key}: expected a count, got {value!r}')
    return value


def read_sums(state: dict[str, object], arrays: dict[str, tuple[int, ...]],
              scalars: tuple[str, ...], what: str, grams: tuple[str, ...] = ()
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
    grams : tuple of str, optional
        Names of the arrays that are sums of outer products (`is_gram`).

    Returns
    -------
    tuple of list
        The arrays, the scalars, in the order asked.

    Raises
    ------
    ValueError
        A missing entry, a wrong shape, a non-finite or negative value, a sum of outer
        products that is not symmetric positive semi-definite.

    """
    out = [np.asarray(state[name], dtype=float) for name in arrays]
    if any(x.shape != shape or not np.all(np.isfinite(x))
           for x, shape in zip(out, arrays.values(), strict=True)):
        raise ValueError(f'{what} sums of the wrong shape or not finite')
    for name, x in zip(arrays, out, strict=True):
        if name in grams and not is_gram(x):
            raise ValueError(f'{what} {name}: not a sum of outer products (symmetric, '
                             'positive semi-definite)')
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
        self.time_sum_s2 = 0.0  # sum of duration x time: the windows' mean time
        self.temperature_sum_c_s = 0.0  # sum of duration x oil temperature, where known
        self.temperature_time_s = 0.0

    @property
    def temperature_c(self) -> float:
        """Return the windows' mean oil temperature, weighted by running [degC] (NaN: none)."""
        return self.temperature_sum_c_s / self.temperature_time_s \
            if self.temperature_time_s > 0.0 else math.nan

    @property
    def mean_time_s(self) -> float:
        """Return the windows' mean time, weighted by their running [s] (NaN: none)."""
        return self.time_sum_s2 / self.learnt_s if self.learnt_s > 0.0 else math.nan

    def add(self, h: np.ndarray, e_nm: float, weight: float, duration_s: float,
            t_s: float = 0.0, temperature_c: float = math.nan) -> None:
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
        t_s : float
            Its time [s] (the clock the drift is measured on).
        temperature_c : float
            Its oil temperature [degC] (NaN: not known).

        """
        self.a += weight * np.outer(h, h)
        self.b += weight * e_nm * h
        self.c += weight * e_nm * e_nm
        self.weight += weight
        self.windows += 1
        self.learnt_s += duration_s
        self.time_sum_s2 += duration_s * t_s
        if math.isfinite(temperature_c):
            self.temperature_sum_c_s += duration_s * temperature_c
            self.temperature_time_s += duration_s

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
            try:
                cov = spd_inverse(precision)
            except ValueError:  # positive definite in theory, not in floats: never raise
                cov = np.linalg.inv(precision)
            coef = cov @ (self.b / var)
            sse = self.c - 2.0 * float(coef @ self.b) + float(coef @ self.a @ coef)
            dof = self.weight - float(np.trace(cov @ self.a) / var)
            if dof <= 1.0:
                break
            var = max(sse / dof, 1e-12)
        return Baseline(coef, 0.5 * (cov + cov.T), var, self.learnt_s, self.temperature_c)

    def state(self) -> dict[str, object]:
        """Return the sums as plain values (for the baseline file)."""
        return {'a': self.a.tolist(), 'b': self.b.tolist(), 'c': float(self.c),
                'weight': float(self.weight), 'windows': int(self.windows),
                'learnt_s': float(self.learnt_s), 'time_sum_s2': float(self.time_sum_s2),
                'temperature_sum_c_s': float(self.temperature_sum_c_s),
                'temperature_time_s': float(self.temperature_time_s)}

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
        (a, b), (c, weight, learnt, time_sum) = read_sums(
            state, {'a': (N_TERMS, N_TERMS), 'b': (N_TERMS,)},
            ('c', 'weight', 'learnt_s', 'time_sum_s2'), 'baseline', grams=('a',))
        windows = read_count(state, 'windows', 'baseline')
        # every window adds a positive weight and running: none of them is zero without
        # the others, and no window leaves the sums at zero
        if (windows == 0) != (weight == 0.0) or (windows == 0) != (learnt == 0.0) or \
                (windows == 0 and (c != 0.0 or a.any() or b.any())):
            raise ValueError(f'baseline sums of {windows} windows with weight {weight!r}, '
                             f'running {learnt!r} s: not what windows add up to')
        self.a, self.b, self.c, self.weight, self.learnt_s = a, b, c, weight, learnt
        self.time_sum_s2 = time_sum
        self.windows = windows
        # the oil temperature's sums came later: a file without them knows no temperature
        temperature = (float(state.get('temperature_sum_c_s', 0.0)),  # type: ignore[arg-type]
                       float(state.get('temperature_time_s', 0.0)))  # type: ignore[arg-type]
        if not all(math.isfinite(x) for x in temperature) or temperature[1] < 0.0:
            raise ValueError('baseline temperature sums negative or not finite')
        self.temperature_sum_c_s, self.temperature_time_s = temperature
