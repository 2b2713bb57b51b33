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
The single-cause explanations of a change that the isolation compares (``attribution``).

Their signatures are in ``signatures``, their words in ``verdict_words``; the table in
``attribution``'s docstring says what each change is.

The spherical joints' friction T_j, the moments R_B mu_B |F_B| summed over the pistons
(Hong & Doh 2004, eq. 3: a Coulomb moment, proportional to the load pressure and nearly
independent of speed, Fig. 13), is the part of the other friction whose shape is not the
bearing's. Alone its change is c |dp|: where the pump drives the load, the shape of a
pressure or torque gain, and not the other friction's (the bearing's, rising with speed).
It is a cause of its own, of the isolation only: the detection's CUSUMs are those of
`DETECTED_CAUSES`, which its change moves (the pressure gain's where the pump drives the
load). A friction cannot fall below none, so the joints' change is fitted over delta >=
-1 (`ChangeStats.glr`): a torque reading 5 % low is not the joints at -10 times their
friction. Where the pump only drives the load, the joints and a pressure gain reading low
are one signature, and where the load only drives the pump (motoring), the joints and one
reading high: the verdict says so. Running in both quadrants parts them.

"""

from __future__ import annotations

import math

import numpy as np

__all__ = ['CAUSES', 'CLASS', 'DETECTED_CAUSES', 'LOWEST', 'Verdict']

CAUSES = ('valve_plate', 'other_friction', 'torque_gain', 'pressure_gain', 'torque_offset',
          'drive_loss', 'spherical_joints')
"""The single-cause explanations of a change, in signature order."""
DETECTED_CAUSES = CAUSES[:6]
"""The causes whose signatures are linear in the baseline's regressors (`signature_matrix`):
a CUSUM each. The spherical joints' change moves them too; the isolation names it."""
LOWEST = np.array([-math.inf] * CAUSES.index('spherical_joints') + [-1.0])
"""The least change of each cause: the joints' friction cannot fall below none (a change of
-1 is no joint friction at all); every other change is unbounded."""


class Verdict:
    """What explains the change, as the classes the status message and the bank use."""

    NONE = 'none'
    VALVE_PLATE = 'valve_plate'
    OTHER_FRICTION = 'other_friction'
    NOT_FRICTION = 'not_friction'
    CANNOT_TELL = 'cannot_tell'


CLASS = (Verdict.VALVE_PLATE, Verdict.OTHER_FRICTION) + (Verdict.NOT_FRICTION,) * 4 + (
    Verdict.OTHER_FRICTION,)
"""Each cause's `Verdict` class, in `CAUSES` order."""
