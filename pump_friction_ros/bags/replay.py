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
Offline replay: the node's outputs from a rosbag2 bag, written back to a bag, CSV, plots.

The replay feeds the same ROS-free core as the live node, in bag order, with the same
timestamps the node would use (header stamps, else the receive time, which in a bag is the
log time): through ``TorqueEstimator.on_chunk``, the chunk-wise twin of the node's
``on_input`` (identical results, ``test_chunk_path.py``). `replay_batches` (``events``) is
the loop: a generator of estimates and of the node's diagnostics timer ticks, emulated on bag
time (first tick one period after the first message). `replay_bag` writes its outputs; the
calibration consumes `bag_estimates`. Outputs carry the log time of the message that
produced them, which is when the node would have published them. For the same message
sequence the outputs are identical to the node's (``test_replay.py`` checks it against the
node's own conversion path, for every combination of input sources).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import ExitStack
import csv
import math
from pathlib import Path
import time
from typing import Any

import numpy as np

from .events import replay_batches, replay_events, ReplayBatch, ReplayEvent
from .outputs import CSV_COLUMNS, csv_row
from .sinks import (
    COMPRESSION_CHOICES,
    DIAGNOSTICS_INDEX,
    float64_cdr,
    open_sink,
    output_compression,
    OUTPUT_INDEX,
    Sink,
)
from .sources import open_source, ProcessSource, Source
from .summary import LevelTracker, ReplaySummary
from ..core.diagnostics import level_message
from ..core.estimate_record import Estimate, EstimateColumns, MONITOR_COLUMNS
from ..core.estimator import TorqueEstimator
from ..core.estimator_setup import estimator_from_config
from ..core.node_parameters import EstimatorConfig, NODE_NAME
from ..errors import BagError
from ..interrupts import raise_if_interrupted, sigint_held
from ..messages.conversions import diagnostic_array, outputs_of, rosbags_types
from ..physics.model import efficiency_of
from ..progress import ProgressBar
from ..staging import looks_like_bag, looks_like_plots, NamedErrorsFile, Staged, StagedOutputs

__all__ = ['CSV_COLUMNS', 'ReplayBatch', 'ReplayEvent', 'ReplaySummary', 'bag_estimates',
           'replay_bag', 'replay_batches', 'replay_events']


def bag_estimates(bag: str | Path, config: EstimatorConfig, core: TorqueEstimator,
                  remaps: dict[str, str] | None = None) -> Iterator[Estimate]:
    """
    Yield every estimate the node would make from a bag (the calibration's input).

    Parameters
    ----------
    bag : str or Path
        The bag.
    config : EstimatorConfig
        Node parameters (topics, joint).
    core : TorqueEstimator
        The core to feed.
    remaps : dict, optional
        Topic remappings.

    Yields
    ------
    Estimate
        In bag order.

    """
    source = open_source(bag, config, remaps)
    try:
        for _, estimates in replay_batches(source, core):
            if estimates is not None:
                yield from estimates.rows()
    finally:
        source.close()


class _Series:
    """What the plots need, one row per published estimate (SI)."""

    KEYS = ('time_s', 'expected_nm', 'measured_nm', 'friction_residual_nm', 'monitored',
            'cusum_pos_nm_s', 'cusum_neg_nm_s', 'vp_scale', 'vp_scale_std', 'other_scale',
            'other_scale_std', 'efficiency', 'measured_efficiency', 'pump_mode', 'level')

    def __init__(self, core: TorqueEstimator) -> None:
        self.data: dict[str, list[float]] = {k: [] for k in self.KEYS}
        self._core = core
        cfg = core.config
        self._min_speed = cfg.monitor_min_speed_rad_s
        self._max_accel = cfg.monitor_max_accel_rad_s2

    def add(self, estimates: EstimateColumns, which: np.ndarray, start_ns: int) -> None:
        """Add the rows ``which`` (indices) of a batch: the published estimates."""
        table = self._core.table
        monitor = estimates.monitor
        for est, cusum_pos, cusum_neg, other, other_std in zip(
                estimates.rows(which), *(monitor[k][which].tolist() for k in MONITOR_COLUMNS),
                strict=True):
            sign = 1.0 if est.speed_rad_s >= 0.0 else -1.0
            monitored = (abs(est.speed_rad_s) >= self._min_speed
                         and abs(est.accel_rad_s2) <= self._max_accel
                         and math.isfinite(est.residual_nm))
            measured_eff = efficiency_of(est.theoretical_nm, est.measured_nm - est.inertia_nm,
                                         est.speed_rad_s, est.pressure_diff_pa,
                                         table.efficiency_min_speed_rad_s,
                                         table.efficiency_min_pressure_pa) \
                if math.isfinite(est.measured_nm) else math.nan
            row = ((est.stamp_ns - start_ns) * 1e-9, est.expected_nm, est.measured_nm,
                   est.residual_nm * sign, float(monitored), cusum_pos, cusum_neg,
                   est.valve_plate_scale, est.valve_plate_scale_std, other, other_std,
                   est.efficiency, measured_eff,
                   float(est.theoretical_nm * est.speed_rad_s > 0.0), est.level)
            for key, value in zip(self.KEYS, row, strict=True):
                self.data[key].append(value)


