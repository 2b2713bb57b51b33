"""Offline replay: the node's outputs from a rosbag2 bag, written back to a bag, CSV, plots.

The replay feeds the same ROS-free core as the live node (`TorqueEstimator`), message by
message in bag order, with the same timestamps the node would use (header stamps, else the
receive time, which in a bag is the log time). Outputs carry the log time of the message
that produced them, which is when the node would have published them; ``/diagnostics`` is
emitted on the node's timer, emulated on bag time (first tick one period after the first
message). For the same message sequence the outputs are identical to the node's
(``test_replay.py`` checks it against the node's own conversion path).

Every output is written under a temporary name and renamed at the end, so a failed replay
leaves nothing that looks complete.
"""

from __future__ import annotations

import csv
import math
import multiprocessing
import os
import shutil
import struct
import tempfile
import time
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path

from .bags import (
    JOINT,
    OIL_TEMPERATURE,
    PORT_A,
    PORT_B,
    PRESSURE,
    SPEED,
    TORQUE,
    BagError,
    BagInputs,
)
from .config import NODE_NAME, EstimatorConfig
from .estimator import COUNTERS, Estimate, TorqueEstimator, estimator_from_config
from .model import COMPONENTS
from .monitor import ERROR, LEVEL_NAMES, WARN
from .progress import ProgressBar
from .ros_messages import OUTPUT_TOPICS, diagnostic_array, outputs_of, rosbags_types

__all__ = ['CSV_COLUMNS', 'ReplayJob', 'ReplaySummary', 'discover_bags', 'fleet_table',
           'float64_cdr', 'replay_bag', 'run_job', 'run_jobs']

CSV_COLUMNS = ('stamp_ns', 'time_s', 'speed_rad_s', 'pressure_diff_pa', 'viscosity_m2_s',
               'theoretical_nm', *(f'{c}_nm' for c in COMPONENTS), 'friction_nm',
               'inertia_nm', 'accel_rad_s2', 'drive_loss_nm', 'expected_nm', 'measured_nm',
               'residual_nm', 'efficiency', 'valve_plate_scale', 'valve_plate_scale_std', 'level',
               'table_flags', 'published')

_CDR_LE = b'\x00\x01\x00\x00'


def float64_cdr(value: float) -> bytes:
    """CDR (little-endian) bytes of a ``std_msgs/Float64``, as rosbags would serialise it.

    Parameters
    ----------
    value : float
        The data field.

    Returns
    -------
    bytes
        Encapsulation header and the double.
    """
    return _CDR_LE + struct.pack('<d', value)


@dataclass
class ReplaySummary:
    """What a replay did, for the printed summary and the fleet table."""

    bag: str
    storage: str = ''
    duration_s: float = 0.0
    messages_read: dict[str, int] = field(default_factory=dict)
    estimates: int = 0
    published: int = 0
    counts: dict[str, int] = field(default_factory=dict)
    decoded_one_by_one: int = 0
    undecodable: int = 0
    missing_joint: int = 0
    warn_intervals: list[tuple[float, float]] = field(default_factory=list)
    error_intervals: list[tuple[float, float]] = field(default_factory=list)
    final_level: int = 0
    final_valve_plate_scale: float = math.nan
    final_valve_plate_scale_std: float = math.nan
    max_valve_plate_scale: float = math.nan
    elapsed_s: float = 0.0
    outputs: dict[str, str] = field(default_factory=dict)
    error: str = ''
    estimates_list: list[Estimate] | None = None

    @property
    def alarm_s(self) -> float:
        """Time spent at WARN or ERROR [s]."""
        return sum(b - a for a, b in self.warn_intervals + self.error_intervals)

    def format(self) -> str:
        """Multi-line summary for a person.

        Returns
        -------
        str
            The summary.
        """
        if self.error:
            return f'{self.bag}: FAILED: {self.error}'

        def intervals(items):
            return ', '.join(f'{a:.1f}-{b:.1f} s' for a, b in items) or 'none'

        lines = [f'bag {self.bag} ({self.storage}): {self.duration_s:.1f} s',
                 '  messages read: ' + ', '.join(f'{t} {n}'
                                                 for t, n in self.messages_read.items()),
                 f'  estimates: {self.estimates} ({self.published} published)',
                 '  skipped: ' + ', '.join(
                     f'{k} {self.counts.get(k, 0)}' for k in COUNTERS
                     if k.startswith(('stale', 'rejected', 'clamped')))
                 + f', without joint {self.missing_joint}, undecodable {self.undecodable}',
                 f'  WARN: {intervals(self.warn_intervals)}',
                 f'  ERROR: {intervals(self.error_intervals)}',
                 f'  final level {LEVEL_NAMES[self.final_level]}, valve-plate friction scale '
                 f'{self.final_valve_plate_scale:.3f} +- {self.final_valve_plate_scale_std:.3f}'
                 f' (max {self.max_valve_plate_scale:.3f})',
                 f'  replayed in {self.elapsed_s:.2f} s']
        lines += [f'  {kind}: {path}' for kind, path in self.outputs.items()]
        return '\n'.join(lines)


