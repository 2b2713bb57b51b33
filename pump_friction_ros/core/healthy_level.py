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
The interval of a friction scale relative to the healthy pump *now*.

A reported scale is the friction's level over the healthy one. The monitor knows the healthy
level as its baseline holds it; with the temperature topic the model follows the oil, so the
healthy level now is the baseline's (within its own uncertainty, `interval`).

Without the temperature topic (``viscosity_source: parameter``) the oil moves the friction
unseen: the valve plate's film shear is linear in the viscosity (Hong & Doh 2004, sec. 4.2)
and the bearing's drag follows it to the 2/3 power (Palmgren, eq. 10). Where the oil has been
seen to move on this installation (commissioning restarted because its halves disagreed, or
the baseline followed a fall of friction, ``oil_follow``), the healthy level now may differ
from the baseline by any change the detection does not see, u = ``undetectable_change``: a
larger one would have raised an alarm, or been followed. The reading c (relative change from
the baseline) is then that of (1 + w)(1 + b) - 1: the wear w over the healthy pump now, times
the unseen oil b, |b| <= u. So 1 + w lies in [(1 + c_lo) / (1 + u), (1 + c_hi) / (1 - u)]
(`with_unseen_level`), unbounded above where u >= 1: the scale is then published as read
with a std of ``inf`` (thin oil on the bank's cold start without temperature topic, seed 3,
left the valve plate's u at 1.0-1.1).

Measured on the bank's cold start without temperature topic (seed 2, installation 0): the
oil warmed 4.5 K (VG 46, 54.2 -> 58.6 degC: its viscosity x0.85) between the baseline and the
onset of a valve plate x1.8, too slowly for any sum to move, and the x1.8 read 1.39 +- 0.10
(95 %) in alarm. Two x1.4, two ramps to 1.6 and two intermittent faults on that family were
out of alarm at the end (not detected, the oil's thinning offsetting them, or cleared as it
went on) and read 1 +- 0.23-0.37. Each interval missed the truth; over the healthy level's
range they hold it (docs/monitor.md, "The healthy level now"). The scale published is the
middle of that range, as for any interval that is not symmetric (``attribution``).
"""

from __future__ import annotations

import math

from .friction_bias import Z95

__all__ = ['interval', 'oil_seen_moving', 'with_unseen_level']


def interval(change: float, var: float, level_rel_std: float) -> tuple[float, float]:
    """
    Return the 95 % interval of a relative change, the baseline level's uncertainty added.

    Parameters
    ----------
    change : float
        The relative change from the baseline [-].
    var : float
        Its variance: noise, lack of fit and the systematic floor [-].
    level_rel_std : float
        The baseline level's standard deviation relative to it [-].

    Returns
    -------
    tuple of float
        Low and high ends of the relative change [-].

    """
    half = Z95 * math.sqrt(var + (change * level_rel_std) ** 2)
    return change - half, change + half


def oil_seen_moving(viscosity_assumed: bool, band_c: float, commissioning_restarts: int,
                    follows: int) -> bool:
    """
    Return whether the healthy level now is known only within the undetectable change.

    Parameters
    ----------
    viscosity_assumed : bool
        The viscosity is a parameter (no temperature topic).
    band_c : float
        ``oil_temperature_band_c`` [K]: where the installation states its band (> 0), the
        band bounds the oil instead (``oil_allowance``).
    commissioning_restarts : int
        Times commissioning restarted because its halves disagreed (the pump was changing),
        and holds after a start or a pause whose check did (``warm_up_hold``).
    follows : int
        Falls of friction the baseline has followed as the oil thinning (``oil_follow``).

    Returns
    -------
    bool
        The viscosity is assumed, no band is stated, and the oil was seen to move.

    """
    return viscosity_assumed and not band_c > 0.0 and (commissioning_restarts > 0 or
                                                       follows > 0)


def with_unseen_level(low: float, high: float, unseen: float) -> tuple[float, float]:
    """
    Return a relative change's interval over a healthy level known within +-``unseen``.

    Parameters
    ----------
    low, high : float
        The interval of the change from the baseline [-] (low > -1: a friction level).
    unseen : float
        The largest relative change of the healthy level the detection does not see [-].

    Returns
    -------
    tuple of float
        (1 + low) / (1 + unseen) - 1 and (1 + high) / (1 - unseen) - 1 [-]: the interval
        holds it for every healthy level within the range (the least and the most of the
        ratio, whatever the signs). Where ``unseen`` >= 1 the healthy level may be nothing
        at all (a change of the whole friction goes unseen: the valve plate's film shear on
        thin oil, measured on the bank's cold start without temperature topic, seed 3): the
        upper end is then ``inf``, not a number divided by almost zero.

    """
    if not unseen > 0.0:
        return low, high
    least, most = 1.0 - unseen, 1.0 + unseen
    lo, hi = 1.0 + low, 1.0 + high
    ends = [x / y for x in (lo, hi) for y in (least, most) if y > 0.0]
    return min(ends) - 1.0, (max(ends) - 1.0 if least > 0.0 else math.inf)
