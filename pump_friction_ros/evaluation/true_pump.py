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
The true pump of a realistic run: the node's pump file with its open parameters perturbed.

`pump_variants` draws a few variants once (fixed seed): film clearance, the Palmgren
coefficients f0 and f1 and the three coulomb curves each scaled (`MismatchSettings`);
`true_table` builds the friction table of one, on a grid whose viscosity axis reaches the
cold oil (the node's table stops at 100 cSt), caches it in ``table_io.cache_dir`` and in
the process. The node keeps the shipped table.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache
import hashlib

import numpy as np

from .eha_settings import MismatchSettings
from .. import MODEL_VERSION
from ..errors import TableError
from ..physics.pump_parameters import Curve, load_pump, PumpParams
from ..table.friction_table import build_table, FrictionTable, TableSpec
from ..table.table_files import cache_dir, load_table

__all__ = ['PumpVariant', 'perturbed_pump', 'pump_variants', 'true_table', 'true_table_spec']


@dataclass(frozen=True)
class PumpVariant:
    """Factors of one true pump against the node's pump file [-]."""

    film_clearance: float = 1.0
    bearing_f0: float = 1.0
    bearing_f1: float = 1.0
    valve_plate_coulomb: float = 1.0
    joint_coulomb: float = 1.0
    head_coulomb: float = 1.0


def _scaled(curve: Curve, factor: float) -> Curve:
    return Curve(curve.x, tuple(float(y) * factor for y in curve.y))


def perturbed_pump(params: PumpParams, variant: PumpVariant) -> PumpParams:
    """
    Return the pump file's parameters with a variant's factors applied.

    Parameters
    ----------
    params : PumpParams
        The node's pump.
    variant : PumpVariant
        The factors.

    Returns
    -------
    PumpParams
        The true pump (its name says it is a variant; its hash differs).

    """
    vp, bearing, pf = params.valve_plate, params.bearing, params.piston_friction
    return replace(
        params, name=f'{params.name}_true',
        valve_plate=replace(vp, film_clearance_m=vp.film_clearance_m * variant.film_clearance,
                            coulomb_coefficient=_scaled(vp.coulomb_coefficient,
                                                        variant.valve_plate_coulomb)),
        bearing=replace(bearing, f0=bearing.f0 * variant.bearing_f0,
                        f1=bearing.f1 * variant.bearing_f1),
        piston_friction=replace(pf, joint_coefficient=_scaled(pf.joint_coefficient,
                                                              variant.joint_coulomb),
                                head_coefficient=_scaled(pf.head_coefficient,
                                                         variant.head_coulomb)))


def pump_variants(settings: MismatchSettings) -> tuple[PumpVariant, ...]:
    """
    Draw the true pumps of the bank (deterministic: ``settings.variant_seed``).

    Parameters
    ----------
    settings : MismatchSettings
        Ranges and count.

    Returns
    -------
    tuple of PumpVariant
        ``settings.variants`` variants, each factor uniform in its range.

    """
    rng = np.random.default_rng(settings.variant_seed)
    out = []
    for _ in range(settings.variants):
        out.append(PumpVariant(
            film_clearance=float(rng.uniform(*settings.film_clearance_factor)),
            bearing_f0=float(rng.uniform(*settings.bearing_factor)),
            bearing_f1=float(rng.uniform(*settings.bearing_factor)),
            valve_plate_coulomb=float(rng.uniform(*settings.coulomb_factor)),
            joint_coulomb=float(rng.uniform(*settings.coulomb_factor)),
            head_coulomb=float(rng.uniform(*settings.coulomb_factor))))
    return tuple(out)


def true_table_spec(settings: MismatchSettings) -> TableSpec:
    """
    Return the grid of the true tables: the default one, viscosity up to cold oil.

    Parameters
    ----------
    settings : MismatchSettings
        Top and count of the viscosity axis.

    Returns
    -------
    TableSpec
        The spec.

    """
    return TableSpec(max_viscosity_m2_s=settings.max_viscosity_m2_s,
                     viscosity_points=settings.viscosity_points)


@lru_cache(maxsize=16)
def true_table(variant: PumpVariant, settings: MismatchSettings | None = None
               ) -> FrictionTable:
    """
    Friction table of a true pump: from this process, the disk cache, or built (seconds).

    Parameters
    ----------
    variant : PumpVariant
        The true pump's factors against the default pump file.
    settings : MismatchSettings, optional
        Grid of the table (viscosity axis); default `MismatchSettings()`.

    Returns
    -------
    FrictionTable
        The true pump's table.

    """
    settings = settings or MismatchSettings()
    params = perturbed_pump(load_pump(None), variant)
    spec = true_table_spec(settings)
    key = hashlib.sha256(repr(spec).encode()).hexdigest()[:8]
    path = cache_dir() / f'{params.name}-{params.sha256[:16]}-s{key}-m{MODEL_VERSION}.npz'
    if path.exists():
        try:
            return load_table(path, params)
        except TableError:
            pass  # corrupt: rebuild
    table = build_table(params, spec)
    try:
        table.save(path)
    except OSError:
        pass  # read-only cache: the table still works
    return table
