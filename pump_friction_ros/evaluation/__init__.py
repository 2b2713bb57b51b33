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
Evaluation bank of the wear monitor: scenarios, runs through the core, figures, plots.

``pump_friction evaluate-monitor`` runs it; `run_bank` and `bank_figures` are the API.
Imports flow settings -> scenarios -> bank -> report / plots -> command; nothing here
imports ROS.

May import: sim, core, table, physics, base.
"""

from .bank import BankResult, MonitorReading, read_monitor, run_bank, RunRecord
from .report import bank_figures, format_table
from .settings import ALL_FAMILIES, BankSettings, FAMILIES, FAULTS, FULL, HELD_OUT_FAMILIES, QUICK

__all__ = ['ALL_FAMILIES', 'FAMILIES', 'FAULTS', 'FULL', 'HELD_OUT_FAMILIES', 'QUICK',
           'BankResult', 'BankSettings',
           'MonitorReading', 'RunRecord', 'bank_figures', 'format_table', 'read_monitor',
           'run_bank']
