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
Friction-torque table: precomputed from the model, persisted with provenance, fast lookup.

Layout
------
Revolution-mean torque magnitude of each friction component (``model.COMPONENTS``) on a grid
of |shaft speed| x |pressure difference| x oil kinematic viscosity, for the two modes of
operation: pumping (speed and pressure difference of the same sign) and motoring (opposite
signs), which differ by the direction-dependent terms of the piston dynamics (up to 0.4 %).
The theoretical torque is not tabulated: it is V_g dp / (2 pi), analytic.

Lookup is trilinear on non-uniform axes. Signs follow the model: the friction torque
opposes the speed through tanh(speed / threshold), the same rule as ``model``. Outside the
envelope the inputs are clamped to its edge and a flag says which axis was exceeded; NaN or
inf in gives NaN out with the ``NOT_FINITE`` flag; nothing is extrapolated. Files and the
cache are in ``table_io``.

Longer than 500 lines because the grid, its two lookup paths (the scalar one of the
estimator and the vectorised one) and the axis locator they share are one data structure
whose private layout must be read together.
"""

from __future__ import annotations

from bisect import bisect_right
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from functools import cached_property
import io
import json
import math
import os
from pathlib import Path
import tempfile
import time
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .. import __version__, MODEL_VERSION
from ..errors import TableError
from ..paths import created_file_mode
from ..physics.friction import smooth_sign, smooth_sign_scalar
from ..physics.model import (
    angle_count,
    COMPONENTS,
    efficiency_of,
    input_torque_nm,
    PumpModel,
    theoretical_torque_nm,
    torque_efficiency,
)
from ..physics.pump_parameters import PumpParams
from ..physics.units import BAR_TO_PA, CST_PER_M2_S, RPM_TO_RAD_S

__all__ = [
    'NOT_FINITE',
    'OK',
    'PRESSURE_CLAMPED',
    'SPEED_CLAMPED',
    'VISCOSITY_CLAMPED',
    'VISCOSITY_STEP_RATIO',
    'FrictionTable',
    'TableSpec',
    'build_table',
    'describe_flags',
]

OK = 0
SPEED_CLAMPED = 1
PRESSURE_CLAMPED = 2
VISCOSITY_CLAMPED = 4
NOT_FINITE = 8
_FLAG_NAMES = {SPEED_CLAMPED: 'speed above the table', PRESSURE_CLAMPED: 'pressure above the '
               'table', VISCOSITY_CLAMPED: 'viscosity outside the table',
               NOT_FINITE: 'non-finite input'}

TABLE_FORMAT = 1
VISCOSITY_STEP_RATIO = 10.0 ** (1.0 / 7.0)
"""Largest ratio of neighbouring viscosity nodes [-]: 8 nodes per decade (1.39).

