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
the change shows, lack of fit 1.0-3.4 and leads +13 to +3826, the valve plate's in all 11,
and the runs test's z (memory-weighted) -8.5 to -20.

So the windows are split as a two-state change model would (on: delta s, off: no change;
Basseville & Nikiforov 1993, sec. 7.2, a change with a nuisance on/off profile): a window
shows the change where its residual is nearer delta s_j than 0, delta x s_j x d > (delta
x s_j)^2 / 2, j the cause that leads on every window and delta its change on the windows
that show it (on every window until some do). Those windows' sums (`ChangeEpisodes.on`) age
with all the change's running, as every window's do. The change comes and goes, and the
verdict reads those windows (`ChangeEpisodes.applies`), where both hold:

- the best single cause's lack of fit on every window is at least
  ``isolation_episode_lack_of_fit``, and that many times its lack of fit on the windows
  that show the change: they fit, every window does not;
- those windows come in runs: a runs test (Wald & Wolfowitz 1940) on the sequence of
  windows that show it and windows that do not gives z <= -``attribution_z``. Episodes
  switch a few times; a split that a nuisance makes window by window (a torque-constant
  drift the single causes do not fit: a step with such a drift read a lack of fit of 4-7
  and windows picked one by one that fitted a torque gain, z ~ 0) switches as often as
  independent windows would.

The verdict takes the split only where those windows name a friction (``attribution``): it
is there to tell which friction; a ramp of other friction with an unlearnt drift, split into
its late windows (one run), fitted a torque gain there. A step or a ramp fits every window
as well as the windows that show it (the bank's
realistic steps, ramps, bearing and torque-constant faults of pick and place: lack of fit
1.0-19.5 on both alike; their runs tests' z -5.9 to +0.4), so they read every window as
before. The runs test is what keeps out a nuisance's split; the ratio, what keeps out a
change that stays.

In this mode the verdict is the single causes' GLR on the windows that show the change,
without the line per cause, the baseline's bias and the unlearnt drift that
``friction_choice`` fits (they describe a change that stays). The reported scales stay those
of every window (the memory's mean since the change began, the truth an intermittent
fault's estimate is held to, ``evaluation.truths.memory_weighted_since``), their
intervals widened where a line through them is significant as for any change
(conservative: a line through on and off says little); the verdict says the change's size
while it shows and the share of the change's windows (memory-weighted) that show it.
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
    z : float
        ``attribution_z`` [-]: the runs test's z score below -z says the windows that show
        the change come in runs.

    """

    def __init__(self, causes: int, lack_of_fit: float, z: float,
                 lowest: np.ndarray | None = None) -> None:
        self._n = causes
        self.lowest = lowest
        self.ratio = lack_of_fit
        self.z = z
        self.clear()

    def clear(self) -> None:
        """Forget every window."""
        self.on = ChangeStats(self._n, self.lowest)
        self.seen = 0.0  # the change's windows, forgotten as the sums (every one's count)
        self.switches = 0.0  # windows that differ from the one before, forgotten as the sums
        self.last: bool | None = None  # whether the window before showed the change

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
        on = self.on
        shows = False
        if not np.isnan(t).all():
            j = int(np.nanargmax(t))
            source = on if on.g[j, j] > 0.0 else every
            x = float(source.b[j] / source.g[j, j]) * float(s[j])  # delta s_j, this window
            shows = bool(x * d_nm > 0.5 * x * x)
        if shows:
            on.add(s, d_nm, weight, keep, duration_s)
        else:
            on.age(keep, duration_s)
        self.seen = keep * self.seen + 1.0
        self.switches = keep * self.switches + float(self.last is not None and
                                                     shows != self.last)
        self.last = shows
        return shows

    def runs_z(self) -> float:
        """
        Return the runs test's z score of the windows that show the change and those not.

        Wald & Wolfowitz (1940): of n windows, n_1 showing it, independent windows switch
        R - 1 times with E[R] = 2 n_1 n_2 / n + 1 and var R = 2 n_1 n_2 (2 n_1 n_2 - n) /
        (n^2 (n - 1)); episodes switch far less (z << 0), windows a nuisance picks one by
        one (a drift, a load) as often (z ~ 0). The counts are the memory-weighted ones
        (the windows this object classified): with weights that sum to n and whose squares
        sum to about n / 2 the score is conservative (simulated, independent windows, the
        isolation's memory: a std of 0.70, not 1).

        Returns
        -------
        float
            (R - E[R]) / std R [-]; 0 where all windows or none show it.

        """
        n, n1 = self.seen, self.on.count
        n2 = n - n1
        if not (n1 > 0.0 and n2 > 0.0 and n > 1.0):
            return 0.0
        pairs = 2.0 * n1 * n2
        var = pairs * (pairs - n) / (n * n * (n - 1.0))
        return (self.switches - pairs / n) / math.sqrt(var) if var > 0.0 else 0.0  # R - E[R]

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
            The windows that show the change (a memory-weighted count of two at least)
            come in runs (`runs_z` <= -z), and the best single cause's lack of fit on every
            window is at least the ratio times that on those windows (so at least the
            ratio: a lack of fit is at least 1).

        """
        if self.on.count < 2.0:
            return False
        return every.lack_of_fit() >= self.ratio * self.on.lack_of_fit() and \
            self.runs_z() <= -self.z

    def fraction(self) -> float:
        """Return the share of the change's windows that show it, memory-weighted [-]."""
        return self.on.count / self.seen if self.seen > 0.0 else math.nan

    def state(self) -> dict[str, object]:
        """Return the sums, the windows seen, the switches and the last window, plain."""
        on = self.on
        return {'g': on.g.tolist(), 'b': on.b.tolist(), 'c': float(on.c),
                'count': float(on.count), 'windows': on.windows, 'g1': on.g1.tolist(),
                'g2': on.g2.tolist(), 'b1': on.b1.tolist(), 'seen': float(self.seen),
                'switches': float(self.switches), 'last': self.last}

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
            Missing or malformed sums, more windows showing the change than seen, a last
            window neither true, false nor null.

        """
        n = self._n
        try:
            (g, b, g1, g2, b1), (c, count, seen, switches) = read_sums(
                state, {'g': (n, n), 'b': (n,), 'g1': (n,), 'g2': (n,), 'b1': (n,)},
                ('c', 'count', 'seen', 'switches'), 'isolation episodes', grams=('g',))
            windows, last = state['windows'], state['last']
        except KeyError as missing:
            raise ValueError(f'isolation episodes: no {missing}') from None
        if type(windows) is not int or windows < 0 or count > seen * (1.0 + 1e-12):
            raise ValueError('isolation episodes: windows not a count, or more showing the '
                             'change than seen')
        if last is not None and type(last) is not bool:
            raise ValueError(f'isolation episodes: last {last!r}, not true, false or null')
        on = ChangeStats(n, self.lowest)
        on.g, on.b, on.c, on.count, on.windows, on.g1, on.g2, on.b1 = \
            g, b, c, count, windows, g1, g2, b1
        self.on, self.seen, self.switches, self.last = on, seen, switches, last
