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

"""The bank's pump and tables, and the node it runs a scenario on (cached per process)."""

from __future__ import annotations

from functools import lru_cache

from .scenarios import Scenario, simulate_scenario, SimulatedScenario
from ..core.estimator import TorqueEstimator
from ..core.node_parameters import EstimatorConfig
from ..core.oil_range import table_spec_for
from ..physics.pump_parameters import load_pump, PumpParams
from ..table.friction_table import FrictionTable, TableSpec
from ..table.table_files import cached_table

__all__ = ['node_spec', 'node_table', 'pump_and_table', 'scenario_node', 'simulated']


@lru_cache(maxsize=1)
def pump_and_table() -> tuple[PumpParams, FrictionTable]:
    """Return the paper's pump and its table (the node's pump file; the truth's base)."""
    params = load_pump(None)
    return params, cached_table(params)


@lru_cache(maxsize=8)
def node_table(spec: TableSpec) -> FrictionTable:
    """Return the table the node builds for its oil (`oil_range.table_spec_for`), cached."""
    return cached_table(pump_and_table()[0], spec=spec)


def node_spec(scenario: Scenario) -> TableSpec:
    """Return the table the node builds for a scenario's parameters (its oil's range)."""
    params = pump_and_table()[0]
    return table_spec_for(scenario.estimator_config(), params.oil.viscosity_m2_s)


def scenario_node(scenario: Scenario, config: EstimatorConfig | None = None
                  ) -> TorqueEstimator:
    """
    Return a fresh node for a scenario: its parameters (or ``config``) and its oil's table.

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    config : EstimatorConfig, optional
        Other parameters than the scenario's own (`Scenario.estimator_config`).

    Returns
    -------
    TorqueEstimator
        The estimator the bank runs the scenario on.

    """
    params = pump_and_table()[0]
    return TorqueEstimator(config or scenario.estimator_config(),
                           node_table(node_spec(scenario)), params.oil.viscosity_m2_s,
                           params.name)


def simulated(scenario: Scenario) -> SimulatedScenario:
    """Return a scenario's signals, simulated on the bank's pump table (`simulate_scenario`)."""
    return simulate_scenario(scenario, pump_and_table()[1])