The spacing of the original 10-100 cSt axis. Linear interpolation of the Palmgren term
(nu n)^(2/3) between nodes a ratio r apart errs by up to (ln r)^2 / 36, 0.30 % here, and the
whole table stays within 0.5 % of the friction torque or 1 mN m over 1-1000 cSt (0.80 of it
at worst; ``test_table_viscosity_axis``); 6 per decade gave 0.91, 5 per decade 1.04."""
_CHUNK = 16384  # points per block of the vectorised lookup
_ARRAYS = ('speed_axis_rad_s', 'pressure_axis_pa', 'viscosity_axis_m2_s', 'torque_nm',
           'metadata')


def describe_flags(flags: int) -> str:
    """
    Human-readable list of the lookup flags set in ``flags``.

    Parameters
    ----------
    flags : int
        Bit mask of lookup flags.

    Returns
    -------
    str
        Comma-separated descriptions, or ``'ok'``.

    """
    names = [text for bit, text in _FLAG_NAMES.items() if flags & bit]
    return ', '.join(names) if names else 'ok'


@dataclass(frozen=True)
class TableSpec:
    """
    Envelope and resolution of a friction table (SI).

    The default axes meet 0.5 % of the friction torque (or 1 mN m) against the full model
    anywhere inside the envelope (``test_table.py`` checks random points). The default
    viscosity axis, 10-100 cSt, is a generic one; the node sizes its own to the oil it is
    configured for with `covering` (``core.oil_range``).
    """

    max_speed_rad_s: float = 12000.0 * RPM_TO_RAD_S
    max_pressure_pa: float = 350.0 * BAR_TO_PA
    min_viscosity_m2_s: float = 10.0 / CST_PER_M2_S
    max_viscosity_m2_s: float = 100.0 / CST_PER_M2_S
    low_speed_rad_s: float = 40.0  # resolved finely: breakaway and Palmgren threshold
    low_speed_step_rad_s: float = 1.0
    high_speed_points: int = 36
    pressure_points: int = 16
    viscosity_points: int = 8
    n_angles: int = 180  # at least; rounded up to a multiple of the piston count

    def __post_init__(self) -> None:
        checks = [
            ('max_speed_rad_s', self.max_speed_rad_s > self.low_speed_rad_s),
            ('max_pressure_pa', self.max_pressure_pa > 0.0),
            ('min_viscosity_m2_s', 0.0 < self.min_viscosity_m2_s < self.max_viscosity_m2_s),
            ('high_speed_points', self.high_speed_points >= 2),
            ('pressure_points', self.pressure_points >= 2),
            ('viscosity_points', self.viscosity_points >= 2),
        ]
        for name, ok in checks:
            if not ok or any(not math.isfinite(v) for v in (
                    self.max_speed_rad_s, self.max_pressure_pa, self.min_viscosity_m2_s,
                    self.max_viscosity_m2_s)):
                raise TableError(f'table spec: invalid {name}')

    def covering(self, min_viscosity_m2_s: float, max_viscosity_m2_s: float) -> TableSpec:
        """
        Return this spec with a viscosity axis from ``min`` to ``max``, as fine as the default.

        The node count grows with the span so that neighbouring nodes are at most
        `VISCOSITY_STEP_RATIO` apart (8 per decade): 8 for 10-100 cSt, 22 for 1-1000 cSt.

        Parameters
        ----------
        min_viscosity_m2_s, max_viscosity_m2_s : float
            Ends of the viscosity axis [m^2/s], 0 < min < max.

        Returns
        -------
        TableSpec
            The spec; the other axes unchanged.

        Raises
        ------
        TableError
            Ends not finite, not positive or not increasing.

        """
        lo, hi = float(min_viscosity_m2_s), float(max_viscosity_m2_s)
        if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
            raise TableError(f'table spec: invalid viscosity range {lo!r} .. {hi!r} m^2/s')
        steps = math.ceil(math.log(hi / lo) / math.log(VISCOSITY_STEP_RATIO) - 1e-9)
        return replace(self, min_viscosity_m2_s=lo, max_viscosity_m2_s=hi,
                       viscosity_points=max(2, steps + 1))

    def axes(self, params: PumpParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Grid axes: speed [rad/s], pressure difference [Pa], viscosity [m^2/s].

        Speed: 1 rad/s steps up to ``low_speed_rad_s`` (the valve plate's breakaway curve
        and the Palmgren viscous threshold, at nu n = 2000 cSt rpm, live there), every
        abscissa of the pump's coulomb curve, the shaft speeds at which the joint and head
        sliding speeds cross the abscissae of their friction curves, then steps growing
        with speed. Pressure: quadratic spacing, dense near zero where the pistons' inertia
        rivals the pressure force. Viscosity: geometric.

        Parameters
        ----------
        params : PumpParams
            Pump whose coulomb-curve abscissae become grid nodes.

        Returns
        -------
        tuple of ndarray
            Strictly increasing axes.

        """
        low = np.arange(0.0, self.low_speed_rad_s + 0.5 * self.low_speed_step_rad_s,
                        self.low_speed_step_rad_s)
        ramp = np.linspace(0.0, 1.0, self.high_speed_points + 1)[1:] ** 1.3
        high = self.low_speed_rad_s + (self.max_speed_rad_s - self.low_speed_rad_s) * ramp
        kinks = [*params.valve_plate.coulomb_coefficient.x, *_curve_kink_speeds(params)]
        kinks = [x for x in kinks if 0.0 < x < self.max_speed_rad_s]
        speed = np.unique(np.concatenate([low, high, kinks]))
        pressure = self.max_pressure_pa * np.linspace(0.0, 1.0, self.pressure_points) ** 2
        viscosity = np.geomspace(self.min_viscosity_m2_s, self.max_viscosity_m2_s,
                                 self.viscosity_points)
        return speed, pressure, viscosity


