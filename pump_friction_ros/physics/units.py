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

"""Unit conversions between SI (used everywhere inside) and the paper's units (edges only)."""

import math
from typing import TypeVar

import numpy as np

RPM_TO_RAD_S = 2.0 * math.pi / 60.0
"""Multiply a speed in rpm by this to get rad/s."""

BAR_TO_PA = 1.0e5
"""Multiply a pressure in bar by this to get Pa."""

CST_TO_M2_S = 1.0e-6
"""A kinematic viscosity of 1 cSt (1 mm^2/s) in m^2/s."""

CST_PER_M2_S = 1.0e6
"""Kinematic viscosity of 1 m^2/s in cSt; dividing by it converts cSt to m^2/s exactly."""

MM_TO_M = 1.0e-3
"""Multiply a length in mm by this to get m."""

CC_TO_M3 = 1.0e-6
"""Multiply a volume in cm^3 (cc) by this to get m^3."""

NMM_TO_NM = 1.0e-3
"""Multiply a torque in N*mm by this to get N*m."""

_Quantity = TypeVar('_Quantity', float, np.ndarray)  # the conversions keep the type


def rpm_to_rad_s(speed_rpm: _Quantity) -> _Quantity:
    """
    Convert a shaft speed from rpm to rad/s.

    Parameters
    ----------
    speed_rpm : float or ndarray
        Shaft speed [rpm].

    Returns
    -------
    float or ndarray
        Shaft speed [rad/s].

    """
    return speed_rpm * RPM_TO_RAD_S


def rad_s_to_rpm(speed_rad_s: _Quantity) -> _Quantity:
    """
    Convert a shaft speed from rad/s to rpm.

    Parameters
    ----------
    speed_rad_s : float or ndarray
        Shaft speed [rad/s].

    Returns
    -------
    float or ndarray
        Shaft speed [rpm].

    """
    return speed_rad_s / RPM_TO_RAD_S


def bar_to_pa(pressure_bar: _Quantity) -> _Quantity:
    """
    Convert a pressure from bar to Pa.

    Parameters
    ----------
    pressure_bar : float or ndarray
        Pressure [bar].

    Returns
    -------
    float or ndarray
        Pressure [Pa].

    """
    return pressure_bar * BAR_TO_PA


def pa_to_bar(pressure_pa: _Quantity) -> _Quantity:
    """
    Convert a pressure from Pa to bar.

    Parameters
    ----------
    pressure_pa : float or ndarray
        Pressure [Pa].

    Returns
    -------
    float or ndarray
        Pressure [bar].

    """
    return pressure_pa / BAR_TO_PA


def cst_to_m2_s(viscosity_cst: _Quantity) -> _Quantity:
    """
    Convert a kinematic viscosity from cSt to m^2/s.

    Parameters
    ----------
    viscosity_cst : float or ndarray
        Kinematic viscosity [cSt].

    Returns
    -------
    float or ndarray
        Kinematic viscosity [m^2/s].

    """
    return viscosity_cst / CST_PER_M2_S


def m2_s_to_cst(viscosity_m2_s: _Quantity) -> _Quantity:
    """
    Convert a kinematic viscosity from m^2/s to cSt.

    Parameters
    ----------
    viscosity_m2_s : float or ndarray
        Kinematic viscosity [m^2/s].

    Returns
    -------
    float or ndarray
        Kinematic viscosity [cSt].

    """
    return viscosity_m2_s * CST_PER_M2_S