class _Staged:
    """An output path written under a temporary name and moved into place at the end."""

    def __init__(self, target: Path, force: bool, is_dir: bool) -> None:
        if target.exists() and not force:
            raise BagError(f'output exists: {target} (remove it, choose another path, or '
                           'pass --force)')
        target.parent.mkdir(parents=True, exist_ok=True)
        self.target = target
        tmp_parent = tempfile.mkdtemp(prefix=f'.{target.name}.partial-', dir=target.parent)
        self._tmp_parent = Path(tmp_parent)
        self.path = self._tmp_parent / target.name
        if is_dir:
            self.path.mkdir()

    def commit(self) -> None:
        if self.target.exists():
            if self.target.is_dir():
                shutil.rmtree(self.target)
            else:
                self.target.unlink()
        os.replace(self.path, self.target)
        shutil.rmtree(self._tmp_parent, ignore_errors=True)

    def discard(self) -> None:
        shutil.rmtree(self._tmp_parent, ignore_errors=True)


class _LevelTracker:
    """Intervals spent at WARN and at ERROR, from the level of each estimate."""

    def __init__(self) -> None:
        self.level = 0
        self.since_ns = 0
        self.warn: list[tuple[int, int]] = []
        self.error: list[tuple[int, int]] = []

    def update(self, level: int, stamp_ns: int) -> None:
        if level == self.level:
            return
        self._close(stamp_ns)
        self.level, self.since_ns = level, stamp_ns

    def _close(self, stamp_ns: int) -> None:
        if self.level == WARN:
            self.warn.append((self.since_ns, stamp_ns))
        elif self.level == ERROR:
            self.error.append((self.since_ns, stamp_ns))

    def finish(self, stamp_ns: int) -> None:
        self._close(stamp_ns)
        self.level = 0