class FrictionTable:
    """
    A friction-torque table with its provenance; see the module docstring.

    Parameters
    ----------
    speed_axis_rad_s, pressure_axis_pa, viscosity_axis_m2_s : ndarray
        Strictly increasing axes starting at 0 (speed, pressure) [rad/s, Pa, m^2/s].
    torque_nm : ndarray, shape (2, n_speed, n_pressure, n_viscosity, 4)
        Component magnitudes [N*m]; first index 0 = pumping, 1 = motoring.
    metadata : dict
        Provenance (see `build_table`).

    """

    def __init__(self, speed_axis_rad_s: np.ndarray, pressure_axis_pa: np.ndarray,
                 viscosity_axis_m2_s: np.ndarray, torque_nm: np.ndarray,
                 metadata: dict[str, Any]) -> None:
        self.speed_axis_rad_s = np.asarray(speed_axis_rad_s, dtype=float)
        self.pressure_axis_pa = np.asarray(pressure_axis_pa, dtype=float)
        self.viscosity_axis_m2_s = np.asarray(viscosity_axis_m2_s, dtype=float)
        self.torque_nm = np.asarray(torque_nm, dtype=float)
        self.metadata = dict(metadata)
        _validate_arrays(self.speed_axis_rad_s, self.pressure_axis_pa, self.viscosity_axis_m2_s,
                         self.torque_nm, '<table>')
        ns, npr, nv = (a.size for a in (self.speed_axis_rad_s, self.pressure_axis_pa,
                                        self.viscosity_axis_m2_s))
        # pure-Python copies for the scalar path
        self._s = self.speed_axis_rad_s.tolist()
        self._p = self.pressure_axis_pa.tolist()
        self._v = self.viscosity_axis_m2_s.tolist()
        self._last_s, self._last_p, self._last_v = ns - 1, npr - 1, nv - 1
        self._inv_ds, self._inv_dp, self._inv_dv = (
            (1.0 / np.diff(axis)).tolist() for axis in (
                self.speed_axis_rad_s, self.pressure_axis_pa, self.viscosity_axis_m2_s))
        # vectorised path: component-major values, corner offsets, fast axis locators
        self._by_component = np.ascontiguousarray(
            self.torque_nm.reshape(-1, len(COMPONENTS)).T)
        ss_, sp_ = npr * nv, nv
        self._corner_offsets = np.array([0, 1, sp_, sp_ + 1, ss_, ss_ + 1, ss_ + sp_,
                                         ss_ + sp_ + 1], dtype=np.intp)
        self._locate = tuple(_AxisLocator(axis) for axis in (
            self.speed_axis_rad_s, self.pressure_axis_pa, self.viscosity_axis_m2_s))
        self._strides = (ns * npr * nv, npr * nv, nv, 1)  # mode, speed, pressure, viscosity
        self.displacement_m3 = float(self.metadata['displacement_m3'])
        self.zero_speed_threshold_rad_s = float(self.metadata['zero_speed_threshold_rad_s'])
        self.efficiency_min_speed_rad_s = float(self.metadata['efficiency_min_speed_rad_s'])
        self.efficiency_min_pressure_pa = float(self.metadata['efficiency_min_pressure_pa'])
        self.default_viscosity_m2_s = float(self.metadata['default_viscosity_m2_s'])

    @cached_property
    def _nodes(self) -> list[tuple[float, ...]]:
        """Return the nodes as tuples of Python floats for the scalar path (made at first use)."""
        return [tuple(row) for row in self.torque_nm.reshape(-1, len(COMPONENTS)).tolist()]

    # -- provenance -----------------------------------------------------------------------

    @property
    def pump_sha256(self) -> str:
        """Hash of the pump parameters the table was built from."""
        return str(self.metadata['pump_sha256'])

    def check_matches(self, params: PumpParams) -> None:
        """
        Refuse the table unless it was built from ``params`` by this model version.

        Parameters
        ----------
        params : PumpParams
            The pump parameters in use.

        Raises
        ------
        TableError
            With the command that rebuilds the table.

        """
        source = self.metadata.get('source', '<table>')
        rebuild = (f'rebuild it: pump_friction build-table --pump {params.source or "PUMP.yaml"}'
                   f' --out {source} --force')
        if self.pump_sha256 != params.sha256:
            raise TableError(
                f'{source}: built for pump "{self.metadata.get("pump_name")}" '
                f'(sha256 {self.pump_sha256[:12]}), not for "{params.name}" in use '
                f'(sha256 {params.sha256[:12]}); {rebuild}')
        if str(self.metadata.get('model_version')) != MODEL_VERSION:
            raise TableError(f'{source}: built by model version '
                             f'{self.metadata.get("model_version")}, this is {MODEL_VERSION};'
                             f' {rebuild}')

    # -- persistence ----------------------------------------------------------------------

    def save(self, path: str | Path) -> Path:
        """
        Write the table to an ``.npz`` file atomically (temporary name, then rename).

        Parameters
        ----------
        path : str or Path
            Destination.

        Returns
        -------
        Path
            The file written.

        """
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        # the archive is made in memory and written at once: a zip file that a full disk
        # broke would complain from its finaliser (numpy 1.26: "seek of closed file")
        archive = io.BytesIO()
        np.savez(archive, speed_axis_rad_s=self.speed_axis_rad_s,
                 pressure_axis_pa=self.pressure_axis_pa,
                 viscosity_axis_m2_s=self.viscosity_axis_m2_s, torque_nm=self.torque_nm,
                 metadata=np.array(json.dumps(self.metadata, sort_keys=True)))
        fd, tmp = tempfile.mkstemp(prefix=path.name + '.', suffix='.tmp', dir=path.parent)
        try:
            with os.fdopen(fd, 'wb') as handle:
                os.fchmod(handle.fileno(), created_file_mode())  # not mkstemp's 0o600
                handle.write(archive.getbuffer())
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        return path

    # -- lookup ---------------------------------------------------------------------------

    def magnitudes(self, speed_abs_rad_s: float, pressure_abs_pa: float, viscosity_m2_s: float,
                   motoring: bool = False) -> tuple[tuple[float, float, float, float], int]:
        """
        Component magnitudes at one point: the scalar path, pure Python.

        Parameters
        ----------
        speed_abs_rad_s : float
            |shaft speed| [rad/s].
        pressure_abs_pa : float
            |pressure difference| [Pa].
        viscosity_m2_s : float
            Oil kinematic viscosity [m^2/s].
        motoring : bool
            Speed and pressure difference of opposite signs.

        Returns
        -------
        tuple
            The four magnitudes [N*m] in ``COMPONENTS`` order (NaN if an input is not
            finite) and the lookup flags.

        """
        s, p, v = speed_abs_rad_s, pressure_abs_pa, viscosity_m2_s
        if not (math.isfinite(s) and math.isfinite(p) and math.isfinite(v)):
            nan = math.nan
            return (nan, nan, nan, nan), NOT_FINITE
        flags = 0
        sa, pa, va = self._s, self._p, self._v
        if s > sa[-1]:
            s, flags = sa[-1], SPEED_CLAMPED
        if p > pa[-1]:
            p, flags = pa[-1], flags | PRESSURE_CLAMPED
        if v > va[-1]:
            v, flags = va[-1], flags | VISCOSITY_CLAMPED
        elif v < va[0]:
            v, flags = va[0], flags | VISCOSITY_CLAMPED
        # cell indices (hi bound keeps the last node out: i <= n - 2) and local coordinates
        i = bisect_right(sa, s, 0, self._last_s) - 1
        j = bisect_right(pa, p, 0, self._last_p) - 1
        k = bisect_right(va, v, 0, self._last_v) - 1
        ts = (s - sa[i]) * self._inv_ds[i]
        tp = (p - pa[j]) * self._inv_dp[j]
        tv = (v - va[k]) * self._inv_dv[k]
        us, up, uv = 1.0 - ts, 1.0 - tp, 1.0 - tv
        w0, w1, w2, w3 = us * up, us * tp, ts * up, ts * tp
        w000, w001, w010, w011 = w0 * uv, w0 * tv, w1 * uv, w1 * tv
        w100, w101, w110, w111 = w2 * uv, w2 * tv, w3 * uv, w3 * tv
        sm, ss, sp, _ = self._strides
        nodes = self._nodes
        b = sm * motoring + ss * i + sp * j + k
        n0, n1, n2, n3 = nodes[b], nodes[b + 1], nodes[b + sp], nodes[b + sp + 1]
        b += ss
        n4, n5, n6, n7 = nodes[b], nodes[b + 1], nodes[b + sp], nodes[b + sp + 1]
        # unrolled over the four components: no loop, no temporary objects
        return ((n0[0] * w000 + n1[0] * w001 + n2[0] * w010 + n3[0] * w011
                 + n4[0] * w100 + n5[0] * w101 + n6[0] * w110 + n7[0] * w111),
                (n0[1] * w000 + n1[1] * w001 + n2[1] * w010 + n3[1] * w011
                 + n4[1] * w100 + n5[1] * w101 + n6[1] * w110 + n7[1] * w111),
                (n0[2] * w000 + n1[2] * w001 + n2[2] * w010 + n3[2] * w011
                 + n4[2] * w100 + n5[2] * w101 + n6[2] * w110 + n7[2] * w111),
                (n0[3] * w000 + n1[3] * w001 + n2[3] * w010 + n3[3] * w011
                 + n4[3] * w100 + n5[3] * w101 + n6[3] * w110 + n7[3] * w111)), flags

    def lookup(self, speed_rad_s: float, pressure_diff_pa: float,
               viscosity_m2_s: float | None = None) -> TableTorque:
        """
        Signed torques at one operating point (scalar path, no numpy).

        Parameters
        ----------
        speed_rad_s : float
            Shaft speed [rad/s], signed.
        pressure_diff_pa : float
            Pressure difference p_A - p_B [Pa], signed.
        viscosity_m2_s : float, optional
            Oil kinematic viscosity [m^2/s]; default the pump's.

        Returns
        -------
        TableTorque
            Component and total torques [N*m], efficiency [-] and flags.

        """
        visc = self.default_viscosity_m2_s if viscosity_m2_s is None else viscosity_m2_s
        speed, dp = speed_rad_s, pressure_diff_pa
        mags, flags = self.magnitudes(abs(speed), abs(dp), visc, speed * dp < 0.0)
        if flags & NOT_FINITE:
            nan = math.nan
            return TableTorque(nan, (nan, nan, nan, nan), nan, nan, nan, flags)
        direction = smooth_sign_scalar(speed, self.zero_speed_threshold_rad_s)
        comps = (direction * mags[0], direction * mags[1], direction * mags[2],
                 direction * mags[3])
        friction = comps[0] + comps[1] + comps[2] + comps[3]
        theoretical = theoretical_torque_nm(self.displacement_m3, dp)
        tin = input_torque_nm(theoretical, mags[0] + mags[1] + mags[2] + mags[3], direction)
        eff = efficiency_of(theoretical, tin, speed, dp, self.efficiency_min_speed_rad_s,
                            self.efficiency_min_pressure_pa)
        return TableTorque(theoretical, comps, friction, tin, eff, flags)

    def magnitudes_array(self, speed_abs_rad_s: ArrayLike, pressure_abs_pa: ArrayLike,
                         viscosity_m2_s: ArrayLike, motoring: ArrayLike = False
                         ) -> tuple[np.ndarray, np.ndarray]:
        """
        Component magnitudes at many points: the vectorised path.

        Parameters
        ----------
        speed_abs_rad_s, pressure_abs_pa, viscosity_m2_s : array_like
            |speed| [rad/s], |pressure difference| [Pa], viscosity [m^2/s], broadcast.
        motoring : array_like of bool
            Speed and pressure difference of opposite signs.

        Returns
        -------
        tuple of ndarray
            Magnitudes, shape (n, 4) [N*m] (NaN rows where an input is not finite), and
            flags, shape (n,).

        """
        s, p, v, mot = (np.ravel(a) for a in np.broadcast_arrays(
            np.asarray(speed_abs_rad_s, dtype=float), np.asarray(pressure_abs_pa, dtype=float),
            np.asarray(viscosity_m2_s, dtype=float), np.asarray(motoring, dtype=bool)))
        out = np.empty((s.size, len(COMPONENTS)))
        flags = np.empty(s.size, dtype=np.int32)
        for start in range(0, s.size, _CHUNK):  # chunks keep the gathers in cache
            part = slice(start, start + _CHUNK)
            self._interpolate(s[part], p[part], v[part], mot[part], out[part], flags[part])
        return out, flags

    def _interpolate(self, s: np.ndarray, p: np.ndarray, v: np.ndarray, mot: np.ndarray,
                     out: np.ndarray, flags: np.ndarray) -> None:
        finite = np.isfinite(s) & np.isfinite(p) & np.isfinite(v)
        all_finite = bool(finite.all())
        flags[:] = 0 if all_finite else np.where(finite, 0, NOT_FINITE)
        stride_mode, stride_s, stride_p, _ = self._strides
        base = stride_mode * mot.astype(np.intp)
        coords = []
        for locator, x, stride, bit in ((self._locate[0], s, stride_s, SPEED_CLAMPED),
                                        (self._locate[1], p, stride_p, PRESSURE_CLAMPED),
                                        (self._locate[2], v, 1, VISCOSITY_CLAMPED)):
            if not all_finite:
                x = np.where(finite, x, locator.axis[0])
            idx, t, clamped = locator(x)
            if clamped is not None:
                flags |= np.where(clamped, bit, 0).astype(np.int32)
            base += stride * idx
            coords.append(t)
        ts, tp, tv = coords
        us, up, uv = 1.0 - ts, 1.0 - tp, 1.0 - tv
        w0, w1, w2, w3 = us * up, us * tp, ts * up, ts * tp
        weights = np.stack([w0 * uv, w0 * tv, w1 * uv, w1 * tv,
                            w2 * uv, w2 * tv, w3 * uv, w3 * tv])  # (8, n)
        corners = base[None, :] + self._corner_offsets[:, None]  # (8, n)
        for c, values in enumerate(self._by_component):
            gathered = np.take(values, corners)
            gathered *= weights
            out[:, c] = gathered.sum(axis=0)
        if not all_finite:
            out[~finite] = np.nan

    def lookup_array(self, speed_rad_s: ArrayLike, pressure_diff_pa: ArrayLike,
                     viscosity_m2_s: ArrayLike | None = None) -> dict[str, np.ndarray]:
        """
        Signed torques at many operating points (vectorised path).

        Parameters
        ----------
        speed_rad_s, pressure_diff_pa : array_like
            Shaft speed [rad/s] and pressure difference [Pa], signed, broadcast.
        viscosity_m2_s : array_like, optional
            Oil kinematic viscosity [m^2/s]; default the pump's.

        Returns
        -------
        dict of ndarray
            ``theoretical_nm``, ``<component>_nm``, ``friction_nm``, ``input_nm``,
            ``efficiency`` and ``flags``, each of shape (n,).

        """
        visc = self.default_viscosity_m2_s if viscosity_m2_s is None else viscosity_m2_s
        speed, dp, visc = (np.ravel(a) for a in np.broadcast_arrays(
            np.asarray(speed_rad_s, dtype=float), np.asarray(pressure_diff_pa, dtype=float),
            np.asarray(visc, dtype=float)))
        mags, flags = self.magnitudes_array(np.abs(speed), np.abs(dp), visc, speed * dp < 0.0)
        direction = smooth_sign(speed, self.zero_speed_threshold_rad_s)
        result = {'theoretical_nm': theoretical_torque_nm(self.displacement_m3, dp)}
        for c, name in enumerate(COMPONENTS):
            result[f'{name}_nm'] = direction * mags[:, c]
        result['friction_nm'] = direction * mags.sum(axis=1)
        result['input_nm'] = input_torque_nm(result['theoretical_nm'], mags.sum(axis=1),
                                             direction)
        result['efficiency'] = torque_efficiency(
            result['theoretical_nm'], result['input_nm'], speed, dp,
            self.efficiency_min_speed_rad_s, self.efficiency_min_pressure_pa)
        result['flags'] = flags
        return result


