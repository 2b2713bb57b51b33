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
change fix c, those of the change delta_j. The normal equations need the sums of u over
every window (g_u = sum w u^2, b_u = sum w d u) and its cross sum with each cause over the
change's windows (x_j = sum w s_j u):

    delta_j = (b_j g_u - x_j b_u) / (g_jj g_u - x_j^2),
    var(delta_j) = g_u / (g_jj g_u - x_j^2)  (noise units),

the single-cause estimate b_j / g_jj with its variance 1 / g_jj where u carries nothing
(no topic, no drift allowed, the oil at T_0). No drift there: the estimate is unbiased
either way, and its std widens by 1 / sqrt(1 - rho^2), rho the cosine of s_j (nothing before
the change) and u over the windows. The drift's sign and size are left free: a bound would
pull the change back towards the single-cause estimate that the drift biases.

The windows of the change are forgotten as the isolation's are (``isolation_memory_s``);
those before it stop ageing while it lasts. A change held for many memories would otherwise
leave only its own windows, where a step and a drift differ by the points' spread alone (on
a steady point, not at all); the drift before the change is what it was. Where the two
cannot be told apart the change is the single cause's, with a variance that says so.

Which friction changed is told the same way (`profile`: each cause's GLR against the drift
alone). On a load-driven cycle the valve plate's and the other friction's signatures
correlate 0.97-0.99, and each one's step alone takes the part of the drift that looks like
it: enough to name one friction for the other (test_drift_nuisance: 6 of 24 such changes
named wrong by the steps alone, none with the drift fitted). Whether the change
is friction at all stays the single causes' call: the drift is itself a gain change, and
``gain_follow`` learns it where it explains the change better than any step.
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
        self.g_before = 0.0  # sum w u^2 over the windows before the change
        self.b_before = 0.0  # sum w d u over them
        self.g_change = 0.0  # the same over the change's windows
        self.b_change = 0.0
        self.x = np.zeros(self._n)  # sum w u s_j over the change's windows
        self.x1 = np.zeros(self._n)  # sum w tau u s_j over them, tau a window's age [s]

    def add(self, s: np.ndarray, u_nm: float, d_nm: float, weight: float, keep: float,
            changing: bool, duration_s: float) -> None:
        """
        Add one window: to the change's sums, or to those before it.

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
            The window belongs to the change (the isolation keeps it). Otherwise no change
            is under way, or it ended: its windows join those before the next one, and the
            cross sums start afresh, as the isolation's do.
        duration_s : float
            Its monitored running [s]: how much older the change's windows get.

        """
        if not (math.isfinite(u_nm) and math.isfinite(d_nm * weight)):
            u_nm = 0.0
        if changing:  # the windows before it do not age while it lasts
            # the cross sum weighted by each window's age, as `ChangeStats.add` ages its own
            self.x1 = keep * (self.x1 + duration_s * self.x)
            self.g_change = keep * self.g_change + weight * u_nm * u_nm
            self.b_change = keep * self.b_change + weight * d_nm * u_nm
            self.x = keep * self.x + weight * u_nm * s
            return
        self.g_before = keep * (self.g_before + self.g_change) + weight * u_nm * u_nm
        self.b_before = keep * (self.b_before + self.b_change) + weight * d_nm * u_nm
        self.g_change = self.b_change = 0.0
        self.x = np.zeros(self._n)
        self.x1 = np.zeros(self._n)

    def profile(self, g: np.ndarray, b: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Return the change's sums with the drift profiled out, and which causes it leaves.

        The GLR of cause j with the drift's c a nuisance parameter (Basseville & Nikiforov
        1993, ch. 7; the drift alone the null) is that of sums projected off u:
        g' = g - x x^T / g_u and b' = b - x b_u / g_u; then delta_j = b'_j / g'_jj with
        variance 1 / g'_jj (noise units), T_j = b'_j^2 / g'_jj, and the cosine of two causes
        over the points seen is g'_jk / sqrt(g'_jj g'_kk).

        Parameters
        ----------
        g : ndarray
            sum w s s^T over the change's windows.
        b : ndarray
            sum w s d over them.

        Returns
        -------
        tuple of ndarray
            g', b' (g and b themselves where the drift's signature carries nothing) and the
            causes with a signature the drift does not take whole (g'_jj > 1e-9 g_jj > 0).

        """
        g_jj = np.diag(g)
        g_u = self.g_before + self.g_change
        if not g_u > 0.0:
            return g, b, g_jj > 0.0
        g_p = g - np.outer(self.x, self.x) / g_u
        b_p = b - self.x * (self.b_before + self.b_change) / g_u
        return g_p, b_p, (g_jj > 0.0) & (np.diag(g_p) > 1e-9 * g_jj)

    def change(self, j: int, g: np.ndarray, b: np.ndarray) -> tuple[float, float]:
        """
        Return cause j's change fitted jointly with the drift, and its variance.

        Parameters
        ----------
        j : int
            The cause (g_jj > 0).
        g, b : ndarray
            As `profile`'s.

        Returns
        -------
        tuple of float
            delta_j [-] and its variance in noise units (times the lack of fit, as the
            single-cause one); the single-cause b_j / g_jj and 1 / g_jj where the drift's
            signature carries nothing; b_j / g_jj and a variance of 1e9 / g_jj where the
            drift and the step cannot be told apart.

        """
        g_p, b_p, told = self.profile(g, b)
        if not told[j]:
            return float(b[j] / g[j, j]), 1e9 / float(g[j, j])
        return float(b_p[j] / g_p[j, j]), 1.0 / float(g_p[j, j])

    def line_sums(self, j: int) -> tuple[float, float, float, float, float, float]:
        """
        Return the sums that fit the drift with cause j's change as a line in time.

        Returns
        -------
        tuple of float
            sum w s_j u, sum w tau s_j u, sum w u^2 and sum w d u over the change's windows,
            sum w u^2 and sum w d u over every window (`ChangeStats.trend`'s ``drift``).

        """
        return (float(self.x[j]), float(self.x1[j]), self.g_change, self.b_change,
                self.g_before + self.g_change, self.b_before + self.b_change)

    def state(self) -> dict[str, object]:
        """Return the sums as plain values."""
        return {'g_before': float(self.g_before), 'b_before': float(self.b_before),
                'g_change': float(self.g_change), 'b_change': float(self.b_change),
                'x': self.x.tolist(),
                'x1': self.x1.tolist()}

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
        try:
            (x,), (g_before, g_change) = read_sums(state, {'x': (self._n,)},
                                                   ('g_before', 'g_change'), 'drift nuisance')
            x1 = np.zeros(self._n)  # a state written before the line's cross sums: none
            if 'x1' in state:
                (x1,), _ = read_sums(state, {'x1': (self._n,)}, (), 'drift nuisance')
            b_before, b_change = (float(state[key])  # type: ignore[arg-type]
                                  for key in ('b_before', 'b_change'))
        except (KeyError, TypeError) as exc:
            raise ValueError(f'drift nuisance sums: {exc!r}') from None
        if not (math.isfinite(b_before) and math.isfinite(b_change)):
            raise ValueError('drift nuisance sums not finite')
        self.g_before, self.b_before, self.g_change, self.b_change, self.x, self.x1 = \
            g_before, b_before, g_change, b_change, x, x1
