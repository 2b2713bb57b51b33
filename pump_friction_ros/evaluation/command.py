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

"""``pump_friction evaluate-monitor``: run the bank, print its table, optionally save it all."""

from __future__ import annotations

from pathlib import Path

from .bank import run_bank
from .next_morning import format_next_mornings, run_next_mornings
from .report import bank_figures, format_table, write_outputs
from .settings import FULL, QUICK
from ..progress import ProgressBar

__all__ = ['evaluate_monitor']


def evaluate_monitor(quick: bool = False, workers: int = 1, out: str | Path | None = None,
                     seed: int = 0, progress: bool = True, next_morning: bool = False) -> int:
    """
    Run the evaluation bank with the current monitor and print one table.

    With ``next_morning``, instead: each installation of the cold start without temperature
    topic, a second day from the first's state (``next_morning``), with and without the hold.

    Parameters
    ----------
    quick : bool
        The test-suite bank (`settings.QUICK`) instead of the benchmark (`settings.FULL`).
    workers : int
        Worker processes.
    out : str or Path, optional
        Folder for records.csv, figures.json, table.md and the PNG plots.
    seed : int
        Bank seed.
    progress : bool
        Progress bar on a terminal.
    next_morning : bool
        Run the next mornings (table and ``next_morning.md`` in ``out``) instead of the bank.

    Returns
    -------
    int
        Exit code 0.

    """
    settings = QUICK if quick else FULL
    if next_morning:
        table = format_next_mornings(run_next_mornings(settings, [seed], workers), [seed])
        print(table)
        if out is not None:
            path = Path(out) / 'next_morning.md'
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(table + '\n', encoding='utf-8')
            print(path)
        return 0
    with ProgressBar(f'evaluate-monitor ({settings.name})', enabled=progress) as bar:
        result = run_bank(settings, workers=workers, seed=seed,
                          progress=lambda done, total: bar(done / total))
    figures = bank_figures(result.records)
    table = format_table(figures, result)
    print(table)
    if out is not None:
        for path in write_outputs(result, figures, table, Path(out)):
            print(path)
    return 0
