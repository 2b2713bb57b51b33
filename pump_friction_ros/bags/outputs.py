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
The replay's CSV of estimates; its outputs are staged (``staging.Staged``), then moved.

Every output is written under a temporary name beside its target and renamed at the end,
so a failed or interrupted replay leaves nothing that looks complete.
"""

from __future__ import annotations

from ..core.estimate_record import Estimate
from ..physics.model import COMPONENTS
from ..staging import Staged

__all__ = ['CSV_COLUMNS', 'Staged', 'csv_row']


def _csv_columns() -> tuple[str, ...]:
    """Return the CSV header, from the `Estimate` fields (components spread, time added)."""
    columns: list[str] = []
    for name in Estimate._fields:
        if name == 'components_nm':
            columns += [f'{c}_nm' for c in COMPONENTS]
        elif name == 'publish':
            columns.append('published')
        else:
            columns.append(name)
        if name == 'stamp_ns':
            columns.append('time_s')
    return tuple(columns)


CSV_COLUMNS = _csv_columns()
"""Header of the replay's CSV: one column per `Estimate` field, ``time_s`` from the start."""


def csv_row(est: Estimate, start_ns: int) -> list[object]:
    """
    Return one CSV row for an estimate, in `CSV_COLUMNS` order.

    Parameters
    ----------
    est : Estimate
        The estimate.
    start_ns : int
        Start of the bag [ns] (``time_s`` is counted from it).

    Returns
    -------
    list
        The row.

    """
    row: list[object] = []
    for name, value in zip(Estimate._fields, est, strict=True):
        if name == 'components_nm':
            row += list(est.components_nm)
        elif name == 'publish':
            row.append(int(est.publish))
        else:
            row.append(value)
        if name == 'stamp_ns':
            row.append(f'{(est.stamp_ns - start_ns) * 1e-9:.6f}')
    return row
