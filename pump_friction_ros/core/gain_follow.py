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
With the temperature topic, the baseline learns the torque measurement's drift with it.

Torque from current reads k_t i with the k_t of one temperature. A permanent magnet loses
remanence as it warms (NdFeB 0.08-0.13 %/K, ferrite about 0.2 %/K), the real k_t falls, the
drive draws more current for the same torque, and the measured torque reads high by
c (T - T_0) of itself: a torque-measurement gain change that follows the temperature. On a
cold start it is 3-5 % by the time the oil is warm (seed 1 of the bank, installation 1:
0.94e-3 / K, commissioned at 20 degC, ERROR "not friction: torque-measurement gain +0.023"
as the oil passed 50 degC; docs/monitor.md). Commissioning sees a few kelvin of it, far too
few to fit c (it would be extrapolated tenfold). The node sees the measured torque only
against the theoretical one from the pressure, so the same drift may show as a
pressure-sensor gain reading low (the two signatures differ by the friction's part alone,
which the true pump's viscous friction, not quite the model's, blurs: on that installation
some runs' alarms named the pressure-sensor gain, -0.017, others the torque gain).

So it is learnt where it shows, and only where a drift explains it. When the detection
would alarm on a change that is not friction, two one-parameter fits of the same windows
are compared (``_drift_fit``): a drift, c (T - T_0) times a gain's signature, over every
window in the isolation's memory (``add``), and a step of one cause over the windows since
the CUSUMs left zero, nothing before. A drift grows with the warming and shows, within the
allowance, before the detection sees it; a step is nothing before it began. The drift must
explain the windows better than every step by ``attribution_z`` squared, as the isolation
asks of a cause it names. That tells apart what the isolation of steps cannot:

* a drift read as an offset: on a load-driven cycle the offset's signature shadows a
  gain's (correlated -0.98 on seed 1's cold start, installation 1, which named the offset
  by 1631 against 1589 while its drive drifted 0.94e-3 / K);
* a step read as a drift: the rules before (learn where the isolation names a gain, or
  where one is within its lead) took a torque gain of +2-3 % on the warm pump as
  0.6-0.9e-3 / K and never alarmed, and on the bank's warm-up family, seed 0, a torque
  offset of +0.2 N m as 0.52-0.59e-3 / K, its detection delayed from 2.5 and 3.4 to 9.3 and
  13.7 s of monitored running (test_gain_follow pins a gain step and an offset on the warm
  pump, and a drift the isolation reads as an offset).

The change must also have the drift's sign (the torque reads high against the pressure when
warmer than commissioning, low when cooler), and the coefficients stay within
``torque_constant_drift_max_per_k`` together. Then the gain's coefficient takes the fitted c
(``follow``), the baseline follows c (T - T_0) from then on (``term_nm``: warmer and cooler
alike, so oil cooling back reads healthy) and detection starts afresh: no alarm, and
/diagnostics says what was learnt (``note``). A change the other way (a torque constant
reading low as the oil warms), one larger than the largest drift, and any friction change
are never followed: they stay what the monitor judges, and nothing is learnt while the
alarm under way was named a friction at its height (an intermittent fault's off episodes
read "not friction"; its alarm clears on its own). Without the temperature topic the
oil's temperature is not known, and nothing here acts (the fixed
``torque_constant_drift_per_k`` allowance, ``oil_allowance``, may).
"""

from __future__ import annotations

import math

import numpy as np

from .attribution import CAUSES, FaultIsolation, Verdict
from .baseline import read_sums

__all__ = ['GainFollow']

_GAINS = (CAUSES.index('torque_gain'), CAUSES.index('pressure_gain'))
"""The causes that drift: a torque gain g reads the torque (1 + g) high, a pressure gain p
the pressure (1 + p) high, which reads the torque low against it."""
_READS_HIGH = (1.0, -1.0)
"""The sign of each gain's change that reads the torque high against the pressure."""
_FRICTIONS = (Verdict.VALVE_PLATE, Verdict.OTHER_FRICTION)
"""The verdicts that name a friction: an alarm that named one is not a drift to learn."""


