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
A friction change estimated together with a torque-constant drift too small to be learnt.

With the temperature topic the drive's torque constant may drift with the temperature
(``gain_follow``): the measured torque reads c (T - T_0) of itself high. A drift large enough
to alarm is learnt; one below the CUSUM allowance is not, and it is still there when a
friction fault comes: on a cold start with 0.32e-3 / K and the oil 40 K above
commissioning, 1.3 % of the measured torque, which the valve plate's single-cause estimate
takes for wear (seed 2 of the bank, installation 0: valve plate x1.8 read 2.00 +- 0.16; the
same run with the drive's k_t exact, 1.82). The valve plate's film shear falls with the
viscosity as the oil warms, so on the warm pump a small gain error is a large part of it.

So a friction cause's change is fitted jointly with that drift (a nuisance parameter):
d = delta_j s_j + c u, u = (T - T_0) times the torque gain's signature. The step s_j is
nothing before the change began, the drift is there throughout: the windows before the
change (in the isolation's memory) fix c, those of the change delta_j. The normal equations
need the sums of u over every window (g_u = sum w u^2, b_u = sum w d u) and its cross sum
with each cause over the change's windows (x_j = sum w s_j u):

    delta_j = (b_j g_u - x_j b_u) / (g_jj g_u - x_j^2),
    var(delta_j) = g_u / (g_jj g_u - x_j^2)  (noise units),

the single-cause estimate b_j / g_jj with its variance 1 / g_jj where u carries nothing
(no topic, no drift possible, the oil at T_0). No drift there: the estimate is unbiased
either way, and the interval widens by 1 / (1 - rho^2), rho the correlation of s_j and u
over the windows. The drift's sign and size are left free: a bound would pull the change
back towards the single-cause estimate that the drift biases.
"""

from __future__ import annotations

import math

import numpy as np

from .baseline import read_sums

__all__ = ['DriftNuisance']


class DriftNuisance:
    """
    The sums of an unlearnt torque-gain drift's signature, over every window and the change.

    Parameters
    ----------
    causes : int
        Number of causes (signature entries).

    """

    def __init__(self, causes: int) -> None:
        self._n = causes
        self.reset()

    def reset(self) -> None:
        """Forget every window."""
        self.g = 0.0  # sum w u^2 over every window in memory
        self.b = 0.0  # sum w d u over every window in memory
        self.x = np.zeros(self._n)  # sum w u s_j over the change's windows

    def add(self, s: np.ndarray, u_nm: float, d_nm: float, weight: float, keep: float,
            changing: bool) -> None:
        """
        Add one window (every window; the cross sums only those of the change).

        Parameters
        ----------
        s : ndarray
            The window's signatures of the causes [N m].
        u_nm : float
            The drift's signature: (T - T_0) times the torque gain's [N m / (1/K)]; 0 or
            NaN where the temperature is not known or no drift is possible (the window then
            only ages the sums).
        d_nm : float
            Its change from the baseline [N m].
        weight : float
            Its inverse noise variance [1/N m^2].
        keep : float
            exp(-duration / isolation_memory_s): how much the older windows keep [-].
        changing : bool
            The window belongs to the change (the isolation keeps it); otherwise the cross
            sums start afresh, as the isolation's do.

        """
        if not (math.isfinite(u_nm) and math.isfinite(d_nm * weight)):
            u_nm = 0.0
        self.g = keep * self.g + weight * u_nm * u_nm
        self.b = keep * self.b + weight * d_nm * u_nm
        self.x = keep * self.x + weight * u_nm * s if changing else np.zeros(self._n)

    def change(self, j: int, g_jj: float, b_j: float) -> tuple[float, float]:
        """
        Return cause j's change fitted jointly with the drift, and its variance.

        Parameters
        ----------
        j : int
            The cause.
        g_jj : float
            sum w s_j^2 over the change's windows (> 0).
        b_j : float
            sum w s_j d over them.

        Returns
        -------
        tuple of float
            delta_j [-] and its variance in noise units (times the lack of fit, as the
            single-cause one); the single-cause b_j / g_jj and 1 / g_jj where the drift's
            signature carries nothing or cannot be told from s_j.

        """
        x = float(self.x[j])
        det = g_jj * self.g - x * x
        if not (self.g > 0.0 and det > 1e-9 * g_jj * self.g):
            return b_j / g_jj, 1.0 / g_jj
        return (b_j * self.g - x * self.b) / det, self.g / det

    def state(self) -> dict[str, object]:
        """Return the sums as plain values."""
        return {'g': self.g, 'b': self.b, 'x': self.x.tolist()}

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
        (x,), (g,) = read_sums(state, {'x': (self._n,)}, ('g',), 'drift nuisance')
        b = float(state['b'])  # type: ignore[arg-type]
        if not math.isfinite(b):
            raise ValueError('drift nuisance sums negative or not finite')
        self.g, self.b, self.x = g, b, x
