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
Which term explains the extra torque: a Kalman filter on friction scales and offsets.

The friction part of the measured torque, in the friction direction (s = sign of the speed),

    y = (T_measured - T_theoretical - J a) s - L_0

is modelled as

    y = th_vp T_vp + th_o T_o + L + c s - g T_th s + noise

with T_vp the modelled valve-plate friction magnitude and T_o that of the other components
(shaft bearing, spherical joints, piston heads) together, L an
extra drive loss (opposes the motion, does not scale with friction), c a torque-sensor
offset (does not turn with the motion), g a pressure-sensor gain error (the theoretical
torque computed from a pressure read (1 + g) too high). The pump as modelled is
x0 = (1, 1, 0, 0, 0). The terms separate only where the duty cycle moves them
differently: both directions of rotation (c against L), pumping and motoring (g against
friction), and a range of speeds and pressures (valve plate, mostly viscous film shear,
against the bearing's load and viscous terms and the pistons' pressure-driven terms).
Where it does not, the posterior correlation of two terms nears +-1 and the verdict says
so instead of naming one. The other components share one scale on purpose: with a scale
each, the valve plate and the bearing (both mostly viscous above a few hundred rad/s)
could not be told apart on ordinary positioning cycles (posterior correlation -0.97 on
the sample duty cycle).

Samples are averaged over windows of ``attribution_window_s`` of monitored running (one
direction each); each window mean is one measurement. Its noise variance is NOT learnt
from the innovations, which would absorb the very bias to be found: it is the white part,
sigma^2 / n, with sigma^2 from the mean square successive difference of the residual
(insensitive to a slowly varying bias), plus a model error, ``model_error_ratio`` times
the modelled friction, independent from window to window. The states walk randomly
(``*_random_walk_*``) so that wear and drift are followed at any age of the filter.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

__all__ = ['TERMS', 'TERM_TABLE', 'AttributionSettings', 'FrictionAttribution', 'Verdict']

TERM_TABLE = (
    ('valve_plate', 'valve_plate_friction_scale', 0.0),
    ('other_friction', 'other_friction_scale', 0.0),
    ('drive_loss_nm', 'extra_drive_loss_nm', 0.0),
    ('torque_offset_nm', 'torque_offset_nm', 0.0),
    ('pressure_gain', 'pressure_sensor_gain_scale', 1.0),
)
"""
Each term of the filter's state, declared once: (name, /diagnostics key, added for the key).

Two friction scales [-], two torques [N m], a gain error g [-], reported as the gain 1 + g;
each key has a ``_std`` twin in /diagnostics.
"""
TERMS = tuple(name for name, _, _ in TERM_TABLE)
"""State of the filter, in `TERM_TABLE` order."""
_VP, _OTHER, _LOSS, _OFFSET, _GAIN = range(5)
_N = len(TERMS)
_NOT_FRICTION = (_LOSS, _OFFSET, _GAIN)
_MAX_PREDICT_S = 600.0
"""A pause longer than this [s] adds no more random-walk uncertainty than this one does
(the variances are capped at their priors anyway)."""
MIN_WINDOW_SAMPLES = 10
"""A window with fewer monitored samples (a short burst between reversals) is not a
measurement: its mean would carry more of the reversal than of the steady friction."""
WHITE_NOISE_GAIN = 0.001
"""Weight of each new successive difference in the running white-noise variance: a memory
of ~1,000 samples (1 s at 1 kHz), long against the noise, short against oil warm-up."""


class Verdict:
    """What explains the friction-direction residual, as words for the status message."""

    NONE = 'none'
    VALVE_PLATE = 'valve_plate'
    OTHER_FRICTION = 'other_friction'
    NOT_FRICTION = 'not_friction'
    CANNOT_TELL = 'cannot_tell'


