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
Which friction changed, told against the friction the baseline already mispredicted.

A baseline commissioned on cold oil predicts the warm pump's friction through the model's
viscosity law, and a real pump follows it only so far: on the bank's cold starts the
healthy warm pump reads valve plate or other friction some 10 % off its baseline, below
what the CUSUMs see (seed 2, cold start, installation 2: over the 900 s before the onset,
valve plate +0.107 or other friction +0.099, other friction leading by 112 in T). A fault
that comes then is read on top of it, and the choice between the two frictions, whose
signatures correlate 0.97-0.99, takes the bias's side: valve plate x1.4 named other
friction, its change read 0.56.

So the choice fits each friction's change together with a bias that was there before it:
d = delta_j s_j (the change's windows) + beta_vp s_vp + beta_o s_o + c u (every window),
u the torque constant's drift where one is possible (``drift_nuisance``). The windows
before the change fix beta and c, those of the change delta_j; the GLR of cause j against
the bias and the drift alone (Basseville & Nikiforov 1993, ch. 7) is the Schur complement

    T_j = (b_j - x_j^T G_u^-1 b_u)^2 / (g_jj - x_j^T G_u^-1 x_j),

with G_u and b_u the sums of U = (s_vp, s_o, u) over every window, x_j the cross sums of
s_j with U over the change's. The same holds for a change along a line in time (s_j and
tau s_j, `ChangeStats.line_glr`). The bias is bounded as the detection bounds it: a bias
above the change the CUSUMs do not see (``WearMonitor.undetectable_change``) would have
raised an alarm before, so beta_j has a normal prior of that size at 95 % (`set_prior`), which
also pins it where few windows came before the change; it weighs against the windows in
the baseline's noise units, those of that bound (not rescaled by the lack of fit that the
isolation's T is divided by). The windows before the change stop ageing while it lasts, as
the drift's do. A state written before these sums, loaded during a change, fits no bias
until that change ends (its sums would begin inside the change and take it for the bias).

Only which friction changed is told so, and only together with the fit without the bias
(``friction_choice``: a friction is named where both fits name it): the size of the change
and its interval stay the single cause's, relative to the baseline (``attribution``).
"""

from __future__ import annotations

import math

import numpy as np

from .baseline import read_sums

__all__ = ['FrictionBias']

_K = 3
"""The nuisance's terms: valve-plate bias, other-friction bias, torque-constant drift."""
Z95 = 1.959963984540054
"""Half-width of a 95 % normal interval in standard deviations (a prior's bound, a reported
scale's interval: ``attribution``)."""


