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

"""Oil viscosity against temperature: ASTM D341 (Walther) through two reference points."""

from __future__ import annotations

import math

__all__ = ['WaltherViscosity']

_KELVIN = 273.15


class WaltherViscosity:
    """
    Kinematic viscosity from temperature, ASTM D341: log log (nu + 0.7) = A - B log T.

    nu in cSt and T in K inside the empirical law; SI (m^2/s, degC) at the interface.

    Parameters
    ----------
    viscosity_40c_m2_s : float
        Kinematic viscosity at 40 degC [m^2/s].
    viscosity_100c_m2_s : float
        Kinematic viscosity at 100 degC [m^2/s].

    """

    def __init__(self, viscosity_40c_m2_s: float, viscosity_100c_m2_s: float) -> None:
        if not 0.0 < viscosity_100c_m2_s < viscosity_40c_m2_s:
            raise ValueError('need 0 < viscosity at 100 degC < viscosity at 40 degC')
        z40 = math.log10(math.log10(viscosity_40c_m2_s * 1e6 + 0.7))
        z100 = math.log10(math.log10(viscosity_100c_m2_s * 1e6 + 0.7))
        t40, t100 = math.log10(40.0 + _KELVIN), math.log10(100.0 + _KELVIN)
        self._b = (z40 - z100) / (t100 - t40)
        self._a = z40 + self._b * t40

    def __call__(self, temperature_c: float) -> float:
        """
        Kinematic viscosity at a temperature.

        Parameters
        ----------
        temperature_c : float
            Oil temperature [degC].

        Returns
        -------
        float
            Kinematic viscosity [m^2/s].

        """
        z = self._a - self._b * math.log10(temperature_c + _KELVIN)
        return (10.0 ** (10.0 ** z) - 0.7) * 1e-6

    def temperature_c(self, viscosity_m2_s: float) -> float:
        """
        Temperature at which the oil has a given viscosity: the law solved for T.

        Parameters
        ----------
        viscosity_m2_s : float
            Kinematic viscosity [m^2/s], above 0.3 cSt (the law's log log needs nu + 0.7 > 1).

        Returns
        -------
        float
            Oil temperature [degC].

        """
        z = math.log10(math.log10(viscosity_m2_s * 1e6 + 0.7))
        return 10.0 ** ((self._a - z) / self._b) - _KELVIN
