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
The viscosity range the node's friction table covers: the configured oil, as it runs.

The oil's viscosity follows its temperature (ASTM D341 through ``oil_viscosity_40c_m2_s``
and ``oil_viscosity_100c_m2_s``), and the node accepts -60 to 250 degC
(``inputs.TEMPERATURE_RANGE_C``), over which ISO VG 46 spans 1 to 7.7 million cSt. The table
covers:

* hot end: the oil at the hottest accepted temperature (1.0 / 1.1 / 1.2 cSt for VG 32 / 46 /
  68 at 250 degC), so no hot oil is ever clamped;
* cold end: the pump maker's cold-start limit ``cold_start_viscosity_m2_s`` (1000 cSt for
  axial piston units; the source is in ``config/torque_estimator.yaml``), or the oil at
  -60 degC if it never gets that thick. Oil thicker than that is outside what the pump may
  start with: the table stops there, and the node says so in /diagnostics (the viscosity,
  the table's range) instead of tabulating thousands of cSt nobody runs at (VG 68 at
  -20 degC: 9,400 cSt). VG 32 / 46 / 68 reach 1000 cSt at -12.2 / -6.1 / +0.4 degC;
* the fixed viscosity (``oil_viscosity_m2_s``, 0: the pump file's), whatever the source.

`table_spec_for` turns that into the node's table grid (8 viscosity nodes per decade, 22 for
ISO VG 46), `coverage_warning` checks a given table file against it.
"""

from __future__ import annotations

import math

from .inputs import TEMPERATURE_RANGE_C
from .node_parameters import EstimatorConfig
from ..physics.oil import WaltherViscosity
from ..physics.units import m2_s_to_cst
from ..table.friction_table import FrictionTable, TableSpec

__all__ = ['coverage_warning', 'oil_viscosity_range_m2_s', 'table_spec_for']

_SLACK = 1e-9  # relative: an axis end equal to the range's end up to rounding covers it


def oil_viscosity_range_m2_s(config: EstimatorConfig, pump_file_viscosity_m2_s: float
                             ) -> tuple[float, float]:
    """
    Return the viscosity range the node's table must cover (see the module docstring).

    Parameters
    ----------
    config : EstimatorConfig
        Node parameters: the oil's temperature law, ``cold_start_viscosity_m2_s`` and
        ``oil_viscosity_m2_s``.
    pump_file_viscosity_m2_s : float
        The pump file's oil viscosity, used when ``oil_viscosity_m2_s`` is 0 [m^2/s].

    Returns
    -------
    tuple of float
        Lowest and highest viscosity [m^2/s], lowest < highest.

    """
    law = WaltherViscosity(config.oil_viscosity_40c_m2_s, config.oil_viscosity_100c_m2_s)
    coldest_c, hottest_c = TEMPERATURE_RANGE_C
    fixed = config.viscosity_m2_s(pump_file_viscosity_m2_s)
    low = min(law(hottest_c), fixed)
    high = max(min(config.cold_start_viscosity_m2_s, law(coldest_c)), fixed)
    return low, max(high, 2.0 * low)  # an oil already past the limit at 250 degC: a stub


def table_spec_for(config: EstimatorConfig, pump_file_viscosity_m2_s: float,
                   base: TableSpec | None = None) -> TableSpec:
    """
    Return the grid of the node's table: ``base`` with its viscosity axis over the oil.

    Parameters
    ----------
    config : EstimatorConfig
        Node parameters.
    pump_file_viscosity_m2_s : float
        The pump file's oil viscosity [m^2/s].
    base : TableSpec, optional
        Speed, pressure and angle resolution (default `TableSpec()`).

    Returns
    -------
    TableSpec
        The grid; its viscosity axis spans `oil_viscosity_range_m2_s`.

    """
    return (base or TableSpec()).covering(
        *oil_viscosity_range_m2_s(config, pump_file_viscosity_m2_s))


def coverage_warning(table: FrictionTable, config: EstimatorConfig,
                     pump_file_viscosity_m2_s: float) -> str:
    """
    Say, in one line, where a table's viscosity axis falls short of the oil; '' if it covers.

    A warning, not an error: the table was built for the pump in use by this model (its
    provenance is checked when it is loaded), and an operator may have cut it to the
    plant's warm range on purpose; refusing it would stop a machine that runs well inside
    that range. Where the oil leaves the axis, each sample is counted in
    ``clamped_to_table`` and /diagnostics says so, with the viscosity and the table's range.

    Parameters
    ----------
    table : FrictionTable
        The table in use (a ``table_file``, or the cached one).
    config : EstimatorConfig
        Node parameters.
    pump_file_viscosity_m2_s : float
        The pump file's oil viscosity [m^2/s].

    Returns
    -------
    str
        The warning, with the temperatures the table does cover and the command that
        builds one that covers the oil; '' when the axis covers the range.

    """
    low, high = oil_viscosity_range_m2_s(config, pump_file_viscosity_m2_s)
    axis = table.viscosity_axis_m2_s
    first, last = float(axis[0]), float(axis[-1])
    if first <= low * (1.0 + _SLACK) and last >= high * (1.0 - _SLACK):
        return ''
    law = WaltherViscosity(config.oil_viscosity_40c_m2_s, config.oil_viscosity_100c_m2_s)
    coldest_c, hottest_c = TEMPERATURE_RANGE_C
    warm_c = hottest_c if first <= law(hottest_c) else law.temperature_c(first)
    cold_c = coldest_c if last >= law(coldest_c) else law.temperature_c(last)
    source = table.metadata.get('source', '<table>')
    pump = table.metadata.get('pump_source') or 'PUMP.yaml'
    return (f'table {source}: its viscosity axis, {_cst(first)}-{_cst(last)} cSt, does not '
            f'cover the oil ({_cst(low)}-{_cst(high)} cSt: from 250 degC to '
            f'cold_start_viscosity_m2_s, and oil_viscosity_m2_s), which it holds only from '
            f'{cold_c:.1f} to {warm_c:.1f} degC; elsewhere the torque is taken at the edge '
            f'(counted in clamped_to_table, said in /diagnostics); a table that covers it: '
            f'pump_friction build-table --pump {pump} --viscosity-cst '
            f'{_cst(low, -1)} {_cst(high, 1)} --out FILE')


def _cst(viscosity_m2_s: float, direction: int = 0) -> str:
    """Return a viscosity in cSt to 4 significant digits, rounded down (-1) or up (1)."""
    value = float(m2_s_to_cst(viscosity_m2_s))
    if direction:
        scale = 10.0 ** (3 - math.floor(math.log10(value)))
        value = (math.floor if direction < 0 else math.ceil)(value * scale) / scale
    return f'{value:.4g}'
