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
Calibration: fit a pump's open friction parameters to bench points or recorded bags.

The friction model is linear, or very nearly, in the parameters a pump file leaves open
(`FIT_PARAMETERS`: scales of the valve-plate, bearing, joint and head friction; from bags
also the rotor inertia and a constant drive loss). The fit is bounded robust least squares
(``scipy.optimize.least_squares``, soft-L1 loss); the parameter covariance
s^2 (X^T X)^-1, inflated by the residuals' integral correlation time (samples of a 1 kHz
record are not independent), gives 95 % intervals. A parameter whose interval is wider
than half its reference value cannot be identified from the data (e.g. one speed cannot
separate coulomb from viscous friction): it is reported, fixed at its base value and the
fit repeated.

Modules: `data` (bench CSV and bag samples), `fit` (regression, identifiability,
cross-validation, inertia), `report` (result, pump file, report folder) and `pipeline`
(`calibrate`, which runs them in turn).

May import: bags, messages, core, table, physics, base.
"""

from .data import load_bag_samples, load_bench_csv, Samples
from .fit import (
    correlation_time,
    FIT_PARAMETERS,
    FitParameter,
    fitted_pump,
    INDEX,
    NAMES,
    regressors,
)
from .pipeline import calibrate
from .report import CalibrationResult, ParameterReport
from ..errors import CalibrationError

__all__ = ['FIT_PARAMETERS', 'INDEX', 'NAMES', 'CalibrationError', 'CalibrationResult',
           'FitParameter', 'ParameterReport', 'Samples', 'calibrate', 'correlation_time',
           'fitted_pump', 'load_bag_samples', 'load_bench_csv', 'regressors']