@dataclass(frozen=True)
class AttributionSettings:
    """The node parameters the attribution uses (declared in ``node_parameters``)."""

    attribution_window_s: float
    scale_prior_std: float
    offset_prior_std_nm: float
    pressure_gain_prior_std: float
    scale_random_walk_per_sqrt_s: float
    offset_random_walk_nm_per_sqrt_s: float
    pressure_gain_random_walk_per_sqrt_s: float
    model_error_ratio: float
    attribution_z: float
    identifiability_correlation: float


class FrictionAttribution:
    """
    Windowed Kalman filter on (valve-plate scale, other scale, drive loss, offset, gain).

    Parameters
    ----------
    settings : AttributionSettings
        The ``attribution_*``, ``scale_*``, ``offset_*``, ``pressure_gain_*`` and
        ``model_error_ratio`` parameters.

    """

    def __init__(self, settings: AttributionSettings) -> None:
        self.settings = config = settings
        self._window_s = config.attribution_window_s
        self.x0 = np.array([1.0, 1.0, 0.0, 0.0, 0.0])
        self._p0 = np.diag([config.scale_prior_std ** 2] * 2
                           + [config.offset_prior_std_nm ** 2] * 2
                           + [config.pressure_gain_prior_std ** 2])
        self._q = np.diag([config.scale_random_walk_per_sqrt_s ** 2] * 2
                          + [config.offset_random_walk_nm_per_sqrt_s ** 2] * 2
                          + [config.pressure_gain_random_walk_per_sqrt_s ** 2])
        self.reset()

    def reset(self) -> None:
        """Forget everything: the pump as modelled, prior uncertainty."""
        self.x = self.x0.copy()
        self.p = self._p0.copy()
        self.windows = 0
        self._publish_estimates()
        self._last_update_s: float | None = None
        self._white_var = math.nan  # sample-level noise variance (successive differences)
        self._prev_residual = math.nan
        self._open(0.0)

    def _open(self, sign: float) -> None:
        self._sign = sign
        self._n = 0
        self._time = 0.0
        self._sy = self._svp = self._so = self._sth = 0.0

    def add(self, t_s: float, dt_s: float, residual_nm: float, friction_nm: float,
            valve_plate_nm: float, bearing_nm: float, pistons_nm: float,
            theoretical_nm: float, sign: float) -> None:
        """
        Take one monitored sample (steady, above the minimum speed).

        Parameters
        ----------
        t_s : float
            Sample time [s].
        dt_s : float
            Monitored time since the previous sample [s] (0 after a gap).
        residual_nm : float
            Measured - expected torque [N m] (for the noise estimate).
        friction_nm : float
            Friction part y of the measured torque, friction direction [N m].
        valve_plate_nm, bearing_nm, pistons_nm : float
            Modelled friction magnitudes [N m] (pistons: joints and heads).
        theoretical_nm : float
            Theoretical torque V_g dp / 2 pi from the measured pressure [N m].
        sign : float
            Direction of rotation, +1 or -1.

        """
        if sign != self._sign or dt_s <= 0.0:
            self._close(t_s)
            self._open(sign)
            self._prev_residual = math.nan
        d = residual_nm - self._prev_residual
        self._prev_residual = residual_nm
        if d == d:  # successive difference within a run: 2 sigma^2 on average
            half = 0.5 * d * d
            wv = self._white_var
            self._white_var = half if wv != wv else wv + WHITE_NOISE_GAIN * (half - wv)
        self._n += 1
        self._time += dt_s
        self._sy += friction_nm
        self._svp += valve_plate_nm
        self._so += bearing_nm + pistons_nm
        self._sth += theoretical_nm * sign
        if self._time >= self._window_s:
            self._close(t_s)
            self._open(sign)

    def add_many(self, t_s: list[float], dt_s: list[float], residual_nm: list[float],
                 friction_nm: list[float], valve_plate_nm: list[float],
                 bearing_nm: list[float], pistons_nm: list[float],
                 theoretical_nm: list[float], sign: list[float]
                 ) -> tuple[tuple[list[float], list[float]], tuple[list[float], list[float]]]:
        """
        Take many monitored samples in order: `add` for each, in one loop (the chunk path).

        The same operations in the same order as `add`: the state is identical to calling
        it sample by sample.

        Parameters
        ----------
        t_s, dt_s, residual_nm, friction_nm : list of float
            Per sample, as `add` takes them [s, s, N m, N m].
        valve_plate_nm, bearing_nm, pistons_nm, theoretical_nm : list of float
            Per sample, as `add` takes them [N m].
        sign : list of float
            Direction of rotation per sample, +1 or -1.

        Returns
        -------
        tuple
            After each sample: the scales (valve plate, other friction), and their standard
            deviations (same order), each a list of float.

        """
        vp_scales: list[float] = []
        other_scales: list[float] = []
        vp_stds: list[float] = []
        other_stds: list[float] = []
        gain, window = WHITE_NOISE_GAIN, self._window_s
        prev, wv = self._prev_residual, self._white_var
        n, time, sy, svp, so, sth = (self._n, self._time, self._sy, self._svp, self._so,
                                     self._sth)
        (vp_scale, other_scale, *_), (vp_std, other_std, *_) = self.values, self.stds
        for t, dt, residual, friction, vp, bearing, pistons, theoretical, sgn in zip(
                t_s, dt_s, residual_nm, friction_nm, valve_plate_nm, bearing_nm, pistons_nm,
                theoretical_nm, sign, strict=True):
            if sgn != self._sign or dt <= 0.0:
                self._store(n, time, sy, svp, so, sth, wv)
                self._close(t)
                self._open(sgn)
                n, time, sy, svp, so, sth = 0, 0.0, 0.0, 0.0, 0.0, 0.0
                prev = math.nan
                (vp_scale, other_scale, *_), (vp_std, other_std, *_) = self.values, self.stds
            d = residual - prev
            prev = residual
            if d == d:  # as in `add`
                half = 0.5 * d * d
                wv = half if wv != wv else wv + gain * (half - wv)
            n += 1
            time += dt
            sy += friction
            svp += vp
            so += bearing + pistons
            sth += theoretical * sgn
            if time >= window:
                self._store(n, time, sy, svp, so, sth, wv)
                self._close(t)
                self._open(sgn)
                n, time, sy, svp, so, sth = 0, 0.0, 0.0, 0.0, 0.0, 0.0
                (vp_scale, other_scale, *_), (vp_std, other_std, *_) = self.values, self.stds
            vp_scales.append(vp_scale)
            other_scales.append(other_scale)
            vp_stds.append(vp_std)
            other_stds.append(other_std)
        self._store(n, time, sy, svp, so, sth, wv)
        self._prev_residual = prev
        return (vp_scales, other_scales), (vp_stds, other_stds)

    def _store(self, n: int, time: float, sy: float, svp: float, so: float, sth: float,
               white_var: float) -> None:
        """Write the open window's sums and the noise variance back (`add_many`)."""
        self._n, self._time, self._sy, self._svp, self._so, self._sth = (n, time, sy, svp, so,
                                                                         sth)
        self._white_var = white_var

    def _close(self, t_s: float) -> None:
        """Update the filter with the open window's mean, if it holds enough samples."""
        n = self._n
        if n < MIN_WINDOW_SAMPLES or self._white_var != self._white_var:
            return
        inv = 1.0 / n
        h = np.array([self._svp * inv, self._so * inv, 1.0, self._sign, -self._sth * inv])
        z = self._sy * inv
        if self._last_update_s is not None:  # predict: random walk since the last window
            elapsed = min(max(t_s - self._last_update_s, 0.0), _MAX_PREDICT_S)
            self.p = self._capped(self.p + self._q * elapsed)
        self._last_update_s = t_s
        model = self.settings.model_error_ratio * (h[_VP] + h[_OTHER])
        r = self._white_var * inv + model * model
        ph = self.p @ h
        s = float(h @ ph) + r
        gain = ph / s
        self.x = self.x + gain * (z - float(h @ self.x))
        self.p = self.p - np.outer(gain, ph)
        self.p = 0.5 * (self.p + self.p.T)
        self.windows += 1
        self._publish_estimates()

    def _publish_estimates(self) -> None:
        """Keep plain floats of the estimates: read at every sample, updated per window."""
        self.values: list[float] = self.x.tolist()
        self.stds: list[float] = self.std.tolist()

    def _capped(self, p: np.ndarray) -> np.ndarray:
        """Scale rows and columns so that no variance exceeds its prior (no wind-up)."""
        d = np.sqrt(np.diag(p))
        scale = np.minimum(1.0, np.sqrt(np.diag(self._p0)) / np.maximum(d, 1e-300))
        return p * np.outer(scale, scale)

    @property
    def std(self) -> np.ndarray:
        """Posterior standard deviations of the terms (`TERMS` order)."""
        return np.sqrt(np.clip(np.diag(self.p), 0.0, None))

    def correlation(self, i: int, j: int) -> float:
        """Posterior correlation of terms ``i`` and ``j`` (indices into `TERMS`)."""
        d = self.std
        return float(self.p[i, j] / (d[i] * d[j])) if d[i] > 0 and d[j] > 0 else 0.0

    def verdict(self, side: float = 0.0) -> tuple[str, str]:
        """
        Return what explains the deviation from the model, and the phrase for the message.

        Parameters
        ----------
        side : float
            +1: the torque is above the model, -1: below, 0: either. A friction scale
            explains it only when it moved that way (less valve-plate friction does not
            explain more torque).

        Returns
        -------
        tuple of str
            (`Verdict` value, short explanation).

        """
        z_sig = self.settings.attribution_z
        dev = self.x - self.x0
        std = self.std
        z = np.divide(dev, std, out=np.zeros(_N), where=std > 0)
        significant = [i for i in range(_N) if abs(z[i]) >= z_sig and (
            i not in (_VP, _OTHER) or side == 0.0 or z[i] * side > 0.0)]
        rho_max = self.settings.identifiability_correlation
        for other in range(1, _N):
            rho = self.correlation(_VP, other)
            if abs(rho) >= rho_max and not (_VP in significant and other in significant):
                # the pair moves together: only their combination is known
                combined = _pair_z(dev, self.p, _VP, other)
                if abs(combined) >= z_sig:
                    return Verdict.CANNOT_TELL, (f'cannot tell valve plate from '
                                                 f'{TERMS[other].replace("_nm", "")} on this '
                                                 f'duty cycle (correlation {rho:+.2f})')
        if not significant:
            return Verdict.NONE, 'no term stands out yet'
        if significant == [_VP]:
            return Verdict.VALVE_PLATE, f'valve plate (scale {self.x[_VP]:.2f})'
        if _VP in significant:
            return Verdict.CANNOT_TELL, ('valve plate and '
                                         + ', '.join(TERMS[i].replace('_nm', '')
                                                     for i in significant if i != _VP))
        if significant == [_OTHER]:
            return Verdict.OTHER_FRICTION, (f'not the valve plate: other friction (scale '
                                            f'{self.x[_OTHER]:.2f})')
        if all(i in _NOT_FRICTION for i in significant):
            return Verdict.NOT_FRICTION, 'not friction: ' + ', '.join(
                f'{TERMS[i].replace("_nm", "")} {self.x[i]:+.3g}' for i in significant)
        return Verdict.CANNOT_TELL, 'several terms: ' + ', '.join(
            TERMS[i].replace('_nm', '') for i in significant)


def _pair_z(dev: np.ndarray, p: np.ndarray, i: int, j: int) -> float:
    """Largest z-score of a combination a dev_i + b dev_j (the pair's joint significance)."""
    sub = p[np.ix_([i, j], [i, j])]
    d = dev[[i, j]]
    try:
        return float(math.sqrt(max(float(d @ np.linalg.solve(sub, d)), 0.0)))
    except np.linalg.LinAlgError:
        return 0.0
