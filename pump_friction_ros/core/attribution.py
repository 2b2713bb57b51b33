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
Which single change from the healthy baseline explains the extra torque: a GLR per cause.

After commissioning (``baseline``) a fault is usually one change. Each candidate cause j
moves a window's residual from its healthy prediction by d = delta_j s_j, with s_j its
signature over the window's operating point (friction direction, N m per unit change):

==================  ===========================================  =====================
cause               signature s_j                                delta_j
==================  ===========================================  =====================
valve_plate         healthy valve-plate friction l_vp T_vp       relative change [-]
other_friction      healthy other friction l_o T_o               relative change [-]
torque_gain         healthy T_th s + friction + L + J a s        relative gain [-]
pressure_gain       -T_th s (a pressure read (1 + g) too high)   relative gain [-]
torque_offset       s (does not turn with the motion)            [N m]
drive_loss          1 (opposes the motion)                       [N m]
spherical_joints    healthy joints' friction l_o T_j             relative change [-]
==================  ===========================================  =====================

(l_vp = 1 + b_vp and l_o = 1 + b_o from the baseline: a change relative to the healthy
pump.)

The spherical joints are a cause of the isolation only, their change fitted over delta >= -1
(``causes``).

Over the windows since the change (those since the alarmed CUSUM last left zero, with
a memory of ``isolation_memory_s``), each weighted by its inverse noise variance, the
generalised likelihood ratio of cause j against no change is T_j = (sum s_j d)^2 / sum s_j^2
(Basseville & Nikiforov 1993, ch. 7; Isermann 2006, ch. 15). The largest names the cause
when it stands out (T_j >= z^2) and leads the runner-up k by z^2 in T (a likelihood ratio of
exp(z^2 / 2)). The noise variance in T is scaled by the lack of fit of the best single cause
(an F-test: systematic model error is not white noise and must not pass for evidence). Where
the lead is short and s_j and s_k are collinear over the points seen (|cos| >=
``identifiability_correlation``) these data cannot tell them apart and the verdict says so,
naming both; where they are not collinear, more running will. A change of the oil's
viscosity scales the valve plate's film shear exactly like wear, and the bearing's drag
with it: with the viscosity a parameter the friction verdicts read "valve plate or oil
viscosity" and "other friction or oil viscosity"; with the temperature topic the model
follows the viscosity and they do not.

The relative change delta_j = sum s_j d / sum s_j^2 is reported with its standard
deviation (1 / sqrt(sum s_j^2 w)), the baseline's uncertainty in l (its relative std in
quadrature with ``level_systematic_std``: the pump is not its model, and the friction levels
commissioning learnt carry that error, times the change) and a floor
``scale_systematic_std``: systematic model error does not average away with more windows.
A friction cause's change is fitted together with a torque-constant drift too small to have
been learnt (``drift_nuisance``), where the temperature topic makes one possible. Which
friction changed (their signatures correlate 0.97-0.99 on a load-driven cycle) is told
with each one's change a line in time, against the drift alone and against the drift and a
friction bias the baseline had before the change (``friction_bias``), and named only where
both fits name it (``friction_choice``). The reported scales (`FaultIsolation.scales`)
span what the data do not rule out: a change still moving (a line through it over the
memory, `FaultIsolation.moving`) up to its present value, and, until one cause is
confirmed, no change as well as the change that the detection does not see.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from .baseline import Baseline
from .causes import CAUSES, CLASS as _CLASS, DETECTED_CAUSES, LOWEST as _LOWEST, Verdict
from .change_episodes import ChangeEpisodes
from .change_stats import ChangeStats
from .drift_nuisance import DriftNuisance
from .friction_bias import FrictionBias, Z95  # a reported scale's std: its 95 % half-width / Z95
from .friction_choice import choose_friction
from .healthy_level import interval, with_unseen_level
from .isolation_state import isolation_state, IsolationSums, read_isolation_state
from .signatures import signature_matrix  # (the isolation's: exported here)
from .verdict_words import friction_named, FRICTIONS, with_oil, WORDS as _WORDS

__all__ = ['CAUSES', 'DETECTED_CAUSES', 'AttributionSettings', 'FaultIsolation', 'Verdict',
           'signature_matrix']

_VP, _OTHER, _JOINTS = 0, 1, CAUSES.index('spherical_joints')
_GAINS = (CAUSES.index('torque_gain'), CAUSES.index('pressure_gain'))
_N = len(CAUSES)
MIN_LEVEL = 0.2
"""The uncertainty of a reported scale divides by the learnt friction level; a level below
this times the model's is taken at it (a guard of the division, not a figure of the pump)."""


