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
Real sensors and message streams of the realistic families (vectorised).

* Motor torque from current: measured = g(t) (delivered + ripple) + offset + noise, with
  g(t) = (1 + e) (1 + d (T(t) - T_ref)) x the fault's gain: a torque-constant error e, an
  optional drift d with temperature; the ripple is a fraction of |V_g dp / (2 pi)| at
  ``ripple_order`` x the shaft angle.
* Speed from an encoder: the angle counted in steps of 2 pi / counts, differenced over one
  JointState period.
* Pressure at its own rate and phase: true dp + offset + noise.
* Message streams: each message lost with a probability, all of them lost during bus
  bursts, some sent twice with the same stamp; `message_indices` gives the samples in the
  order they are sent.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from .eha_settings import SensorSettings

__all__ = ['SensorDraw', 'bursts', 'draw_sensors', 'encoder_speed', 'measured_torque',
           'message_indices', 'ripple_nm']


@dataclass(frozen=True)
class SensorDraw:
    """The sensors of one run (SI)."""

    pressure_rate_hz: float
    pressure_phase_s: float  # first pressure sample's time
    pressure_noise_pa: float
    pressure_offset_pa: float
    torque_constant_error: float
    torque_drift_per_k: float  # 0: no drift
    torque_offset_nm: float
    torque_noise_nm: float
    ripple_fraction: float
    ripple_phase_rad: float
    encoder_counts_per_rev: int
    encoder_offset_rad: float
    drop_probability: float
    burst_rate_per_h: float
    duplicate_probability: float


def draw_sensors(s: SensorSettings, rng: np.random.Generator) -> SensorDraw:
    """
    Draw one run's sensors.

    Parameters
    ----------
    s : SensorSettings
        Ranges and choices.
    rng : numpy.random.Generator
        The scenario's stream.

    Returns
    -------
    SensorDraw
        The draws.

    """
    def draw(bounds: tuple[float, float]) -> float:
        return float(rng.uniform(*bounds))

    rate = float(s.pressure_rates_hz[rng.integers(len(s.pressure_rates_hz))])
    drift = draw(s.torque_drift_per_k) if rng.random() < s.torque_drift_probability else 0.0
    return SensorDraw(
        pressure_rate_hz=rate, pressure_phase_s=draw((0.0, 1.0 / rate)),
        pressure_noise_pa=draw(s.pressure_noise_pa), pressure_offset_pa=draw(s.pressure_offset_pa),
        torque_constant_error=draw(s.torque_constant_error), torque_drift_per_k=drift,
        torque_offset_nm=draw(s.torque_offset_nm), torque_noise_nm=draw(s.torque_noise_nm),
        ripple_fraction=draw(s.ripple_fraction), ripple_phase_rad=draw((0.0, 2.0 * math.pi)),
        encoder_counts_per_rev=int(s.encoder_counts_per_rev[
            rng.integers(len(s.encoder_counts_per_rev))]),
        encoder_offset_rad=draw((0.0, 2.0 * math.pi)),
        drop_probability=draw(s.drop_probability), burst_rate_per_h=draw(s.burst_rate_per_h),
        duplicate_probability=draw(s.duplicate_probability))


def ripple_nm(angle_rad: np.ndarray, theoretical_nm: np.ndarray, fraction: float, order: int,
              phase_rad: float) -> np.ndarray:
    """
    Torque ripple: ``fraction`` x |theoretical torque| x sin(order x angle + phase) [N m].

    Parameters
    ----------
    angle_rad : ndarray
        Shaft angle [rad].
    theoretical_nm : ndarray
        V_g dp / (2 pi) [N m].
    fraction : float
        Relative amplitude [-].
    order : int
        Ripple periods per revolution.
    phase_rad : float
        Phase [rad].

    Returns
    -------
    ndarray
        The ripple [N m].

    """
    return fraction * np.abs(theoretical_nm) * np.sin(order * angle_rad + phase_rad)


def measured_torque(delivered_nm: np.ndarray, gain: np.ndarray | float, offset_nm: float,
                    noise_nm: float, rng: np.random.Generator) -> np.ndarray:
    """
    Torque the drive reports from its current: gain x delivered + offset + white noise.

    Parameters
    ----------
    delivered_nm : ndarray
        Torque the motor delivers (ripple included) [N m].
    gain : ndarray or float
        (1 + torque-constant error) x drift x fault gain [-].
    offset_nm : float
        Current-sensor offset [N m].
    noise_nm : float
        Noise std [N m].
    rng : numpy.random.Generator
        Noise stream.

    Returns
    -------
    ndarray
        Measured torque [N m].

    """
    return gain * delivered_nm + offset_nm + rng.normal(0.0, noise_nm, delivered_nm.size)


def encoder_speed(angle_rad: np.ndarray, counts_per_rev: int, period_s: float,
                  offset_rad: float = 0.0) -> np.ndarray:
    """
    Speed from an encoder: counted angle differenced over one sample period.

    Parameters
    ----------
    angle_rad : ndarray
        True shaft angle at each sample, one period apart [rad].
    counts_per_rev : int
        Encoder counts per revolution.
    period_s : float
        Sample period [s].
    offset_rad : float
        Angle of the encoder's zero against the shaft's [rad].

    Returns
    -------
    ndarray
        Speed [rad/s], integer multiples of 2 pi / (counts x period); 0 at the first sample.

    """
    counts = np.floor((angle_rad + offset_rad) * (counts_per_rev / (2.0 * math.pi)))
    return np.diff(counts, prepend=counts[:1]) * (2.0 * math.pi / (counts_per_rev * period_s))


def bursts(duration_s: float, rate_per_h: float, length_s: tuple[float, float],
           rng: np.random.Generator) -> np.ndarray:
    """
    Draw bus bursts: Poisson starts at ``rate_per_h``, lengths uniform in ``length_s``.

    Parameters
    ----------
    duration_s : float
        Length of the run [s].
    rate_per_h : float
        Bursts per hour.
    length_s : tuple of float
        Range of a burst's length [s].
    rng : numpy.random.Generator
        The stream.

    Returns
    -------
    ndarray, shape (k, 2)
        Start and end of each burst [s].

    """
    count = int(rng.poisson(rate_per_h * duration_s / 3600.0))
    start = np.sort(rng.uniform(0.0, duration_s, count))
    return np.column_stack([start, start + rng.uniform(*length_s, count)])


def message_indices(t_s: np.ndarray, drop_probability: float, duplicate_probability: float,
                    burst_windows: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """
    Return the samples as their messages arrive: some lost, some sent twice.

    Parameters
    ----------
    t_s : ndarray
        Sample times [s], increasing.
    drop_probability : float
        Each message is lost with this probability.
    duplicate_probability : float
        Each message that arrives is sent twice (same stamp) with this probability.
    burst_windows : ndarray, shape (k, 2)
        Every message with start <= t < end is lost.
    rng : numpy.random.Generator
        The stream.

    Returns
    -------
    ndarray of int
        Indices into ``t_s`` in arrival order (a duplicate right after its original).

    """
    keep = rng.random(t_s.size) >= drop_probability
    if burst_windows.size:
        inside = np.searchsorted(burst_windows[:, 0], t_s, side='right') - 1
        ok = inside >= 0
        keep[ok] &= t_s[ok] >= burst_windows[inside[ok], 1]
    kept = np.flatnonzero(keep)
    return np.repeat(kept, 1 + (rng.random(kept.size) < duplicate_probability))
