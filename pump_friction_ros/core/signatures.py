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
The causes' signatures over a window, as linear maps of its regressors.

Each single cause of a change from the healthy baseline (``attribution``: valve plate, other
friction, torque-measurement gain, pressure-sensor gain, torque offset, drive loss) moves a
window's residual by delta_j s_j; s = M h with h the window's regressor vector
(``baseline.baseline_regressors``). Split from ``attribution`` (which exports it) so that the
isolation's module stays one decision.
"""

from __future__ import annotations

import numpy as np

from .baseline import Baseline

__all__ = ['signature_matrix']


def signature_matrix(baseline: Baseline, drive_loss_nm: float,
                     rotor_inertia_kg_m2: float) -> np.ndarray:
    """
    Return M such that the causes' signatures over a window are s = M h (`CAUSES` order).

    h is the window's regressor vector (``baseline.baseline_regressors``: T_vp, T_o, 1, s,
    T_th s, a s); every signature is linear in it.

    Parameters
    ----------
    baseline : Baseline
        The healthy signature (its friction levels, drive loss and inertia).
    drive_loss_nm : float
        The configured drive loss [N m].
    rotor_inertia_kg_m2 : float
        The configured rotor inertia [kg m^2]: a torque gain scales the measured J a too.

    Returns
    -------
    ndarray, shape (6, 6)
        M [N m per unit of delta_j, per unit of h].

    """
    b = baseline.coefficients
    vp, other = 1.0 + b[0], 1.0 + b[1]
    inertia = rotor_inertia_kg_m2 + b[5]
    return np.array([[vp, 0.0, 0.0, 0.0, 0.0, 0.0],  # valve plate, healthy level
                     [0.0, other, 0.0, 0.0, 0.0, 0.0],  # other friction, healthy level
                     [vp, other, drive_loss_nm + b[2], 0.0, 1.0, inertia],  # measured torque
                     [0.0, 0.0, 0.0, 0.0, -1.0, 0.0],  # pressure read too high
                     [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],  # torque offset
                     [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]])  # drive loss