@dataclass(frozen=True)
class AttributionSettings:
    """The node parameters the baseline and the isolation use (``node_parameters``)."""

    attribution_window_s: float
    scale_prior_std: float
    offset_prior_std_nm: float
    torque_gain_prior_std: float
    inertia_prior_std_kg_m2: float
    attribution_z: float
    identifiability_correlation: float
    isolation_memory_s: float
    isolation_episode_lack_of_fit: float
    scale_systematic_std: float
    level_systematic_std: float


def _evidence(stats: ChangeStats) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return T_j, delta_j and its std on these sums (`FaultIsolation.evidence`)."""
    gjj = np.diag(stats.g)
    ok = gjj > 0.0
    safe, t = np.where(ok, gjj, 1.0), stats.glr()
    # an F-test rather than a chi-square: the noise scaled by how badly even the best
    inflation = stats.lack_of_fit()  # single cause fits (model error is not white noise)
    delta = np.where(ok, np.maximum(stats.b / safe, stats.lowest), math.nan)
    std = np.where(ok, np.sqrt(inflation / safe), math.nan)
    return t / inflation, delta, std


class FaultIsolation:
    """
    GLR of the single causes on the windows since the change.

    Parameters
    ----------
    settings : AttributionSettings
        ``attribution_z``, ``identifiability_correlation``, ``isolation_memory_s``,
        ``isolation_episode_lack_of_fit``, ``scale_systematic_std``,
        ``level_systematic_std``.
    viscosity_assumed : bool
        The viscosity is a parameter (no temperature topic): a friction change may be the
        oil's.

    """

    def __init__(self, settings: AttributionSettings, viscosity_assumed: bool) -> None:
        self.settings = settings
        self.viscosity_assumed = viscosity_assumed
        self.stats = ChangeStats(_N, _LOWEST)
        # the windows that show the change: one that comes and goes (change_episodes)
        self.episodes = ChangeEpisodes(_N, settings.isolation_episode_lack_of_fit,
                                       settings.attribution_z, _LOWEST)
        self.drift = DriftNuisance(_N)  # a k_t drift too small to learn (drift_nuisance)
        self.bias = FrictionBias()  # what the baseline mispredicted before the change

    def reset(self) -> None:
        """Forget every window."""
        self.stats.clear()
        self.episodes.clear()
        self.drift.reset()
        self.bias.reset()

    def add(self, s: np.ndarray, d_nm: float, weight: float, duration_s: float,
            changing: bool, drift_nm: float = 0.0, oil_nm: float = 0.0,
            joints_nm: float = 0.0) -> None:
        """
        Add one window, or forget the windows when no change is under way.

        Parameters
        ----------
        s : ndarray
            Signatures of the window of `DETECTED_CAUSES` (``signature_matrix @ h``).
        d_nm : float
            Its residual minus the baseline's prediction [N m].
        weight : float
            Its inverse noise variance [1/N m^2].
        duration_s : float
            Its monitored running [s] (the memory's clock).
        changing : bool
            A CUSUM of the monitor is above zero after this window: the window belongs to
            the change; otherwise the sums start afresh.
        drift_nm : float
            The signature of a torque-constant drift not learnt: (T - T_0) times the
            torque gain's [N m / (1/K)] (0 or NaN: none possible, or the temperature not
            known).
        oil_nm : float
            The friction change of the oil's band at this window, where the viscosity is
            assumed (``oil_allowance``; 0: none) [N m]: the intervals span it (`scales`).
        joints_nm : float
            The spherical joints' signature (``signatures.joints_signature``) [N m per
            unit] (0: none, the joints never named).

        """
        s = np.append(s, joints_nm)
        keep = math.exp(-duration_s / self.settings.isolation_memory_s)
        self.drift.add(s, drift_nm, d_nm, weight, keep, changing, duration_s)
        self.bias.add(s, drift_nm, d_nm, weight, keep, changing, duration_s)
        if not changing:
            self.stats.clear()
            self.episodes.clear()
            return
        self.stats.add(s, d_nm, weight, keep, duration_s, oil_nm)
        self.episodes.add(self.stats, s, d_nm, weight, keep, duration_s)

    def evidence(self, shown: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Return the GLR statistic, the change and its std of each cause since the change.

        Parameters
        ----------
        shown : bool
            On the windows that show the change only (``change_episodes``), not every one.

        Returns
        -------
        tuple of ndarray
            T_j [-], delta_j, std of delta_j (noise and lack of fit) (`CAUSES` order; NaN
            where the windows carry no signature). T_j and the std are scaled by the lack of
            fit of the best single cause, so that model error does not pass for evidence.

        """
        return _evidence(self.episodes.on if shown else self.stats)

    def comes_and_goes(self) -> bool:
        """
        Return whether the change comes and goes (``change_episodes``).

        Returns
        -------
        bool
            The windows that show the change come in runs (a runs test at
            ``attribution_z``) and fit ``isolation_episode_lack_of_fit`` times better than
            every window, whose fit leaves at least that times the noise.

        """
        return bool(self.stats.windows) and self.episodes.applies(self.stats)

    def friction_change(self, j: int) -> tuple[float, float]:
        """
        Return a friction cause's change and its std, a drift too small to be learnt fitted too.

        Returns
        -------
        tuple of float
            delta_j and its std (noise and the best single cause's lack of fit, as
            `evidence`) [-]; (NaN, NaN) where the windows carry no signature of j.

        """
        stats = self.stats
        if not stats.g[j, j] > 0.0:
            return math.nan, math.nan
        delta, var = self.drift.change(j, stats.g, stats.b)
        return delta, math.sqrt(stats.lack_of_fit() * var)

    def moving(self, j: int) -> tuple[float, float, float] | None:
        """
        Return cause j's change as it is now where it still moves, else None.

        Moving: the slope of a line through the change over the memory
        (`ChangeStats.trend`, with a drift too small to be learnt where one is possible) is
        significant at ``attribution_z``.

        Returns
        -------
        tuple of float or None
            The change now, its variance, the slope's z score (negative: rising) [-].

        """
        line = self.stats.trend(j, self.drift.line_sums(j))
        z = self.settings.attribution_z
        return line if line is not None and line[2] * line[2] >= z * z else None

    def verdict(self) -> tuple[str, str, int]:
        """
        Return what explains the change, in words, and the cause named.

        Returns
        -------
        tuple
            (`Verdict` value, phrase for the status message, index into `CAUSES` of the
            cause named or -1).

        """
        verdict, words, named, _ = self._reading()
        return verdict, words, named

    def may_be_measurement(self) -> bool:
        """
        Return whether the change may be the torque measurement's or the pressure sensor's.

        Returns
        -------
        bool
            The verdict is not friction, or cannot tell a gain from the spherical joints
            (one signature where the pump only drives the load): a drift of the gain with
            the oil temperature may still explain it (``gain_follow`` tells by its time
            course, which a step of the joints does not have).

        """
        verdict, _, _, pair = self._reading()
        return verdict == Verdict.NOT_FRICTION or (
            verdict == Verdict.CANNOT_TELL and _JOINTS in pair and any(g in pair for g in _GAINS))

    def _reading(self) -> tuple[str, str, int, tuple[int, ...]]:
        """Return `verdict`'s tuple and, where it cannot tell two causes apart, their indices."""
        stats = self.stats
        if not stats.windows:
            return Verdict.NONE, 'no change from the baseline', -1, ()
        # a change that comes and goes, read on the windows that show it (change_episodes)
        # to tell which friction; a split naming none is not taken (test_friction_line)
        episodic = self.comes_and_goes() and \
            int(np.argmax(np.nan_to_num(self.evidence(True)[0], nan=-1.0))) in (_VP, _OTHER)
        if episodic:
            stats = self.episodes.on
        t, delta, _ = self.evidence(episodic)
        z2, assumed = self.settings.attribution_z ** 2, self.viscosity_assumed
        order = [int(i) for i in np.argsort(-np.nan_to_num(t, nan=-1.0))]
        j, k = order[0], order[1]
        if not t[j] >= z2:
            return Verdict.NONE, 'no single cause stands out yet', -1, ()
        if {j, k} == {_OTHER, _JOINTS} and not t[j] - t[k] >= z2:
            # the joints are a part of the other friction: where the two lead together, the
            # other friction is named, its lead taken over the next cause
            j, k = _OTHER, order[2]
        g = stats.g
        cos = float(g[j, k] / math.sqrt(g[j, j] * g[k, k])) if g[k, k] > 0.0 else 0.0
        close = not t[j] - t[k] >= z2
        tied = close and abs(cos) >= self.settings.identifiability_correlation
        if close and _CLASS[j] == _CLASS[k] == Verdict.NOT_FRICTION:
            return (Verdict.NOT_FRICTION, f'not friction: {_WORDS[CAUSES[j]]} or '
                    f'{_WORDS[CAUSES[k]]}', j, ())
        if not episodic and j in (_VP, _OTHER) and (not close or k in (_VP, _OTHER)):
            # friction: which one is told with a k_t drift too small to be learnt profiled
            # out, as its size is (the same as above where the drift carries nothing)
            choice = choose_friction(stats, self.drift, self.bias, t)
            j, k, t, cos = choice.first, choice.second, choice.t, choice.cos
            split = choice.split
            if split is not None and max(abs(split[0] - split[1]), abs(split[2] - split[3])) >= z2:
                return (Verdict.CANNOT_TELL, with_oil(
                    f'{_WORDS[CAUSES[_VP]]} or {_WORDS[CAUSES[_OTHER]]}: the choice turns on '
                    'whether the baseline was already off before the change (evidence: valve '
                    'plate {:.0f} against other friction {:.0f} with that bias fitted, {:.0f} '
                    'against {:.0f} without)'.format(*split), FRICTIONS, assumed), -1,
                    (_VP, _OTHER))
            close = not t[j] - t[k] >= z2
            tied = close and abs(cos) >= self.settings.identifiability_correlation
        pair = (CAUSES[j], CAUSES[k])
        if tied:
            parted = ''
            if _JOINTS in (j, k) and any(i in _GAINS for i in (j, k)):
                parted = ': running that both drives and overruns the load tells them apart'
            return (Verdict.CANNOT_TELL, with_oil(
                f'cannot tell {_WORDS[pair[0]]} from {_WORDS[pair[1]]} on this duty cycle '
                f'(signatures correlated {cos:+.3f} over the points seen{parted})', pair,
                assumed), -1, (j, k))
        if close:
            return (Verdict.CANNOT_TELL, with_oil(
                f'{_WORDS[pair[0]]} or {_WORDS[pair[1]]}: not yet told apart (evidence '
                f'{t[j]:.0f} against {t[k]:.0f})', pair, assumed), -1, (j, k))
        episodes = ''
        if episodic:
            episodes = (f'it comes and goes, shown in {100.0 * self.episodes.fraction():.0f} '
                        "% of the change's windows")
        if _CLASS[j] == Verdict.NOT_FRICTION:
            size = f'{delta[j]:+.3g}' + (' N m' if CAUSES[j] in ('torque_offset', 'drive_loss')
                                         else '')
            return _CLASS[j], f'not friction: {_WORDS[CAUSES[j]]} {size}' + (
                f' while it shows ({episodes})' if episodic else ''), j, ()
        scale = f'scale {1.0 + self.friction_change(j)[0]:.2f} of healthy'
        if episodic:  # a line through on and off means nothing: its size while it shows
            scale += f', {1.0 + delta[j]:.2f} while it shows: {episodes}'
        else:
            line = self.moving(j)
            if line is not None:
                scale += (f', {1.0 + line[0]:.2f} now and '
                          f'{"rising" if line[2] < 0.0 else "falling"}')
        return _CLASS[j], friction_named(CAUSES[j], scale, assumed), j, ()

    def scales(self, baseline: Baseline, undetectable: np.ndarray, confirmed: bool,
               oil_moved: bool = False) -> tuple[float, float, float, float]:
        """
        Return the valve-plate and other friction scales relative to healthy, with stds.

        Each interval (scale +- 1.96 std, 95 %) spans the changes the data do not rule out:

        * the cause the verdict names, once the change is confirmed (WARN or ERROR): its
          change (`friction_change`: a torque-constant drift too small to be learnt fitted
          with it) +- 1.96 std (noise and lack of fit; the baseline's uncertainty of the
          level, its relative std in quadrature with ``level_systematic_std``, times the
          change; the floor ``scale_systematic_std``); where the change still moves (the
          slope of a line through it over the memory is significant at ``attribution_z``)
          the span reaches the line's present value too: a wear still growing is larger
          now than the memory's mean;
        * another cause named: no change, +- 1.96 times the std its own fit would have;
        * two causes that cannot be told apart: from no change to this cause's estimate;
        * a change not confirmed yet (level OK) or that no single cause stands out in: 1
          (no change confirmed), the interval reaching this cause's estimate and any
          change the detection does not see (``undetectable``: a change that the CUSUM
          allowance and the baseline's margin absorb);
        * no change under way (every CUSUM at zero): 1, the interval spanning any change
          the detection does not see. A fault below it is there, unseen: a scale of 1 +-
          the floor alone would claim that it is not.

        In every case but another cause named, where the viscosity is assumed and the oil
        has a band (``oil_temperature_band_c``), each end of the fit's span (and of the
        line's) first moves out by what an oil anywhere in the band moves it
        (`ChangeStats.oil_bias`): the reading is the valve plate's or the oil's, and the
        interval must hold the valve plate's. Where no band is stated and the oil was seen
        to move (``oil_moved``), every interval holds each healthy level within ``undetectable``
        (at >= 1, a level that may be nothing: the change as read, std ``inf``).

        Parameters
        ----------
        baseline : Baseline
            The healthy signature (the uncertainty of its friction levels).
        undetectable : ndarray
            Per cause (`CAUSES` order), the largest relative change the detection does not
            see on this duty cycle [-] (``WearMonitor.undetectable_change``).
        confirmed : bool
            The monitor is at WARN or ERROR.
        oil_moved : bool
            The healthy level now is known only within ``undetectable`` (`healthy_level`).

        Returns
        -------
        tuple of float
            Valve-plate scale, its std, other scale, its std [-].

        """
        floor = self.settings.scale_systematic_std
        out: list[float] = []
        if not self.stats.windows:
            for i in (_VP, _OTHER):
                half, u = max(Z95 * floor, float(undetectable[i])), float(undetectable[i])
                out += [1.0, with_unseen_level(-half, half, u * oil_moved)[1] / Z95]
            return out[0], out[1], out[2], out[3]
        verdict, _, named = self.verdict()
        if named == _JOINTS:  # a part of the other friction: its own fit spans their change
            named = _OTHER
        level_std, coef = baseline.std(), baseline.coefficients
        for i in (_VP, _OTHER):
            delta, std = self.friction_change(i)
            noise = std if std == std else 1.0
            u = float(undetectable[i]) if oil_moved else 0.0  # the healthy level's range
            if confirmed and named >= 0 and named != i:  # another cause explains it
                half = Z95 * math.hypot(noise, floor)
                out += [1.0, with_unseen_level(-half, half, u)[1] / Z95]
                continue
            # the baseline's uncertainty of the friction level, relative to it
            level = max(1.0 + float(coef[i]), MIN_LEVEL)
            level_rel_std = math.hypot(float(level_std[i]) / level,
                                       self.settings.level_systematic_std)
            change = delta if delta == delta else 0.0
            low, high = interval(change, noise * noise + floor * floor, level_rel_std)
            oil, oil_now = self.stats.oil_bias(i)
            if oil > 0.0:  # the oil anywhere in its band
                low, high = low - oil, high + oil
            point = change  # published (std inf) where the range has no upper end
            if confirmed and named == i:
                line = self.moving(i)
                if line is not None:
                    now_low, now_high = interval(line[0], line[1] + floor * floor, level_rel_std)
                    if oil_now > 0.0:
                        now_low, now_high = now_low - oil_now, now_high + oil_now
                    low, high = min(low, now_low), max(high, now_high)
            elif confirmed and verdict == Verdict.CANNOT_TELL:
                low, high = min(0.0, low), max(0.0, high)
            else:  # no change confirmed: 1, +- whatever might be there
                high, point = max(-low, high, float(undetectable[i])), 0.0
                low = -high
            middle = 0.5 * (low + high)  # as read, +- what holds it over the levels within u
            low, high = with_unseen_level(low, high, u)
            out += [1.0 + middle, max(high - middle, middle - low) / Z95] if math.isfinite(
                high) else [1.0 + point, math.inf]  # healthy level unknown: no upper end
        return out[0], out[1], out[2], out[3]

    def state(self) -> dict[str, object]:
        """Return the sums as plain values (``isolation_state``)."""
        return isolation_state(IsolationSums(self.stats, self.drift, self.bias, self.episodes))

    def load(self, state: dict[str, object]) -> None:
        """
        Restore `state`'s sums, of this release or an older one (``isolation_state``).

        Parameters
        ----------
        state : dict
            A `state` result.

        Raises
        ------
        ValueError
            Missing or malformed sums.

        """
        sums = read_isolation_state(state, IsolationSums(self.stats, self.drift, self.bias,
                                                         self.episodes))
        self.stats, self.drift, self.bias, self.episodes = (sums.stats, sums.drift, sums.bias,
                                                            sums.episodes)
