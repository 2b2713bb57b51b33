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
Every number of the realistic EHA families of the evaluation bank, with its reason.

A realistic family (`EhaSettings`) is a position-controlled electro-hydrostatic actuator:
a cylinder following position setpoints through a position loop that commands the pump
speed, a fast speed loop, a load of mass, spring, damper and gravity, an oil grade whose
temperature may start cold, real sensors (`SensorSettings`) and a true pump that differs
from the node's pump file (`MismatchSettings`). Ranges ``(low, high)`` are drawn uniformly
per scenario from its seed; ``choices`` tuples are drawn from with equal probability. None
of these numbers is the paper's: each says where it comes from.
"""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = [
    'OIL_GRADES',
    'CylinderSettings',
    'EhaSettings',
    'LoadSettings',
    'LoopSettings',
    'MismatchSettings',
    'OilGrade',
    'PlantSettings',
    'SensorSettings',
    'SetpointSettings',
    'TemperatureSettings',
]

Range = tuple[float, float]


@dataclass(frozen=True)
class OilGrade:
    """An ISO VG hydraulic oil: its kinematic viscosity at 40 and 100 degC [m^2/s]."""

    name: str
    viscosity_40c_m2_s: float
    viscosity_100c_m2_s: float


OIL_GRADES: tuple[OilGrade, ...] = (
    # 40 degC: the ISO 3448 mid-point of the grade. 100 degC: a mineral oil of viscosity
    # index ~100 (the ASTM D2270 relation), e.g. HM/HLP oils' data sheets give 5.4, 6.7-6.9
    # and 8.6-8.8 cSt; the node's shipped VG 46 pair (46 / 6.8 cSt) is the same rule.
    OilGrade('ISO VG 32', 32.0e-6, 5.4e-6),
    OilGrade('ISO VG 46', 46.0e-6, 6.8e-6),
    OilGrade('ISO VG 68', 68.0e-6, 8.7e-6),
)
"""The oil grades a realistic run draws from (equal probability)."""


@dataclass(frozen=True)
class CylinderSettings:
    """The cylinder the pump drives (equal-area equivalent; SI)."""

    area_m2: Range = (8.0e-4, 2.0e-3)
    """Piston area A [m^2]: bores of 32-50 mm, so the 4.9 cc pump at 1000 rad/s moves it at
    0.4-1 m/s, the speed class of EHA positioning axes."""
    stroke_m: Range = (0.15, 0.4)
    """Stroke [m]; setpoints stay within `SetpointSettings.margin_fraction` of the ends."""
    leakage_m3_s_pa: Range = (0.0, 1.0e-13)
    """Internal leakage of pump and cylinder, flow per pressure difference [m^3/(s Pa)]:
    at 200 bar at most 0.12 l/min, so holding a load turns the pump at <= 2.5 rad/s, below
    the monitor's minimum speed (the leakage the brief allows: none or small)."""


@dataclass(frozen=True)
class LoadSettings:
    """Load of the cylinder: F = m a + c v + k (x - x_mid) + m g s (+ payload, SI)."""

    mass_kg: Range = (100.0, 800.0)
    """Moving mass m [kg] (rod, slide, tool)."""
    gravity_sine: Range = (-1.0, 1.0)
    """Sine of the axis' inclination s: the sign is the load's direction (s > 0 loads
    extension, so extending pumps and retracting motors)."""
    payload_kg: Range = (0.0, 300.0)
    """Payload picked at the pick end and released at the place end (pick-and-place)."""
    spring_pressure_pa: Range = (0.0, 60.0e5)
    """Spring force at half a stroke from mid-stroke, over A [Pa] (k = that A / (stroke/2))."""
    damping_pressure_pa: Range = (5.0e5, 30.0e5)
    """Viscous damper force at the largest cylinder speed, over A [Pa]."""
    max_static_pressure_pa: float = 200.0e5
    """Gravity with payload plus spring is scaled down to stay below this [Pa]: with the
    dynamic part the pressure stays inside the node's 350-bar table."""
    gravity_m_s2: float = 9.81
    """Standard gravity [m/s^2]."""


