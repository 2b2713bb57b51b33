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
A change that comes and goes: named from the windows where it shows.

The isolation's GLR per cause (``attribution``) fits one change delta_j s_j to every window
since the CUSUMs left zero. A fault that comes and goes (a valve plate that tilts under some
loads, contamination that passes through) is there in some windows and not in others: one
delta fits neither, the best single cause leaves a lack of fit tens of times the noise, and
the F-test that keeps model error from passing for evidence (`ChangeStats.lack_of_fit`)
divides every cause's T by it. Two frictions whose signatures correlate 0.97-0.99 are then
told apart by a lead of a few units where z^2 = 9 is needed. Measured on the bank's
intermittent valve-plate faults (x1.8 in episodes of 20-90 s, off 20-180 s; pick and place
and steps, seeds 0 and 1, 11 runs): lack of fit 4-121, leads -1 to +24; on the windows where
the change shows, lack of fit 1.0-3.4 and leads +13 to +3826, the valve plate's in all 11.

So the windows are split as a two-state change model would (on: delta s, off: no change;
Basseville & Nikiforov 1993, sec. 7.2, a change with a nuisance on/off profile): a window
shows the change where its residual is nearer delta s_j than 0, delta x s_j x d > (delta
x s_j)^2 / 2, j the cause that leads on every window and delta its change on the windows
that show it (on every window until some do). Those windows' sums (`episodes`) age with all
the change's running, as every window's do. Where the best single cause's lack of fit on
every window is at least ``isolation_episode_lack_of_fit`` and that many times its lack of
fit on the windows that show the change, the change comes and goes and the verdict reads
the latter (`ChangeEpisodes.applies`). A step, a ramp (its line, ``friction_choice``) or a
drift fits every window to within model error (lack of fit 1.0-1.1 on the bank's x1.4
steps), so they read every window as before.

The reported scales stay those of every window (the memory's mean, the truth an intermittent
fault's estimate is held to, ``evaluation.eha_scenarios.memory_weighted_factor``); the
verdict says the change's size while it shows too.
"""

from __future__ import annotations

import math

import numpy as np

from .baseline import read_sums
from .change_stats import ChangeStats

__all__ = ['ChangeEpisodes']


class ChangeEpisodes:
    """
    The sums of the windows that show the change, beside those of every window.

    Parameters
    ----------
    causes : int
        Length of a window's signature vector (the isolation's causes).
    lack_of_fit : float
        ``isolation_episode_lack_of_fit`` [-]: the ratio from which the change is taken as
        coming and going (> 1).

    """

    def __init__(self, causes: int, lack_of_fit: float) -> None:
        self._n = causes
        self.ratio = lack_of_fit
        self.on = ChangeStats(causes)

    def clear(self) -> None:
        """Forget every window."""
        self.on.clear()

    def add(self, every: ChangeStats, s: np.ndarray, d_nm: float, weight: float,
            keep: float, duration_s: float) -> bool:
        """
        Add a window of the change if it shows the change, else age the others by it.

        Parameters
        ----------
        every : ChangeStats
            Every window's sums, this window included.
        s : ndarray
            Its signatures [N m per unit of each cause's change].
        d_nm : float
            Its change from the baseline's prediction [N m].
        weight : float
            Its inverse noise variance [1/N m^2].
        keep : float
            exp(-duration / isolation_memory_s) [-].
        duration_s : float
            Its monitored running [s].

        Returns
        -------
        bool
            Whether it shows the change.

        """
        t = every.glr()
        if np.isnan(t).all():
            self.on.age(keep, duration_s)
            return False
        j = int(np.nanargmax(t))
        on = self.on
        source = on if on.g[j, j] > 0.0 else every
        x = float(source.b[j] / source.g[j, j]) * float(s[j])  # delta s_j, this window
        shows = x * d_nm > 0.5 * x * x
        if shows:
            on.add(s, d_nm, weight, keep, duration_s)
        else:
            on.age(keep, duration_s)
        return shows

    def applies(self, every: ChangeStats) -> bool:
        """
        Return whether the change comes and goes: the windows that show it fit far better.

        Parameters
        ----------
        every : ChangeStats
            Every window's sums.

        Returns
        -------
        bool
            The best single cause's lack of fit on every window is at least the ratio, and
            the ratio times that on the windows that show the change (which number two at
            least).

        """
        if self.on.count < 2.0:
            return False
        lack = every.lack_of_fit()
        return lack >= self.ratio and lack >= self.ratio * self.on.lack_of_fit()

    def fraction(self, every: ChangeStats) -> float:
        """Return the share of the change's windows that show it, memory-weighted [-]."""
        return self.on.count / every.count if every.count > 0.0 else math.nan

    def state(self) -> dict[str, object]:
        """Return the sums as plain values."""
        on = self.on
        return {'g': on.g.tolist(), 'b': on.b.tolist(), 'c': on.c, 'count': on.count,
                'windows': on.windows, 'g1': on.g1.tolist(), 'g2': on.g2.tolist(),
                'b1': on.b1.tolist()}

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
        n = self._n
        (g, b, g1, g2, b1), (c, count) = read_sums(
            state, {'g': (n, n), 'b': (n,), 'g1': (n,), 'g2': (n,), 'b1': (n,)},
            ('c', 'count'), 'isolation episodes')
        windows = int(state['windows'])  # type: ignore[call-overload]
        on = ChangeStats(n)
        on.g, on.b, on.c, on.count, on.windows, on.g1, on.g2, on.b1 = \
            g, b, c, count, windows, g1, g2, b1
        self.on = on
