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

With ``viscosity_source: parameter`` the model's oil keeps one viscosity, and the valve
plate's film shear (rho nu omega / h over the lands, Hong & Doh 2004 sec. 4.2) follows the
real oil, which no input shows: its change from commissioning reads as a valve-plate change.
A cold start's oil goes on warming long after commissioning: the bank's slow warm-ups (tau
490-880 s) were learnt at 1200-1440 s, where the commissioning's halves agreed, with 6-7 K
still to come, and the valve plate then read 0.60-0.77 of healthy, in alarm
(docs/monitor.md, "Other seeds").

A *fall* of the valve plate's friction is, without the temperature, the oil thinning: the
wear this monitor is for raises it (a plate losing its film runs into the Coulomb friction
of eq. 9: more torque, not less), and a torque-measurement change has its own signature (the
isolation tells it apart, ``attribution``). So where the detection would raise an alarm on
the side below the baseline and the isolation names the valve plate (or oil viscosity) as
falling, the baseline's valve-plate level is lowered to the fall's present value and
detection starts afresh: no alarm, and /diagnostics says how far the baseline has followed
the oil (`OilFollow.note`). A rise is never followed: wear, and oil colder than at
commissioning (``oil_temperature_band_c``), stay what the monitor judges. With the
temperature topic the model follows the viscosity itself and nothing here acts.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .attribution import FaultIsolation
from .baseline import Baseline

__all__ = ['OilFollow', 'followed', 'valve_plate_fall']

_VP = 0  # valve plate: first in `attribution.CAUSES` and `baseline.BASELINE_TERMS`


def followed(baseline: Baseline, factor: float) -> Baseline:
    """
    Return the baseline with its valve-plate level times ``factor`` (the oil followed).

    The level l_vp = 1 + b_vp becomes factor l_vp; the covariance of b_vp scales by
    factor^2 and its covariances with the other terms by factor.

    Parameters
    ----------
    baseline : Baseline
        The learnt baseline.
    factor : float
        The valve-plate level's ratio to the learnt one (0 < factor <= 1) [-].

    Returns
    -------
    Baseline
        The baseline with the oil followed (the learnt one when factor is 1).

    """
    if factor == 1.0:
        return baseline
    coefficients = baseline.coefficients.copy()
    coefficients[_VP] = (1.0 + coefficients[_VP]) * factor - 1.0
    scale = np.ones(len(coefficients))
    scale[_VP] = factor
    return dataclasses.replace(baseline, coefficients=coefficients,
                               covariance=baseline.covariance * np.outer(scale, scale))


def valve_plate_fall(isolation: FaultIsolation) -> float:
    """
    Return the valve plate's present relative fall where the isolation names it, else NaN.

    Parameters
    ----------
    isolation : FaultIsolation
        The isolation of the change since the detection left zero.

    Returns
    -------
    float
        The present relative change of the valve-plate level (< 0; of a change still
        moving, the value its line reaches now), or NaN where the isolation does not name
        the valve plate or its change is not a fall [-].

    """
    if isolation.verdict()[2] != _VP:
        return math.nan
    line = isolation.moving(_VP)
    change = line[0] if line is not None else float(isolation.evidence()[1][_VP])
    return change if change < 0.0 else math.nan


class OilFollow:
    """How far the baseline's valve-plate level has followed the oil down."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """Forget the following: the learnt level again (a new baseline)."""
        self.factor = 1.0
        """Valve-plate level over the learnt one [-]."""
        self.times = 0
        """Falls followed since the baseline was learnt."""

    def take(self, change: float) -> None:
        """
        Follow a fall of the valve-plate level.

        Parameters
        ----------
        change : float
            Its relative change from the present baseline, -1 < change < 0 [-].

        """
        self.factor *= 1.0 + change
        self.times += 1

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
            The learnt baseline with the valve-plate level followed down, or None where
            the change is not a fall of the valve plate (the alarm stands).

        """
        change = valve_plate_fall(isolation)
        if not change > -1.0:  # NaN: not a named fall (a fall of all of it is no oil)
            return None
        self.take(change)
        return followed(learnt, self.factor)

    def note(self) -> str:
        """Return how far the baseline has followed the oil, or '' (for /diagnostics)."""
        if not self.times:
            return ''
        return (f'valve-plate baseline lowered {self.times} times to {self.factor:.2f} of the '
                'learnt level: without temperature topic its fall is taken as the oil '
                'thinning, not a fault')

    def state(self) -> dict[str, object]:
        """Return the following as plain values."""
        return {'factor': self.factor, 'times': self.times}

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
        factor = float(state['factor'])  # type: ignore[arg-type]
        times = int(state['times'])  # type: ignore[call-overload]
        if not 0.0 < factor <= 1.0 or times < 0:
            raise ValueError(f'oil follow factor {factor!r} or count {times!r}')
        self.factor, self.times = factor, times