@dataclass(frozen=True)
class LoopSettings:
    """The drive's position and speed loops (the brief of issue #17, point 6)."""

    position_gain_1_s: Range = (10.0, 30.0)
    """P gain Kp: commanded cylinder speed per position error [1/s]; with the speed loop an
    order faster, the position response is a lag of time constant 1/Kp (33-100 ms)."""
    integral_ratio: Range = (0.0, 0.2)
    """PI: Ki = ratio x Kp^2 [1/s^2] (a zero a decade or more below Kp); 0 is a P loop."""
    integral_limit_fraction: float = 0.1
    """Anti-windup: the integral's speed command stays within this x max speed [-]."""
    velocity_feedforward: bool = True
    """The setpoint's own speed is fed forward (ramps are followed without lag)."""
    speed_bandwidth_hz: Range = (50.0, 100.0)
    """Speed loop: first-order lag of this bandwidth from speed command to speed [Hz]."""
    slew_rad_s2: Range = (1.0e4, 3.0e4)
    """Slew limit of the speed command [rad/s^2]."""
    max_speed_rad_s: Range = (600.0, 1000.0)
    """Speed command limit [rad/s] (5,700-9,500 rpm, inside the table's 12,000 rpm)."""
    step_s: float = 1.0e-3
    """Integration step [s]: 1 kHz, the JointState rate; the speed lag is integrated
    exactly over each step (zero-order-held command), so any bandwidth is stable."""


@dataclass(frozen=True)
class SetpointSettings:
    """Position setpoints: moves (steps or ramps) to targets, each followed by a dwell."""

    pick_place: bool = False
    """Targets alternate between a pick and a place zone, with a payload in between;
    otherwise targets are anywhere in the stroke."""
    step_probability: float = 0.3
    """A move is a setpoint step (the loop saturates and slews); otherwise a ramp."""
    step_max_fraction: float = 0.15
    """A step jumps by at most this fraction of the stroke [-] (larger jumps would let the
    slew-limited loop overshoot into the end stops)."""
    ramp_speed_fraction: Range = (0.15, 0.9)
    """Peak speed of a ramp as a fraction of the cylinder speed at the loop's max pump
    speed [-]."""
    dwell_s: Range = (0.3, 3.0)
    """Hold at the target [s]: the pump dwells at (near) zero speed under pressure."""
    margin_fraction: float = 0.05
    """Targets keep this fraction of the stroke from either end [-]."""
    zone_fraction: float = 0.25
    """Pick-and-place: each zone is this fraction of the stroke at its end [-]."""
    small_move_probability: float = 0.2
    """A move is a small correction (creep, frequent reversals)."""
    small_move_fraction: Range = (0.01, 0.05)
    """Size of a small correction as a fraction of the stroke [-]."""


@dataclass(frozen=True)
class TemperatureSettings:
    """Oil temperature: a cold start warming up, or steady; with or without the topic."""

    cold_start: bool = False
    """T(t) = T1 - (T1 - T0) exp(-t / tau) from a cold start; otherwise steady."""
    start_c: Range = (12.0, 18.0)
    """Cold start T0 [degC] (a machine hall in the morning)."""
    end_c: Range = (50.0, 60.0)
    """Warm T1 [degC] (an EHA's working temperature)."""
    time_constant_s: Range = (300.0, 900.0)
    """Warm-up time constant tau [s]: a small EHA's oil volume under load."""
    steady_c: Range = (40.0, 55.0)
    """Steady temperature when not a cold start [degC]."""
    swing_c: Range = (0.0, 3.0)
    """Slow sinusoidal swing of the steady temperature [degC]."""
    swing_period_s: Range = (600.0, 1800.0)
    """Period of the swing [s]."""
    topic: bool = True
    """The node gets the temperature topic (``viscosity_source: temperature``); otherwise it
    is configured with the grade's viscosity at ``nominal_c`` (``viscosity_source:
    parameter``), as an engineer would."""
    nominal_c: float = 50.0
    """The engineer's expected working temperature [degC]."""
    rate_hz: float = 10.0
    """Temperature topic rate [Hz]."""
    noise_c: float = 0.2
    """Std of its white noise [degC]."""


@dataclass(frozen=True)
class PlantSettings:
    """Rotor inertia and drive loss of the motor, and what the node is told of them."""

    rotor_inertia_kg_m2: Range = (5.0e-4, 1.0e-3)
    """True rotor + coupling + rotating group inertia J [kg m^2] (servo motors of EHAs)."""
    inertia_config_error: Range = (-0.1, 0.1)
    """The node's J = true J x (1 + this): a data-sheet rotor plus an estimated coupling."""
    drive_loss_nm: Range = (0.0, 0.05)
    """True constant drive loss (seals, motor bearings) [N m]; the node is configured with
    it (measured at commissioning)."""


