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

from dataclasses import replace
from pathlib import Path

from .bank import run_bank
from .next_morning import format_next_mornings, run_next_mornings
from .report import bank_figures, format_table, write_outputs
from .settings import FULL, QUICK
from ..progress import ProgressBar
from ..staging import Staged, StagedOutputs

__all__ = ['EVALUATION_FILES', 'NEXT_MORNING_FILE', 'evaluate_monitor',
           'looks_like_evaluation']

NEXT_MORNING_FILE = 'next_morning.md'
"""The file ``--next-morning`` writes into ``--out`` (beside a bank's outputs, if any)."""
EVALUATION_FILES = ('records.csv', 'figures.json', 'table.md', NEXT_MORNING_FILE)
"""What an ``--out`` folder of this command holds, besides its PNG plots."""


def looks_like_evaluation(path: Path) -> bool:
    """
    Return whether an existing folder holds only an earlier evaluation's outputs.

    Parameters
    ----------
    path : Path
        The folder.

    Returns
    -------
    bool
        Every entry a file named in `EVALUATION_FILES` or a PNG plot.

    """
    return all(p.is_file() and (p.name in EVALUATION_FILES or p.suffix == '.png')
               for p in path.iterdir())


def evaluate_monitor(quick: bool = False, workers: int = 1, out: str | Path | None = None,
                     seed: int = 0, progress: bool = True, next_morning: bool = False,
                     force: bool = False, held_out: bool = False) -> int:
    """
    Run the evaluation bank with the current monitor and print one table.

    With ``next_morning``, instead: each installation of the cold start without temperature
    topic, a second day from the first's state (``next_morning``), with and without the hold.
    With ``held_out``, what the bank holds out instead of the bank, at its size
    (`settings.Fault.applies_to`): the held-out duty cycles (`settings.HELD_OUT_FAMILIES`)
    with every realistic fault, and the held-out faults on every realistic family.

    Parameters
    ----------
    quick : bool
        The test-suite bank (`settings.QUICK`) instead of the benchmark (`settings.FULL`).
    workers : int
        Worker processes.
    out : str or Path, optional
        Folder for records.csv, figures.json, table.md and the PNG plots: checked and made
        before the bank runs, written under a temporary name and moved into place at the
        end (``staging``), so that a bad path fails at once and an interrupted run leaves
        nothing that looks complete. With ``next_morning``, the one file
        ``next_morning.md`` in it, staged the same way.
    seed : int
        Bank seed.
    progress : bool
        Progress bar on a terminal.
    next_morning : bool
        Run the next mornings (table and ``next_morning.md`` in ``out``) instead of the bank.
    force : bool
        Replace an existing ``out`` folder that holds only an earlier evaluation's outputs
        (its ``next_morning.md`` too), or with ``next_morning`` that file.
    held_out : bool
        Run what the bank holds out instead of the bank (not with ``next_morning``).

    Returns
    -------
    int
        Exit code 0.

    Raises
    ------
    OutputError
        ``out`` exists (without ``force``), is not such a folder, or cannot be made.
    ValueError
        ``held_out`` with ``next_morning`` (the next mornings are the bank's cold starts).

    """
    if held_out and next_morning:
        raise ValueError('held_out and next_morning exclude each other: the next mornings '
                         "are the bank's cold starts without temperature topic")
    settings = replace(QUICK if quick else FULL, held_out=held_out)
    outputs = StagedOutputs()
    try:
        if next_morning:  # one file, beside a bank's outputs in the same folder if any
            staged = None if out is None else outputs.add(Path(out) / NEXT_MORNING_FILE,
                                                          force, False, flag='--out')
            table = format_next_mornings(run_next_mornings(settings, [seed], workers), [seed])
            print(table)  # (printed before it is written: a failed write loses nothing)
            if staged is not None:
                with staged.writing():
                    staged.path.write_text(table + '\n', encoding='utf-8')
                outputs.commit()
                print(staged.target)
            return 0
        staged = None if out is None else outputs.add(out, force, True,
                                                      looks_like=looks_like_evaluation,
                                                      flag='--out')
        with ProgressBar(f'evaluate-monitor ({settings.name})', enabled=progress) as bar:
            result = run_bank(settings, workers=workers, seed=seed,
                              progress=lambda done, total: bar(done / total))
        figures = bank_figures(result.records)
        table = format_table(figures, result)
        print(table)
        if staged is not None:
            with staged.writing():
                written = write_outputs(result, figures, table, staged.path)
            _commit(outputs, staged, [path.name for path in written])
    except BaseException:
        outputs.discard()
        raise
    return 0


def _commit(outputs: StagedOutputs, staged: Staged, names: list[str]) -> None:
    """Move the staged folder into place and print the files written, at their place."""
    outputs.commit()
    for name in names:
        print(staged.target / name)
