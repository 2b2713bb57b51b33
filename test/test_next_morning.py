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

"""The next morning's cold start on the bank's simulated EHA, from the first day's state."""

from dataclasses import replace

from pump_friction_ros.core.monitor import OK
from pump_friction_ros.evaluation.next_morning import (
    format_next_mornings,
    next_morning_scenarios,
    run_next_morning,
)
from pump_friction_ros.evaluation.settings import FULL


def test_the_next_mornings_cold_start_raises_no_alarm_with_the_hold_and_one_without():
    """
    Seed 0's third cold start without topic (ISO VG 32, 14 -> 57 degC, tau 337 s), 30 min.

    Day one warms from cold and learns its baseline on warm oil; day two, a day later from
    that state, starts cold again: the hold waits for the oil, the node without it alarms.
    """
    scenario = next_morning_scenarios(FULL, 0)[2]
    assert scenario.scenario_id == 'eha_cold_no_temp/nominal/2'
    record = run_next_morning(replace(scenario, duration_s=1800.0))
    assert record.learnt and record.day_one_alarms == 0
    assert record.alarms == 0 and record.level == OK
    assert 0.0 < record.released_s < 1800.0  # held from day two's first window, then judged
    assert record.alarms_without_hold >= 1  # the cold oil read as valve plate or oil
    table = format_next_mornings([record], [0])
    assert table.endswith('day two with the hold 0 alarms in 1 cold starts, without it '
                          f'{record.alarms_without_hold}.')