class FrictionBias:
    """The sums that fit a friction change against a bias from before it, and the drift."""

    def __init__(self) -> None:
        self.prior_precision = np.zeros(_K)  # 1 / std^2 of each beta (0: free; c always)
        self.reset()

    def reset(self) -> None:
        """Forget every window."""
        self.usable = True  # False: a change under way whose start these sums did not see
        self._open = False  # the change's sums hold windows
        self.g_before = np.zeros((_K, _K))  # sum w U U^T over the windows before the change
        self.b_before = np.zeros(_K)  # sum w U d over them
        self.g0 = np.zeros((_K, _K))  # the same over the change's windows
        self.g1 = np.zeros((_K, _K))  # ... weighted by each window's age tau
        self.g2 = np.zeros((_K, _K))  # ... by tau^2
        self.b0 = np.zeros(_K)
        self.b1 = np.zeros(_K)

    def set_prior(self, undetectable: np.ndarray) -> None:
        """
        Bound each friction's bias by the change the detection does not see.

        Parameters
        ----------
        undetectable : ndarray
            Per cause (valve plate, other friction first), the largest relative change the
            CUSUMs do not see [-]; taken as the prior's 95 % bound (0, NaN: free).

        """
        std = np.asarray(undetectable[:2], dtype=float) / Z95
        ok = np.isfinite(std) & (std > 0.0)
        self.prior_precision[:2] = np.where(ok, 1.0 / np.where(ok, std, 1.0) ** 2, 0.0)

    def add(self, s: np.ndarray, u_nm: float, d_nm: float, weight: float, keep: float,
            changing: bool, duration_s: float) -> None:
        """
        Add one window: to the change's sums, or to those before it.

        Parameters
        ----------
        s : ndarray
            Its signatures of the causes, valve plate and other friction first [N m].
        u_nm : float
            The drift's signature (``DriftNuisance.add``; 0 or NaN: none) [N m / (1/K)].
        d_nm : float
            Its change from the baseline [N m].
        weight : float
            Its inverse noise variance [1/N m^2].
        keep : float
            exp(-duration / isolation_memory_s) [-].
        changing : bool
            The window belongs to the change; otherwise the change's windows join those
            before the next one.
        duration_s : float
            Its monitored running [s]: how much older the change's windows get.

        """
        if not (math.isfinite(u_nm) and math.isfinite(d_nm * weight)):
            u_nm = 0.0
        self.usable = self.usable or not changing  # the next change is seen from its start
        x = np.array([s[0], s[1], u_nm])
        outer = weight * np.outer(x, x)
        if changing:  # the windows before it do not age while it lasts
            self._open = True
            a = duration_s
            self.g2 = keep * (self.g2 + 2.0 * a * self.g1 + a * a * self.g0)
            self.g1 = keep * (self.g1 + a * self.g0)
            self.b1 = keep * (self.b1 + a * self.b0)
            self.g0 = keep * self.g0 + outer
            self.b0 = keep * self.b0 + weight * d_nm * x
            return
        if self._open:  # the change's windows join those before the next one
            self.g_before = self.g_before + self.g0
            self.b_before = self.b_before + self.b0
            self.g0, self.g1, self.g2 = (np.zeros((_K, _K)) for _ in range(3))
            self.b0, self.b1 = np.zeros(_K), np.zeros(_K)
            self._open = False
        self.g_before = keep * self.g_before + outer
        self.b_before = keep * self.b_before + weight * d_nm * x

    def glr(self, j: int, line: bool) -> float | None:
        """
        Return friction j's GLR against the bias and the drift alone.

        Parameters
        ----------
        j : int
            0: valve plate, 1: other friction.
        line : bool
            The change a line in time (level and slope) rather than a step.

        Returns
        -------
        float or None
            T_j [-] (noise units); None where the windows cannot tell the change from the
            bias (no signature of j, or none that the windows before and the prior do not
            take whole), or the sums began after the change did (a state written before
            them, `load`: until the change ends).

        """
        return self.glr_pair(line)[j]

    def glr_pair(self, line: bool) -> tuple[float | None, float | None]:
        """
        Return both frictions' GLRs against the bias and the drift, with one solve.

        Parameters
        ----------
        line : bool
            Each change a line in time (level and slope) rather than a step.

        Returns
        -------
        tuple of float or None
            (T_vp, T_o) [-], each as `glr`.

        """
        if not self.usable:
            return None, None
        keep = np.flatnonzero(np.diag(self.g_before + self.g0) > 0.0)
        frictions = [j for j in (0, 1) if j in keep]
        if not frictions:
            return None, None
        g_u = (self.g_before + self.g0 + np.diag(self.prior_precision))[np.ix_(keep, keep)]
        n = 2 if line else 1
        x = np.vstack([(self.g0[j, keep], self.g1[j, keep])[:n] for j in frictions])
        try:
            solved = np.linalg.solve(g_u, np.column_stack([x.T, (self.b_before + self.b0)[keep]]))
        except np.linalg.LinAlgError:
            return None, None
        out: list[float | None] = [None, None]
        for m, j in enumerate(frictions):
            x_j, s_j = x[m * n:(m + 1) * n], solved[:, m * n:(m + 1) * n]
            g_a = np.array([[self.g0[j, j], self.g1[j, j]], [self.g1[j, j], self.g2[j, j]]])
            g_p = g_a[:n, :n] - x_j @ s_j
            r_p = np.array([self.b0[j], self.b1[j]])[:n] - x_j @ solved[:, -1]
            if not np.all(np.diag(g_p) > 1e-9 * np.diag(g_a)[:n]):
                continue
            if n == 1:
                out[j] = float(r_p[0] * r_p[0] / g_p[0, 0])
                continue
            det = g_p[0, 0] * g_p[1, 1] - g_p[0, 1] * g_p[1, 0]
            if det > 1e-9 * g_p[0, 0] * g_p[1, 1]:  # r^T G^-1 r, G 2x2 symmetric
                out[j] = float((g_p[1, 1] * r_p[0] ** 2 - (g_p[0, 1] + g_p[1, 0]) * r_p[0]
                                * r_p[1] + g_p[0, 0] * r_p[1] ** 2) / det)
        return out[0], out[1]

    def state(self) -> dict[str, object]:
        """Return the sums as plain values (the prior is the monitor's, set anew)."""
        return {'g_before': self.g_before.tolist(), 'b_before': self.b_before.tolist(),
                'g0': self.g0.tolist(), 'g1': self.g1.tolist(), 'g2': self.g2.tolist(),
                'b0': self.b0.tolist(), 'b1': self.b1.tolist(), 'usable': self.usable}

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
        square, vector = (_K, _K), (_K,)
        try:
            sums, _ = read_sums(state, {'g_before': square, 'b_before': vector, 'g0': square,
                                        'g1': square, 'g2': square, 'b0': vector,
                                        'b1': vector}, (), 'friction bias',
                                grams=('g_before', 'g0', 'g1', 'g2'))
        except (KeyError, TypeError) as exc:
            raise ValueError(f'friction bias sums: {exc!r}') from None
        (self.g_before, self.b_before, self.g0, self.g1, self.g2, self.b0, self.b1) = sums
        self.usable = state.get('usable', True) is not False
        self._open = True
