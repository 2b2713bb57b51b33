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
The words a verdict names its causes with, and the oil where its viscosity is assumed.

With ``viscosity_source: parameter`` the model's oil keeps one viscosity. The real oil moves
the valve plate's film shear (rho nu omega / h over the lands, Hong & Doh 2004 sec. 4.2)
exactly as wear does, and the bearing's drag (Palmgren's (nu n)^(2/3), eq. 10) with it. So
every verdict that names a friction, alone or as one of two that cannot be told apart, names
the oil's viscosity beside it: a colder oil raises both frictions together, and a verdict
"cannot tell valve plate from other friction" on such an oil would send maintenance to open
a pump whose only change is its oil's temperature. With the temperature topic the model
follows the viscosity and the words name the frictions alone.
"""

from __future__ import annotations

__all__ = ['FRICTIONS', 'OIL_ASSUMED', 'WORDS', 'friction_named', 'with_oil']

WORDS = {'valve_plate': 'valve plate', 'other_friction': 'other friction (bearing, '
         'joints, piston heads)', 'torque_gain': 'torque-measurement gain',
         'pressure_gain': 'pressure-sensor gain', 'torque_offset': 'torque offset',
         'drive_loss': 'drive loss', 'spherical_joints': 'spherical joints'}
"""Each cause of ``attribution.CAUSES`` as a status message names it."""
FRICTIONS = ('valve_plate', 'other_friction')
"""The causes whose torque the oil's viscosity moves (not the spherical joints': a Coulomb
moment R_B mu_B |F_B|, Hong & Doh 2004 eq. 3, mu_B 0.07-0.09 over their sliding speeds, Fig. 9)."""
OIL_ASSUMED = 'the viscosity is a parameter: no temperature topic'
"""Why the oil is named beside a friction."""


def friction_named(cause: str, scale: str, viscosity_assumed: bool) -> str:
    """
    Return the phrase of a verdict that names one friction.

    Parameters
    ----------
    cause : str
        ``valve_plate``, ``other_friction`` or ``spherical_joints``.
    scale : str
        Its scale as the status message gives it.
    viscosity_assumed : bool
        The oil viscosity is a parameter, not measured.

    Returns
    -------
    str
        ``valve plate (...)``, ``not the valve plate: other friction (...)``, each with
        ``or oil viscosity`` where the viscosity is assumed, or ``not the valve plate:
        other friction, the spherical joints (...)``.

    """
    name = {'valve_plate': 'valve plate', 'other_friction': 'not the valve plate: other '
            'friction'}.get(cause, f'not the valve plate: other friction, the {WORDS[cause]}')
    if viscosity_assumed and cause in FRICTIONS:
        return f'{name} or oil viscosity ({OIL_ASSUMED}) ({scale})'
    return f'{name} ({scale})'


def with_oil(phrase: str, causes: tuple[str, ...], viscosity_assumed: bool) -> str:
    """
    Return a verdict's phrase that cannot tell ``causes`` apart, the oil named if it may be.

    Parameters
    ----------
    phrase : str
        The phrase naming the causes.
    causes : tuple of str
        The causes it names (of ``attribution.CAUSES``).
    viscosity_assumed : bool
        The oil viscosity is a parameter, not measured.

    Returns
    -------
    str
        The phrase, with ``; or oil viscosity (...)`` where a friction is among the causes
        and the viscosity is assumed.

    """
    if viscosity_assumed and any(c in FRICTIONS for c in causes):
        return f'{phrase}; or oil viscosity ({OIL_ASSUMED})'
    return phrase
