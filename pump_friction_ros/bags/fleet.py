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
Fleets: many bags replayed in local processes or on a Dask cluster, and their table.

Each bag's outputs are named by `output_names` (unique within the fleet) under the folders
the command line names, which `plan_outputs` checks and makes before any bag starts; every
path a job carries is absolute, so that a Dask worker running in another directory finds
the same files (it needs the same paths: shared storage).

Locally each bag is replayed in a process of its own (daemonic, so the replay runs inline
in it), at most ``workers`` at a time. A worker sets its own signal handling when it starts,
whatever its parent had (rclpy's handlers in a ROS test process): Ctrl-C is left to the
parent, and SIGTERM makes it discard its staged outputs and exit. On Ctrl-C the parent
starts no more bags, stops the running workers (each with a bounded wait and a kill after
it) and the command removes the output folders this run made if they are left empty; a
worker whose parent is gone ends with its one bag. On Dask, Ctrl-C cancels the bags not yet
started; running ones finish.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
import multiprocessing
import multiprocessing.connection
from multiprocessing.connection import Connection
import os
from pathlib import Path
import shutil
import signal
from typing import Any, cast

from .replay import replay_bag, ReplaySummary
from .sources import process_context, stop_process
from ..core.baseline_store import BaselineStore
from ..core.estimator_setup import estimator_from_config
from ..core.monitor import LEVEL_NAMES
from ..core.node_parameters import EstimatorConfig
from ..errors import BagError, PumpFrictionError, UsageError
from ..interrupts import raise_if_interrupted, sigint_held, sigterm_kept
from ..staging import refuse_at_inputs, remove_empty_folders

__all__ = ['FleetOutputs', 'ReplayJob', 'discover_bags', 'fleet_table', 'output_names',
           'plan_outputs', 'refuse_repeats', 'run_job', 'run_jobs']


def discover_bags(paths: list[str | Path]) -> list[Path]:
    """
    Expand the command line's BAG arguments: bags as given, folders to the bags inside.

    Parameters
    ----------
    paths : list of str or Path
        Bag directories, or directories holding bag directories (searched recursively).

    Returns
    -------
    list of Path
        Bag directories, sorted within each folder.

    Raises
    ------
    BagError
        A path that does not exist, or a folder with no bag in it.

    """
    bags: list[Path] = []
    for item in map(Path, paths):
        if not item.exists():
            raise BagError(f'bag not found: {item}')
        if item.is_file() or (item / 'metadata.yaml').exists():
            bags.append(item)
            continue
        found = sorted(p.parent for p in item.rglob('metadata.yaml'))
        if not found:
            raise BagError(f'not a rosbag2 bag and no bag inside: {item}')
        bags.extend(found)
    return bags


def refuse_repeats(bags: list[Path]) -> list[Path]:
    """
    Refuse a bag given twice (by another path, a link, a folder holding it); resolve them.

    Parameters
    ----------
    bags : list of Path
        The bags (as found by `discover_bags`).

    Returns
    -------
    list of Path
        The bags, resolved.

    Raises
    ------
    BagError
        The same bag given twice.

    """
    resolved = [b.resolve() for b in bags]
    seen: dict[Path, Path] = {}
    for given, path in zip(bags, resolved, strict=True):
        if path in seen:
            raise BagError(f'bag given twice: {seen[path]} and {given}')
        seen[path] = given
    return resolved


def output_names(bags: list[Path]) -> list[str]:
    """
    Return a unique output name per bag of a fleet.

    The bag's folder name when the names differ (``eha_nominal``); when two bags share a
    name (``site_a/run1``, ``site_b/run1``), every bag is named by its path relative to the
    folder all the bags are in, so that outputs neither overwrite each other nor look alike.

    Parameters
    ----------
    bags : list of Path
        The bags (as found by `discover_bags`).

    Returns
    -------
    list of str
        Names, possibly with ``/`` (outputs then go into sub-folders).

    Raises
    ------
    BagError
        The same bag given twice.

    """
    resolved = refuse_repeats(bags)
    names = [p.name for p in resolved]
    if len(set(names)) == len(names):
        return names
    common = Path(os.path.commonpath(resolved))
    return [p.relative_to(common).as_posix() for p in resolved]


@dataclass
class FleetOutputs:
    """Where each bag's outputs go (absolute paths) and the folders made for them."""

    out_bags: list[str | None]
    csv_paths: list[str | None]
    plots_dirs: list[str | None]
    made: list[Path] = field(default_factory=list)

    def remove_empty(self) -> None:
        """
        Remove what an interrupted fleet leaves: staging folders, then empty folders it made.

        A worker stopped while it was creating an output's staging folder (SIGTERM between
        ``mkdtemp`` and its registration) cannot discard it; its name, ``.<output>.partial-*``
        beside the output, says whose it is.
        """
        with sigint_held():
            for target in (*self.out_bags, *self.csv_paths, *self.plots_dirs):
                if target is not None:
                    path = Path(target)
                    for stray in path.parent.glob(f'.{path.name}.partial-*'):
                        shutil.rmtree(stray, ignore_errors=True)
            remove_empty_folders(self.made)


def _make_folders(folder: Path, made: list[Path], flag: str) -> None:
    missing = []
    for parent in (folder, *folder.parents):
        if parent.is_dir():
            break
        if parent.exists():
            raise UsageError(f'{flag}: {parent} is not a folder')
        missing.append(parent)
    for parent in reversed(missing):
        try:
            parent.mkdir()
        except OSError as exc:
            remove_empty_folders(made)
            raise UsageError(f'{flag}: cannot make the folder {parent} '
                             f'({exc.strerror or type(exc).__name__})') from exc
        made.append(parent)


def plan_outputs(bags: list[Path], out: str | None, csv: str | None, plots: str | None
                 ) -> FleetOutputs:
    """
    Check the output flags against the bags and return every bag's output paths.

    One bag: the flags are the outputs themselves. Several bags: each flag names a folder
    (made here, before any bag starts) holding one output per bag, named by
    `output_names`: ``OUT/<name>`` (a bag), ``CSV/<name>.csv``, ``PLOTS/<name>/``.

    Parameters
    ----------
    bags : list of Path
        The bags.
    out, csv, plots : str or None
        ``--out``, ``--csv`` and ``--plots``.

    Returns
    -------
    FleetOutputs
        Absolute paths per bag (None where not asked for), and the folders made.

    Raises
    ------
    UsageError
        For several bags: a flag naming a file (``--csv out/m3.csv``); for any: two outputs
        at the same path, or an output at, in or around an input bag.

    """
    inputs = [b.resolve() for b in bags]
    flags = (('--out', out, ''), ('--csv', csv, '.csv'), ('--plots', plots, ''))
    plan = FleetOutputs([], [], [])
    columns = (plan.out_bags, plan.csv_paths, plan.plots_dirs)
    if len(bags) == 1:
        for (_, value, _), column in zip(flags, columns, strict=True):
            column.append(None if value is None else str(Path(value).resolve()))
    else:
        names = output_names(bags)
        for (flag, value, suffix), column in zip(flags, columns, strict=True):
            if value is None:
                column.extend([None] * len(bags))
                continue
            folder = Path(value).resolve()
            if folder.suffix.lower() in ('.csv', '.mcap', '.db3', '.png') or folder.is_file():
                raise UsageError(f'{flag} {value}: with {len(bags)} bags {flag} names a folder '
                                 f'(one {"<bag>" + suffix if suffix else "<bag>"} per bag '
                                 'in it), not a file')
            column.extend(str(folder / f'{name}{suffix}') for name in names)
    targets: dict[Path, str] = {}
    for (flag, _, _), column in zip(flags, columns, strict=True):
        for path in filter(None, column):
            target = Path(path)
            if target in targets:
                raise UsageError(f'{targets[target]} and {flag} name the same output {target}')
            targets[target] = flag
            refuse_at_inputs(flag, target, inputs)
    if len(bags) > 1:
        try:
            for (flag, _, _), column in zip(flags, columns, strict=True):
                for path in filter(None, column):
                    _make_folders(Path(path).parent, plan.made, flag)
        except BaseException:
            plan.remove_empty()
            raise
    return plan


@dataclass(frozen=True)
class ReplayJob:
    """One bag's replay, as shipped to a worker process or a Dask worker (picklable)."""

    bag: str
    config: EstimatorConfig
    out_bag: str | None = None
    csv_path: str | None = None
    plots_dir: str | None = None
    remaps: tuple[tuple[str, str], ...] = ()
    storage: str | None = None
    compression: str = 'auto'
    force: bool = False
    progress: bool = False
    label: str = ''
    baseline: str | None = None  # start from this learnt healthy baseline file


def run_job(job: ReplayJob) -> ReplaySummary:
    """
    Replay one bag; never raises: a failure comes back as ``summary.error``.

    Parameters
    ----------
    job : ReplayJob
        What to replay and where to write.

    Returns
    -------
    ReplaySummary
        The summary, with ``error`` set when the bag could not be replayed.

    """
    try:
        core = None
        if job.baseline:
            core = estimator_from_config(job.config)
            core.baseline = BaselineStore.opened(Path(job.baseline), core)
        summary = replay_bag(job.bag, job.config, out_bag=job.out_bag, csv_path=job.csv_path,
                             plots_dir=job.plots_dir, remaps=dict(job.remaps),
                             storage=job.storage, compression=job.compression,
                             force=job.force, progress=job.progress, core=core)
    except PumpFrictionError as exc:
        summary = ReplaySummary(bag=job.bag, error=str(exc))
    except Exception as exc:
        summary = ReplaySummary(bag=job.bag, error=f'{type(exc).__name__}: {exc}')
    return replace(summary, label=job.label)


def run_jobs(jobs: list[ReplayJob], workers: int = 1, dask_address: str | None = None
             ) -> list[ReplaySummary]:
    """
    Run replay jobs serially, in local processes, or on a Dask cluster.

    Parameters
    ----------
    jobs : list of ReplayJob
        The bags (absolute paths, for Dask workers in other directories).
    workers : int
        Local worker processes (1: in this process).
    dask_address : str, optional
        Scheduler address (``tcp://host:8786``); maps `run_job` over the cluster instead.

    Returns
    -------
    list of ReplaySummary
        In the order of ``jobs``.

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C: pending bags cancelled, running ones interrupted (outputs discarded).

    """
    if dask_address:
        return _run_on_dask(jobs, dask_address)
    if workers <= 1 or len(jobs) <= 1:
        return [run_job(job) for job in jobs]
    return _run_local(jobs, min(workers, len(jobs)))


def _worker(conn: Any, job: ReplayJob) -> None:
    """Replay one bag (in a fleet worker process) and send its summary to the parent."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the parent, which stops us
    # SIGTERM unwinds the replay, which discards its staged outputs; one that a finaliser
    # swallowed stops it at its next check (`sigterm_kept`)
    sigterm_kept()
    # started under `sigint_held`: a signal that came meanwhile is delivered now, handled
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        conn.send(run_job(job))
    except KeyboardInterrupt as exc:  # that check: exit as the SIGTERM would have
        raise SystemExit(128 + signal.SIGTERM) from exc
    except OSError:
        pass  # the parent is gone
    finally:
        conn.close()


def _run_local(jobs: list[ReplayJob], workers: int) -> list[ReplaySummary]:
    """Run the jobs in worker processes, ``workers`` at a time; summaries in job order."""
    ctx = process_context()
    results: list[ReplaySummary | None] = [None] * len(jobs)
    running: dict[Any, tuple[int, Any]] = {}  # result pipe -> (job index, process)
    queued = iter(enumerate(jobs))
    try:
        while True:
            for index, job in queued:
                conn, child = ctx.Pipe(duplex=False)
                proc = ctx.Process(target=_worker, args=(child, job), daemon=True)
                with sigint_held():  # the worker's handlers are set before a signal lands
                    proc.start()
                    running[conn] = (index, proc)  # a Ctrl-C held meanwhile stops it too
                child.close()
                if len(running) >= workers:
                    break
            if not running:
                return results  # type: ignore[return-value]
            raise_if_interrupted()  # a Ctrl-C swallowed by a pipe's finaliser
            for ready in multiprocessing.connection.wait(list(running)):
                conn = cast(Connection, ready)  # wait() returns the objects it was given
                index, proc = running.pop(conn)
                try:
                    results[index] = conn.recv()
                except (EOFError, OSError):
                    results[index] = None
                conn.close()
                stop_process(proc)
                if results[index] is None:
                    results[index] = ReplaySummary(
                        bag=jobs[index].bag, label=jobs[index].label,
                        error=f'the worker process died (exit code {proc.exitcode})')
    except BaseException:
        for conn, (_, proc) in running.items():  # interrupted: stop what still runs
            conn.close()
            proc.terminate()
        for _, proc in running.values():
            stop_process(proc)
        raise


def _run_on_dask(jobs: list[ReplayJob], dask_address: str) -> list[ReplaySummary]:
    try:
        from dask.distributed import Client
    except ImportError as exc:
        raise BagError('--dask needs dask.distributed: pip install '
                       '"pump_friction_ros[fleet]"') from exc
    try:
        client = Client(dask_address, timeout='20s')
    except (ValueError, TypeError) as exc:  # '::::', 'foo://bar:1'; tls:// without TLS set up
        raise BagError(f'--dask {dask_address}: not a scheduler address '
                       f'({" ".join(str(exc).split())})') from exc
    except OSError as exc:
        raise BagError(f'cannot reach the Dask scheduler at {dask_address}: {exc}') from exc
    try:
        with client:
            futures = client.map(run_job, jobs, pure=False)
            try:
                summaries: list[ReplaySummary] = client.gather(futures)
                return summaries
            except BaseException:
                client.cancel(futures)  # bags not started; running ones finish
                raise
    except OSError as exc:
        raise BagError(f'cannot reach the Dask scheduler at {dask_address}: {exc}') from exc


def fleet_table(summaries: list[ReplaySummary]) -> str:
    """
    One line per bag and the fleet's totals.

    Parameters
    ----------
    summaries : list of ReplaySummary
        Results of `run_jobs`.

    Returns
    -------
    str
        The table.

    """
    width = max([40, *(len(s.label or Path(s.bag).name) for s in summaries)])
    head = (f'{"bag":<{width}} {"hours":>7} {"estimates":>10} {"onset s":>8} {"level":>6} '
            f'{"vp scale":>8} {"+-95%":>6} {"other":>6}  explanation')
    lines = [head, '-' * len(head)]
    for s in summaries:
        if s.error:
            lines.append(f'{s.label or Path(s.bag).name:<{width}} FAILED: {s.error}')
            continue
        lines.append(f'{s.label or Path(s.bag).name:<{width}} {s.duration_s / 3600:>7.3f} '
                     f'{s.estimates:>10} '
                     f'{_or_dash(s.alarm_onset_s):>8} {LEVEL_NAMES[s.final_level]:>6} '
                     f'{s.final_valve_plate_scale:>8.3f} '
                     f'{1.96 * s.final_valve_plate_scale_std:>6.3f} '
                     f'{s.final_other_scale:>6.3f}  {s.attribution}')
    ok = [s for s in summaries if not s.error]
    worst = max((s.final_valve_plate_scale for s in ok), default=math.nan)
    lines.append('-' * len(head))
    lines.append(f'fleet: {len(summaries)} bags ({len(summaries) - len(ok)} failed), '
                 f'{sum(s.duration_s for s in ok) / 3600:.3f} h, '
                 f'{sum(1 for s in ok if s.alarm_s > 0)} with alarms, '
                 f'highest valve-plate scale at the end {worst:.3f}')
    return '\n'.join(lines)


def _or_dash(value: float) -> str:
    return '-' if math.isnan(value) else f'{value:.1f}'
