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
The next morning: a cold start again, from the state the first day left.

The bank's runs each start a fresh node. An installation without temperature topic lives
longer: the node keeps its baseline in a file, and the next morning the pump starts cold
against the baseline of warm oil. `run_next_morning` runs a nominal scenario of the cold
start without temperature topic (``eha_cold_no_temp``) as day one, then the same cold start
a day later (``DAY_S``, the stamps shifted) on a node restored from day one's state, once
with the node's ``warm_up_pause_s`` (``core.warm_up_hold``) and once with the hold off
(0), and counts the alarms of each second day. ``pump_friction evaluate-monitor
--next-morning`` prints the table (docs/monitor.md gives the figures).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
import math

from .bank import build_scenarios, feed_signals, prepare_true_tables
from .bank_node import scenario_node, simulated
from .scenarios import Scenario, SimulatedScenario
from .settings import BankSettings
from ..core.monitor import LEVEL_NAMES
from ..process_pool import process_map

__all__ = ['DAY_S', 'NextMorning', 'format_next_mornings', 'next_morning_scenarios',
           'run_next_morning', 'run_next_mornings']

DAY_S = 86400.0
"""The night between the two days [s]: the oil is at ambient again."""


@dataclass(frozen=True)
class NextMorning:
    """One installation's two days (`run_next_morning`)."""

    scenario_id: str
    day_one_alarms: int  # entries into WARN / ERROR on day one
    learnt: bool  # day one learnt the baseline
    alarms: int  # on day two, with the hold
    released_s: float  # when the hold let the detection go on, from day two's start [s]
    level: int  # at day two's end, with the hold
    alarms_without_hold: int  # on day two, warm_up_pause_s 0
    level_without_hold: int
    verdict_without_hold: str  # at day two's end


def _shifted(sim: SimulatedScenario, by_s: float) -> SimulatedScenario:
    return replace(sim, t_s=sim.t_s + by_s, pressure_t_s=sim.pressure_t_s + by_s,
                   temperature_t_s=sim.temperature_t_s + by_s)


def run_next_morning(scenario: Scenario) -> NextMorning:
    """
    Run a scenario as day one, then again a day later from its state, with and without hold.

    Parameters
    ----------
    scenario : Scenario
        A nominal scenario (its configuration: the node's parameters).

    Returns
    -------
    NextMorning
        Day one's alarms and baseline; day two's alarms, release time and end level with the
        hold, and alarms, level and verdict without it.

    """
    sim = simulated(scenario)
    config = scenario.estimator_config()
    day_one = scenario_node(scenario)
    day_one_alarms = feed_signals(day_one, sim, math.inf)[0]
    state = day_one.monitor.state_dict()
    morning = _shifted(sim, DAY_S)
    days = []
    for pause_s in (config.warm_up_pause_s, 0.0):
        core = scenario_node(scenario, replace(config, warm_up_pause_s=pause_s))
        core.monitor.load_state_dict(state)
        alarms = feed_signals(core, morning, math.inf)[0]
        days.append((alarms, core.monitor.hold_released_s - DAY_S, core.monitor.level,
                     core.monitor.verdict(1.0)[0] if core.monitor.level else ''))
    (alarms, released_s, level, _), (without, _, level_without, verdict) = days
    return NextMorning(scenario.scenario_id, day_one_alarms, day_one.monitor.baseline is not
                       None, alarms, released_s, level, without, level_without, verdict)


def next_morning_scenarios(settings: BankSettings, seed: int = 0) -> list[Scenario]:
    """
    Return the nominal scenarios of the cold start without temperature topic of a bank.

    Parameters
    ----------
    settings : BankSettings
        The bank's size (`settings.FULL`: three installations per seed).
    seed : int
        Bank seed.

    Returns
    -------
    list of Scenario
        One per installation.

    """
    cold = replace(settings, families=('eha_cold_no_temp',))
    return [s for s in build_scenarios(cold, seed) if s.fault.name == 'nominal']


def run_next_mornings(settings: BankSettings, seeds: list[int], workers: int = 1
                      ) -> list[NextMorning]:
    """
    Run `run_next_morning` on every installation of the cold start without topic.

    Parameters
    ----------
    settings : BankSettings
        The bank's size.
    seeds : list of int
        Bank seeds.
    workers : int
        Worker processes (1: in this process); the records do not depend on it.

    Returns
    -------
    list of NextMorning
        In seed and installation order.

    """
    scenarios = [s for seed in seeds for s in next_morning_scenarios(settings, seed)]
    prepare_true_tables(scenarios)  # (the pump's and the node's tables too)
    if workers == 1:
        return [run_next_morning(s) for s in scenarios]
    return process_map(run_next_morning, scenarios, workers)


def format_next_mornings(records: list[NextMorning], seeds: list[int]) -> str:
    """
    Return the records as a Markdown table, with their sums.

    Parameters
    ----------
    records : list of NextMorning
        `run_next_mornings`'s.
    seeds : list of int
        Their bank seeds (for the caption).

    Returns
    -------
    str
        The table.

    """
    rows = ['| installation | day one: alarms | day two with the hold: alarms | released after '
            '[s] | level at the end | without the hold: alarms | level at the end | verdict |',
            '|---|---|---|---|---|---|---|---|']
    for r in records:
        rows.append(f'| {r.scenario_id} | {r.day_one_alarms}'
                    f'{"" if r.learnt else " (never learnt)"} | {r.alarms} | '
                    f'{_released(r.released_s)} | {LEVEL_NAMES[r.level]} | '
                    f'{r.alarms_without_hold} | '
                    f'{LEVEL_NAMES[r.level_without_hold]} | {r.verdict_without_hold or "-"} |')
    rows.append(f'\nSeed{"s" if len(seeds) > 1 else ""} {", ".join(map(str, seeds))}: '
                f'day two with the hold '
                f'{sum(r.alarms for r in records)} alarms in {len(records)} cold starts, '
                f'without it {sum(r.alarms_without_hold for r in records)}.')
    return '\n'.join(rows)


def _released(released_s: float) -> str:
    return 'held to the end' if math.isnan(released_s) else f'{released_s:.0f}'