def replay_bag(bag: str | Path, config: EstimatorConfig | None = None, *,
               out_bag: str | Path | None = None, csv_path: str | Path | None = None,
               plots_dir: str | Path | None = None, remaps: dict[str, str] | None = None,
               storage: str | None = None, force: bool = False, progress: bool = False,
               keep_estimates: bool = False, core: TorqueEstimator | None = None,
               pipeline: bool | None = None) -> ReplaySummary:
    """Replay one bag through the estimator core.

    Parameters
    ----------
    bag : str or Path
        Input rosbag2 directory (sqlite3 or mcap).
    config : EstimatorConfig, optional
        Node parameters (default: the node's defaults).
    out_bag : str or Path, optional
        Output bag with the node's published topics.
    csv_path : str or Path, optional
        CSV file, one row per estimate.
    plots_dir : str or Path, optional
        Folder for the PNG plots.
    remaps : dict, optional
        Topic remappings (node name -> bag name).
    storage : {'sqlite3', 'mcap'}, optional
        Storage of the output bag (default: the input's).
    force : bool
        Replace existing outputs.
    progress : bool
        Progress bar on stderr (on a terminal).
    keep_estimates : bool
        Keep every estimate in the summary (tests).
    core : TorqueEstimator, optional
        Core to use (default: built from ``config``).
    pipeline : bool, optional
        Read and write the bags in two helper processes while this one runs the core
        (default: yes, unless this process is daemonic, e.g. a Dask worker). The results
        are the same either way: the core runs here, in bag order.

    Returns
    -------
    ReplaySummary
        What happened.

    Raises
    ------
    BagError
        Unusable bag or output path; nothing is left behind.
    """
    started = time.perf_counter()
    config = config or EstimatorConfig()
    if pipeline is None:
        pipeline = not multiprocessing.current_process().daemon
    staged: list[_Staged] = []
    source = (_ProcessSource if pipeline else _InlineSource)(bag, config, remaps)
    sink = None
    try:
        core = core or estimator_from_config(config)
        summary = ReplaySummary(bag=str(bag), storage=source.meta['storage'])

        def stage(path, is_dir):
            if path is None:
                return None
            staged.append(_Staged(Path(path), force, is_dir))
            return staged[-1]

        out = stage(out_bag, False)
        table = stage(csv_path, False)
        figs = stage(plots_dir, True)
        if out is not None:
            sink = (_ProcessSink if pipeline else _InlineSink)(
                out.path, storage or source.meta['storage'])
        with ExitStack() as stack:
            csv_file = stack.enter_context(open(table.path, 'w', newline='')) if table \
                else None
            series = _run(source, core, config, summary, sink, csv_file, keep_estimates,
                          progress)
        if sink is not None:
            sink.close()
        if figs is not None:
            from .plots import write_replay_figures
            write_replay_figures(series, figs.path, Path(bag).name)
        for item, kind in ((out, 'bag'), (table, 'csv'), (figs, 'plots')):
            if item is not None:
                item.commit()
                summary.outputs[kind] = str(item.target)
    except BaseException:
        if sink is not None:
            sink.abort()
        for item in staged:
            item.discard()
        raise
    finally:
        source.close()
    summary.elapsed_s = time.perf_counter() - started
    return summary


def _output_topics() -> list[tuple[str, str]]:
    """Topics and types of the output bag: the node's Float64 outputs, then /diagnostics."""
    return [(f'/{NODE_NAME}/{name}', 'std_msgs/msg/Float64') for name in OUTPUT_TOPICS] + \
        [('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray')]


_DIAGNOSTICS_INDEX = len(OUTPUT_TOPICS)
_OUTPUT_INDEX = {name: i for i, name in enumerate(OUTPUT_TOPICS)}


# -- sources: decoded input chunks, read here or in a helper process -----------------------


class _InlineSource:
    """Reads and decodes the bag in this process."""

    def __init__(self, bag, config, remaps) -> None:
        self._inputs = BagInputs(bag, config, remaps)
        self.meta = self._inputs.meta()

    def chunks(self):
        yield from self._inputs.chunks()

    def stats(self) -> dict:
        return self._inputs.stats()

    def close(self) -> None:
        self._inputs.close()


def _reader_process(conn, bag, config, remaps) -> None:
    """Read and batch-decode the bag in a helper process; send the chunks down the pipe."""
    try:
        with BagInputs(bag, config, remaps) as inputs:
            conn.send(('meta', inputs.meta()))
            for chunk in inputs.chunks():
                conn.send(('chunk', chunk))
            conn.send(('done', inputs.stats()))
    except BagError as exc:
        conn.send(('error', str(exc)))
    except Exception as exc:  # report, never hang the replay
        conn.send(('error', f'{type(exc).__name__}: {exc}'))
    finally:
        conn.close()


class _ProcessSource:
    """Reads and decodes the bag in a helper process, one chunk ahead of the core."""

    def __init__(self, bag, config, remaps) -> None:
        ctx = multiprocessing.get_context()
        self._conn, child = ctx.Pipe(duplex=False)
        self._proc = ctx.Process(target=_reader_process, args=(child, str(bag), config,
                                                               remaps), daemon=True)
        self._proc.start()
        child.close()
        self._stats: dict = {}
        kind, payload = self._receive()
        if kind != 'meta':
            raise BagError(f'bag reader: unexpected {kind}')
        self.meta = payload

    def _receive(self):
        try:
            kind, payload = self._conn.recv()
        except EOFError:
            raise BagError('the bag reader process died') from None
        if kind == 'error':
            self.close()
            raise BagError(payload)
        return kind, payload

    def chunks(self):
        while True:
            kind, payload = self._receive()
            if kind == 'done':
                self._stats = payload
                return
            yield payload

    def stats(self) -> dict:
        return self._stats

    def close(self) -> None:
        if self._proc.is_alive():
            self._proc.terminate()
        self._proc.join()
        self._conn.close()


