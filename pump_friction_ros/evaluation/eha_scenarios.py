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
Scenarios of the realistic EHA families: draws, the node's configuration, the signals.

`draw_eha` draws everything of a run from its seed (actuator, oil grade and temperature,
inertia and drive loss, sensors, which true pump); `eha_estimator_config` configures the
node as an engineer would (the grade's viscosity law with the temperature topic, or its
viscosity at the nominal temperature without it; J within +-10 %; the commissioned drive
loss) and keeps the shipped pump file and table; `simulate_eha` runs the closed loop
(``closed_loop``) and makes the motor torque

    T = V_g dp / (2 pi) + sum_c f_c(t) T_c,true(speed, dp, nu_true) + J a
        + (drive loss + its fault's change from the onset) tanh(speed / w0),

with T_c,true from the true pump's table (``true_pump``), then measures it and the other
signals with real sensors (``sensors``), a fault's torque-constant, offset or pressure-gain
change included. The valve-plate truth is the least-squares ratio
of the true valve-plate friction to the node's modelled one where the monitor learns, x
the fault factor at the end: what a perfect monitor would report.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache, partial
import math

import numpy as np

from .closed_loop import ClosedLoopRun, draw_plant, make_setpoints, Plant, simulate_closed_loop
from .eha_settings import EhaSettings, OIL_GRADES, OilGrade, TemperatureSettings
from .scenarios import running_fault_torque_nm, Scenario, SimulatedScenario
from .sensors import (
    bursts,
    draw_sensors,
    encoder_speed,
    measured_torque,
    message_indices,
    ripple_nm,
    SensorDraw,
)
from .settings import Fault
from .true_pump import pump_variants, PumpVariant, true_table
from .truths import commissioned_since, memory_weighted_since
from ..core.node_parameters import EstimatorConfig, ViscositySource
from ..physics.model import COMPONENTS
from ..physics.oil import WaltherViscosity
from ..physics.pump_parameters import load_pump
from ..table.friction_table import FrictionTable

__all__ = ['EhaDraw', 'draw_eha', 'eha_estimator_config', 'fault_episodes', 'fault_factor',
           'oil_temperature', 'simulate_eha']

_PLANT_STREAM = 2  # sub-stream of the scenario's seed for the draws (the noise: its own)
_EPISODE_STREAM = 3  # sub-stream of the intermittent fault's episodes
_WALTHER_GRID_C = 0.01  # temperature step of the tabulated viscosity law [degC]


@dataclass(frozen=True)
class EhaDraw:
    """Everything drawn for one realistic run."""

    plant: Plant
    variant_index: int
    variant: PumpVariant
    oil: OilGrade
    temperature_start_c: float
    temperature_end_c: float
    temperature_time_constant_s: float  # warm-up; inf when steady
    temperature_swing_c: float
    temperature_swing_period_s: float
    rotor_inertia_kg_m2: float
    config_inertia_kg_m2: float
    drive_loss_nm: float
    sensors: SensorDraw


def _settings(scenario: Scenario) -> EhaSettings:
    motion = scenario.family.motion
    if not isinstance(motion, EhaSettings):
        raise TypeError(f'{scenario.family.name} is not a realistic EHA family')
    return motion


def draw_eha(scenario: Scenario) -> EhaDraw:
    """
    Draw a realistic run's actuator, oil, plant constants, sensors and true pump.

    Parameters
    ----------
    scenario : Scenario
        A scenario of a realistic family.

    Returns
    -------
    EhaDraw
        The draws (the same for the same seed, whatever the fault).

    """
    s = _settings(scenario)
    key = [scenario.bank_seed, *scenario.seed_key[1:2], scenario.replicate, _PLANT_STREAM]
    rng = np.random.default_rng(key)  # family and replicate only: faults share the plant

    def draw(bounds: tuple[float, float]) -> float:
        return float(rng.uniform(*bounds))

    plant = draw_plant(s.cylinder, s.load, s.loop, _displacement_m3(), rng)
    variants = pump_variants(s.mismatch)
    index = int(rng.integers(len(variants)))
    oil = OIL_GRADES[int(rng.integers(len(OIL_GRADES)))]
    t = s.temperature
    if t.cold_start:
        start, end, tau = draw(t.start_c), draw(t.end_c), draw(t.time_constant_s)
    else:
        start = end = draw(t.steady_c)
        tau = math.inf
    swing, period = draw(t.swing_c), draw(t.swing_period_s)
    inertia = draw(s.plant.rotor_inertia_kg_m2)
    return EhaDraw(plant, index, variants[index], oil, start, end, tau, swing, period, inertia,
                   inertia * (1.0 + draw(s.plant.inertia_config_error)),
                   draw(s.plant.drive_loss_nm), draw_sensors(s.sensors, rng))


def oil_temperature(d: EhaDraw, t: np.ndarray) -> np.ndarray:
    """
    Oil temperature: T1 - (T1 - T0) exp(-t / tau) plus a slow swing [degC].

    Parameters
    ----------
    d : EhaDraw
        The run's draws.
    t : ndarray
        Times [s].

    Returns
    -------
    ndarray
        Temperature [degC].

    """
    warm = d.temperature_end_c - (d.temperature_end_c - d.temperature_start_c) * np.exp(
        -t / d.temperature_time_constant_s)
    return warm + d.temperature_swing_c * np.sin(2.0 * math.pi * t / d.temperature_swing_period_s)


def _node_viscosity(t: TemperatureSettings, oil: OilGrade) -> tuple[ViscositySource, float]:
    if t.topic:
        return ViscositySource.TEMPERATURE, 0.0
    return ViscositySource.PARAMETER, WaltherViscosity(
        oil.viscosity_40c_m2_s, oil.viscosity_100c_m2_s)(t.nominal_c)


def eha_estimator_config(scenario: Scenario) -> EstimatorConfig:
    """
    Configure the node for a realistic run as an engineer would (module docstring).

    Parameters
    ----------
    scenario : Scenario
        A scenario of a realistic family.

    Returns
    -------
    EstimatorConfig
        The scenario's config with the oil, inertia and drive loss of the installation.

    """
    d = draw_eha(scenario)
    source, viscosity = _node_viscosity(_settings(scenario).temperature, d.oil)
    return replace(scenario.config, viscosity_source=source, oil_viscosity_m2_s=viscosity,
                   oil_viscosity_40c_m2_s=d.oil.viscosity_40c_m2_s,
                   oil_viscosity_100c_m2_s=d.oil.viscosity_100c_m2_s,
                   rotor_inertia_kg_m2=d.config_inertia_kg_m2,
                   drive_loss_torque_nm=d.drive_loss_nm)


def fault_episodes(fault: Fault, onset_s: float, end_s: float,
                   rng: np.random.Generator) -> np.ndarray:
    """
    Draw an intermittent fault's on/off episodes once, for every factor it moves.

    Parameters
    ----------
    fault : Fault
        The fault (``intermittent`` and the episode ranges).
    onset_s : float
        Onset [s] (inf: never).
    end_s : float
        The episodes run at least to this time [s].
    rng : numpy.random.Generator
        Stream of the episodes' lengths.

    Returns
    -------
    ndarray
        The edges [s]: the onset, then each end of an episode (on, off, on, ...); empty for
        a fault that is not intermittent or never starts.

    """
    if not fault.intermittent or not math.isfinite(onset_s):
        return np.zeros(0)
    edges, now, on = [onset_s], onset_s, True  # on, off, on, ... from the onset
    while now < end_s:
        now += float(rng.uniform(*(fault.episode_on_s if on else fault.episode_off_s)))
        edges.append(now)
        on = not on
    return np.array(edges)


def fault_factor(fault: Fault, value: float, t: np.ndarray, onset_s: float, ramp_s: float,
                 episodes: np.ndarray) -> np.ndarray | float:
    """
    Return a fault's factor over time: 1 before the onset, then a step, ramp or episodes.

    Every factor of one fault (its friction factors, an additive share, a gain) follows
    the same episodes, so that an intermittent fault that moves several comes and goes as
    one.

    Parameters
    ----------
    fault : Fault
        The fault (``ramp``, ``intermittent``).
    value : float
        Its factor (friction factor, torque or pressure gain); 2 gives an additive fault's
        share plus 1 (0 before the onset, 1 at full size).
    t : ndarray
        Times [s].
    onset_s : float
        Onset [s] (inf: never).
    ramp_s : float
        Duration of a ramp [s].
    episodes : ndarray
        An intermittent fault's episode edges, `fault_episodes` [s].

    Returns
    -------
    ndarray or float
        The factor (1.0 when ``value`` is 1).

    """
    if value == 1.0 or not math.isfinite(onset_s):
        return 1.0
    if fault.ramp:
        return 1.0 + (value - 1.0) * np.clip((t - onset_s) / ramp_s, 0.0, 1.0)
    if not fault.intermittent:
        return np.where(t >= onset_s, value, 1.0)
    inside = np.searchsorted(episodes, t, side='right')
    return np.where(inside % 2 == 1, value, 1.0)  # odd: inside an 'on' episode


def _ratio(true: np.ndarray, model: np.ndarray) -> float:
    """Least-squares ratio of true to modelled magnitudes (nan without samples)."""
    den = float(np.dot(model, model))
    return float(np.dot(model, true)) / den if den > 0.0 else math.nan


def simulate_eha(scenario: Scenario, table: FrictionTable) -> SimulatedScenario:
    """
    Make a realistic scenario's message streams and truths (deterministic per seed).

    Parameters
    ----------
    scenario : Scenario
        A scenario of a realistic family.
    table : FrictionTable
        The node's table (the truth uses the true pump's, `true_pump.true_table`).

    Returns
    -------
    SimulatedScenario
        Streams as the node receives them (drops, duplicates), truths at their samples.

    """
    s, fault = _settings(scenario), scenario.fault
    d = draw_eha(scenario)
    rng = np.random.default_rng(scenario.seed_key)  # setpoints, noise and message streams
    dt = d.plant.step_s
    n = round(scenario.duration_s / dt)
    setpoints = make_setpoints(s.setpoints, d.plant, n, rng)
    run = simulate_closed_loop(d.plant, setpoints)
    t, speed, dp = run.t_s, run.speed_rad_s, run.pressure_diff_pa
    temperature = oil_temperature(d, t)
    law = WaltherViscosity(d.oil.viscosity_40c_m2_s, d.oil.viscosity_100c_m2_s)
    visc = _walther_array(law, temperature)
    true = true_table(d.variant, s.mismatch).lookup_array(speed, dp, visc)
    onset, ramp = scenario.onset_s, scenario.ramp_s
    episodes = fault_episodes(fault, onset, max(float(t[-1]), scenario.duration_s),
                              np.random.default_rng([*scenario.seed_key, _EPISODE_STREAM]))
    factors = {c: fault_factor(fault, f, t, onset, ramp, episodes)
               for c, f in fault.factors.items()}
    direction = np.tanh(speed / table.zero_speed_threshold_rad_s)
    delivered = true['theoretical_nm'] + d.rotor_inertia_kg_m2 * run.accel_rad_s2 + \
        d.drive_loss_nm * direction
    if fault.drive_loss_nm or fault.torque_offset_nm:  # additive: 0 before, 1 from the onset
        came = fault_factor(fault, 2.0, t, onset, ramp, episodes) - 1.0
        delivered += fault.drive_loss_nm * came * direction
    for c in COMPONENTS:
        delivered += factors[c] * true[f'{c}_nm']
    sens = d.sensors
    delivered += ripple_nm(run.angle_rad, true['theoretical_nm'], sens.ripple_fraction,
                           s.sensors.ripple_order, sens.ripple_phase_rad)
    gain = (1.0 + sens.torque_constant_error) * (1.0 + sens.torque_drift_per_k * (
        temperature - s.sensors.torque_drift_reference_c)) * fault_factor(
        fault, fault.torque_gain, t, onset, ramp, episodes)
    torque = measured_torque(delivered, gain, sens.torque_offset_nm, sens.torque_noise_nm, rng)
    if fault.torque_offset_nm:  # a change of the drive's current offset
        torque += fault.torque_offset_nm * came
    measured_speed = encoder_speed(run.angle_rad, sens.encoder_counts_per_rev, dt,
                                   sens.encoder_offset_rad)
    # the truths the report needs, where the monitor learns (true speed and acceleration)
    config = eha_estimator_config(scenario)
    gate = (np.abs(speed) >= config.monitor_min_speed_rad_s) & \
        (np.abs(run.accel_rad_s2) <= config.monitor_max_accel_rad_s2)
    # the truths are relative to the healthy true pump: the monitor reports the change
    # from its learnt baseline (other friction: the healthy-weighted ratio of its parts)
    vp_truth = float(np.atleast_1d(factors['valve_plate'])[-1])
    commissioned = commissioned_since(factors['valve_plate'], t, true['valve_plate_nm'], gate,
                                      config.baseline_learn_s)
    vp_truth_since = None
    taken = gate & (t >= onset)
    if fault.intermittent and taken.any():  # on and off: the level over the isolation's memory
        vp_factor = np.broadcast_to(factors['valve_plate'], t.shape)[taken]
        vp_nm = np.abs(true['valve_plate_nm'][taken])
        vp_truth_since = partial(memory_weighted_since, t[taken], vp_factor, vp_nm, dt,
                                 config.isolation_memory_s)
        vp_truth = vp_truth_since(-math.inf)
    other_true = sum(float(np.atleast_1d(factors[c])[-1]) * np.abs(true[f'{c}_nm'][gate])
                     for c in COMPONENTS[1:])
    other_healthy = sum(np.abs(true[f'{c}_nm'][gate]) for c in COMPONENTS[1:])
    other_truth = _ratio(np.asarray(other_true), np.asarray(other_healthy))
    fault_running = running_fault_torque_nm(fault, true, true['theoretical_nm'], delivered,
                                            direction, taken)
    del true, delivered
    # message streams: bursts hit every stream of the bus; drops and duplicates per message
    windows = bursts(scenario.duration_s, sens.burst_rate_per_h, s.sensors.burst_length_s, rng)
    joint = message_indices(t, sens.drop_probability, sens.duplicate_probability, windows, rng)
    tp = np.arange(sens.pressure_phase_s, scenario.duration_s, 1.0 / sens.pressure_rate_hz)
    dp_p = np.interp(tp, t, dp) * fault_factor(fault, fault.pressure_gain, tp, onset, ramp,
                                               episodes) + sens.pressure_offset_pa + \
        rng.normal(0.0, sens.pressure_noise_pa, tp.size)
    press = message_indices(tp, sens.drop_probability, sens.duplicate_probability, windows,
                            rng)
    tt, temp_true = np.zeros(0), np.zeros(0)
    if s.temperature.topic:
        tt = np.arange(math.ceil(scenario.duration_s * s.temperature.rate_hz)) / \
            s.temperature.rate_hz
        temp_true = oil_temperature(d, tt)
    motion = _describe(d, run, setpoints.moves)
    return SimulatedScenario(
        t_s=t[joint], speed_rad_s=measured_speed[joint], torque_nm=torque[joint],
        pressure_t_s=tp[press], pressure_diff_pa=dp_p[press], temperature_t_s=tt,
        temperature_c=temp_true + rng.normal(0.0, s.temperature.noise_c, tt.size),
        true_speed_rad_s=speed[joint], true_accel_rad_s2=run.accel_rad_s2[joint],
        true_pressure_diff_pa=dp[joint], true_viscosity_m2_s=visc[joint],
        true_temperature_c=temp_true, motion=motion, vp_truth=vp_truth,
        other_truth=other_truth, other_truth_exact=False, vp_truth_since=vp_truth_since,
        vp_commissioned=commissioned,
        above_min_speed_fraction=float(np.mean(np.abs(speed) >= config.monitor_min_speed_rad_s)),
        fault_running_nm=fault_running)


def _walther_array(law: WaltherViscosity, temperature_c: np.ndarray) -> np.ndarray:
    """
    Walther's law over an array: the scalar law on a 0.01 degC grid, interpolated.

    The law's curvature makes the interpolation error ~1e-7 relative: far below anything
    the bank measures, at a thousandth of the cost of a call per sample.
    """
    low, high = float(temperature_c.min()), float(temperature_c.max())
    grid = np.arange(low, high + _WALTHER_GRID_C, _WALTHER_GRID_C)
    values = np.fromiter(map(law, grid.tolist()), dtype=float, count=grid.size)
    return np.interp(temperature_c, grid, values)


@lru_cache(maxsize=1)
def _displacement_m3() -> float:
    """Displacement of the node's pump file (the true pumps share its geometry) [m^3]."""
    return load_pump(None).geometry.displacement_m3


def _describe(d: EhaDraw, run: ClosedLoopRun, moves: int) -> dict[str, float]:
    p = d.plant
    return {'area_m2': p.area_m2, 'stroke_m': p.stroke_m, 'position_gain_1_s':
            p.position_gain_1_s, 'speed_bandwidth_hz': p.speed_bandwidth_rad_s / (2 * math.pi),
            'slew_rad_s2': p.slew_rad_s2, 'rotor_inertia_kg_m2': d.rotor_inertia_kg_m2,
            'variant': float(d.variant_index), 'oil_vg': d.oil.viscosity_40c_m2_s * 1e6,
            'temperature_start_c': d.temperature_start_c, 'moves': float(moves),
            'torque_constant_error': d.sensors.torque_constant_error,
            'max_pressure_pa': float(np.abs(run.pressure_diff_pa).max())}
