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
The friction change of an oil whose temperature the node does not know: the allowance.

With ``viscosity_source: parameter`` the node is told one viscosity, and the healthy
baseline is learnt at the oil temperature of commissioning. Later the oil is a few kelvin
warmer or cooler. The valve plate's film shear is linear in the viscosity (Couette shear,
sec. 4.2) and the bearing's drag rises with it, so the torque moves though nothing wore: on
an ISO VG 68 oil at 50 degC, 3 K are 14 % of the viscosity (ASTM D341). Measured on the
bank's steps without temperature topic, seed 1: an oil swinging +-2.9 K over 20 min raised a
WARN at every swing's warm side (3 in an hour, valve plate and other friction leading).

The friction change over ``oil_temperature_band_c`` either side (0, none, by default: the
band is the installation's, from its records), along the speed axis
(`band_friction_nm`), is a bound, not an estimate: the change from the baseline is shrunk by
it before the CUSUM accumulates it (``monitor``), as it is by the baseline's own
uncertainty. A friction change smaller than the allowance at a point is not seen there; the
undetectable change that the published intervals span includes it. With the temperature
topic the table follows the viscosity and there is no allowance.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from ..physics.oil import WaltherViscosity

__all__ = ['OilAllowance', 'band_friction_nm']


class _MagnitudeTable(Protocol):
    """The friction table's scalar lookup (``table.FrictionTable``)."""

    speed_axis_rad_s: np.ndarray
    pressure_axis_pa: np.ndarray

    def magnitudes(self, speed_abs_rad_s: float, pressure_abs_pa: float,
                   viscosity_m2_s: float, motoring: bool = False
                   ) -> tuple[tuple[float, float, float, float], int]:
        """Component magnitudes at one point [N m] and the lookup flags."""


def band_friction_nm(table: _MagnitudeTable, viscosity_m2_s: float, oil: WaltherViscosity,
                     band_c: float) -> tuple[list[float], list[float]]:
    """
    Return the friction change over the oil temperature band, along the table's speed axis.

    The change of the total friction magnitude when the oil is ``band_c`` colder or warmer
    than where it has ``viscosity_m2_s`` (the larger of the two sides), at the middle of the
    pressure axis: the viscous terms do not depend on the load pressure (the film is
    sheared whatever presses on it; docs/model.md).

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
        Speeds [rad/s] (the table's axis) and the friction change there [N m], >= 0.

    """
    speeds = [float(x) for x in np.asarray(table.speed_axis_rad_s)]
    if not band_c > 0.0:
        return speeds, [0.0] * len(speeds)
    temperature = oil.temperature_c(viscosity_m2_s)
    cold, warm = oil(temperature - band_c), oil(temperature + band_c)
    pressures = np.asarray(table.pressure_axis_pa)
    pressure = float(pressures[pressures.size // 2])
    change = []
    for speed in speeds:
        middle, low, high = (sum(table.magnitudes(speed, pressure, nu)[0])
                             for nu in (viscosity_m2_s, warm, cold))
        change.append(max(abs(high - middle), abs(middle - low)))
    return speeds, change


class OilAllowance:
    """
    The friction change the oil's unknown temperature may make at a window's speed.

    Parameters
    ----------
    speeds_rad_s : list of float
        Speeds [rad/s], increasing (`band_friction_nm`).
    change_nm : list of float
        The friction change over the band there [N m].

    """

    def __init__(self, speeds_rad_s: list[float], change_nm: list[float]) -> None:
        self._speeds = np.asarray(speeds_rad_s, dtype=float)
        self._change = np.asarray(change_nm, dtype=float)

    def window_nm(self, speed_abs_rad_s: float) -> float:
        """
        Return the allowance at a window's mean |speed| [N m].

        Parameters
        ----------
        speed_abs_rad_s : float
            The window's mean |speed| [rad/s].

        Returns
        -------
        float
            The friction change over the band, interpolated (held beyond the axis), >= 0.

        """
        return float(np.interp(speed_abs_rad_s, self._speeds, self._change))
