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
Scenarios of the monitor evaluation bank: duty cycle, fault and noise, vectorised.

A scenario is a duty-cycle family (`settings.ALL_FAMILIES`), a fault (`settings.FAULTS`) with
its onset, and a seed. `simulate_scenario` draws the family's random parameters from the
seed and makes the signals the node would receive, as ``simulate.simulate_duty_cycle``
does: the true speed and acceleration (closed forms), a load pressure that follows a
gravity-like slowly varying load plus damping x speed, and the motor torque the drive
measures,

    T = V_g dp / (2 pi) + sum_c f_c(t) T_c(speed, dp, nu) + J a
        + (drive loss + extra(t)) tanh(speed / w0) + offset(t) + noise,

where T_c are the signed friction components of the true pump's table and f_c their fault
factors; the measured pressure difference is gain(t) x dp + noise; the oil temperature,
when the family uses it, is measured at its own rate with noise. The plant constants (J,
drive loss, viscosity and its temperature law) are those the estimator is configured with.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
import math
import zlib

import numpy as np

from .settings import (
    CreepSettings,
    CruiseSettings,
    Family,
    Fault,
    HighDynamicsSettings,
    SetpointLagSettings,
    SineSettings,
    TrapezoidSettings,
    WarmUpSettings,
)
from .truths import commissioned_since
from ..core.node_parameters import EstimatorConfig, ViscositySource
from ..physics.model import COMPONENTS
from ..physics.oil import WaltherViscosity
from ..sim.duty_cycle import DutyCycle, trapezoid_speed_profile
from ..table.friction_table import FrictionTable

__all__ = ['Scenario', 'SimulatedScenario', 'running_fault_torque_nm', 'simulate_scenario',
           'speed_profile', 'warm_up_temperature']

_NS = 1_000_000_000


@dataclass(frozen=True)
class Scenario:
    """One run of the bank: family, fault, onset, length, seed and the estimator's config."""

    family: Family
    fault: Fault
    replicate: int
    duration_s: float
    onset_s: float  # inf for the nominal pump
    ramp_s: float
    bank_seed: int
    config: EstimatorConfig = field(default_factory=EstimatorConfig)

    @property
    def scenario_id(self) -> str:
        """``family/fault/replicate``."""
        return f'{self.family.name}/{self.fault.name}/{self.replicate}'

    @property
    def seed_key(self) -> list[int]:
        """
        Seed of the scenario's random stream: bank seed, family, fault, replicate.

        Names enter through their CRC-32, so adding a family or a fault leaves the others'
        streams as they are.
        """
        return [self.bank_seed, zlib.crc32(self.family.name.encode()),
                zlib.crc32(self.fault.name.encode()), self.replicate]

    def estimator_config(self) -> EstimatorConfig:
        """Return the estimator's config (oil temperature input for the warm-up)."""
        if self.family.realistic:  # the installation's oil, inertia and drive loss
            from .eha_scenarios import eha_estimator_config

            return eha_estimator_config(self)
        if self.family.uses_temperature:
            return replace(self.config, viscosity_source=ViscositySource.TEMPERATURE)
        return self.config


@dataclass(frozen=True)
class SimulatedScenario:
    """Signals of a scenario, each on its own time base [s], and the truth the bank needs."""

    t_s: np.ndarray  # joint states
    speed_rad_s: np.ndarray  # measured
    torque_nm: np.ndarray  # measured
    pressure_t_s: np.ndarray
    pressure_diff_pa: np.ndarray  # measured
    temperature_t_s: np.ndarray  # empty unless the family uses it
    temperature_c: np.ndarray  # measured
    true_speed_rad_s: np.ndarray
    true_accel_rad_s2: np.ndarray
    true_pressure_diff_pa: np.ndarray  # at t_s
    true_viscosity_m2_s: np.ndarray  # at t_s
    true_temperature_c: np.ndarray  # at temperature_t_s
    motion: dict[str, float]  # the family's drawn parameters
    vp_truth: float  # valve-plate factor at the end of the run
    other_truth: float  # factor of the other components at the end (see other_truth_exact)
    other_truth_exact: bool  # the other components share one factor; else a fitted ratio
    above_min_speed_fraction: float
    fault_running_nm: float = math.nan
    """Mean |torque the fault adds at its full size| over the running samples after the
    onset [N m] (`running_fault_torque_nm`); NaN for the nominal pump."""
    vp_truth_since: Callable[[float], float] | None = None
    """An intermittent fault's valve-plate truth over the change a monitor in alarm reads at
    the end: the factor over the isolation's memory of the running since that change began
    (the stamp given [s]; ``truths.memory_weighted_since``). None: `vp_truth`."""
    vp_commissioned: Callable[[float], float] | None = None
    """The valve-plate factor the healthy baseline holds where it was learnt at the stamp
    given [s], after the onset (`commissioned_factor`); None: the valve plate never
    changes."""


