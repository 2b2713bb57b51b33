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
friction, torque-measurement gain, pressure-sensor gain, torque offset, drive loss, the
spherical joints) moves a window's residual by delta_j s_j; s = M h with h the window's
regressor vector (``baseline.baseline_regressors``), and the joints' `joints_signature`.
Split from ``attribution`` (which exports it) so that the isolation's module stays one
decision. `undetectable_change` is what the detection's sums
do not see of each cause's change over the recent signatures.
"""

from __future__ import annotations

import numpy as np

from .baseline import Baseline

__all__ = ['joints_signature', 'signature_matrix', 'undetectable_change']


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


def joints_signature(baseline: Baseline, joints_nm: float) -> float:
    """
    Return the spherical joints' signature over a window: their healthy friction.

    A relative change delta of the joints' friction moves the window's residual by delta
    l_o T_j: the healthy level of the other friction, of which they are a part, times the
    modelled joints' friction (Hong & Doh 2004, eq. 3). Not linear in the regressors h
    (it follows |dp|, not dp s): a cause of the isolation, beside `signature_matrix`'s.

    Parameters
    ----------
    baseline : Baseline
        The healthy signature (its other-friction level).
    joints_nm : float
        The window mean of the modelled spherical joints' friction magnitude [N m].

    Returns
    -------
    float
        The signature [N m per unit of delta].

    """
    return (1.0 + float(baseline.coefficients[1])) * joints_nm


def undetectable_change(k_nm: float, norm: np.ndarray, margin_nm: float,
                        recent_s2: np.ndarray, recent_s: float, cap: float) -> np.ndarray:
    """
    Return the undetectable change per cause on the recent points, the margin taken off.

    A change delta of cause j moves d by delta s_j, and the CUSUM of every cause i by
    z_i = s_i (delta s_j - m) / n_i: n_i the RMS of s_i over commissioning, m the margin and
    allowances taken off d. On average over the recent points (the isolation's memory: C
    the mean of s s^T over them, r_i = sqrt(C_ii) >= |mean s_i sign(s_j)|) sum i stays at
    zero while delta < (k n_i + m r_i) / |C_ij|; the change goes unseen while no sum moves:
    below the least of these. On commissioning's points the own sum is the least
    (Cauchy-Schwarz); on a pump commissioned cold and now warm the valve plate's film shear
    is a quarter of what it was, its own sum sees a sixteenth, and the sums whose
    signatures did not shrink (drive loss, offset) see more.

    Parameters
    ----------
    k_nm : float
        The CUSUM allowance k [N m].
    norm : ndarray
        n_i, each cause's signature RMS over commissioning [N m per unit].
    margin_nm : float
        m, the margin and allowances taken off the change [N m].
    recent_s2 : ndarray
        The forgotten sum of s s^T times running over the recent points [N^2 m^2 s].
    recent_s : float
        Its running [s] (0: commissioning's points, C = diag(n^2)).
    cap : float
        The value published for a change that moves no sum [-] (offset, drive loss: [N m]).

    Returns
    -------
    ndarray
        Per cause, the largest change no sum sees [-] (offset and drive loss [N m]).

    """
    if not recent_s > 0.0:  # commissioning's points: C = diag(n^2), the own sum
        own: np.ndarray = (k_nm + margin_nm) / norm
        return own
    second = recent_s2 / recent_s
    rms = np.sqrt(np.maximum(np.diag(second), 0.0))
    sums = (k_nm * norm + margin_nm * rms)[:, None]  # (cause i's sum, change j)
    seen = np.abs(second)
    unseen = np.where(seen > 1e-12 * np.outer(rms, rms), sums / np.where(
        seen > 0.0, seen, 1.0), np.inf)
    # (a change that moves no sum at all goes unseen whatever its size: published as the
    # cap, a million, not infinite)
    least: np.ndarray = np.minimum(unseen.min(axis=0), cap)
    return least
