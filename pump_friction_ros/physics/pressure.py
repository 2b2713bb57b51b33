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
Cylinder-chamber pressure over a revolution, in the spirit of Hong & Doh (2004) Fig. 12.

Construction
------------
The valve plate (Fig. 2(b)) has two kidney ports, A over phi in (0, pi) and B over
(pi, 2 pi), separated at the dead centres (phi = 0, pi) by lands ("bridges") of angular
width beta (see ``ValvePlate.bridge_angle_rad``: 25.5 deg for the paper's pump). A chamber
is at the pressure of the port it faces; while its kidney crosses a bridge the pressure
moves from one port's pressure to the other's along a raised-cosine ramp of width beta
centred on the dead centre (pre-compression / decompression of a zero-overlap plate). The
delivery-port pulsation that Fig. 12 also omits is not modelled.

The high side is port A when the pressure difference dp = p_A - p_B is positive and port B
when it is negative; the low side is at the charge (case) pressure. With positive shaft
speed the chambers over port A are compressing, so (speed > 0, dp > 0) is pumping.
"""

from __future__ import annotations

import numpy as np

__all__ = ['chamber_pressure', 'port_a_weight']


def port_a_weight(phi: np.ndarray, bridge_rad: float) -> np.ndarray:
    """
    Fraction (0..1) of the port-A pressure seen by a chamber at phase ``phi``.

    Parameters
    ----------
    phi : ndarray
        Piston phase angle [rad].
    bridge_rad : float
        Angular width of the bridges between the ports [rad].

    Returns
    -------
    ndarray
        1 over port A, 0 over port B, a raised-cosine ramp over each bridge [-].

    """
    psi = np.mod(phi + np.pi, 2.0 * np.pi) - np.pi  # in [-pi, pi)
    weight = (psi > 0.0).astype(float)
    half = 0.5 * bridge_rad
    near_bdc = np.abs(psi) < half
    weight = np.where(near_bdc, 0.5 * (1.0 + np.sin(np.pi * psi / bridge_rad)), weight)
    psi_tdc = np.mod(phi, 2.0 * np.pi) - np.pi  # 0 at top dead centre
    near_tdc = np.abs(psi_tdc) < half
    return np.where(near_tdc, 0.5 * (1.0 - np.sin(np.pi * psi_tdc / bridge_rad)), weight)


def chamber_pressure(phi: np.ndarray, pressure_diff_pa: np.ndarray, charge_pressure_pa: float,
                     bridge_rad: float) -> np.ndarray:
    """
    Chamber pressure for each operating point and phase angle.

    Parameters
    ----------
    phi : ndarray, shape (n,)
        Piston phase angle [rad].
    pressure_diff_pa : ndarray, shape (m,)
        Pressure difference across the pump, p_A - p_B [Pa] (either sign).
    charge_pressure_pa : float
        Pressure of the low-pressure side [Pa].
    bridge_rad : float
        Angular width of the bridges between the ports [rad].

    Returns
    -------
    ndarray, shape (m, n)
        Chamber pressure [Pa].

    """
    dp = np.asarray(pressure_diff_pa, dtype=float)[:, None]
    w_a = port_a_weight(np.asarray(phi, dtype=float), bridge_rad)[None, :]
    w_high = np.where(dp >= 0.0, w_a, 1.0 - w_a)
    return charge_pressure_pa + np.abs(dp) * w_high
