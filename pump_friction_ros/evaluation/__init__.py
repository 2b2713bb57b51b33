"""
Evaluation bank of the wear monitor: scenarios, runs through the core, figures, plots.

``pump_friction evaluate-monitor`` runs it; `run_bank` and `bank_figures` are the API.
Imports flow settings -> scenarios -> bank -> report / plots -> command; nothing here
imports ROS.
"""

from .bank import BankResult, MonitorReading, read_monitor, run_bank, RunRecord
from .report import bank_figures, format_table
from .settings import BankSettings, FAMILIES, FAULTS, FULL, QUICK

__all__ = ['FAMILIES', 'FAULTS', 'FULL', 'QUICK', 'BankResult', 'BankSettings',
           'MonitorReading', 'RunRecord', 'bank_figures', 'format_table', 'read_monitor',
           'run_bank']
