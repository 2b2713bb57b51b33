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
Every number of the monitor evaluation bank, in one place, with its meaning.

Duty-cycle families (`FAMILIES`; `HELD_OUT_FAMILIES`, run apart), faults (`FAULTS`, some
held out: `Fault.scope`), sensor and load settings (`SignalSettings`) and the size of the
bank (`QUICK`, `FULL`). Ranges ``(low, high)`` are drawn uniformly per scenario from its
seed. The plant constants that the estimator of the classic families must share with the
truth (rotor inertia, nominal drive loss, oil viscosity and its 40 / 100 degC law) are not
here: they come from the package's node parameters (``config/torque_estimator.yaml``), so
that the estimator is configured as the truth is.

The realistic families (position-controlled EHAs with real sensors, oils, cold starts and a
true pump that is not the node's model) have their numbers in ``eha_settings``; their
faults are those with ``scope='eha'`` and their bank size is `BankSettings.eha`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .eha_settings import EhaSettings, SetpointSettings, TemperatureSettings

__all__ = [
    'ACCEPTED_ATTRIBUTIONS',
    'ALL_FAMILIES',
    'ATTRIBUTIONS',
    'FAMILIES',
    'FAULTS',
    'FLOORS',
    'FULL',
    'HELD_OUT_FAMILIES',
    'QUICK',
    'BankSettings',
    'CreepSettings',
    'CruiseSettings',
    'EhaBankSettings',
    'Family',
    'Fault',
    'Floors',
    'HighDynamicsSettings',
    'SetpointLagSettings',
    'SignalSettings',
    'SineSettings',
    'TrapezoidSettings',
    'WarmUpSettings',
]

Range = tuple[float, float]


@dataclass(frozen=True)
class SignalSettings:
    """Sampling, sensor noise and load of a scenario (SI; per family, see `Family`)."""

    joint_rate_hz: float = 1000.0
    """JointState rate: speed and measured torque [Hz]."""
    pressure_rate_hz: float = 500.0
    """FluidPressure rate (pressure difference p_A - p_B) [Hz]."""
    temperature_rate_hz: float = 10.0
    """Oil Temperature rate, when the family uses it [Hz]."""
    torque_noise_nm: float = 0.05
    """Std of the white noise on the measured motor torque [N m]."""
    speed_noise_rad_s: float = 0.5
    """Std of the white noise on the measured shaft speed [rad/s]."""
    pressure_noise_pa: float = 1.0e5
    """Std of the white noise on the measured pressure difference [Pa]."""
    temperature_noise_c: float = 0.2
    """Std of the white noise on the measured oil temperature [degC]."""
    load_pressure_pa: Range = (40e5, 220e5)
    """Gravity-like load: the static pressure difference swings between these [Pa]."""
    load_period_s: Range = (15.0, 40.0)
    """Period of the sinusoidal swing of the static load [s]."""
    damping_pa_per_rad_s: float = 2.0e3
    """Damping: dp += damping x speed [Pa/(rad/s)]; retracting then runs the pump as a motor."""


@dataclass(frozen=True)
class TrapezoidSettings:
    """Family 1: the moves of ``simulate.trapezoid_speed_profile`` (its `DutyCycle` fields)."""

    max_speed_rad_s: float = 900.0
    """Largest cruise speed of a move [rad/s] (~8,600 rpm)."""
    min_speed_rad_s: float = 150.0
    """Smallest cruise speed of a move [rad/s]."""
    accel_time_s: Range = (0.05, 0.15)
    """Duration of each (cosine-smoothed) ramp [s]."""
    cruise_time_s: Range = (0.3, 1.5)
    """Duration of the cruise of a move [s]."""
    dwell_time_s: Range = (0.05, 0.6)
    """Standstill between moves [s]."""


@dataclass(frozen=True)
class SineSettings:
    """
    Family 2: sinusoidal positioning, speed = A sin(2 pi t / T1) + B sin(2 pi t / T2).

    The issue's example is A = 6000 rpm (628 rad/s), T1 = 8 s, B = 2500 rpm (262 rad/s),
    T2 = 2.3 s; the defaults bracket it.
    """

    amplitude_1_rad_s: Range = (400.0, 700.0)
    """A [rad/s]."""
    period_1_s: Range = (6.0, 10.0)
    """T1 [s]."""
    amplitude_2_rad_s: Range = (150.0, 300.0)
    """B [rad/s]."""
    period_2_s: Range = (1.8, 3.0)
    """T2 [s]."""


@dataclass(frozen=True)
class SetpointLagSettings:
    """Family 3: random speed setpoints reached through a first-order lag."""

    setpoint_rad_s: Range = (100.0, 900.0)
    """|setpoint| of a moving segment [rad/s]; the sign is random."""
    stop_probability: float = 0.2
    """Probability that a segment's setpoint is standstill [-]."""
    hold_time_s: Range = (0.5, 4.0)
    """How long each setpoint is held [s]."""
    lag_time_constant_s: Range = (0.08, 0.4)
    """Time constant of the lag (drawn once per scenario) [s]."""


@dataclass(frozen=True)
class CruiseSettings:
    """
    Family 4: long cruise at one speed with slow small variations.

    speed = S r(t) (1 + a sin(2 pi t / T + phase)), r a cosine spin-up from rest.
    """

    speed_rad_s: Range = (300.0, 1000.0)
    """|S| [rad/s]; the sign is random."""
    variation: Range = (0.02, 0.08)
    """Relative amplitude a of the slow variation [-]."""
    variation_period_s: Range = (20.0, 90.0)
    """Period T of the slow variation [s]."""
    spin_up_s: float = 3.0
    """Duration of the spin-up from rest [s]."""


@dataclass(frozen=True)
class CreepSettings:
    """Family 5: low-speed creep with many reversals, speed = A sin(2 pi t / T1) + B sin(...)."""

    amplitude_1_rad_s: Range = (10.0, 45.0)
    """A [rad/s] (the monitor learns only above ``monitor_min_speed_rad_s``, 20 by default)."""
    period_1_s: Range = (1.0, 4.0)
    """T1 [s]: two reversals per period."""
    amplitude_2_rad_s: Range = (0.0, 15.0)
    """B [rad/s]."""
    period_2_s: Range = (0.3, 1.0)
    """T2 [s]."""


@dataclass(frozen=True)
class WarmUpSettings:
    """
    Family 6: oil warm-up under trapezoidal moves, with the temperature input.

    T(t) = T0 + (T1 - T0) (1 - exp(-t / tau)) / (1 - exp(-D / tau)), tau = fraction x D for
    a run of duration D: T0 at the start, exactly T1 at the end. The truth viscosity follows
    ASTM D341 (`oil.WaltherViscosity`) through the node parameters' 40 and 100 degC values;
    the estimator runs with ``viscosity_source: temperature``.
    """

    start_c: float = 30.0
    """Oil temperature at the start [degC]."""
    end_c: float = 60.0
    """Oil temperature at the end [degC]."""
    time_constant_fraction: float = 0.3
    """Warm-up time constant as a fraction of the run [-]."""
    moves: TrapezoidSettings = field(default_factory=TrapezoidSettings)
    """The duty cycle during the warm-up."""


@dataclass(frozen=True)
class HighDynamicsSettings:
    """
    Family 7: back-and-forth moves that spend most of the time above the monitor's accel gate.

    Alternating peaks, each reached by a cosine-smoothed ramp of mean acceleration drawn
    from ``mean_accel_rad_s2`` (peak acceleration pi / 2 times that), held for a short dwell.
    """

    peak_speed_rad_s: Range = (200.0, 900.0)
    """|peak speed| [rad/s]; peaks alternate in sign."""
    mean_accel_rad_s2: Range = (800.0, 3000.0)
    """Mean acceleration of a ramp between peaks [rad/s^2]."""
    peak_dwell_s: Range = (0.0, 0.1)
    """Hold at each peak [s]."""


Motion = (TrapezoidSettings | SineSettings | SetpointLagSettings | CruiseSettings
          | CreepSettings | WarmUpSettings | HighDynamicsSettings | EhaSettings)


@dataclass(frozen=True)
class Family:
    """A duty-cycle family: a name, a short column label, its motion and its signals."""

    name: str
    label: str
    motion: Motion
    signals: SignalSettings = field(default_factory=SignalSettings)

    @property
    def realistic(self) -> bool:
        """Return whether this is a realistic EHA family (``eha_scenarios``; its own sizes)."""
        return isinstance(self.motion, EhaSettings)

    @property
    def uses_temperature(self) -> bool:
        """Return whether the family feeds oil temperature and runs the estimator on it."""
        if isinstance(self.motion, EhaSettings):
            return self.motion.temperature.topic
        return isinstance(self.motion, WarmUpSettings)


_COLD = TemperatureSettings(cold_start=True)
FAMILIES: tuple[Family, ...] = (
    Family('trapezoid', 'trap', TrapezoidSettings()),
    Family('sine', 'sine', SineSettings()),
    Family('setpoint_lag', 'lag', SetpointLagSettings()),
    Family('cruise', 'cruise', CruiseSettings(), SignalSettings(load_period_s=(40.0, 120.0))),
    Family('creep', 'creep', CreepSettings()),
    Family('warm_up', 'warm', WarmUpSettings()),
    Family('high_dynamics', 'dyn', HighDynamicsSettings()),
    # realistic EHAs: closed position loop, real sensors, an oil grade, a mismatched pump
    Family('eha_pick_place', 'eha pnp', EhaSettings(SetpointSettings(pick_place=True))),
    Family('eha_steps_no_temp', 'eha steps nt', EhaSettings(
        SetpointSettings(step_probability=0.4), TemperatureSettings(topic=False))),
    Family('eha_cold_start', 'eha cold', EhaSettings(SetpointSettings(pick_place=True), _COLD)),
    Family('eha_cold_no_temp', 'eha cold nt', EhaSettings(
        SetpointSettings(), TemperatureSettings(cold_start=True, topic=False))),
)
"""The duty-cycle families, in table order: the classic ones, then the realistic EHAs."""

HELD_OUT_FAMILIES: tuple[Family, ...] = (
    Family('eha_ramps_temp', 'eha ramps', EhaSettings(SetpointSettings(step_probability=0.0))),
    Family('eha_jerky_temp', 'eha jerky', EhaSettings(SetpointSettings(
        step_probability=0.7, small_move_probability=0.5))),
    Family('eha_long_dwell', 'eha dwell', EhaSettings(SetpointSettings(
        pick_place=True, dwell_s=(3.0, 12.0)))),
    Family('eha_pnp_nt_thermo', 'eha pnp nt thermo', EhaSettings(
        SetpointSettings(pick_place=True), TemperatureSettings(topic=False, swing_c=(0.0, 0.0)))),
)
"""
Realistic duty cycles held out of the bank (``evaluate-monitor --held-out``): no number of
the monitor was set on them. With the temperature topic: ramps only, no setpoint steps;
jerky, 70 % of the moves steps and, drawn apart, half of all moves small corrections
(reversals, little steady running); pick and place with dwells of 3-12 s under pressure (a
few % of the time monitored).
Without it: pick and place on an oil held by a thermostat (no swing). Everything else is
drawn as for `FAMILIES`' realistic ones.
"""

ALL_FAMILIES: tuple[Family, ...] = FAMILIES + HELD_OUT_FAMILIES
"""Every family, in table order (a bank's records name one of these)."""

ATTRIBUTIONS = ('valve_plate', 'other_friction', 'not_friction', 'cannot_tell', 'none')
"""Possible attributions of a monitor reading ('none': no alarm), in table order."""


@dataclass(frozen=True)
class Fault:
    """
    A fault applied as a step at the scenario's onset (or a ramp, or on/off episodes).

    Friction factors multiply one friction component of the true pump each; the drive loss
    is added opposing the motion (extra x tanh(speed / zero-speed threshold)); the offset is
    added to the measured motor torque; the gain multiplies the measured pressure difference;
    the torque gain multiplies the measured motor torque (a torque-constant change).
    """

    name: str
    truth_class: str
    """'nominal', 'valve_plate', 'other_friction', 'drive_loss', 'not_friction' or
    'measurement' (a change of the torque measurement: not friction)."""
    size: float = 1.0
    """Fault size on the x axis of the delay plot (the factor, the extra torque, the gain)."""
    valve_plate: float = 1.0
    """Friction factor of the valve plate [-] (reached at the end of the ramp if ``ramp``)."""
    bearing: float = 1.0
    """Friction factor of the shaft bearing [-]."""
    spherical_joints: float = 1.0
    """Friction factor of the spherical joints [-]."""
    piston_heads: float = 1.0
    """Friction factor of the piston heads [-]."""
    ramp: bool = False
    """The valve-plate factor (and the torque gain) ramps linearly from 1 over the bank's
    ``ramp_s``."""
    drive_loss_nm: float = 0.0
    """Extra constant drive loss opposing the motion [N m]."""
    torque_offset_nm: float = 0.0
    """Offset of the measured-torque sensor [N m]."""
    pressure_gain: float = 1.0
    """Gain of the pressure sensor: measured dp = gain x true dp [-]."""
    torque_gain: float = 1.0
    """Gain change of the measured motor torque (torque constant) [-] (realistic families)."""
    intermittent: bool = False
    """Every factor of the fault applies in the same on/off episodes from the onset, starting
    on."""
    episode_on_s: Range = (20.0, 90.0)
    """Length of an 'on' episode [s] (intermittent faults)."""
    episode_off_s: Range = (20.0, 180.0)
    """Length of an 'off' episode [s] (intermittent faults)."""
    scope: str = 'classic'
    """The families the fault is run on: 'classic', 'eha' (the realistic ones), 'all', or
    'held_out' (the realistic ones, only in a held-out bank)."""

    def applies_to(self, family: Family, held_out: bool = False) -> bool:
        """
        Return whether a bank runs this fault on ``family``.

        Parameters
        ----------
        family : Family
            A duty-cycle family.
        held_out : bool
            The held-out bank (`BankSettings.held_out`): what the default bank holds out,
            every realistic fault on `HELD_OUT_FAMILIES` and the held-out faults on every
            realistic family.

        Returns
        -------
        bool
            Whether the bank runs it.

        """
        if held_out:
            return family.realistic and (self.scope == 'held_out' or (
                self.scope in ('eha', 'all') and family in HELD_OUT_FAMILIES))
        return self.scope == 'all' or self.scope == ('eha' if family.realistic else 'classic')

    @property
    def factors(self) -> dict[str, float]:
        """Friction factor of each component (``model.COMPONENTS`` names) [-]."""
        return {'valve_plate': self.valve_plate, 'bearing': self.bearing,
                'spherical_joints': self.spherical_joints, 'piston_heads': self.piston_heads}


FAULTS: tuple[Fault, ...] = (
    Fault('nominal', 'nominal', scope='all'),
    Fault('valve_plate_x1.2', 'valve_plate', 1.2, valve_plate=1.2),
    Fault('valve_plate_x1.6', 'valve_plate', 1.6, valve_plate=1.6),
    Fault('valve_plate_x2.0', 'valve_plate', 2.0, valve_plate=2.0),
    Fault('valve_plate_ramp_1.5', 'valve_plate', 1.5, valve_plate=1.5, ramp=True),
    Fault('bearing_x1.8', 'other_friction', 1.8, bearing=1.8),
    Fault('joints_x3', 'other_friction', 3.0, spherical_joints=3.0),
    Fault('drive_loss_+0.2nm', 'drive_loss', 0.2, drive_loss_nm=0.2),
    Fault('torque_offset_+0.2nm', 'not_friction', 0.2, torque_offset_nm=0.2),
    Fault('pressure_gain_1.05', 'not_friction', 1.05, pressure_gain=1.05),
    # the realistic families' faults (issue #17, point 6)
    Fault('valve_plate_x1.4', 'valve_plate', 1.4, valve_plate=1.4, scope='eha'),
    Fault('valve_plate_x1.8', 'valve_plate', 1.8, valve_plate=1.8, scope='eha'),
    Fault('valve_plate_ramp_1.6', 'valve_plate', 1.6, valve_plate=1.6, ramp=True, scope='eha'),
    Fault('valve_plate_intermittent_1.8', 'valve_plate', 1.8, valve_plate=1.8,
          intermittent=True, scope='eha'),
    Fault('bearing_x2.0', 'other_friction', 2.0, bearing=2.0, scope='eha'),
    Fault('torque_constant_-5%', 'measurement', 0.95, torque_gain=0.95, ramp=True,
          scope='eha'),
    # held out of the bank: other frictions and non-friction changes on the realistic EHAs
    Fault('spherical_joints_x3', 'other_friction', 3.0, spherical_joints=3.0,
          scope='held_out'),
    Fault('piston_heads_x2', 'other_friction', 2.0, piston_heads=2.0, scope='held_out'),
    Fault('pressure_gain_0.95', 'not_friction', 0.95, pressure_gain=0.95, scope='held_out'),
    Fault('torque_offset_+0.1nm', 'not_friction', 0.1, torque_offset_nm=0.1,
          scope='held_out'),
    Fault('drive_loss_+0.1nm', 'drive_loss', 0.1, drive_loss_nm=0.1, scope='held_out'),
)
"""The faults, in table order; the first is the nominal pump."""

ACCEPTED_ATTRIBUTIONS: dict[str, frozenset[str]] = {
    'nominal': frozenset({'none'}),
    'valve_plate': frozenset({'valve_plate'}),
    'other_friction': frozenset({'other_friction'}),
    'not_friction': frozenset({'not_friction'}),
    'measurement': frozenset({'not_friction'}),  # the monitor's word for any non-friction
    # a drive loss may fairly read as other friction or as not friction: wrong only if the
    # valve plate is named (or nothing is)
    'drive_loss': frozenset({'other_friction', 'not_friction', 'cannot_tell'}),
}
"""Final attributions counted as correct, per true fault class."""


@dataclass(frozen=True)
class Floors:
    """The issue's floors (#17), stated on the runs in their scope (`floors`)."""

    monitored_delay_p90_s: tuple[tuple[str, float], ...] = (
        ('valve_plate_x1.8', 15.0), ('valve_plate_x1.4', 40.0))
    """p90 of the monitored running from the onset to the first alarm, per fault [s]."""
    named: float = 0.9
    """Valve-plate faults named valve plate, of the runs in scope (undetected: not named)."""
    cannot_tell: float = 0.1
    """At most this share of the valve-plate faults in scope `cannot tell` [-]."""


FLOORS = Floors()
"""The issue's floors; false alarms (none) and coverage (85-99 %) are in the main table."""


@dataclass(frozen=True)
class EhaBankSettings:
    """Size of the realistic families' part of a bank (their runs are longer)."""

    nominal_seeds: int
    """Nominal runs per family."""
    nominal_duration_s: float
    """Length of a nominal run [s]."""
    fault_seeds: int
    """Runs per family and fault."""
    fault_duration_s: float
    """Length of a fault run [s]."""
    ramp_s: float
    """Duration of the ramp faults (valve plate, torque constant) [s]."""
    onset_s: Range
    """The fault starts at a time drawn in this range [s]."""
    faults: tuple[str, ...] | None = None
    """Only these faults on the realistic families (None: all that apply)."""


@dataclass(frozen=True)
class BankSettings:
    """Size of a bank: replicates (seeds) and run lengths."""

    name: str
    nominal_seeds: int
    """Nominal runs per family."""
    nominal_duration_s: float
    """Length of a nominal run [s]."""
    fault_seeds: int
    """Runs per family and fault."""
    fault_duration_s: float
    """Length of a fault run [s]."""
    ramp_s: float
    """Duration of the valve-plate ramp fault [s]."""
    onset_fraction: Range = (0.4, 0.6)
    """The fault starts at this fraction of the run [-]."""
    families: tuple[str, ...] | None = None
    """Only these families (None: all)."""
    held_out: bool = False
    """Run what the bank holds out instead (`Fault.applies_to`): `HELD_OUT_FAMILIES` with
    every realistic fault and the held-out faults on every realistic family."""
    faults: tuple[str, ...] | None = None
    """Only these faults (None: all)."""
    eha: EhaBankSettings | None = None
    """Size of the realistic families (None: they are left out)."""


QUICK = BankSettings('quick', nominal_seeds=2, nominal_duration_s=150.0, fault_seeds=1,
                     fault_duration_s=150.0, ramp_s=40.0,
                     eha=EhaBankSettings(1, 150.0, 1, 150.0, ramp_s=40.0, onset_s=(60.0, 90.0),
                                         faults=('nominal', 'valve_plate_x1.8')))
"""
The test-suite bank: about a minute and a half on 2 cores: the classic families (~3.2 h
simulated, 0.58 h nominal) and 8 runs of 150 s of the realistic ones."""

FULL = BankSettings('full', nominal_seeds=6, nominal_duration_s=900.0, fault_seeds=5,
                    fault_duration_s=600.0, ramp_s=180.0,
                    eha=EhaBankSettings(3, 3600.0, 3, 2700.0, ramp_s=600.0,
                                        onset_s=(1800.0, 1860.0)))
"""
The benchmark bank: classic families 7 x 6 x 900 s = 10.5 h of nominal running,
7 x 9 x 5 x 600 s = 52.5 h of fault runs (half of it before the onset); realistic families
4 x 3 x 1 h = 12 h of nominal running, 4 x 6 x 3 x 45 min = 54 h of fault runs, each with
30-31 min of nominal running before the onset (36 h in all)."""
