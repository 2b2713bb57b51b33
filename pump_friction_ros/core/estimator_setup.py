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

"""Building the `TorqueEstimator` the node's parameters describe: pump file and table."""

from __future__ import annotations

from .estimator import TorqueEstimator
from .node_parameters import EstimatorConfig
from .oil_range import table_spec_for
from ..paths import resolve_path
from ..physics.pump_parameters import load_pump
from ..table.table_files import cached_table, load_table

__all__ = ['estimator_from_config']


def estimator_from_config(config: EstimatorConfig) -> TorqueEstimator:
    """
    Build the estimator a config describes: pump file, table (given or cached), tuning.

    The cached table's viscosity axis covers the configured oil (``oil_range``); a given
    ``table_file`` that does not is used all the same, with ``table_coverage`` saying so.

    Parameters
    ----------
    config : EstimatorConfig
        Validated parameters.

    Returns
    -------
    TorqueEstimator
        Ready to take samples.

    Raises
    ------
    ConfigError
        Invalid pump file.
    TableError
        Unreadable table, or a table built for another pump or model version.

    """
    params = load_pump(config.pump_file or None)
    table = load_table(resolve_path(config.table_file, 'table_file', must_exist=False), params) \
        if config.table_file else cached_table(
            params, spec=table_spec_for(config, params.oil.viscosity_m2_s))
    return TorqueEstimator(config, table, params.oil.viscosity_m2_s, params.name)
