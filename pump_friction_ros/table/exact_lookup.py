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
`FrictionTable.magnitudes` over arrays, bit for bit: the estimator's chunk path uses it.

``FrictionTable.magnitudes_array`` is the fast vectorised lookup (its own cell search, a sum
over the corners in another order) and may differ from the scalar path in the last bit;
this one repeats the scalar path's arithmetic element by element, so that the offline
replay gives exactly what the node gives (``test_chunk_path``).
"""

from __future__ import annotations

import math

import numpy as np

from .friction_table import (
    FrictionTable,
    NOT_FINITE,
    PRESSURE_CLAMPED,
    SPEED_CLAMPED,
    VISCOSITY_CLAMPED,
)

__all__ = ['ExactTableLookup']


class ExactTableLookup:
    """
    `FrictionTable.magnitudes` over arrays, with the scalar path's arithmetic exactly.

    The same cell (``bisect_right`` bounded as there), the same weights and the same sum
    order, so every element equals the scalar result bit for bit (``magnitudes_array`` sums
    in another order and may differ in the last bit).

    Parameters
    ----------
    table : FrictionTable
        The table.

    """

    def __init__(self, table: FrictionTable) -> None:
        self.table = table
        self._axes = (table.speed_axis_rad_s, table.pressure_axis_pa, table.viscosity_axis_m2_s)
        self._inner = tuple(axis[:axis.size - 1] for axis in self._axes)  # bisect's hi bound
        self._inv = tuple(1.0 / np.diff(axis) for axis in self._axes)
        n_components = table.torque_nm.shape[-1]
        self._nodes = [np.ascontiguousarray(col) for col in
                       table.torque_nm.reshape(-1, n_components).T]
        n_speed, n_pressure, n_viscosity = (axis.size for axis in self._axes)
        self._strides = (n_speed * n_pressure * n_viscosity, n_pressure * n_viscosity,
                         n_viscosity)

    def magnitudes(self, speed_abs_rad_s: np.ndarray, pressure_abs_pa: np.ndarray,
                   viscosity_m2_s: np.ndarray, motoring: np.ndarray
                   ) -> tuple[list[np.ndarray], np.ndarray]:
        """
        Component magnitudes and lookup flags at many points.

        Parameters
        ----------
        speed_abs_rad_s, pressure_abs_pa, viscosity_m2_s : ndarray
            |shaft speed| [rad/s], |pressure difference| [Pa], viscosity [m^2/s], float64.
        motoring : ndarray of bool
            Speed and pressure difference of opposite signs.

        Returns
        -------
        tuple
            The magnitudes per component [N*m] (four arrays, ``COMPONENTS`` order, NaN
            where an input is not finite) and the flags (int64 array).

        """
        s, p, v = speed_abs_rad_s, pressure_abs_pa, viscosity_m2_s
        finite = np.isfinite(s) & np.isfinite(p) & np.isfinite(v)
        all_finite = bool(finite.all())
        sa, pa, va = self._axes
        if not all_finite:  # any finite stand-in: those rows are set to NaN at the end
            s, p, v = (np.where(finite, x, axis[0]) for x, axis in ((s, sa), (p, pa), (v, va)))
        flags = np.zeros(s.size, dtype=np.int64)
        high = s > sa[-1]
        if high.any():
            s = np.where(high, sa[-1], s)
            flags[high] = SPEED_CLAMPED
        high = p > pa[-1]
        if high.any():
            p = np.where(high, pa[-1], p)
            flags[high] |= PRESSURE_CLAMPED
        high, low = v > va[-1], v < va[0]
        if high.any() or low.any():
            v = np.where(high, va[-1], np.where(low, va[0], v))
            flags[high | low] |= VISCOSITY_CLAMPED
        (s_in, p_in, v_in), (s_inv, p_inv, v_inv) = self._inner, self._inv
        i = np.searchsorted(s_in, s, side='right') - 1
        j = np.searchsorted(p_in, p, side='right') - 1
        k = np.searchsorted(v_in, v, side='right') - 1
        ts = (s - sa[i]) * s_inv[i]
        tp = (p - pa[j]) * p_inv[j]
        tv = (v - va[k]) * v_inv[k]
        us, up, uv = 1.0 - ts, 1.0 - tp, 1.0 - tv
        w0, w1, w2, w3 = us * up, us * tp, ts * up, ts * tp
        weights = (w0 * uv, w0 * tv, w1 * uv, w1 * tv, w2 * uv, w2 * tv, w3 * uv, w3 * tv)
        sm, ss, sp = self._strides
        b = sm * motoring.astype(np.int64) + ss * i + sp * j + k
        corners = (b, b + 1, b + sp, b + sp + 1, b + ss, b + ss + 1, b + ss + sp,
                   b + ss + sp + 1)
        out = []
        for nodes in self._nodes:  # n0 w000 + n1 w001 + ... + n7 w111, left to right
            total = nodes[corners[0]] * weights[0]
            for corner, weight in zip(corners[1:], weights[1:], strict=True):
                total += nodes[corner] * weight
            if not all_finite:
                total[~finite] = math.nan
            out.append(total)
        if not all_finite:
            flags[~finite] = NOT_FINITE
        return out, flags
