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

So it is learnt where it shows: when the detection would alarm and the isolation names
the torque gain or the pressure gain (a cause merely close behind the one named is not
enough: on the bank's warm-up family, seed 0, a torque offset of +0.2 N m, the pressure
gain within the lead, was taken as 0.52-0.59e-3 / K of drift and its detection delayed
from 2.5 and 3.4 to 9.3 and 13.7 s of monitored running), the change has the drift's sign
(the torque reads high against the pressure when warmer than commissioning, low when
cooler), and the coefficients stay within ``torque_constant_drift_max_per_k`` together, the
gain's coefficient takes the change over T - T_0 (``follow``), the baseline follows
c (T - T_0) from then on (``term_nm``: warmer and cooler alike, so oil cooling back reads
healthy) and detection starts afresh: no alarm, and /diagnostics says what was learnt
(``note``). A change the other way (a torque constant reading low as the oil warms), one
larger than the largest drift, and any friction change are never followed: they stay what
the monitor judges. Without the temperature topic the oil's temperature is not known, and
nothing here acts (the fixed ``torque_constant_drift_per_k`` allowance, ``oil_allowance``,
may).
"""

from __future__ import annotations

import math

import numpy as np

from .attribution import CAUSES, FaultIsolation, Verdict

__all__ = ['GainFollow']

_GAINS = (CAUSES.index('torque_gain'), CAUSES.index('pressure_gain'))
"""The causes that drift: a torque gain g reads the torque (1 + g) high, a pressure gain p
the pressure (1 + p) high, which reads the torque low against it."""
_READS_HIGH = (1.0, -1.0)
"""The sign of each gain's change that reads the torque high against the pressure."""


class GainFollow:
    """
    The measurement gains' temperature coefficients learnt after commissioning.

    Parameters
    ----------
    max_per_k : float
        ``torque_constant_drift_max_per_k``: the largest drift learnt, both gains together
        [1/K].

    """

    def __init__(self, max_per_k: float) -> None:
        self.max_per_k = max_per_k
        self.reset()

    def reset(self) -> None:
        """Forget the learnt drift (a new baseline)."""
        self.per_k = np.zeros(len(_GAINS))
        """The learnt coefficients of the torque and the pressure gain [1/K]: each gain is
        its coefficient times (T - T_0); the torque reads high by their difference."""
        self.times = 0
        """Changes followed since the baseline was learnt."""

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
        return term if math.isfinite(term) else 0.0

    def follow(self, isolation: FaultIsolation, temperature_c: float,
               reference_c: float) -> bool:
        """
        Learn the change the isolation finds if it is the measurement's drift; return whether.

        Parameters
        ----------
        isolation : FaultIsolation
            The isolation of the change the detection alarms on.
        temperature_c : float
            The oil temperature now [degC].
        reference_c : float
            Commissioning's mean oil temperature T_0 [degC].

        Returns
        -------
        bool
            True where the change was learnt as drift (`per_k` updated); False where the
            alarm stands.

        """
        delta_c = temperature_c - reference_c
        verdict, _, named = isolation.verdict()
        if not (math.isfinite(delta_c) and delta_c) or verdict != Verdict.NOT_FRICTION:
            return False
        if named not in _GAINS:  # an offset or a drive loss is no drift, however close
            return False
        i = _GAINS.index(named)
        line = isolation.moving(named)
        step = (line[0] if line is not None else float(isolation.evidence()[1][named])) / delta_c
        per_k = self.per_k.copy()
        per_k[i] += step
        if not (_READS_HIGH[i] * step > 0.0 and float(per_k @ _READS_HIGH) <= self.max_per_k):
            return False
        self.per_k = per_k
        self.times += 1
        return True

    def note(self) -> str:
        """Return the drift learnt, or '' (for /diagnostics)."""
        if not self.times:
            return ''
        times = 'once' if self.times == 1 else f'{self.times} times'
        return ('measured torque against pressure follows the oil temperature: '
                f"{self.drift_per_k * 1e3:.2f} x 1e-3 / K learnt ({times}) as the drive's "
                'torque constant (or the pressure sensor) drifting, not a fault')

    def state(self) -> dict[str, object]:
        """Return the learnt drift as plain values."""
        return {'torque_gain_per_k': float(self.per_k[0]),
                'pressure_gain_per_k': float(self.per_k[1]), 'times': self.times}

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
            A coefficient of the wrong sign or not finite, or a negative count.

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
        self.per_k, self.times = per_k, times
