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
What the oil's temperature does to the torque without any fault: the monitor's allowances.

The healthy baseline is learnt at the oil temperature of commissioning. Later the oil is
warmer or cooler, and two things move the torque though nothing wore:

1. **The viscosity, where it is assumed** (``viscosity_source: parameter``). The valve
   plate's film shear is linear in the viscosity (Couette shear, sec. 4.2) and the
   bearing's drag rises with it; on an ISO VG 68 oil at 50 degC, 3 K are 14 % of the
   viscosity (ASTM D341). Measured on the bank's steps without temperature topic, seed 1:
   an oil swinging +-2.9 K over 20 min raised a WARN at every swing's cold side. The
   friction change over ``oil_temperature_band_c`` either side (0, none, by default: the
   band is the installation's, from its records), along the speed axis
   (`band_friction_nm`), per component, times the installation's friction levels that the
   baseline learnt (`OilAllowance.window_nm`: the model's N m are not the pump's, least
   where the oil runs colder than the viscosity assumed), is taken off the change of
   every cause. With the temperature topic the table follows the viscosity and this part
   is zero.
2. **The drive's torque constant.** Torque from current reads k_t i with a k_t of one
   temperature; NdFeB magnets lose about 0.12 % of their remanence per K, so a warm motor
   delivers less than the drive assumes and the measured torque reads high by up to
   ``torque_constant_drift_per_k`` times the temperature change times the torque: 4-5 %
   over a cold start. Measured on the bank's cold start with the topic, seed 1: a drive
   drifting 0.94e-3 / K, commissioned at 23 degC, went to ERROR (not friction) as the oil
   reached 57 degC (``gain_follow`` now learns such a drift where it shows; this
   allowance is for a drift known beforehand, or without the topic, over the band). With
   the topic the change is the oil temperature's from commissioning's mean (the oil
   standing for the flanged motor's); without it, the band, either way. The
   drift is one-sided (`OilAllowance.gain_interval_nm`): warmer, a pumping window reads high
   and a motoring one low. In each window only its own side is allowed, so wear, which adds
   friction in both, keeps its full sensitivity in the windows whose drift goes the other
   way. (A symmetric allowance of the same size hid a valve plate's x1.8 on the bank's cold
   starts; one on the measurement causes' sums alone let the friction causes' two-sided
   sums collect the drift's excursions.)

Both are bounds, not estimates: the change from the baseline is shrunk by them before the
CUSUMs accumulate it (``monitor``), as it is by the baseline's own uncertainty. A change
smaller than its allowance is not seen; the undetectable change that the published intervals
span includes the viscous allowance's mean and half the drift interval's mean width.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError
from ..physics.oil import WaltherViscosity
from ..physics.units import m2_s_to_cst
from ..table.friction_table import FrictionTable

__all__ = ['OilAllowance', 'band_friction_nm', 'oil_allowance']


def band_friction_nm(table: FrictionTable, viscosity_m2_s: float, oil: WaltherViscosity,
                     band_c: float) -> tuple[list[float], list[float], list[float]]:
    """
    Return the friction change over the oil temperature band, along the table's speed axis.

    The change of the valve plate's and of the other components' friction magnitudes when
    the oil is ``band_c`` colder or warmer than where it has ``viscosity_m2_s`` (the larger
    of the two sides), at the middle of the pressure axis: the viscous terms do not depend
    on the load pressure (the film is sheared whatever presses on it; docs/model.md).

    Parameters
    ----------
    table : FrictionTable
        The node's table.
    viscosity_m2_s : float
        The assumed viscosity [m^2/s].
    oil : WaltherViscosity
        The oil's viscosity-temperature law.
    band_c : float
        How far the oil temperature strays [K]; 0: no change.

    Returns
    -------
    tuple of list
        Speeds [rad/s] (the table's axis), the valve plate's friction change there and the
        other components' [N m], >= 0.

    Raises
    ------
    ConfigError
        The band reaches beyond the oil's law (one line).

    """
    speeds = [float(x) for x in np.asarray(table.speed_axis_rad_s)]
    if not band_c > 0.0:
        return speeds, [0.0] * len(speeds), [0.0] * len(speeds)
    try:
        temperature = oil.temperature_c(viscosity_m2_s)
        cold, warm = oil(temperature - band_c), oil(temperature + band_c)
    except (ValueError, OverflowError):
        raise ConfigError(f'oil_temperature_band_c {band_c:g} K about the oil viscosity '
                          f'{viscosity_m2_s:g} m^2/s is outside the viscosity law of the oil '
                          '(oil_viscosity_40c/100c_m2_s)') from None
    pressures = np.asarray(table.pressure_axis_pa)
    pressure = float(pressures[pressures.size // 2])
    valve_plate, other = [], []
    for speed in speeds:
        middle, low, high = (table.magnitudes(speed, pressure, nu)[0]
                             for nu in (viscosity_m2_s, warm, cold))
        valve_plate.append(max(abs(high[0] - middle[0]), abs(middle[0] - low[0])))
        other.append(max(abs(sum(high[1:]) - sum(middle[1:])),
                         abs(sum(middle[1:]) - sum(low[1:]))))
    return speeds, valve_plate, other


class OilAllowance:
    """
    The torque change the oil's temperature may make at a window's operating point.

    Parameters
    ----------
    speeds_rad_s : list of float
        Speeds [rad/s], increasing (`band_friction_nm`).
    valve_plate_change_nm : list of float
        The valve plate's friction change over the band there [N m] (zeros with the
        temperature topic).
    oil : WaltherViscosity, optional
        The oil's law, where the viscosity is measured (the temperature topic): a window's
        temperature is read back from its viscosity. None: the temperature is not known.
    drift_per_k : float
        ``torque_constant_drift_per_k`` [1/K].
    band_c : float
        ``oil_temperature_band_c`` [K]: the temperature change where it is not known.
    other_change_nm : list of float, optional
        The other components' friction change over the band there [N m] (None: zeros).

    """

    def __init__(self, speeds_rad_s: list[float], valve_plate_change_nm: list[float],
                 oil: WaltherViscosity | None = None, drift_per_k: float = 0.0,
                 band_c: float = 0.0, other_change_nm: list[float] | None = None) -> None:
        self._speeds = np.asarray(speeds_rad_s, dtype=float)
        self._change = np.asarray(valve_plate_change_nm, dtype=float)
        self._other = np.zeros_like(self._change) if other_change_nm is None else \
            np.asarray(other_change_nm, dtype=float)
        if not self._speeds.shape == self._change.shape == self._other.shape:
            raise ValueError('the band needs one change of each part per speed')
        self._oil = oil
        self.drift_per_k = drift_per_k
        self.band_c = band_c

    def window_nm(self, speed_abs_rad_s: float, valve_plate_level: float = 1.0,
                  other_level: float = 1.0) -> float:
        """
        Return the viscous friction's change over the band at a window's mean |speed| [N m].

        The band's change is the model's, at the assumed viscosity; the installation's
        friction is the baseline's learnt level times the model's (``baseline``: the
        pump's film clearance, and the oil's viscosity where it runs against the one
        assumed), and a viscous friction's change over the band is that level times the
        model's too. Measured on the bank's steps without temperature topic, seed 4,
        installation 1 (an ISO VG 68 assumed at 50 degC, running at 38-43 degC, learnt at
        1.89 times the model's valve plate): at a 5 K band in the model's N m an alarm
        went through at a trough of the swing, none with the band scaled (docs/monitor.md).
        The level is of a component's whole magnitude, Coulomb part included: where it is
        a Coulomb friction's difference, or the fit shares a level between the two causes
        that the duty cycle cannot tell apart, the band is that much wider or narrower than
        the film's.

        Parameters
        ----------
        speed_abs_rad_s : float
            The window's mean |speed| [rad/s].
        valve_plate_level, other_level : float
            The installation's friction levels against the model [-] (1: as modelled;
            below 0 taken as 0).

        Returns
        -------
        float
            The friction change over the band, interpolated (held beyond the axis), >= 0.

        """
        speed = speed_abs_rad_s
        return max(0.0, valve_plate_level) * float(np.interp(speed, self._speeds,
                                                             self._change)) + \
            max(0.0, other_level) * float(np.interp(speed, self._speeds, self._other))

    def temperature_c(self, viscosity_m2_s: float) -> float:
        """
        Return a window's oil temperature from its mean viscosity [degC].

        Parameters
        ----------
        viscosity_m2_s : float
            The window's mean viscosity [m^2/s].

        Returns
        -------
        float
            The temperature; NaN where the viscosity is assumed or not a viscosity.

        """
        if self._oil is None or not m2_s_to_cst(viscosity_m2_s) > 0.3 or \
                not math.isfinite(viscosity_m2_s):  # the inverse law's domain (ASTM D341)
            return math.nan
        return self._oil.temperature_c(viscosity_m2_s)

    def gain_interval_nm(self, delivered_nm: float, temperature_c: float,
                         reference_c: float) -> tuple[float, float]:
        """
        Return the interval the torque constant's drift may move a window's residual in [N m].

        A warm NdFeB motor has a smaller torque constant than the drive assumes, so the
        measured torque reads high by c (T - T_ref) times the delivered torque, c between 0
        and ``drift_per_k``: one-sided, its sign that of (T - T_ref) times the torque. In a
        window where the drift moves the residual one way, a change the other way keeps its
        full sensitivity (motoring while warmer: wear still adds friction).

        Parameters
        ----------
        delivered_nm : float
            The window's mean delivered torque in the friction direction [N m] (theoretical
            times the direction of rotation, plus friction; the drive loss and the inertia
            torque, which the drive also reads through k_t, are left out: a little less).
        temperature_c : float
            Its oil temperature [degC] (NaN: not known).
        reference_c : float
            Commissioning's mean oil temperature [degC] (NaN: not known).

        Returns
        -------
        tuple of float
            (low, high), low <= 0 <= high; where the temperature change is not known, the
            band either way: -+ drift x band x |torque|.

        """
        delta = temperature_c - reference_c
        if not math.isfinite(delta):
            bound = self.drift_per_k * self.band_c * abs(delivered_nm)
            return -bound, bound
        drift = self.drift_per_k * delta * delivered_nm
        return (drift, 0.0) if drift < 0.0 else (0.0, drift)

    def note(self, reference_c: float, learnt: bool) -> str:
        """
        Return why a configured drift allowance has no effect, or ''.

        Parameters
        ----------
        reference_c : float
            Commissioning's mean oil temperature [degC] (NaN: not known).
        learnt : bool
            Whether the baseline is complete.

        Returns
        -------
        str
            One line for /diagnostics; '' where the allowance works or none is configured.

        """
        if not self.drift_per_k > 0.0 or self.band_c > 0.0:
            return ''
        if self._oil is None:
            return ('torque_constant_drift_per_k has no effect: the oil temperature is not '
                    'known and oil_temperature_band_c is 0')
        if learnt and not math.isfinite(reference_c):
            return ('torque_constant_drift_per_k has no effect until the baseline is learnt '
                    'again: it holds no oil temperature')
        return ''


def oil_allowance(table: FrictionTable, viscosity_m2_s: float, oil: WaltherViscosity,
                  viscosity_assumed: bool, band_c: float, drift_per_k: float) -> OilAllowance:
    """
    Return the node's allowances from its parameters.

    Parameters
    ----------
    table : FrictionTable
        The node's table.
    viscosity_m2_s : float
        The assumed viscosity [m^2/s] (used where ``viscosity_assumed``).
    oil : WaltherViscosity
        The oil's law.
    viscosity_assumed : bool
        ``viscosity_source: parameter``: the oil temperature is not known.
    band_c : float
        ``oil_temperature_band_c`` [K].
    drift_per_k : float
        ``torque_constant_drift_per_k`` [1/K].

    Returns
    -------
    OilAllowance
        The viscous band where the viscosity is assumed (zeros otherwise), the oil's law
        where it is measured, and the drift.

    """
    speeds, valve_plate, other = band_friction_nm(table, viscosity_m2_s, oil,
                                                  band_c if viscosity_assumed else 0.0)
    return OilAllowance(speeds, valve_plate, None if viscosity_assumed else oil, drift_per_k,
                        band_c, other)
