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
Which friction changed, named only where the choice does not turn on the nuisance fitted.

The valve plate's and the other friction's signatures correlate 0.97-0.99 on a load-driven
cycle, so which one changed rests on the small part of the change that is not common to
both; how that part reads depends on what else the fit takes out. Two fits are made
(``attribution``):

- against the torque constant's drift alone (``drift_nuisance``);
- against that drift and a friction bias the baseline already had before the change
  (``friction_bias``);

each change a line in time where both fits have one for both frictions
(`ChangeStats.line_glr`, `FrictionBias.glr_pair`), else a step in both.

Where both name the same friction, the evidence is the one with the smaller lead: the
name has to survive either nuisance model. Where they name different ones and either
leads by the verdict's margin, the choice turns on whether the baseline was already off
before the change, which these windows cannot settle, and the verdict says so (a bias fit
that is not finite counts as none). Measured on the bank (``docs/monitor.md``):
a cold start whose baseline read the warm pump's valve plate 10 % off named a valve plate
x1.4 other friction without the bias (leading by more than 100 in T) and the valve plate
with it; a creep cycle's bearing x1.8 tied without the bias (44052 against 44050) and
read valve plate with it (10725 against 10703): a tie that the bias's fit tipped.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from .change_stats import ChangeStats
from .drift_nuisance import DriftNuisance
from .friction_bias import FrictionBias

__all__ = ['FrictionChoice', 'choose_friction', 'reconcile']

_VP, _OTHER = 0, 1


@dataclass(frozen=True)
class FrictionChoice:
    """Which friction leads, on evidence that either nuisance model gives."""

    first: int
    """The friction that leads (0: valve plate, 1: other friction)."""
    second: int
    """The other one."""
    t: np.ndarray
    """Every cause's T [-], the frictions' from the fit with the smaller lead."""
    cos: float
    """Cosine of the two frictions' signatures over the change's windows [-]."""
    split: tuple[float, float, float, float] | None
    """Where the two fits name different frictions: (T_vp, T_o) with the bias, then
    without it [-]; else None."""


def reconcile(without: tuple[float, float], with_bias: tuple[float, float] | None
              ) -> tuple[tuple[float, float], bool]:
    """
    Return the frictions' evidence that both fits support, and whether they disagree.

    Parameters
    ----------
    without : tuple of float
        (T_vp, T_o) against the drift alone [-].
    with_bias : tuple of float or None
        (T_vp, T_o) against the drift and a bias from before the change [-]; None: no bias
        fitted (one not finite counts as none).

    Returns
    -------
    tuple
        (T_vp, T_o) of the fit whose lead is the smaller (``without`` where there is no
        bias), and True where the two fits lead with different frictions.

    """
    if with_bias is None or not math.isfinite(with_bias[0] - with_bias[1]):
        return without, False
    lead, lead_bias = without[0] - without[1], with_bias[0] - with_bias[1]
    return (without if abs(lead) <= abs(lead_bias) else with_bias), lead * lead_bias < 0.0


def _fits(stats: ChangeStats, drift: DriftNuisance, bias: FrictionBias, g: np.ndarray,
          b: np.ndarray, told: np.ndarray) -> tuple[list[float], list[float] | None]:
    # each friction's GLR against the drift alone and against the drift and the bias (None
    # where the bias cannot be fitted), both a line per cause where both fits have one, else
    # both a step: a difference of form must not pass for the bias's
    lines = [stats.line_glr(i, drift.line_sums(i)) for i in (_VP, _OTHER)]
    plain = [x for x in lines if x is not None]
    if len(plain) == 2:
        fits = bias.glr_pair(True)
        if fits[0] is not None and fits[1] is not None:
            return plain, [fits[0], fits[1]]
    steps = [float(b[i] ** 2 / g[i, i]) if told[i] else 0.0 for i in (_VP, _OTHER)]
    fits = bias.glr_pair(False)
    if fits[0] is not None and fits[1] is not None:
        return steps, [fits[0], fits[1]]
    return (plain if len(plain) == 2 else steps), None


def choose_friction(stats: ChangeStats, drift: DriftNuisance, bias: FrictionBias,
                    t: np.ndarray) -> FrictionChoice:
    """
    Return which friction leads, on the evidence of both nuisance models.

    Parameters
    ----------
    stats : ChangeStats
        The change's sums (``attribution``).
    drift : DriftNuisance
        The torque constant's drift not learnt.
    bias : FrictionBias
        The friction bias from before the change.
    t : ndarray
        Every cause's T from ``FaultIsolation.evidence`` [-]; the frictions' are replaced.

    Returns
    -------
    FrictionChoice
        The leader and runner-up, the evidence (each T divided by the lack of fit of the
        best single cause, 0 for a friction whose signature the drift takes whole), the
        signatures' cosine, and the two fits' evidence where they disagree.

    """
    g, b, told = drift.profile(stats.g, stats.b)
    plain, fits = _fits(stats, drift, bias, g, b, told)
    lack = stats.lack_of_fit()

    def scaled(x: list[float]) -> tuple[float, float]:
        return (x[_VP] / lack if told[_VP] else 0.0, x[_OTHER] / lack if told[_OTHER] else 0.0)

    without, with_bias = scaled(plain), None if fits is None else scaled(fits)
    chosen, split = reconcile(without, with_bias)
    t = t.copy()
    t[_VP], t[_OTHER] = chosen
    cos = float(g[_VP, _OTHER] / math.sqrt(g[_VP, _VP] * g[_OTHER, _OTHER])) \
        if told[_VP] and told[_OTHER] else 0.0
    first, second = (_VP, _OTHER) if t[_VP] >= t[_OTHER] else (_OTHER, _VP)
    if not split or with_bias is None:
        return FrictionChoice(first, second, t, cos, None)
    return FrictionChoice(first, second, t, cos, (*with_bias, *without))
