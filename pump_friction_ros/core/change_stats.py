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
The sums over the windows of a change that the isolation's GLR per cause reads.

Over the windows since the monitor's CUSUMs left zero, each weighted by its inverse noise
variance w and forgotten with the isolation's memory: g = sum w s s^T, b = sum w s d,
c = sum w d^2 and their count. Cause j alone (d = delta_j s_j) fits with delta_j = b_j /
g_jj and explains T_j = b_j^2 / g_jj of c (`glr`, Basseville & Nikiforov 1993, ch. 7); what
the best single cause leaves, per degree of freedom, is the lack of fit (`lack_of_fit`,
at least the noise). Each cause's sums weighted by the windows' age too fit a change
moving along a line in time (`trend`). Where the viscosity is assumed, the oil may sit
anywhere in its band (``oil_allowance``): sum w v s, with v the band's friction change at
each window, bounds how far that moves each fit (`oil_bias`).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ['ChangeStats']


class ChangeStats:
    """
    Weighted sums of the causes' signatures and the change over the change's windows.

    Parameters
    ----------
    causes : int
        Length of a window's signature vector s (the isolation's `CAUSES`).
    lowest : ndarray, optional
        Per cause, the least change it can have (a friction cannot fall below none: -1;
        -inf: no bound) [cause's units]; None: no cause bounded.

    """

    def __init__(self, causes: int, lowest: np.ndarray | None = None) -> None:
        self._n = causes
        self.lowest = np.full(causes, -math.inf) if lowest is None else np.asarray(
            lowest, dtype=float)
        self.clear()

    def clear(self) -> None:
        """Forget every window."""
        self.g = np.zeros((self._n, self._n))
        self.b = np.zeros(self._n)
        self.c = 0.0
        self.count = 0.0  # windows, forgotten as the sums are
        self.windows = 0
        # per cause, the same sums weighted by each window's age (monitored running since
        # it) and its square: a change that moves along a line (`trend`)
        self.g1 = np.zeros(self._n)
        self.g2 = np.zeros(self._n)
        self.b1 = np.zeros(self._n)
        # per cause, sum w v s and its age-weighted sum: an oil offset within the band
        self.bv = np.zeros(self._n)
        self.bv1 = np.zeros(self._n)

    def add(self, s: np.ndarray, d: float, w: float, keep: float, age_s: float,
            oil_nm: float = 0.0) -> None:
        """
        Add one window: the older ones kept by ``keep``, aged by its running.

        Parameters
        ----------
        s : ndarray
            Its signatures of the causes [N m].
        d : float
            Its change from the baseline [N m].
        w : float
            Its inverse noise variance [1/N m^2].
        keep : float
            exp(-duration / isolation_memory_s) [-].
        age_s : float
            Its monitored running [s].
        oil_nm : float
            The friction change of the oil's band at this window (``oil_allowance``; 0:
            none, the viscosity measured or no band) [N m].

        """
        self.age(keep, age_s)
        self.bv += w * oil_nm * s
        self.g += w * np.outer(s, s)
        self.b += w * d * s
        self.c += w * d * d
        self.count += 1.0
        self.windows += 1

    def age(self, keep: float, age_s: float) -> None:
        """
        Age the windows by one that is not added: its running passes, it is not a window.

        Parameters
        ----------
        keep : float
            exp(-duration / isolation_memory_s) [-].
        age_s : float
            Its monitored running [s].

        """
        # the older windows age by the new one's running: tau -> tau + age_s
        g0 = np.diag(self.g)
        self.g2 = keep * (self.g2 + 2.0 * age_s * self.g1 + age_s * age_s * g0)
        self.g1 = keep * (self.g1 + age_s * g0)
        self.b1 = keep * (self.b1 + age_s * self.b)
        self.bv1 = keep * (self.bv1 + age_s * self.bv)
        self.bv = keep * self.bv
        self.g = keep * self.g
        self.b = keep * self.b
        self.c = keep * self.c
        self.count = keep * self.count

    def trend(self, j: int, drift: tuple[float, ...] = ()) -> tuple[float, float, float] | None:
        """
        Fit cause j's change as a line in time, delta(tau) = now + slope tau.

        Parameters
        ----------
        j : int
            The cause.
        drift : tuple of float
            A drift c u fitted with the line (`DriftNuisance.line_sums`: sum w s_j u and
            sum w tau s_j u over the change's windows, sum w u^2 and sum w d u over them and
            over every window); empty: none.

        Returns
        -------
        tuple of float or None
            The change now, its variance and the slope's z score (noise units, scaled
            by the line's own lack of fit over the change's windows; the slope is against
            the age tau, so negative: rising); None where the windows cannot fit a line.

        """
        g0, g1, g2, b0, b1 = self._line_sums(j, drift)
        a0, a1, a2 = float(self.g[j, j]), float(self.g1[j]), float(self.g2[j])
        r0, r1 = float(self.b[j]), float(self.b1[j])
        x0, x1, g_ch, b_ch, g_u, b_u = drift or (0.0,) * 6
        det = g0 * g2 - g1 * g1
        dof = self.count - 2.0
        if not (g0 > 0.0 and det > 1e-9 * g0 * g2 and dof >= 1.0):
            return None
        now = (g2 * b0 - g1 * b1) / det
        slope = (g0 * b1 - g1 * b0) / det
        rss = self.c - now * b0 - slope * b1
        if g_u > 0.0:  # what the line and the drift c u leave of the change's windows
            c = (b_u - x0 * now - x1 * slope) / g_u
            rss = (self.c - 2.0 * (now * r0 + slope * r1 + c * b_ch)
                   + now * now * a0 + 2.0 * now * slope * a1 + slope * slope * a2
                   + 2.0 * c * (x0 * now + x1 * slope) + c * c * g_ch)
        inflation = max(1.0, rss / dof)
        return now, inflation * g2 / det, slope / math.sqrt(inflation * g0 / det)

    def _line_sums(self, j: int, drift: tuple[float, ...]
                   ) -> tuple[float, float, float, float, float]:
        # cause j's sums for a line in time (g0, g1, g2 over 1 and the age tau; b0, b1 of
        # the change), the drift's c profiled out where it has any (as
        # `DriftNuisance.profile`)
        g0, g1, g2 = float(self.g[j, j]), float(self.g1[j]), float(self.g2[j])
        b0, b1 = float(self.b[j]), float(self.b1[j])
        x0, x1, _, _, g_u, b_u = drift or (0.0,) * 6
        if g_u > 0.0:
            g0, g1, g2 = g0 - x0 * x0 / g_u, g1 - x0 * x1 / g_u, g2 - x1 * x1 / g_u
            b0, b1 = b0 - x0 * b_u / g_u, b1 - x1 * b_u / g_u
        return g0, g1, g2, b0, b1

    def line_glr(self, j: int, drift: tuple[float, ...] = ()) -> float | None:
        """
        Return cause j's GLR statistic for a change along a line in time, against none.

        The change delta(tau) = now + slope tau (`trend`'s line, a drift too small to be
        learnt profiled out where ``drift`` has one) explains T = r^T G^-1 r of the
        windows' sum w d^2, with G = [[g0, g1], [g1, g2]] the sums of w s_j^2 weighted by
        1, tau and tau^2 and r = (b0, b1) those of w s_j d by 1 and tau (Basseville &
        Nikiforov 1993, ch. 7, with two parameters). Two causes each fitted so are compared
        on equal terms: a wear that grows over the memory, or a step whose signature's
        share moves as the oil warms, no longer favours the cause whose signature happens
        to follow the change's time course.

        Parameters
        ----------
        j : int
            The cause.
        drift : tuple of float
            As `trend`'s.

        Returns
        -------
        float or None
            T [-] (noise units); None where the windows cannot fit a line (too few, or no
            spread of age).

        """
        g0, g1, g2, b0, b1 = self._line_sums(j, drift)
        det = g0 * g2 - g1 * g1
        if not (g0 > 0.0 and det > 1e-9 * g0 * g2 and self.count - 2.0 >= 1.0):
            return None
        return (g2 * b0 * b0 - 2.0 * g1 * b0 * b1 + g0 * b1 * b1) / det

    def oil_bias(self, j: int) -> tuple[float, float]:
        """
        Return how far an oil offset within the band can move cause j's change and its line.

        An oil that sits off commissioning's temperature by up to the band adds e v to
        every window's change, v the band's friction change there (``oil_allowance``) and
        e in [-1, 1]. Least squares carries e v into the change as e sum w v s_j / sum w
        s_j^2 (for a friction, whose s_j and v are both >= 0, a bound for any e per window)
        and into the line's present value (`trend`) as e times the line fitted to v alone
        (a bound for one e over the memory: an oil that swings within the memory can move
        the line further).

        Parameters
        ----------
        j : int
            The cause.

        Returns
        -------
        tuple of float
            The largest shift of the change and of the line's present value, in the
            cause's units (relative [-] for the frictions); 0, 0: no band, or no signature
            of j; the line's 0 where the windows cannot fit a line.

        """
        g0 = float(self.g[j, j])
        if not (g0 > 0.0 and self.bv[j]):
            return 0.0, 0.0
        r0, r1 = float(self.bv[j]), float(self.bv1[j])
        g1, g2 = float(self.g1[j]), float(self.g2[j])
        det = g0 * g2 - g1 * g1
        now = abs((g2 * r0 - g1 * r1) / det) if det > 1e-9 * g0 * g2 else 0.0
        return abs(r0) / g0, now

    def glr(self) -> np.ndarray:
        """
        Return each cause's GLR statistic [-] (NaN: no signature of it).

        Unbounded, b_j^2 / g_jj at delta_j = b_j / g_jj. Where that change lies below the
        least the cause can have (``lowest``: a friction cannot fall below none), the
        likelihood over the changes it can have is largest at the bound l: T_j = 2 l b_j -
        l^2 g_jj, less than b_j^2 / g_jj by g_jj (delta_j - l)^2 (the GLR maximises the
        likelihood over the admissible changes only).

        Returns
        -------
        ndarray
            T_j per cause [-].

        """
        gjj = np.diag(self.g)
        ok = gjj > 0.0
        safe = np.where(ok, gjj, 1.0)
        delta = self.b / safe
        bound = np.where(delta < self.lowest, self.lowest, delta)
        bound = np.where(np.isfinite(bound), bound, 0.0)
        t = np.where(delta < self.lowest, 2.0 * bound * self.b - bound * bound * gjj,
                     self.b ** 2 / safe)
        return np.where(ok, t, math.nan)

    def best_glr(self) -> float:
        """Return the best single cause's GLR statistic [-] (0: no cause has a signature)."""
        t = self.glr()
        return 0.0 if np.isnan(t).all() else float(np.nanmax(t))

    def lack_of_fit(self) -> float:
        """Return the residual variance about the best single cause, in noise units (>= 1)."""
        dof = self.count - 1.0
        return max(1.0, (self.c - self.best_glr()) / dof) if dof >= 1.0 else 1.0