# -- sinks: the output bag, written here or in a helper process -------------------------------


def _open_writer(path, storage: str):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_JAZZY)
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    writer = Writer(path, version=9, storage_plugin=plugin)
    writer.open()
    connections = [writer.add_connection(topic, msgtype, typestore=typestore)
                   for topic, msgtype in _output_topics()]
    return writer, connections


class _InlineSink:
    """Writes the output bag in this process."""

    def __init__(self, path, storage: str) -> None:
        try:
            self._writer, self._connections = _open_writer(path, storage)
        except Exception as exc:  # WriterError and storage errors
            raise BagError(f'cannot write output bag {path}: {exc}') from None

    def write(self, index: int, log_ns: int, payload: bytes) -> None:
        self._writer.write(self._connections[index], log_ns, payload)

    def flush(self) -> None:
        pass

    def close(self) -> None:
        self._writer.close()

    def abort(self) -> None:
        try:
            self._writer.close()
        except Exception:  # the staged output is discarded anyway
            pass


def _writer_process(conn, path, storage) -> None:
    """Write the batches received into the output bag (in a helper process)."""
    try:
        writer, connections = _open_writer(path, storage)
        try:
            while True:
                batch = conn.recv()
                if batch is None:
                    break
                for index, log_ns, payload in zip(*batch, strict=True):
                    writer.write(connections[index], log_ns, payload)
        finally:
            writer.close()
        conn.send(('ok', ''))
    except Exception as exc:
        conn.send(('error', f'cannot write output bag {path}: {exc}'))
    finally:
        conn.close()


class _ProcessSink:
    """Writes the output bag in a helper process, in batches, while the core runs."""

    def __init__(self, path, storage: str) -> None:
        ctx = multiprocessing.get_context()
        self._conn, child = ctx.Pipe(duplex=True)
        self._proc = ctx.Process(target=_writer_process, args=(child, str(path), storage),
                                 daemon=True)
        self._proc.start()
        child.close()
        self._batch: tuple[list, list, list] = ([], [], [])

    def write(self, index: int, log_ns: int, payload: bytes) -> None:
        batch = self._batch
        batch[0].append(index)
        batch[1].append(log_ns)
        batch[2].append(payload)

    def flush(self) -> None:
        if self._batch[0]:
            self._send(self._batch)
            self._batch = ([], [], [])

    def _send(self, item) -> None:
        try:
            self._conn.send(item)
        except (BrokenPipeError, OSError):
            self._finish()  # the writer died: report its error

    def _finish(self) -> None:
        try:
            kind, message = self._conn.recv()
        except EOFError:
            kind, message = 'error', 'the bag writer process died'
        self._proc.join()
        self._conn.close()
        if kind != 'ok':
            raise BagError(message)

    def close(self) -> None:
        self.flush()
        self._send(None)
        self._finish()

    def abort(self) -> None:
        if self._proc.is_alive():
            self._proc.terminate()
        self._proc.join()
        self._conn.close()


