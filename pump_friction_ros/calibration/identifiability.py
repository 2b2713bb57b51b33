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
Which calibration parameters the data identify: fit, fix the least identifiable, refit.

A parameter is identified when its 95 % interval is within half its ``reference``
(`fit.FIT_PARAMETERS`) and its column of the design is not a combination of the other free
ones at the points given: in the design's null space a least-squares covariance says
nothing (zero), so that test is made on the design itself.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .fit import FIT_PARAMETERS, NAMES, solve

__all__ = ['IdentifiedFit', 'fit_identifiable']


@dataclasses.dataclass
class IdentifiedFit:
    """
    Outcome of `fit_identifiable`.

    Attributes
    ----------
    theta : ndarray
        All parameters in `NAMES` order [unit of each].
    ci95 : ndarray
        95 % half-intervals, NaN where not fitted [unit of each].
    free : ndarray of bool
        Parameters left free at the end (the unidentifiable ones are not).
    noise_std_nm : float
        Residual noise std [N m].
    unidentifiable : dict of str to str
        Parameters fixed at their start value because the data cannot identify them, each
        with its warning.

    """

    theta: np.ndarray
    ci95: np.ndarray
    free: np.ndarray
    noise_std_nm: float
    unidentifiable: dict[str, str]


def fit_identifiable(x: np.ndarray, y: np.ndarray, theta0: np.ndarray, free: np.ndarray,
                     upper: np.ndarray) -> IdentifiedFit:
    """
    Fit, then fix the least identifiable parameter at its start value and refit, until all fit.

    A parameter is unidentifiable if its 95 % half-interval exceeds half its
    ``reference``, if its column is zero, or if its column is a combination of the other
    free ones at the points given (the design's null space: there the covariance of a
    least-squares fit says nothing; a stuck logger repeating one row fits any parameter
    "exactly").

    Parameters
    ----------
    x : ndarray
        Design matrix (n, 8) [N m per unit].
    y : ndarray
        Measured torque minus the theoretical torque [N m].
    theta0 : ndarray
        Start values [unit of each].
    free : ndarray of bool
        Parameters to fit (not modified).
    upper : ndarray
        Upper bounds [unit of each].

    Returns
    -------
    IdentifiedFit
        The last fit and the parameters it had to fix.

    """
    free = free.copy()
    refs = np.array([p.reference for p in FIT_PARAMETERS])
    column_zero = np.abs(x).max(axis=0) < 1e-12
    dropped: dict[str, str] = {}
    while True:
        theta, cov, noise = solve(x, y, theta0, free, upper)
        ci = np.full(len(NAMES), math.nan)
        ci[free] = 1.96 * np.sqrt(np.clip(np.diag(cov), 0.0, None)) if free.any() else []
        ratio = np.where(free, ci / (0.5 * refs), 0.0)
        ratio = np.where(free & column_zero, np.inf, ratio)
        collinear = np.zeros(len(NAMES))
        collinear[free] = _null_space_share(x[:, free] * refs[free])
        if not free.any() or (ratio.max() <= 1.0 and not collinear.any()):
            return IdentifiedFit(theta, ci, free, noise, dropped)
        if collinear.any() and not np.isinf(ratio).any():
            worst = int(np.argmax(collinear))
            why = "its effect is a combination of the others' at the points given"
        else:
            worst = int(np.argmax(ratio))
            why = f'95 % interval +-{ci[worst]:.3g}'
        free[worst] = False
        dropped[NAMES[worst]] = (f'{NAMES[worst]} cannot be identified from these data '
                                 f'({why}): kept at its base value {theta0[worst]:g}')


def _null_space_share(xs: np.ndarray) -> np.ndarray:
    """
    Return how much each column takes part in the design's null space (0: none).

    Parameters
    ----------
    xs : ndarray
        Design matrix (n, k), each column scaled by its parameter's reference.

    Returns
    -------
    ndarray
        Per column, the norm of its components in the right singular vectors whose singular
        value is below 1e-9 of the largest (all of them if every one is zero) [-].

    """
    n, k = xs.shape
    if n < k:  # zero rows: the directions n rows cannot reach get zero singular values
        xs = np.vstack([xs, np.zeros((k - n, k))])
    # the triangular factor R (k x k) has the singular values and right vectors of xs, and
    # its QR makes no n x k matrix (a bag's design has 1e5 rows)
    sv, vt = np.linalg.svd(np.linalg.qr(xs, mode='r'))[1:]
    top = float(sv[0]) if sv.size else 0.0
    rank = int(np.sum(sv > 1e-9 * top)) if top > 0.0 else 0
    null = vt[rank:]  # (k - rank, k)
    share = np.sqrt(np.sum(null ** 2, axis=0))
    return np.where(share > 1e-6, share, 0.0)
