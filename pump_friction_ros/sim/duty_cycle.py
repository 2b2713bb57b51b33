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
Synthetic EHA duty cycles: the test streams and the sample bags are made from these.

A positioning duty cycle: moves of random length and speed in both directions (trapezoidal
speed with cosine-smoothed corners, reversals through zero, dwells), a load pressure that
follows a gravity-like load plus a damping term (so retracting runs the pump as a motor),
and the motor torque the drive would measure: theoretical + friction (components from a
friction table, the valve plate scaled by a wear factor) + rotor inertia x true
acceleration + drive loss, plus white noise on every signal.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
import math

import numpy as np

from ..physics.friction import smooth_sign
from ..physics.model import input_torque_nm, theoretical_torque_nm
from ..table.friction_table import FrictionTable

__all__ = ['DutyCycle', 'SimulatedRun', 'simulate_duty_cycle', 'wear_step']


@dataclass(frozen=True)
class DutyCycle:
    """Settings of a synthetic EHA duty cycle (SI)."""

    duration_s: float = 60.0
    rate_hz: float = 1000.0  # shaft speed, measured torque
    pressure_rate_hz: float = 500.0
    max_speed_rad_s: float = 900.0  # ~8,600 rpm
    min_speed_rad_s: float = 150.0
    accel_time_s: tuple[float, float] = (0.05, 0.15)
    cruise_time_s: tuple[float, float] = (0.3, 1.5)
    dwell_time_s: tuple[float, float] = (0.05, 0.6)
    load_pressure_pa: tuple[float, float] = (40e5, 220e5)  # gravity load, slowly varying
    load_period_s: float = 23.0
    damping_pa_per_rad_s: float = 2.0e3  # adds to dp with the speed
    rotor_inertia_kg_m2: float = 2.0e-4
    drive_loss_torque_nm: float = 0.05
    viscosity_m2_s: float = 46e-6
    speed_noise_rad_s: float = 0.5
    pressure_noise_pa: float = 1.0e5
    torque_noise_nm: float = 0.05


@dataclass(frozen=True)
class SimulatedRun:
    """Signals of a simulated run, each with its own time base [s]."""

    t_s: np.ndarray  # speed / torque samples
    speed_rad_s: np.ndarray  # measured (noisy)
    true_speed_rad_s: np.ndarray
    true_accel_rad_s2: np.ndarray
    torque_nm: np.ndarray  # measured motor torque (noisy)
    wear_scale: np.ndarray  # valve-plate friction factor in force at t_s
    pressure_t_s: np.ndarray
    pressure_diff_pa: np.ndarray  # measured (noisy)


def wear_step(start_s: float, scale: float, ramp_s: float = 0.0
              ) -> Callable[[np.ndarray], np.ndarray]:
    """
    Valve-plate friction factor: 1 before ``start_s``, ``scale`` after (optional ramp).

    Parameters
    ----------
    start_s : float
        Time the wear starts [s].
    scale : float
        Friction factor reached [-].
    ramp_s : float
        Duration of a linear ramp to it [s] (0: a step).

    Returns
    -------
    callable
        Factor as a function of time [-].

    """
    def factor(t: np.ndarray) -> np.ndarray:
        if ramp_s <= 0.0:
            return np.where(t >= start_s, scale, 1.0)
        return 1.0 + (scale - 1.0) * np.clip((t - start_s) / ramp_s, 0.0, 1.0)

    return factor


def trapezoid_speed_profile(cycle: DutyCycle, t: np.ndarray, rng: np.random.Generator
                            ) -> np.ndarray:
    """Trapezoidal moves with cosine-smoothed ramps, alternating mostly, with dwells."""
    t_knots, v_knots = [0.0], [0.0]
    now, direction = 0.0, 1.0
    while now < cycle.duration_s + 2.0:
        if rng.random() < 0.75:
            direction = -direction
        speed = direction * rng.uniform(cycle.min_speed_rad_s, cycle.max_speed_rad_s)
        ramp = rng.uniform(*cycle.accel_time_s)
        cruise = rng.uniform(*cycle.cruise_time_s)
        dwell = rng.uniform(*cycle.dwell_time_s)
        for dt, v in ((ramp, speed), (cruise, speed), (ramp, 0.0), (dwell, 0.0)):
            now += dt
            t_knots.append(now)
            v_knots.append(v)
    knots_t, knots_v = np.array(t_knots), np.array(v_knots)
    seg = np.clip(np.searchsorted(knots_t, t, side='right') - 1, 0, knots_t.size - 2)
    frac = (t - knots_t[seg]) / (knots_t[seg + 1] - knots_t[seg])
    smooth = 0.5 - 0.5 * np.cos(np.pi * frac)  # zero slope at both ends of each segment
    return knots_v[seg] + (knots_v[seg + 1] - knots_v[seg]) * smooth


def simulate_duty_cycle(table: FrictionTable, cycle: DutyCycle | None = None, seed: int = 0,
                        wear: Callable[[np.ndarray], np.ndarray] | None = None
                        ) -> SimulatedRun:
    """
    Simulate a duty cycle; the friction comes from ``table`` (vectorised lookup).

    Parameters
    ----------
    table : FrictionTable
        Friction table of the simulated pump.
    cycle : DutyCycle, optional
        Settings (default `DutyCycle()`).
    seed : int
        Random seed (the run is reproducible).
    wear : callable, optional
        Valve-plate friction factor as a function of time (e.g. `wear_step`).

    Returns
    -------
    SimulatedRun
        The signals.

    """
    cycle = cycle or DutyCycle()
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, cycle.duration_s, 1.0 / cycle.rate_hz)
    speed = trapezoid_speed_profile(cycle, t, rng)
    accel = np.gradient(speed, t)
    lo, hi = cycle.load_pressure_pa
    phase = rng.uniform(0.0, 2.0 * math.pi)

    def load(time: np.ndarray, spd: np.ndarray) -> np.ndarray:
        static = lo + (hi - lo) * 0.5 * (1.0 + np.sin(2.0 * math.pi * time / cycle.load_period_s
                                                      + phase))
        return static + cycle.damping_pa_per_rad_s * spd

    dp = load(t, speed)
    scale = np.ones_like(t) if wear is None else np.asarray(wear(t), dtype=float)
    mags, _ = table.magnitudes_array(np.abs(speed), np.abs(dp), cycle.viscosity_m2_s,
                                     speed * dp < 0.0)
    mags[:, 0] *= scale  # valve-plate wear
    direction = smooth_sign(speed, table.zero_speed_threshold_rad_s)
    torque = (input_torque_nm(theoretical_torque_nm(table.displacement_m3, dp),
                              mags.sum(axis=1), direction, cycle.drive_loss_torque_nm)
              + cycle.rotor_inertia_kg_m2 * accel)
    tp = np.arange(0.0, cycle.duration_s, 1.0 / cycle.pressure_rate_hz)
    dp_meas = load(tp, np.interp(tp, t, speed))
    return SimulatedRun(
        t_s=t,
        speed_rad_s=speed + rng.normal(0.0, cycle.speed_noise_rad_s, t.size),
        true_speed_rad_s=speed, true_accel_rad_s2=accel,
        torque_nm=torque + rng.normal(0.0, cycle.torque_noise_nm, t.size),
        wear_scale=scale, pressure_t_s=tp,
        pressure_diff_pa=dp_meas + rng.normal(0.0, cycle.pressure_noise_pa, tp.size))