def _run(source, core: TorqueEstimator, config: EstimatorConfig, summary: ReplaySummary,
         sink, csv_file, keep_estimates: bool, progress: bool):
    """Run the replay loop: events in bag order -> core -> outputs."""
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_JAZZY)
    types = rosbags_types(typestore)
    rows = csv.writer(csv_file) if csv_file is not None else None
    if rows is not None:
        rows.writerow(CSV_COLUMNS)
    status_name = f'{NODE_NAME}: {core.pump_name}'
    period_ns = round(1e9 / config.diagnostics_rate_hz)
    meta = source.meta
    start_ns = meta['start_ns']
    next_tick = start_ns + period_ns
    levels = _LevelTracker()
    series: dict[str, list[float]] = {k: [] for k in (
        'time_s', 'expected_nm', 'measured_nm', 'residual_nm', 'scale', 'scale_std',
        'efficiency', 'level')}
    kept: list[Estimate] = []
    total = max(meta['input_message_count'], 1)
    done = 0
    max_scale = -math.inf
    last_stamp = start_ns
    on_joint, on_pressure, on_port = core.on_joint_state, core.on_pressure, core.on_port_pressure
    on_speed, on_torque, on_temperature = core.on_speed, core.on_torque, core.on_temperature
    write = sink.write if sink is not None else None
    output_index = _OUTPUT_INDEX

    def emit_diagnostics(tick_ns: int) -> None:
        if write is not None:
            msg = diagnostic_array(types, core.diagnostics(tick_ns), tick_ns, status_name,
                                   config.hardware_id)
            write(_DIAGNOSTICS_INDEX, tick_ns,
                  bytes(typestore.serialize_cdr(msg, 'diagnostic_msgs/msg/DiagnosticArray')))

    with ProgressBar(f'replay {Path(summary.bag).name}', enabled=progress) as bar:
        for chunk in source.chunks():
            for kind, stamp, log_ns, value, torque, has_speed in zip(
                    chunk.kinds, chunk.stamps, chunk.log_times, chunk.values, chunk.torques,
                    chunk.has_speed, strict=True):
                while next_tick <= log_ns:  # the node's diagnostics timer
                    emit_diagnostics(next_tick)
                    next_tick += period_ns
                est = None
                if kind == JOINT:
                    est = on_joint(stamp, value if has_speed else None,
                                   None if torque != torque else torque)
                elif kind == PRESSURE:
                    on_pressure(stamp, value)
                elif kind == SPEED:
                    est = on_speed(log_ns, value)
                elif kind == TORQUE:
                    on_torque(log_ns, value)
                elif kind == PORT_A:
                    on_port('a', stamp, value)
                elif kind == PORT_B:
                    on_port('b', stamp, value)
                elif kind == OIL_TEMPERATURE:
                    on_temperature(stamp, value)
                if est is None:
                    continue
                last_stamp = est.stamp_ns
                levels.update(est.level, est.stamp_ns)
                if keep_estimates:
                    kept.append(est)
                if rows is not None:
                    rows.writerow(_csv_row(est, start_ns))
                if est.publish:
                    summary.published += 1
                    if write is not None:
                        for name, v in outputs_of(est):
                            write(output_index[name], log_ns, float64_cdr(v))
                    if est.valve_plate_scale > max_scale:
                        max_scale = est.valve_plate_scale
                    for key, v in (('time_s', (est.stamp_ns - start_ns) * 1e-9),
                                   ('expected_nm', est.expected_nm),
                                   ('measured_nm', est.measured_nm),
                                   ('residual_nm', est.residual_nm),
                                   ('scale', est.valve_plate_scale),
                                   ('scale_std', est.valve_plate_scale_std),
                                   ('efficiency', est.efficiency), ('level', est.level)):
                        series[key].append(v)
            done += len(chunk.kinds)
            if sink is not None:
                sink.flush()
            bar(done / total)
        end_ns = meta['end_ns']
        while next_tick <= end_ns:
            emit_diagnostics(next_tick)
            next_tick += period_ns
    levels.finish(last_stamp)
    stats = source.stats()
    summary.duration_s = (meta['end_ns'] - start_ns) * 1e-9
    summary.messages_read = dict(stats['messages_read'])
    summary.estimates = core.counts['estimates']
    summary.counts = dict(core.counts)
    summary.decoded_one_by_one = stats['fallbacks']
    summary.undecodable = stats['undecodable']
    summary.missing_joint = stats['missing_joint']
    summary.warn_intervals = [((a - start_ns) * 1e-9, (b - start_ns) * 1e-9)
                              for a, b in levels.warn]
    summary.error_intervals = [((a - start_ns) * 1e-9, (b - start_ns) * 1e-9)
                               for a, b in levels.error]
    if core.last is not None:
        summary.final_level = core.last.level
        summary.final_valve_plate_scale = core.last.valve_plate_scale
        summary.final_valve_plate_scale_std = core.last.valve_plate_scale_std
    summary.max_valve_plate_scale = max_scale if max_scale > -math.inf else math.nan
    if keep_estimates:
        summary.estimates_list = kept
    return series