def replay_bag(bag: str | Path, config: EstimatorConfig | None = None, *,
               out_bag: str | Path | None = None, csv_path: str | Path | None = None,
               plots_dir: str | Path | None = None, remaps: dict[str, str] | None = None,
               storage: str | None = None, compression: str = 'auto', force: bool = False,
               progress: bool = False, keep_estimates: bool = False,
               core: TorqueEstimator | None = None, pipeline: bool | None = None
               ) -> ReplaySummary:
    """
    Replay one bag through the estimator core and write the outputs asked for.

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
    compression : {'auto', 'none', 'zstd'}
        zstd compression of the output bag: ``auto`` follows the input (MCAP chunk, sqlite3
        file or message compression), ``zstd`` uses chunks for MCAP and file compression
        for sqlite3 (`sinks.output_compression`).
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
        Unusable bag or output path, or a bag from which no estimate could be made (the
        message says which skips); nothing is left behind.

    """
    started = time.perf_counter()
    config = config or EstimatorConfig()
    if compression not in COMPRESSION_CHOICES:
        raise BagError(f'compression must be one of {", ".join(COMPRESSION_CHOICES)}, got '
                       f'{compression!r}')
    source = open_source(bag, config, remaps, pipeline)
    pipelined = isinstance(source, ProcessSource)
    staged = StagedOutputs()
    sink: Sink | None = None
    try:
        core = core or estimator_from_config(config)
        summary = ReplaySummary(bag=str(bag), storage=source.meta.storage)

        def stage(path: str | Path | None, is_dir: bool, **kwargs: Any) -> Staged | None:
            return None if path is None else staged.add(path, force, is_dir, **kwargs)

        out = stage(out_bag, True, create=False, looks_like=looks_like_bag,  # the sink makes it
                    flag='--out')
        table = stage(csv_path, False, flag='--csv')
        figs = stage(plots_dir, True, looks_like=looks_like_plots, flag='--plots')
        if out is not None:
            out_storage = storage or source.meta.storage
            sink = open_sink(str(out.path), out_storage, pipelined,
                             output_compression(compression, out_storage, source.meta),
                             out.name)
        with ExitStack() as stack:
            csv_file = stack.enter_context(table.open_text()) if table else None
            series = _run(source, core, config, summary, sink, csv_file, keep_estimates,
                          progress, figs is not None)
        if summary.estimates == 0:  # every sample skipped: say why rather than write nothing
            raise BagError(_no_estimate_message(summary, core))
        if sink is not None:
            sink.close()
            sink = None
        if figs is not None:
            from .replay_figures import write_replay_figures
            with figs.writing():
                write_replay_figures(series.data, figs.path, Path(bag).name, config)
        staged.commit()
        for item, kind in ((out, 'bag'), (table, 'csv'), (figs, 'plots')):
            if item is not None:
                summary.outputs[kind] = str(item.target)
    except BaseException:
        with sigint_held():  # a second Ctrl-C must not cut the clean-up short
            if sink is not None:
                sink.abort()
            staged.discard()
        raise
    finally:
        source.close()
    summary.elapsed_s = time.perf_counter() - started
    return summary


_WHY = {
    'rejected_missing_joint': 'no JointState names joint "{joint}", the joint_name parameter',
    'rejected_malformed': 'JointState arrays empty or not as long as name, '
                          'or the joint named twice',
    'rejected_undecodable': 'messages that do not deserialise',
    'rejected_future_stamp': 'header stamps more than max_stamp_lead_s ahead of the log time',
    'rejected_negative_stamp': 'header stamps before 1970 (negative)',
    'rejected_non_finite': 'NaN or infinite values',
    'rejected_out_of_range': 'implausible values',
    'rejected_out_of_order': 'stamps going back in time',
    'rejected_duplicate': 'repeated stamps',
}