class GainFollow:
    """
    The measurement gains' temperature coefficients learnt after commissioning.

    Parameters
    ----------
    max_per_k : float
        ``torque_constant_drift_max_per_k``: the largest drift learnt, both gains together
        [1/K].
    memory_s : float
        ``isolation_memory_s``: the windows the drift is fitted on are forgotten as the
        isolation's are [s].

    """

    def __init__(self, max_per_k: float, memory_s: float) -> None:
        self.max_per_k = max_per_k
        self._memory_s = memory_s
        self.reset()

    def reset(self) -> None:
        """Forget the learnt drift (a new baseline)."""
        self.per_k = np.zeros(len(_GAINS))
        """The learnt coefficients of the torque and the pressure gain [1/K]: each gain is
        its coefficient times (T - T_0); the torque reads high by their difference."""
        self.times = 0
        """Changes followed since the baseline was learnt."""
        self.clear()

    def clear(self) -> None:
        """Forget the windows the drift was fitted on."""
        self._g = np.zeros(len(_GAINS))  # each drift signature's weighted square sum
        self._b = np.zeros(len(_GAINS))  # and its weighted product with the change

    def add(self, signatures: np.ndarray, d_nm: float, weight: float, duration_s: float,
            delta_c: float) -> None:
        """
        Add one window to the drift's fit, the change's and the ones before it alike.

        A drift shows, within the allowance, before the detection sees it, and it grows
        with T - T_0; a step is nothing before it began. So the fit spans every window in
        the isolation's memory, not only those since the CUSUMs left zero.

        Parameters
        ----------
        signatures : ndarray
            The window's signatures of the causes [N m].
        d_nm : float
            Its change from the baseline, the learnt drift taken off [N m].
        weight : float
            Its inverse noise variance [1/N m^2].
        duration_s : float
            Its monitored running [s] (older windows weigh exp(-age / memory)).
        delta_c : float
            Its oil temperature less commissioning's, T - T_0 [K] (NaN: not known; the
            window then tells the drift nothing).

        """
        u = np.array([float(signatures[j]) for j in _GAINS]) * delta_c
        if not (np.all(np.isfinite(u)) and math.isfinite(d_nm * weight)):
            u = np.zeros(len(_GAINS))  # the window tells the drift nothing, it only ages
        keep = math.exp(-duration_s / self._memory_s)
        self._g = keep * self._g + weight * u * u
        self._b = keep * self._b + weight * d_nm * u

    @property
    def drift_per_k(self) -> float:
        """Return the learnt drift: the torque reads this times (T - T_0) high [1/K]."""
        return float(self.per_k @ _READS_HIGH)

    def term_nm(self, signatures: np.ndarray, temperature_c: float,
                reference_c: float) -> float:
        """
        Return the learnt drift's part of a window's residual [N m].

        Parameters
        ----------
        signatures : ndarray
            The window's signatures of the causes (``attribution.signature_matrix`` times
            its regressors) [N m].
        temperature_c : float
            Its oil temperature [degC] (NaN: not known).
        reference_c : float
            Commissioning's mean oil temperature T_0 [degC] (NaN: not known).

        Returns
        -------
        float
            (T - T_0) times each gain's coefficient times its signature, summed; 0 where a
            temperature is not known.

        """
        per_k = self.per_k
        term = (temperature_c - reference_c) * (per_k[0] * float(signatures[_GAINS[0]])
                                                + per_k[1] * float(signatures[_GAINS[1]]))
        return float(term) if math.isfinite(term) else 0.0  # (a plain float: it is state)

    def follow(self, isolation: FaultIsolation, temperature_c: float, reference_c: float,
               alarm_verdict: str = Verdict.NONE) -> bool:
        """
        Learn the measurement's drift where it explains the change; return whether.

        Parameters
        ----------
        isolation : FaultIsolation
            The isolation of the change the detection alarms on.
        temperature_c : float
            The oil temperature now [degC] (NaN, or T_0 itself: nothing is learnt; the fit
            uses each window's own temperature).
        reference_c : float
            Commissioning's mean oil temperature T_0 [degC].
        alarm_verdict : str
            The verdict at the height of the alarm under way (`LastAlarm.verdict`; none
            before its first window): where it named a friction, nothing is learnt. An
            intermittent fault turns "not friction" in its off episodes (seed 2's cold
            start, installation 0: a valve plate 1.38 at the height, then a torque drift
            learnt that ended its alarm); the alarm clears instead as its CUSUM decays.

        Returns
        -------
        bool
            True where the drift was learnt (`per_k` takes the c fitted over the windows in
            memory); False where the alarm stands.

        """
        delta_c = temperature_c - reference_c
        if not (math.isfinite(delta_c) and delta_c) or alarm_verdict in _FRICTIONS or \
                not isolation.may_be_measurement():
            return False
        i, step = self._drift_fit(isolation)
        if i < 0:
            return False
        per_k = self.per_k.copy()
        per_k[i] += step
        if not (_READS_HIGH[i] * step > 0.0 and float(per_k @ _READS_HIGH) <= self.max_per_k):
            return False
        self.per_k = per_k
        self.times += 1
        self.clear()
        return True

    def _drift_fit(self, isolation: FaultIsolation) -> tuple[int, float]:
        """
        Return the gain whose drift clearly explains the windows better than any step.

        Both are one-parameter fits to the same windows: a drift c (T - T_0) times the
        gain's signature over all of them (`add`), a step of one cause over those since the
        change began (the isolation's), nothing before. Their GLR statistics b^2 / g, scaled
        by the best step's lack of fit as the isolation's are, must differ by
        ``attribution_z`` squared, as the isolation's verdict asks of a cause it names.

        Returns
        -------
        tuple
            The index into the gains (-1: no drift explains it clearly better) and the
            drift's coefficient fitted [1/K].

        """
        stats = isolation.stats
        ok = self._g > 0.0
        drifts = np.where(ok, self._b ** 2 / np.where(ok, self._g, 1.0), 0.0)
        i = int(np.argmax(drifts))
        lead = (float(drifts[i]) - stats.best_glr()) / stats.lack_of_fit()
        if not lead >= isolation.settings.attribution_z ** 2:
            return -1, 0.0
        return i, float(self._b[i] / self._g[i])

    def note(self) -> str:
        """Return the drift learnt, or '' (for /diagnostics)."""
        if not self.times:
            return ''
        times = 'once' if self.times == 1 else f'{self.times} times'
        return ('measured torque against pressure follows the oil temperature: '
                f"{self.drift_per_k * 1e3:.2f} x 1e-3 / K learnt ({times}) as the drive's "
                'torque constant (or the pressure sensor) drifting, not a fault')

    def state(self) -> dict[str, object]:
        """Return the learnt drift, and the sums of its fit over the windows, as plain values."""
        return {'torque_gain_per_k': float(self.per_k[0]),
                'pressure_gain_per_k': float(self.per_k[1]), 'times': self.times,
                'g': self._g.tolist(), 'b': self._b.tolist()}

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
            A coefficient of the wrong sign or not finite, a negative count, or malformed
            sums of the fit.

        """
        per_k = np.array([float(state[key]) for key in (  # type: ignore[arg-type]
            'torque_gain_per_k', 'pressure_gain_per_k')])
        times = int(state['times'])  # type: ignore[call-overload]
        if not (np.all(np.isfinite(per_k)) and np.all(per_k * _READS_HIGH >= 0.0)) \
                or times < 0:
            raise ValueError(f'gain follow coefficients {per_k.tolist()!r} or count {times!r}')
        # a largest drift lowered since: scaled down to it (the history is kept, not refused)
        drift = float(per_k @ _READS_HIGH)
        if drift > self.max_per_k:
            per_k *= max(self.max_per_k, 0.0) / drift
        # the fit's sums came later (a file without them: fitted from the next window on)
        n = len(_GAINS)
        (g, b), _ = read_sums(state, {'g': (n,), 'b': (n,)}, (), 'gain follow') \
            if 'g' in state or 'b' in state else ([np.zeros(n), np.zeros(n)], [])
        if np.any(g < 0.0):
            raise ValueError(f'gain follow square sums {g.tolist()!r}')
        if drift > self.max_per_k:  # the sums were of the change less the drift before
            g, b = np.zeros(n), np.zeros(n)
        self.per_k, self.times = per_k, times
        self._g, self._b = g, b