@dataclass(frozen=True)
class SensorSettings:
    """Real sensors and message streams (drawn per seed)."""

    joint_rate_hz: float = 1000.0
    """JointState rate [Hz]: the drive's speed and torque."""
    pressure_rates_hz: tuple[float, ...] = (100.0, 200.0, 250.0, 500.0)
    """FluidPressure rate choices [Hz]: a transmitter on a field bus, 100-500 Hz."""
    pressure_noise_pa: Range = (0.3e5, 1.5e5)
    """Std of the white noise of the measured pressure difference [Pa]."""
    pressure_offset_pa: Range = (-1.0e5, 1.0e5)
    """Offset [Pa]: +-0.25 % of a 400-bar span, a transmitter's zero error."""
    torque_constant_error: Range = (-0.03, 0.03)
    """Torque from current: measured = (1 + e) x delivered, e the torque-constant error [-]
    (a servo motor's k_t tolerance, +-3 % in the brief)."""
    torque_drift_probability: float = 0.5
    """Share of runs whose torque constant drifts with temperature [-]."""
    torque_drift_per_k: Range = (0.0, 1.2e-3)
    """Gain drift per K above ``torque_drift_reference_c`` [1/K]: NdFeB magnets lose ~0.12 %
    of remanence per K, so a drive with a cold k_t over-reads a warm motor by as much (the
    oil temperature stands for the flanged motor's)."""
    torque_drift_reference_c: float = 40.0
    """Temperature at which the drive's k_t is right (+ the error above) [degC]."""
    torque_offset_nm: Range = (-0.02, 0.02)
    """Current-sensor offset, as torque [N m]."""
    torque_noise_nm: Range = (0.02, 0.06)
    """Std of the white noise of the measured torque [N m]."""
    ripple_fraction: Range = (0.01, 0.04)
    """Torque ripple amplitude as a fraction of |V_g dp / (2 pi)| [-]."""
    ripple_order: int = 5
    """Ripple frequency in multiples of the shaft frequency (5 pistons; the brief's 5x)."""
    encoder_counts_per_rev: tuple[int, ...] = (4096, 16384, 65536)
    """Encoder resolution choices: the speed is the counted angle's difference over one
    JointState period, so quantised to 2 pi / (counts x period) (1.5 to 0.1 rad/s)."""
    drop_probability: Range = (0.0, 0.01)
    """Each JointState and FluidPressure message is lost with this probability [-]."""
    burst_rate_per_h: Range = (0.0, 30.0)
    """Bus hiccups per hour: every joint and pressure message lost for a burst [1/h]."""
    burst_length_s: Range = (0.02, 0.3)
    """Length of a burst [s] (longer than ``max_input_age_s``: the node goes stale)."""
    duplicate_probability: Range = (0.0, 0.005)
    """Each message is sent twice (same stamp) with this probability [-]."""


@dataclass(frozen=True)
class MismatchSettings:
    """How the true pump differs from the node's pump file (a few cached variants)."""

    film_clearance_factor: Range = (0.8, 1.2)
    """Valve-plate film clearance x this: 8-12 um for a 10 um pump (the brief's range);
    the shipped paper set's 1.07 um effective film likewise +-20 %."""
    bearing_factor: Range = (0.8, 1.2)
    """Palmgren f0 and f1 each x this (independent draws) [-]."""
    coulomb_factor: Range = (0.8, 1.2)
    """Each coulomb curve (valve plate, spherical joints, piston heads) x this [-]."""
    variants: int = 6
    """Distinct true pumps: each builds a table (seconds), cached on disk and per process."""
    variant_seed: int = 17
    """Seed of the variants' draws (fixed: the bank's seed picks among them)."""
    max_viscosity_m2_s: float = 450.0e-6
    """Top of the true tables' viscosity axis [m^2/s]: VG 68 at 12 degC is ~370 cSt, far
    above the node's 100-cSt table, which clamps there."""
    viscosity_points: int = 12
    """Viscosity nodes of the true tables (geometric; the node's has 8 over 10-100 cSt)."""


@dataclass(frozen=True)
class EhaSettings:
    """A realistic family: setpoints, loops, cylinder, load, plant, oil, sensors, true pump."""

    setpoints: SetpointSettings = field(default_factory=SetpointSettings)
    temperature: TemperatureSettings = field(default_factory=TemperatureSettings)
    loop: LoopSettings = field(default_factory=LoopSettings)
    cylinder: CylinderSettings = field(default_factory=CylinderSettings)
    load: LoadSettings = field(default_factory=LoadSettings)
    plant: PlantSettings = field(default_factory=PlantSettings)
    sensors: SensorSettings = field(default_factory=SensorSettings)
    mismatch: MismatchSettings = field(default_factory=MismatchSettings)