def _no_estimate_message(summary: ReplaySummary, core: TorqueEstimator) -> str:
    """Why a replay made no estimate: the skip counters that are not zero, largest first."""
    counts = {k: v for k, v in summary.counts.items()
              if v and k.startswith(('rejected', 'stale'))}
    if not counts:
        return f'bag {summary.bag}: no estimate made (no shaft-speed sample)'
    parts = []
    for name, n in sorted(counts.items(), key=lambda item: -item[1]):
        why = core.last_stale_reason if name == 'stale_skips' else \
            _WHY.get(name, '').format(joint=core.config.joint_name)
        parts.append(f'{name} {n}' + (f' ({why})' if why else ''))
    read = sum(summary.messages_read.values())
    return f'bag {summary.bag}: no estimate made from {read} input messages: ' + \
        ', '.join(parts)


def _run(source: Source, core: TorqueEstimator, config: EstimatorConfig,
         summary: ReplaySummary, sink: Sink | None, csv_file: NamedErrorsFile | None,
         keep_estimates: bool, progress: bool, plots: bool) -> _Series:
    """
    Consume `replay_batches`: outputs, CSV rows, level intervals, the summary.

    The diagnostics timer ticks only where they are written (the output bag).
    """
    from rosbags.typesys import get_typestore, Stores

    typestore = get_typestore(Stores.ROS2_JAZZY)
    types = rosbags_types(typestore)
    rows = csv.writer(csv_file) if csv_file is not None else None
    if rows is not None:
        rows.writerow(CSV_COLUMNS)
    status_name = f'{NODE_NAME}: {core.pump_name}'
    meta = source.meta
    start_ns = meta.start_ns
    levels = LevelTracker()
    series = _Series(core)
    kept: list[Estimate] = []
    last_stamp = start_ns
    write = sink.write if sink is not None else None
    period = round(1e9 / config.diagnostics_rate_hz) if write is not None else None
    with ProgressBar(f'replay {Path(summary.bag).name}', enabled=progress) as bar:
        for log_ns, estimates in replay_batches(source, core, period, bar,
                                                summary.diagnostics_gaps):
            raise_if_interrupted()  # a Ctrl-C swallowed by a finaliser stops us here
            if estimates is None:  # the node's diagnostics timer
                if write is not None:
                    tick = log_ns[0]
                    status = core.diagnostics(tick)
                    summary.count_status(status.level, status.message)
                    msg = diagnostic_array(types, status, tick, status_name,
                                           config.hardware_id)
                    write(DIAGNOSTICS_INDEX, tick, bytes(typestore.serialize_cdr(
                        msg, 'diagnostic_msgs/msg/DiagnosticArray')))
                continue
            stamps = estimates.column('stamp_ns')
            last_stamp = int(stamps[-1])
            level = estimates.column('level')
            for i in np.flatnonzero(level != np.append(levels.level, level[:-1])).tolist():
                levels.update(int(level[i]), int(stamps[i]))
            if keep_estimates or rows is not None:
                every = estimates.rows()
                kept.extend(every if keep_estimates else ())
                if rows is not None:
                    rows.writerows(csv_row(est, start_ns) for est in every)
            published = np.flatnonzero(estimates.column('publish'))
            summary.published += published.size
            if write is not None:
                for i, est in zip(published.tolist(), estimates.rows(published), strict=True):
                    t = log_ns[i]
                    for name, v in outputs_of(est):
                        write(OUTPUT_INDEX[name], t, float64_cdr(v))
            if plots:
                series.add(estimates, published, start_ns)
    levels.finish(last_stamp)
    stats = source.stats()
    summary.duration_s = (meta.end_ns - start_ns) * 1e-9
    summary.span_ns = (start_ns, meta.end_ns)
    summary.messages_read = dict(stats.messages_read)
    summary.unread = stats.unread()
    summary.other_type = dict(stats.other_type)
    summary.estimates = core.counts['estimates']
    summary.counts = dict(core.counts)
    summary.decoded_one_by_one = stats.fallbacks
    summary.warn_intervals = [((a - start_ns) * 1e-9, (b - start_ns) * 1e-9)
                              for a, b in levels.warn]
    summary.error_intervals = [((a - start_ns) * 1e-9, (b - start_ns) * 1e-9)
                               for a, b in levels.error]
    if core.last is not None:
        summary.final_level = core.last.level
        summary.final_valve_plate_scale = core.last.valve_plate_scale
        summary.final_valve_plate_scale_std = core.last.valve_plate_scale_std
        summary.final_other_scale = core.monitor.theta_rest
        summary.final_other_scale_std = core.monitor.rest_scale_std
        summary.attribution = level_message(core.monitor.level, core.monitor)
    if keep_estimates:
        summary.estimates_list = kept
    return series
