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
Without a temperature topic, the healthy baseline follows the oil down as it thins.

With ``viscosity_source: parameter`` the model's oil keeps one viscosity, and the real oil,
which no input shows, moves the friction: the valve plate's film shear (rho nu omega / h
over the lands, Hong & Doh 2004 sec. 4.2) is linear in the viscosity, and the bearing's
drag rises with it (Palmgren's (nu n)^(2/3), eq. 10). Its change from commissioning reads
as a friction change. A cold start's oil goes on warming long after commissioning: the
bank's slow warm-ups (tau 490-880 s) were learnt at 660-1440 s, where the commissioning's
halves agreed, with up to 7 K still to come, and the valve plate then read 0.60-0.77 of
healthy, in alarm (docs/monitor.md).

A *fall* of a friction is, without the temperature, the oil thinning: the wear this monitor
is for raises friction (a valve plate losing its film runs into the Coulomb friction of eq.
9; a worn bearing drags more), and a torque-measurement change has its own signature (the
isolation tells it apart, ``attribution``). So where the detection would raise an alarm on
the side below the baseline and the isolation names the valve plate or the other friction
as falling (or cannot tell which of the two fell, each one's own explanation a fall: then
the one that explains it better; both thin with the oil), that friction's baseline level is
lowered to the fall's present value (as the isolation estimates it when the alarm would be
raised) and detection starts afresh: no alarm, and /diagnostics says how far the baseline
has followed the oil (`OilFollow.note`). A rise is never followed: wear stays what the
monitor judges, and so does oil that cools back after a follow (a pause, the next cold
start: the followed levels are kept in the baseline file), which reads above the lowered
baseline as "valve plate or oil viscosity"; following it back up would hide as much wear.
With the temperature topic the model follows the viscosity itself and nothing here acts.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .attribution import FaultIsolation, Verdict
from .baseline import Baseline
from .verdict_words import FRICTIONS

__all__ = ['FOLLOWED', 'OilFollow', 'followed', 'friction_fall']

FOLLOWED = FRICTIONS
"""The frictions that follow the oil (``verdict_words.FRICTIONS``): the first two of
`attribution.CAUSES` and of `baseline.BASELINE_TERMS` (their levels l = 1 + b)."""


def followed(baseline: Baseline, factors: np.ndarray) -> Baseline:
    """
    Return the baseline with its friction levels times ``factors`` (the oil followed).

    Each level l = 1 + b of `FOLLOWED` becomes factor l; the covariance of the b's scales
    by the product of their factors (1 for the other terms).

    Parameters
    ----------
    baseline : Baseline
        The learnt baseline.
    factors : ndarray
        Each followed friction's level over the learnt one (0 < factor <= 1) [-].

    Returns
    -------
    Baseline
        The baseline with the oil followed (the learnt one where every factor is 1).

    """
    if np.all(factors == 1.0):
        return baseline
    scale = np.ones(len(baseline.coefficients))
    scale[:len(FOLLOWED)] = factors
    coefficients = baseline.coefficients.copy()
    coefficients[:len(FOLLOWED)] = (1.0 + coefficients[:len(FOLLOWED)]) * factors - 1.0
    return dataclasses.replace(baseline, coefficients=coefficients,
                               covariance=baseline.covariance * np.outer(scale, scale))


def friction_fall(isolation: FaultIsolation) -> tuple[int, float]:
    """
    Return the friction the isolation names falling, and its present relative change.

    Parameters
    ----------
    isolation : FaultIsolation
        The isolation of the change since the detection left zero.

    Returns
    -------
    tuple
        (index into `FOLLOWED`, change < 0: of a change still moving, the value its line
        reaches now), or (-1, NaN) where the isolation names neither friction, its change
        is not a fall, or it comes and goes (an oil thins, it does not come and go). Where
        it cannot tell the valve plate from the other friction, both lead every other
        cause by ``attribution_z`` squared and each one's change is a fall, the one with the
        larger evidence, its change.

    """
    verdict, _, j = isolation.verdict()
    if isolation.comes_and_goes():
        return -1, math.nan
    if j < 0 and verdict == Verdict.CANNOT_TELL:
        # the valve plate or the other friction, not told apart: a fall whichever it is
        # (each one's own explanation a fall) is the oil thinning, followed on the one
        # whose evidence leads (the single-cause GLR; the verdict's own ranking fits a small
        # k_t drift with each, and either friction's fall lowers the baseline by the same
        # torque where their signatures are one), both ahead of every other cause by
        # attribution_z^2, as a friction named is; a tie with a measurement change is not
        t = np.nan_to_num(isolation.evidence()[0], nan=-1.0)
        order = [int(i) for i in np.argsort(-t)]
        if sorted(order[:2]) != list(range(len(FOLLOWED))) or \
                not t[order[1]] - t[order[2]] >= isolation.settings.attribution_z ** 2 or \
                not _present_change(isolation, order[1]) < 0.0:
            return -1, math.nan
        j = order[0]
    if not 0 <= j < len(FOLLOWED):
        return -1, math.nan
    change = _present_change(isolation, j)
    return (j, change) if change < 0.0 else (-1, math.nan)


def _present_change(isolation: FaultIsolation, j: int) -> float:
    """Return cause j's relative change now: its line's present value while it moves."""
    line = isolation.moving(j)
    return line[0] if line is not None else float(isolation.evidence()[1][j])


class OilFollow:
    """How far the baseline's friction levels have followed the oil down."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """Forget the following: the learnt levels again (a new baseline)."""
        self.factors = np.ones(len(FOLLOWED))
        """Each followed friction's level over the learnt one [-]."""
        self.times = 0
        """Falls followed since the baseline was learnt."""

    def follow(self, isolation: FaultIsolation, learnt: Baseline) -> Baseline | None:
        """
        Follow the fall the isolation names, if it names one; return the baseline then.

        Parameters
        ----------
        isolation : FaultIsolation
            The isolation of the change the detection alarms on.
        learnt : Baseline
            The baseline as learnt (before any following).

        Returns
        -------
        Baseline or None
            The learnt baseline with the friction levels followed down, or None where the
            change is not a fall of a friction (the alarm stands).

        """
        j, change = friction_fall(isolation)
        if j < 0 or not change > -1.0:  # a fall of all of it is no oil
            return None
        self.factors[j] *= 1.0 + change
        self.times += 1
        return followed(learnt, self.factors)

    def note(self) -> str:
        """Return how far the baseline has followed the oil, or '' (for /diagnostics)."""
        if not self.times:
            return ''
        levels = ', '.join(f'{name.replace("_", " ")} {f:.2f}'
                           for name, f in zip(FOLLOWED, self.factors.tolist(), strict=True))
        times = 'once' if self.times == 1 else f'{self.times} times'
        return (f'friction baseline lowered {times}, to {levels} of the learnt levels: '
                'without temperature topic a fall of friction is taken as the oil thinning, '
                'not a fault; oil cooling back reads above it')

    def state(self) -> dict[str, object]:
        """Return the following as plain values."""
        return {**dict(zip(FOLLOWED, self.factors.tolist(), strict=True)), 'times': self.times}

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
            A factor outside (0, 1] or a negative count.

        """
        factors = np.array([float(state[name]) for name in FOLLOWED])  # type: ignore[arg-type]
        times = int(state['times'])  # type: ignore[call-overload]
        if not (np.all(factors > 0.0) and np.all(factors <= 1.0)) or times < 0:
            raise ValueError(f'oil follow factors {factors.tolist()!r} or count {times!r}')
        self.factors, self.times = factors, times