def _csv_row(est: Estimate, start_ns: int) -> list:
    return [est.stamp_ns, f'{(est.stamp_ns - start_ns) * 1e-9:.6f}', est.speed_rad_s,
            est.pressure_diff_pa, est.viscosity_m2_s, est.theoretical_nm, *est.components_nm,
            est.friction_nm, est.inertia_nm, est.accel_rad_s2, est.drive_loss_nm, est.expected_nm,
            est.measured_nm, est.residual_nm, est.efficiency, est.valve_plate_scale,
            est.valve_plate_scale_std, est.level, est.table_flags, int(est.publish)]


# -- fleets: many bags, in parallel processes or on a Dask cluster ------------------------


def discover_bags(paths: list[str | Path]) -> list[Path]:
    """Expand the command line's BAG arguments: bags as given, folders to the bags inside.

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
    force: bool = False
    progress: bool = False


def run_job(job: ReplayJob) -> ReplaySummary:
    """Replay one bag; never raises: a failure comes back as ``summary.error``.

    Parameters
    ----------
    job : ReplayJob
        What to replay and where to write.

    Returns
    -------
    ReplaySummary
        The summary, with ``error`` set when the bag could not be replayed.
    """
    from .errors import PumpFrictionError

    try:
        return replay_bag(job.bag, job.config, out_bag=job.out_bag, csv_path=job.csv_path,
                          plots_dir=job.plots_dir, remaps=dict(job.remaps),
                          storage=job.storage, force=job.force, progress=job.progress)
    except PumpFrictionError as exc:
        return ReplaySummary(bag=job.bag, error=str(exc))
    except Exception as exc:  # one bad bag must not stop a fleet: report it
        return ReplaySummary(bag=job.bag, error=f'{type(exc).__name__}: {exc}')


def run_jobs(jobs: list[ReplayJob], workers: int = 1, dask_address: str | None = None
             ) -> list[ReplaySummary]:
    """Run replay jobs serially, in local processes, or on a Dask cluster.

    Parameters
    ----------
    jobs : list of ReplayJob
        The bags.
    workers : int
        Local worker processes (1: in this process).
    dask_address : str, optional
        Scheduler address (``tcp://host:8786``); maps `run_job` over the cluster instead.

    Returns
    -------
    list of ReplaySummary
        In the order of ``jobs``.
    """
    if dask_address:
        try:
            from dask.distributed import Client
        except ImportError:
            raise BagError('--dask needs dask.distributed: pip install '
                           '"pump_friction_ros[fleet]"') from None
        try:
            with Client(dask_address, timeout='20s') as client:
                return client.gather(client.map(run_job, jobs, pure=False))
        except OSError as exc:
            raise BagError(f'cannot reach the Dask scheduler at {dask_address}: {exc}') from None
    if workers <= 1 or len(jobs) <= 1:
        return [run_job(job) for job in jobs]
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max_workers=min(workers, len(jobs))) as pool:
        return list(pool.map(run_job, jobs))


def fleet_table(summaries: list[ReplaySummary]) -> str:
    """One line per bag and the fleet's totals.

    Parameters
    ----------
    summaries : list of ReplaySummary
        Results of `run_jobs`.

    Returns
    -------
    str
        The table.
    """
    head = (f'{"bag":<40} {"hours":>7} {"estimates":>10} {"alarm s":>8} {"level":>6} '
            f'{"max vp scale":>12}')
    lines = [head, '-' * len(head)]
    for s in summaries:
        if s.error:
            lines.append(f'{Path(s.bag).name:<40} FAILED: {s.error}')
            continue
        lines.append(f'{Path(s.bag).name:<40} {s.duration_s / 3600:>7.3f} {s.estimates:>10} '
                     f'{s.alarm_s:>8.1f} {LEVEL_NAMES[s.final_level]:>6} '
                     f'{s.max_valve_plate_scale:>12.3f}')
    ok = [s for s in summaries if not s.error]
    worst = max((s.max_valve_plate_scale for s in ok), default=math.nan)
    lines.append('-' * len(head))
    lines.append(f'fleet: {len(summaries)} bags ({len(summaries) - len(ok)} failed), '
                 f'{sum(s.duration_s for s in ok) / 3600:.3f} h, '
                 f'{sum(1 for s in ok if s.alarm_s > 0)} with alarms, '
                 f'worst valve-plate scale {worst:.3f}')
    return '\n'.join(lines)
