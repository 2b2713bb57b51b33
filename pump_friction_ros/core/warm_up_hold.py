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
Without a temperature topic, the detection waits after a start until the friction settles.

With ``viscosity_source: parameter`` the node cannot see the oil's temperature, and the
baseline holds the friction of warm oil (commissioning waits for its halves to agree,
``commissioning``; the baseline follows the oil down as it thins, ``oil_follow``). The
next morning the pump starts cold: ISO VG 46 at 20 degC is 4.5 times as viscous as at 50
degC (ASTM D341), the valve plate's film shear is linear in the viscosity (Hong & Doh 2004
sec. 4.2) and the bearing's drag rises with it (eq. 10), so a healthy pump reads far above
its baseline, `valve plate or oil viscosity`, until it is warm again: an alarm at every cold
start. A pause does the same on a smaller scale: a small EHA's oil cools with a time
constant of 5-15 min once the pump stops heating it.

So, without the temperature, where more than ``warm_up_pause_s`` of the node's time passed
between two windows of monitored running (a pause; a restart, the last window's time kept
in the baseline file; a replay from a baseline file learnt days before, by the header
stamps; a clock that went back is taken as no pause: a bag made with another clock's
zero, a simulation), the change from the baseline is not judged until it stops moving: its
windows go to a check of their own, the commissioning's (`commissioning.Commissioning` on
the change d instead of the residual, over `CHECK_SPAN_RATIO` times ``baseline_learn_s`` of
monitored running: the fits of its two halves must agree, the drift between them
extrapolated over ``baseline_settle_time_constant_s`` below half the CUSUM allowance, from
the first check on: a start is a change until shown otherwise). Meanwhile the CUSUMs, the
level and the isolation stay as they were (an alarm from before the start stands) and
/diagnostics says why; a new pause starts the hold afresh, and a restart resumes it
(`state`). A steady pump is released after one check or a little more (its halves agree);
a warming one once its friction has settled: the check assumes the slowest settling, so an
oil warming faster is released when little of it is left to come, and one as slow at
`HOLD_LIMIT_TIME_CONSTANTS` settle time constants of the node's time at the latest (with
``baseline_settle_time_constant_s`` 0, the drift alone, at the first check). Wear that came
with the start (or during the pause) is then judged as any change; a pump that settles
warmer than the baseline follows the oil down; one that stays colder reads above it, `valve
plate or oil viscosity`, which it may be. With the temperature topic the model follows the
viscosity and nothing is held.
"""

from __future__ import annotations

import math

import numpy as np

from .commissioning import Commissioning

__all__ = ['CHECK_SPAN_RATIO', 'HOLD_LIMIT_TIME_CONSTANTS', 'WarmUpHold']

CHECK_SPAN_RATIO = 2.0
"""The hold's check spans this many times ``baseline_learn_s`` of monitored running: its
halves' fits are half as noisy in variance as the commissioning's and a warm-up's drift
between them twice as large. (At 1, the noise of 15-s fits hid the tail of an ISO VG 32
warm-up, 14 -> 59 degC with tau 884 s: the bank's seed 2, installation 2, the next morning,
released at 1323 s with 22 % of the warm-up to come, WARN 363 s later; at 2 it is released
at 1707 s and raises none. A steady pump waits 60 s of monitored running instead of 30.)"""

HOLD_LIMIT_TIME_CONSTANTS = 5.0
"""The longest hold, in settle time constants of the node's time since the first held window:
an exponential settling is 99.3 % done after five. (At three, 95 %, an ISO VG 46 oil warming
from 20 to 50 degC with the settle time constant, 900 s, was released with 0.03-0.05 N m of
its friction still to come and alarmed 240 s later: test_warm_up_hold, with a check over
``baseline_learn_s`` alone.) A friction that
still moves by then (an oil that swings, an intermittent fault) is judged as it is."""


class WarmUpHold:
    """
    Hold the detection after a start or a pause until the change from the baseline settles.

    Parameters
    ----------
    prior_std : tuple of float
        Prior standard deviation of each coefficient of the change's fit (the baseline's).
    learn_s : float
        ``baseline_learn_s`` [s]: the check spans `CHECK_SPAN_RATIO` times it of monitored
        running, in two halves.
    tolerance_nm : float
        Largest drift still to come of a settled change [N m] (the commissioning's).
    settle_time_constant_s : float
        ``baseline_settle_time_constant_s`` [s] (0: the drift between the halves alone, and
        the hold ends at its first check).
    pause_s : float
        ``warm_up_pause_s``: a gap of the node's time between two windows longer than this
        holds the detection [s]; 0: nothing is ever held, not even after a start.

    """

    def __init__(self, prior_std: tuple[float, ...], learn_s: float, tolerance_nm: float,
                 settle_time_constant_s: float, pause_s: float) -> None:
        self.check = Commissioning(prior_std, CHECK_SPAN_RATIO * learn_s, tolerance_nm,
                                   settle_time_constant_s)
        self.pause_s = pause_s
        self.limit_s = HOLD_LIMIT_TIME_CONSTANTS * settle_time_constant_s
        self.moved = 0
        """Holds whose change was seen moving (its check restarted): the oil moved."""
        self.released_s = math.nan
        """The time of the window that ended the last hold [s] (NaN: none since the start)."""
        self.reset()

    def reset(self, last_s: float = math.nan) -> None:
        """
        Hold nothing; the last window at ``last_s`` (a new baseline: its last window).

        Parameters
        ----------
        last_s : float
            The last window's time [s] (NaN: none).

        """
        self.held = False
        self.reason = ''
        self._since_s = math.nan  # the first held window's time
        self.last_s = last_s
        self.check.reset()

    def forget(self) -> None:
        """Forget the holds seen (with the baseline, after a repair)."""
        self.reset()
        self.moved = 0

    def arm(self, reason: str) -> None:
        """
        Hold the detection from the next window on, until the change settles.

        Parameters
        ----------
        reason : str
            Why, in words (``after a restart``).

        """
        if not self.pause_s > 0.0:
            return
        self.check.reset()
        self.check.restarts = 1  # a start is a change until shown otherwise: extrapolate
        self.held, self.reason, self._since_s = True, reason, math.nan

    def holds(self, h: np.ndarray, d_nm: float, weight: float, duration_s: float,
              t_s: float) -> bool:
        """
        Take a window's change; return whether it is held (not judged).

        Parameters
        ----------
        h : ndarray
            The window's regressors (``baseline.baseline_regressors``).
        d_nm : float
            Its change from the baseline's prediction [N m].
        weight : float
            Its length over the nominal window length [-].
        duration_s : float
            Its monitored running [s].
        t_s : float
            Its time [s].

        Returns
        -------
        bool
            True while the detection waits: the window is the check's, not the CUSUMs'.

        """
        if not math.isfinite(t_s):  # no time: no pause seen, and a hold goes on
            return self.held
        gap = t_s - self.last_s
        self.last_s = t_s
        if gap > self.pause_s > 0.0:  # a pause during a hold starts it afresh
            self.arm(f'after {_duration(gap)} without monitored running (a pause or a restart)')
        if not self.held:
            return False
        if math.isnan(self._since_s):
            self._since_s = t_s
        restarts = self.check.restarts
        settled = self.check.add(h, d_nm, weight, duration_s, t_s)
        checked = self.check.restarts > restarts  # a check that failed
        limit = self.limit_s
        if settled or (checked if not limit > 0.0 else not t_s - self._since_s < limit):
            if self.check.restarts > 1:
                self.moved += 1  # it moved after the start: the oil (or a change) did
            self.held, self.released_s = False, t_s
        return True

    def status(self) -> str:
        """Return what is held and why, or '' (for /diagnostics)."""
        if not self.held:
            return ''
        check = self.check
        moving = f', restarted {check.restarts - 1} times, drift still to come ' \
            f'{check.drift_nm:.3f} N m' if check.restarts > 1 else ''
        return (f'holding the detection {self.reason}: without temperature topic the oil may '
                'be colder than at commissioning; waiting for the friction to settle '
                f'({check.learner.learnt_s:.0f} of {check.learn_s:.0f} s of monitored '
                f'running{moving})')

    def state(self) -> dict[str, object]:
        """Return what outlives a restart: holds seen moving, the last window's time, a hold."""
        return {'moved': self.moved, 'last_s': float(self.last_s), 'held': self.held,
                'reason': self.reason, 'since_s': float(self._since_s),
                'check': self.check.state()}

    def load(self, state: dict[str, object]) -> None:
        """
        Restore what `state` returned.

        Parameters
        ----------
        state : dict
            A `state` result.

        Raises
        ------
        ValueError
            A negative count, an infinite time (NaN: none), or malformed check sums.
        KeyError
            A missing entry.

        """
        moved = int(state['moved'])  # type: ignore[call-overload]
        last, since = (float(state[key])  # type: ignore[arg-type]
                       for key in ('last_s', 'since_s'))
        held = state['held']
        if moved < 0 or math.isinf(last) or math.isinf(since) or not isinstance(held, bool):
            raise ValueError(f'warm-up holds seen moving {moved!r}, last window {last!r}, '
                             f'held {held!r} since {since!r}')
        self.check.load(state['check'])  # type: ignore[arg-type]
        self.moved, self.last_s, self.held, self._since_s = moved, last, held, since
        self.reason = str(state['reason'])


def _duration(seconds: float) -> str:
    """Return a gap in words: seconds, minutes or hours."""
    if seconds < 600.0:
        return f'{seconds:.0f} s'
    return f'{seconds / 60.0:.0f} min' if seconds < 36000.0 else f'{seconds / 3600.0:.0f} h'