class _AxisLocator:
    """
    Cell index and local coordinate on a non-uniform axis, faster than searchsorted.

    Uniform buckets no wider than the axis' smallest step (up to 2**20 of them) each point
    to the last node at or below the bucket's start; one or two vectorised compares fix
    the index up. Works for any strictly increasing axis.
    """

    def __init__(self, axis: np.ndarray) -> None:
        self.axis = axis
        n = axis.size
        span = float(axis[-1] - axis[0])
        buckets = int(min(np.ceil(span / float(np.diff(axis).min())), 1 << 20))
        self._x0 = float(axis[0])
        self._scale = buckets / span
        self._last_bucket = buckets - 1
        starts = self._x0 + np.arange(buckets) / self._scale
        self._lut = np.clip(np.searchsorted(axis, starts, side='right') - 1, 0, n - 2)
        ends = np.append(starts[1:], axis[-1])
        self._fixups = int((np.searchsorted(axis, ends, side='right') - 1
                            - self._lut).max(initial=0))
        self._upper = np.append(axis[1:], np.inf)  # axis[i + 1], inf past the last cell
        self._upper[n - 2] = np.inf  # the last cell also takes x == axis[-1]
        self._inv_step = 1.0 / np.diff(axis)

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Return (index, local coordinate in [0, 1], clamped mask or None)."""
        axis = self.axis
        low, high = x < axis[0], x > axis[-1]
        clamped = None
        if low.any() or high.any():
            clamped = low | high
            x = np.clip(x, axis[0], axis[-1])
        bucket = ((x - self._x0) * self._scale).astype(np.intp)
        np.clip(bucket, 0, self._last_bucket, out=bucket)
        idx = self._lut[bucket]
        for _ in range(self._fixups):
            idx += x >= self._upper[idx]
        t = (x - axis[idx]) * self._inv_step[idx]
        return idx, t, clamped


@dataclass(frozen=True)
class TableTorque:
    """Torques at one operating point from the table (scalar path), all signed [N*m]."""

    theoretical_nm: float
    components_nm: tuple[float, float, float, float]  # COMPONENTS order
    friction_nm: float
    input_nm: float
    efficiency: float  # NaN where undefined
    flags: int


def build_table(params: PumpParams, spec: TableSpec | None = None,
                progress: Callable[[float], None] | None = None) -> FrictionTable:
    """
    Evaluate the full model on the table grid.

    Parameters
    ----------
    params : PumpParams
        Pump parameters.
    spec : TableSpec, optional
        Envelope and resolution (default `TableSpec()`).
    progress : callable, optional
        Called with the fraction done (0..1) as the build proceeds.

    Returns
    -------
    FrictionTable
        The table, with metadata: axes and units, component names, pump name and hash,
        model and package versions, creation time, build settings.

    """
    spec = spec or TableSpec()
    model = PumpModel(params, n_angles=angle_count(params.geometry.n_pistons, spec.n_angles))
    speed, pressure, viscosity = spec.axes(params)
    grid = np.stack(np.meshgrid(speed, pressure, viscosity, indexing='ij'), axis=-1)
    flat = grid.reshape(-1, 3)
    torque = np.empty((2, flat.shape[0], len(COMPONENTS)))
    block = 512
    total = 2 * flat.shape[0]
    done = 0
    started = time.perf_counter()
    for mode, sign in enumerate((1.0, -1.0)):
        for start in range(0, flat.shape[0], block):
            part = flat[start:start + block]
            res = model.evaluate(sign * part[:, 0], part[:, 1], part[:, 2])
            torque[mode, start:start + block] = np.column_stack(
                [res.magnitudes_nm[c] for c in COMPONENTS])
            done += part.shape[0]
            if progress is not None:
                progress(done / total)
    metadata = {
        'format': TABLE_FORMAT,
        'components': list(COMPONENTS),
        'modes': ['pumping', 'motoring'],
        'axes': ['mode', 'speed_abs', 'pressure_diff_abs', 'viscosity'],
        'units': {'speed_axis_rad_s': 'rad/s', 'pressure_axis_pa': 'Pa',
                  'viscosity_axis_m2_s': 'm^2/s', 'torque_nm': 'N*m'},
        'pump_name': params.name,
        'pump_sha256': params.sha256,
        'pump_source': params.source,
        'model_version': MODEL_VERSION,
        'package_version': __version__,
        'created_utc': time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime()),
        'build_seconds': round(time.perf_counter() - started, 3),
        'n_angles': model.n_angles,
        'spec': asdict(spec),
        'displacement_m3': params.geometry.displacement_m3,
        'zero_speed_threshold_rad_s': params.operation.zero_speed_threshold_rad_s,
        'efficiency_min_speed_rad_s': params.operation.efficiency_min_speed_rad_s,
        'efficiency_min_pressure_pa': params.operation.efficiency_min_pressure_pa,
        'default_viscosity_m2_s': params.oil.viscosity_m2_s,
    }
    shape = (2, speed.size, pressure.size, viscosity.size, len(COMPONENTS))
    return FrictionTable(speed, pressure, viscosity, torque.reshape(shape), metadata)


def _curve_kink_speeds(params: PumpParams) -> list[float]:
    """
    Shaft speeds [rad/s] at which joint or head sliding speeds cross a curve abscissa.

    Over a revolution the sliding speed per unit shaft speed ranges between a minimum and
    a maximum, so each kink of a friction curve is smeared over a band of shaft speeds;
    both ends and the middle of each band become grid nodes.
    """
    from ..physics.dynamics import joint_angular_velocity_per_speed
    from ..physics.kinematics import piston_kinematics

    geom = params.geometry
    phi = np.linspace(0.0, 2.0 * np.pi, 361)
    kin = piston_kinematics(geom, phi, params.piston.joint_to_cg_m)
    joint = geom.joint_ball_radius_m * np.linalg.norm(
        joint_angular_velocity_per_speed(params, kin), axis=-1)
    head = np.abs(kin.head_vel_per_speed)
    speeds = []
    for curve, per_speed in ((params.piston_friction.joint_coefficient, joint),
                             (params.piston_friction.head_coefficient, head)):
        lo, hi = float(per_speed.min()), float(per_speed.max())
        for v in curve.x[1:]:
            ends = [v / hi] + ([v / lo] if lo > 0.0 else [])
            speeds.extend([*ends, 0.5 * (ends[0] + ends[-1])])
    return speeds


def _validate_arrays(speed: np.ndarray, pressure: np.ndarray, viscosity: np.ndarray,
                     torque: np.ndarray, where: str) -> None:
    for name, axis in (('speed_axis_rad_s', speed), ('pressure_axis_pa', pressure),
                       ('viscosity_axis_m2_s', viscosity)):
        if axis.ndim != 1 or axis.size < 2 or not np.all(np.isfinite(axis)) \
                or not np.all(np.diff(axis) > 0):
            raise TableError(f'{where}: {name} must be a finite, strictly increasing 1-D axis')
    if speed[0] != 0.0 or pressure[0] != 0.0 or viscosity[0] <= 0.0:
        raise TableError(f'{where}: speed and pressure axes must start at 0, viscosity > 0')
    expected = (2, speed.size, pressure.size, viscosity.size, len(COMPONENTS))
    if torque.shape != expected:
        raise TableError(f'{where}: torque_nm has shape {torque.shape}, expected {expected}')
    if not np.all(np.isfinite(torque)) or np.any(torque < 0.0):
        raise TableError(f'{where}: torque_nm must hold finite, non-negative magnitudes')
