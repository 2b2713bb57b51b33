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

from typing import NamedTuple

__all__ = ['COUNTERS', 'Estimate']

COUNTERS = ('estimates', 'stale_skips', 'rejected_non_finite', 'rejected_out_of_order',
            'rejected_duplicate', 'rejected_out_of_range', 'rejected_future_stamp',
            'rejected_missing_joint', 'rejected_malformed', 'rejected_undecodable',
            'stamp_resyncs', 'clamped_to_table', 'residuals', 'monitor_samples')
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
