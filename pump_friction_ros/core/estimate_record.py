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

"""What the estimator makes of one shaft-speed sample, and the counters of what it skipped."""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import numpy as np

__all__ = ['COUNTERS', 'MONITOR_COLUMNS', 'Estimate', 'EstimateColumns']

COUNTERS = ('estimates', 'stale_skips', 'rejected_non_finite', 'rejected_out_of_order',
            'rejected_duplicate', 'rejected_out_of_range', 'rejected_future_stamp',
            'rejected_negative_stamp', 'rejected_missing_joint', 'rejected_malformed',
            'rejected_undecodable', 'stamp_resyncs', 'clamped_to_table', 'residuals',
            'monitor_samples')
"""Counters of the estimator, in the order /diagnostics and the replay report them."""


class Estimate(NamedTuple):
    """
    One estimate (what the node publishes), SI units; NaN where not available.

    A NamedTuple: made a thousand times a second, it must be cheap to build.
    """

    stamp_ns: int
    speed_rad_s: float
    pressure_diff_pa: float
    viscosity_m2_s: float
    theoretical_nm: float
    components_nm: tuple[float, float, float, float]  # COMPONENTS order, signed
    friction_nm: float
    inertia_nm: float
    accel_rad_s2: float  # filtered shaft acceleration
    drive_loss_nm: float
    expected_nm: float
    efficiency: float  # NaN where undefined (near zero speed or pressure)
    measured_nm: float  # NaN without a fresh measured torque
    residual_nm: float  # NaN without a fresh measured torque
    valve_plate_scale: float
    valve_plate_scale_std: float
    level: int
    table_flags: int
    publish: bool  # output decimation: publish this one


_new_estimate = partial(tuple.__new__, Estimate)


MONITOR_COLUMNS = ('cusum_pos_nm_s', 'cusum_neg_nm_s', 'other_scale', 'other_scale_std')
"""The wear monitor's state after each estimate that `EstimateColumns` carries besides the
fields (the replay's plots draw them)."""


class EstimateColumns:
    """
    Estimates made one after the other, column by column: what the chunk path returns.

    One numpy array per `Estimate` field, in field order (``components_nm``: four arrays,
    ``COMPONENTS`` order), all of one length, and the monitor's state after each estimate
    (`MONITOR_COLUMNS`). Rows become `Estimate` objects only when asked for (`rows`): the
    replay reads most fields as columns.

    Parameters
    ----------
    columns : list of ndarray
        The 22 columns: the fields, the components spread.
    monitor : dict of ndarray
        The `MONITOR_COLUMNS`, one value per estimate.

    """

    def __init__(self, columns: list[np.ndarray], monitor: dict[str, np.ndarray]) -> None:
        if len(columns) != len(Estimate._fields) + 3 or set(monitor) != set(MONITOR_COLUMNS):
            raise ValueError('expected a column per Estimate field (four components) and the '
                             f'monitor columns {MONITOR_COLUMNS}')
        self.columns = columns
        self.monitor = monitor

    @classmethod
    def from_rows(cls, rows: list[Estimate], monitor: dict[str, list[float]]
                  ) -> EstimateColumns:
        """
        Return the columns of `Estimate` objects.

        Parameters
        ----------
        rows : list of Estimate
            The estimates.
        monitor : dict of list
            The `MONITOR_COLUMNS`, one value per estimate.

        Returns
        -------
        EstimateColumns
            Whose `rows` are equal to ``rows``.

        """
        n = len(Estimate._fields) + 3
        flat = [(*row[:5], *row[5], *row[6:]) for row in rows]
        columns = [np.asarray(col) for col in zip(*flat, strict=True)] if flat else \
            [np.empty(0) for _ in range(n)]
        return cls(columns, {k: np.asarray(monitor[k], dtype=float) for k in MONITOR_COLUMNS})

    def __len__(self) -> int:
        return int(self.columns[0].size)

    def column(self, name: str) -> np.ndarray:
        """
        Return the values of one field, an array (not for ``components_nm``).

        Parameters
        ----------
        name : str
            An `Estimate` field.

        Returns
        -------
        ndarray
            Its values, one per estimate.

        """
        index = Estimate._fields.index(name)
        return self.columns[index if index < 5 else index + 3]

    def rows(self, which: np.ndarray | slice | None = None) -> list[Estimate]:
        """
        Return estimates as `Estimate` objects, with Python numbers as the scalar path's.

        Parameters
        ----------
        which : ndarray or slice, optional
            Which rows (indices, mask or slice); default all.

        Returns
        -------
        list of Estimate
            In order.

        """
        cols = [c.tolist() if which is None else c[which].tolist() for c in self.columns]
        rows = [*cols[:5], list(zip(*cols[5:9], strict=True)), *cols[9:]]
        return list(map(_new_estimate, zip(*rows, strict=True)))