def _draw(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    return float(rng.uniform(*bounds))


def _sign(rng: np.random.Generator) -> float:
    return 1.0 if rng.random() < 0.5 else -1.0


def _two_sines(t: np.ndarray, a1: float, p1: float, a2: float, p2: float
               ) -> tuple[np.ndarray, np.ndarray]:
    w1, w2 = 2.0 * math.pi / p1, 2.0 * math.pi / p2
    return (a1 * np.sin(w1 * t) + a2 * np.sin(w2 * t),
            a1 * w1 * np.cos(w1 * t) + a2 * w2 * np.cos(w2 * t))


def _cosine_knots(knots_t: np.ndarray, knots_v: np.ndarray, t: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Speed through knots, cosine-smoothed in each segment, and its exact derivative."""
    seg = np.clip(np.searchsorted(knots_t, t, side='right') - 1, 0, knots_t.size - 2)
    span = knots_t[seg + 1] - knots_t[seg]
    frac = np.clip((t - knots_t[seg]) / span, 0.0, 1.0)
    dv = knots_v[seg + 1] - knots_v[seg]
    return (knots_v[seg] + dv * (0.5 - 0.5 * np.cos(np.pi * frac)),
            dv * (0.5 * np.pi / span) * np.sin(np.pi * frac))


def _trapezoid(s: TrapezoidSettings, t: np.ndarray, duration_s: float,
               rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, dict]:
    cycle = DutyCycle(duration_s=duration_s, max_speed_rad_s=s.max_speed_rad_s,
                      min_speed_rad_s=s.min_speed_rad_s, accel_time_s=s.accel_time_s,
                      cruise_time_s=s.cruise_time_s, dwell_time_s=s.dwell_time_s)
    speed = trapezoid_speed_profile(cycle, t, rng)
    return speed, np.gradient(speed, t), {}


def _setpoint_lag(s: SetpointLagSettings, t: np.ndarray, duration_s: float,
                  rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, dict]:
    tau = _draw(rng, s.lag_time_constant_s)
    starts, setpoints, now = [], [], 0.0
    while now <= duration_s:
        starts.append(now)
        setpoints.append(0.0 if rng.random() < s.stop_probability
                         else _sign(rng) * _draw(rng, s.setpoint_rad_s))
        now += _draw(rng, s.hold_time_s)
    starts_a, sp = np.array(starts), np.array(setpoints)
    y0 = np.empty_like(sp)  # speed at the start of each segment (exact lag response)
    y = 0.0
    for k in range(sp.size):
        y0[k] = y
        if k + 1 < sp.size:
            y = sp[k] + (y - sp[k]) * math.exp(-(starts_a[k + 1] - starts_a[k]) / tau)
    seg = np.searchsorted(starts_a, t, side='right') - 1
    speed = sp[seg] + (y0[seg] - sp[seg]) * np.exp(-(t - starts_a[seg]) / tau)
    return speed, (sp[seg] - speed) / tau, {'lag_time_constant_s': tau,
                                            'setpoints': float(sp.size)}


def _cruise(s: CruiseSettings, t: np.ndarray, rng: np.random.Generator
            ) -> tuple[np.ndarray, np.ndarray, dict]:
    speed0 = _sign(rng) * _draw(rng, s.speed_rad_s)
    amp, period = _draw(rng, s.variation), _draw(rng, s.variation_period_s)
    phase = _draw(rng, (0.0, 2.0 * math.pi))
    up = t < s.spin_up_s
    ramp = np.where(up, 0.5 - 0.5 * np.cos(np.pi * t / s.spin_up_s), 1.0)
    d_ramp = np.where(up, 0.5 * np.pi / s.spin_up_s * np.sin(np.pi * t / s.spin_up_s), 0.0)
    w = 2.0 * math.pi / period
    mod = 1.0 + amp * np.sin(w * t + phase)
    d_mod = amp * w * np.cos(w * t + phase)
    return speed0 * ramp * mod, speed0 * (d_ramp * mod + ramp * d_mod), {
        'speed_rad_s': speed0, 'variation': amp, 'variation_period_s': period,
        'variation_phase_rad': phase}


def _high_dynamics(s: HighDynamicsSettings, t: np.ndarray, duration_s: float,
                   rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, dict]:
    knots_t, knots_v = [0.0], [0.0]
    sign = _sign(rng)
    while knots_t[-1] <= duration_s:
        peak = sign * _draw(rng, s.peak_speed_rad_s)
        sign = -sign
        knots_t.append(knots_t[-1] + abs(peak - knots_v[-1]) / _draw(rng, s.mean_accel_rad_s2))
        knots_v.append(peak)
        dwell = _draw(rng, s.peak_dwell_s)
        if dwell > 0.0:
            knots_t.append(knots_t[-1] + dwell)
            knots_v.append(peak)
    speed, accel = _cosine_knots(np.array(knots_t), np.array(knots_v), t)
    return speed, accel, {'peaks': float(len(knots_t))}


def speed_profile(motion, t: np.ndarray, duration_s: float, rng: np.random.Generator
                  ) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
    """
    Make the true shaft speed and acceleration of a family's duty cycle.

    Parameters
    ----------
    motion : settings of one family (e.g. `settings.SineSettings`)
        The family's motion.
    t : ndarray
        Sample times [s].
    duration_s : float
        Length of the run [s].
    rng : numpy.random.Generator
        The scenario's random stream (the family's parameters are drawn from it).

    Returns
    -------
    tuple
        Speed [rad/s], acceleration [rad/s^2] and the drawn parameters (closed forms).

    """
    if isinstance(motion, WarmUpSettings):
        motion = motion.moves
    if isinstance(motion, TrapezoidSettings):
        return _trapezoid(motion, t, duration_s, rng)
    if isinstance(motion, (SineSettings, CreepSettings)):
        params = {'amplitude_1_rad_s': _draw(rng, motion.amplitude_1_rad_s),
                  'period_1_s': _draw(rng, motion.period_1_s),
                  'amplitude_2_rad_s': _draw(rng, motion.amplitude_2_rad_s),
                  'period_2_s': _draw(rng, motion.period_2_s)}
        return (*_two_sines(t, *params.values()), params)
    if isinstance(motion, SetpointLagSettings):
        return _setpoint_lag(motion, t, duration_s, rng)
    if isinstance(motion, CruiseSettings):
        return _cruise(motion, t, rng)
    if isinstance(motion, HighDynamicsSettings):
        return _high_dynamics(motion, t, duration_s, rng)
    raise TypeError(f'unknown motion settings: {type(motion).__name__}')


def warm_up_temperature(s: WarmUpSettings, t: np.ndarray, duration_s: float) -> np.ndarray:
    """
    Oil temperature of the warm-up family, exactly ``start_c`` at 0 and ``end_c`` at the end.

    Parameters
    ----------
    s : WarmUpSettings
        The family's settings.
    t : ndarray
        Times [s].
    duration_s : float
        Length of the run [s].

    Returns
    -------
    ndarray
        Temperature [degC].

    """
    tau = s.time_constant_fraction * duration_s
    rise = -np.expm1(-t / tau) / -math.expm1(-duration_s / tau)
    return s.start_c + (s.end_c - s.start_c) * rise


def _factor(fault: Fault, value: float, t: np.ndarray, onset_s: float, ramp_s: float
            ) -> np.ndarray | float:
    """Fault factor over time: 1 before the onset, ``value`` after (or a ramp to it)."""
    if value == 1.0:
        return 1.0
    if fault.ramp:
        return 1.0 + (value - 1.0) * np.clip((t - onset_s) / ramp_s, 0.0, 1.0)
    return np.where(t >= onset_s, value, 1.0)


def _step(value: float, t: np.ndarray, onset_s: float) -> np.ndarray | float:
    return 0.0 if value == 0.0 else np.where(t >= onset_s, value, 0.0)


def running_fault_torque_nm(fault: Fault, friction_nm: dict[str, np.ndarray],
                            theoretical_nm: np.ndarray, delivered_nm: np.ndarray,
                            direction: np.ndarray, running: np.ndarray) -> float:
    """
    Return the torque a fault at its full size adds to the residual, over running [N m].

    What the issue's floors are conditioned on ("where the fault's torque exceeds the
    CUSUM allowance while running"): the mean over the running samples of |dT|, with dT
    what the fault moves measured minus modelled torque by at its full size (a ramp's end
    value: the bank's ramps end inside the run; an intermittent fault's on episodes):
    (f_c - 1) T_c per friction component, the extra drive loss times the direction of
    rotation, the torque offset, (g - 1) times the delivered torque for a torque-constant
    change g (the drive's own gain error of a few % left out), and, to first order,
    -(g - 1) T_th for a pressure gain g (the model's theoretical torque follows the
    measured pressure; its pressure-dependent friction moves too, ~2 % of that).

    Parameters
    ----------
    fault : Fault
        The fault.
    friction_nm : dict of ndarray
        Signed friction components of the true pump, ``'<component>_nm'`` keys [N m].
    theoretical_nm, delivered_nm, direction : ndarray
        Theoretical torque V_g dp / (2 pi) [N m], torque the motor delivers [N m] and
        tanh(speed / w0) [-], on the same samples.
    running : ndarray of bool
        The samples to average over: running after the onset.

    Returns
    -------
    float
        The mean [N m]; NaN for the nominal pump, 0 where nothing runs after the onset.

    """
    if fault.truth_class == 'nominal':
        return math.nan
    if not running.any():
        return 0.0
    added = np.zeros(int(np.count_nonzero(running)))
    for c, factor in fault.factors.items():
        if factor != 1.0:
            added += (factor - 1.0) * friction_nm[f'{c}_nm'][running]
    if fault.drive_loss_nm:
        added += fault.drive_loss_nm * direction[running]
    added += fault.torque_offset_nm
    if fault.torque_gain != 1.0:
        added += (fault.torque_gain - 1.0) * delivered_nm[running]
    if fault.pressure_gain != 1.0:
        added -= (fault.pressure_gain - 1.0) * theoretical_nm[running]
    return float(np.mean(np.abs(added)))


def simulate_scenario(scenario: Scenario, table: FrictionTable) -> SimulatedScenario:
    """
    Make a scenario's signals (deterministic: the scenario's seed fixes every draw).

    Parameters
    ----------
    scenario : Scenario
        What to simulate.
    table : FrictionTable
        Friction table the estimator uses; the classic families' true pump (the pump as
        modelled); the realistic families' truth has its own (``eha_scenarios``).

    Returns
    -------
    SimulatedScenario
        Measured signals, the truth behind them and the end-of-run truths.

    """
    if scenario.family.realistic:  # closed-loop EHA, real sensors, a true pump of its own
        from .eha_scenarios import simulate_eha

        return simulate_eha(scenario, table)
    fam, fault, sig = scenario.family, scenario.fault, scenario.family.signals
    if fault.torque_gain != 1.0 or fault.intermittent:
        raise ValueError(f'fault {fault.name!r}: a torque-constant change and intermittent '
                         'faults are simulated on the realistic families only')
    config = scenario.config
    rng = np.random.default_rng(scenario.seed_key)
    duration, onset = scenario.duration_s, scenario.onset_s
    t = np.arange(round(duration * sig.joint_rate_hz)) / sig.joint_rate_hz
    speed, accel, motion = speed_profile(fam.motion, t, duration, rng)
    lo, hi = sig.load_pressure_pa
    load_period, load_phase = _draw(rng, sig.load_period_s), _draw(rng, (0.0, 2.0 * math.pi))

    def load(time: np.ndarray, spd: np.ndarray) -> np.ndarray:
        swing = 0.5 * (1.0 + np.sin(2.0 * math.pi * time / load_period + load_phase))
        return lo + (hi - lo) * swing + sig.damping_pa_per_rad_s * spd

    dp = load(t, speed)
    tt = np.zeros(0)
    temp_true = np.zeros(0)
    if fam.uses_temperature:
        assert isinstance(fam.motion, WarmUpSettings)  # the warm-up family's settings
        law = WaltherViscosity(config.oil_viscosity_40c_m2_s, config.oil_viscosity_100c_m2_s)
        temps = warm_up_temperature(fam.motion, t, duration)
        visc = np.fromiter(map(law, temps.tolist()), dtype=float, count=t.size)
        tt = np.arange(math.ceil(duration * sig.temperature_rate_hz)) / sig.temperature_rate_hz
        temp_true = warm_up_temperature(fam.motion, tt, duration)
    else:
        visc = np.full(t.size, config.viscosity_m2_s(table.default_viscosity_m2_s))
    res = table.lookup_array(speed, dp, visc)
    direction = np.tanh(speed / table.zero_speed_threshold_rad_s)
    factors = {c: _factor(fault, f, t, onset, scenario.ramp_s)
               for c, f in fault.factors.items()}
    torque = res['theoretical_nm'] + config.rotor_inertia_kg_m2 * accel + \
        (config.drive_loss_torque_nm + _step(fault.drive_loss_nm, t, onset)) * direction + \
        _step(fault.torque_offset_nm, t, onset)
    for c in COMPONENTS:
        torque += factors[c] * res[f'{c}_nm']
    vp_truth = float(np.atleast_1d(factors['valve_plate'])[-1])
    others = [fault.bearing, fault.spherical_joints, fault.piston_heads]
    exact = len(set(others)) == 1
    # running (after the onset: gate), where the monitor learns (true speed and acceleration)
    running = (np.abs(speed) >= config.monitor_min_speed_rad_s) & \
        (np.abs(accel) <= config.monitor_max_accel_rad_s2)
    gate = (t >= onset) & running
    commissioned = commissioned_since(factors['valve_plate'], t, res['valve_plate_nm'],
                                      running, config.baseline_learn_s)
    fault_running = running_fault_torque_nm(fault, res, res['theoretical_nm'], torque,
                                            direction, gate)
    if exact:
        other_truth = others[0]
    else:  # least-squares ratio of true to modelled other friction where the monitor learns
        model = sum(np.abs(res[f'{c}_nm'][gate]) for c in COMPONENTS[1:])
        true = sum(factors[c] * np.abs(res[f'{c}_nm']) for c in COMPONENTS[1:])
        true = np.broadcast_to(true, t.shape)[gate]
        other_truth = float(np.dot(model, true) / np.dot(model, model)) if gate.any() \
            else math.nan
    del res, factors
    tp = np.arange(round(duration * sig.pressure_rate_hz)) / sig.pressure_rate_hz
    dp_p = load(tp, np.interp(tp, t, speed))
    gain = _factor(fault, fault.pressure_gain, tp, onset, scenario.ramp_s) \
        if fault.pressure_gain != 1.0 else 1.0
    above = float(np.mean(np.abs(speed) >= config.monitor_min_speed_rad_s))
    return SimulatedScenario(
        t_s=t, speed_rad_s=speed + rng.normal(0.0, sig.speed_noise_rad_s, t.size),
        torque_nm=torque + rng.normal(0.0, sig.torque_noise_nm, t.size),
        pressure_t_s=tp,
        pressure_diff_pa=gain * dp_p + rng.normal(0.0, sig.pressure_noise_pa, tp.size),
        temperature_t_s=tt,
        temperature_c=temp_true + rng.normal(0.0, sig.temperature_noise_c, tt.size),
        true_speed_rad_s=speed, true_accel_rad_s2=accel, true_pressure_diff_pa=dp,
        true_viscosity_m2_s=visc, true_temperature_c=temp_true, motion=motion,
        vp_truth=vp_truth, other_truth=float(other_truth), other_truth_exact=exact,
        above_min_speed_fraction=above, fault_running_nm=fault_running,
        vp_commissioned=commissioned)
