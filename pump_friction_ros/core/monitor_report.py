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
What the wear monitor tells: its verdict, its baseline's state, what it cannot see.

`MonitorReport` is the read-only part of ``monitor.WearMonitor`` that the diagnostics and
the published scales read (a mixin, as ``monitor_state.MonitorPersistence`` is its
persistence).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from .attribution import DETECTED_CAUSES, Verdict
from .healthy_level import oil_seen_moving

if TYPE_CHECKING:
    from .attribution import FaultIsolation
    from .baseline import Baseline
    from .commissioning import Commissioning
    from .gain_follow import GainFollow
    from .oil_allowance import OilAllowance
    from .oil_follow import OilFollow
    from .warm_up_hold import WarmUpHold

__all__ = ['MonitorReport']


class MonitorReport:
    """The wear monitor's verdict and state in words (a mixin of ``WearMonitor``)."""

    baseline: Baseline | None
    commissioning: Commissioning
    isolation: FaultIsolation
    _var: float
    _undetectable: np.ndarray
    _oil: OilAllowance | None
    _follow: OilFollow | None
    _gain_follow: GainFollow | None
    _hold: WarmUpHold | None

    @property
    def residual_std_nm(self) -> float:
        """Return the running standard deviation of the change from the baseline [N m]."""
        return math.sqrt(self._var)

    @property
    def undetectable_change(self) -> dict[str, float]:
        """
        Return, per cause, the largest relative change the detection does not see.

        A change delta of cause j feeds every cause i's CUSUM delta C_ij / n_i less the
        margin taken off the change (``cusum_baseline_sigmas`` times the RMS of the
        baseline's prediction std, and the oil allowance's mean over the windows since)
        times at most r_i / n_i: n_i the RMS of s_i over commissioning's points, C the mean
        of s s^T over the recent ones (the isolation's memory), r_i = sqrt(C_ii). Below the
        allowance k no sum moves: the least of (k n_i + m r_i) / |C_ij|. On commissioning's
        points that is the own sum's (k + m) / n_j; on a pump commissioned cold and running
        warm the valve plate's film shear is a quarter of what it was and the figure grows
        (x1.08 to x1.35-1.40 on the bank's seed-2 cold start). A reported scale holds it in
        its interval while no change is under way. Zero before the baseline is learnt; 1e6
        for a change that moves no sum.

        Returns
        -------
        dict
            Cause (`attribution.DETECTED_CAUSES`) -> relative change [-] (torque offset and drive
            loss: [N m]).

        """
        return dict(zip(DETECTED_CAUSES, self._undetectable.tolist(), strict=True))

    @property
    def oil_note(self) -> str:
        """Return why an allowance has no effect, the oil followed or seen moving, or ''."""
        baseline = self.baseline
        notes = (self._oil.note(math.nan if baseline is None else baseline.temperature_c,
                                baseline is not None) if self._oil is not None else '',
                 *(f.note() for f in (self._follow, self._gain_follow) if f is not None),
                 "the oil was seen moving without temperature topic: the friction scales' "
                 'intervals hold the healthy level anywhere within the change the detection '
                 'does not see' if baseline is not None and self.oil_moved else '')
        return '; '.join(x for x in notes if x)

    @property
    def oil_moved(self) -> bool:
        """
        Return whether the healthy friction level now is known only within the unseen change.

        Returns
        -------
        bool
            Without temperature topic and band, the oil was seen to move: commissioning
            restarted (its halves disagreed), so did the check after a start or a pause
            (``warm_up_hold``), or the baseline followed a fall
            (`healthy_level.oil_seen_moving`).

        """
        band = self._oil.band_c if self._oil is not None else 0.0
        follows = self._follow.times if self._follow is not None else 0
        moved = self._hold.moved if self._hold is not None else 0
        return oil_seen_moving(self._follow is not None, band,
                               self.commissioning.restarts + moved, follows)

    @property
    def hold_released_s(self) -> float:
        """Return when the last hold after a start or a pause ended [s] (NaN: none)."""
        return self._hold.released_s if self._hold is not None else math.nan

    @property
    def held(self) -> str:
        """Return why the detection waits after a start or a pause, or '' (``warm_up_hold``)."""
        return self._hold.status() if self._hold is not None and self.baseline is not None \
            else ''

    @property
    def baseline_temperature_c(self) -> float:
        """
        Return the oil temperature the healthy baseline was learnt at [degC].

        Returns
        -------
        float
            The running-weighted mean over its windows (``Baseline.temperature_c``); NaN
            before it is learnt or without temperature topic.

        """
        return self.baseline.temperature_c if self.baseline is not None else math.nan

    def oil_temperature_c(self, viscosity_m2_s: float) -> float:
        """
        Return the oil temperature at a viscosity, by the oil's law [degC].

        Parameters
        ----------
        viscosity_m2_s : float
            An estimate's viscosity [m^2/s].

        Returns
        -------
        float
            The temperature the oil's Walther law gives it (`OilAllowance.temperature_c`);
            NaN where the viscosity is assumed (no temperature topic).

        """
        return self._oil.temperature_c(viscosity_m2_s) if self._oil is not None else math.nan

    @property
    def measurement_drift_per_k(self) -> float:
        """Return the learnt drift of the torque against the pressure (``gain_follow``) [1/K]."""
        return math.nan if self._gain_follow is None else self._gain_follow.drift_per_k

    @property
    def learning(self) -> bool:
        """Whether the healthy baseline is still being learnt (no alarm meanwhile)."""
        return self.baseline is None

    def baseline_status(self) -> str:
        """Return the baseline's state in words (for /diagnostics)."""
        if self.baseline is None:
            return (f'{self.commissioning.status()}; no alarm until then, the scales are '
                    'the pump against the model')
        return f'baseline learnt over {self.baseline.learnt_s:.0f} s of monitored running'

    def verdict(self, side: float) -> tuple[str, str]:
        """
        Return what explains the change on one side of the baseline, and the phrase.

        Parameters
        ----------
        side : float
            +1: torque above the baseline, -1: below.

        Returns
        -------
        tuple of str
            (`attribution.Verdict` value, explanation for the status message).

        """
        if self.baseline is None:
            return Verdict.NONE, self.baseline_status()
        verdict, words, _ = self.isolation.verdict()
        return verdict, words
