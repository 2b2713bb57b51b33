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
The replay's event loop: a bag's messages through the core, and the node's timer ticks.

`replay_batches` feeds the core the messages between two ticks of the diagnostics timer at
once (``TorqueEstimator.on_chunk``, identical to the node's ``on_input`` per message), so
that at each tick the core is exactly in the state the node's would be in; the timer is
emulated on bag time (first tick one period after the first message). `replay_events` is the
same, one event at a time.

Across a gap in the log (a recording paused, clocks of another epoch), the node would repeat
one STALE status every period; the ticks are written until the status has turned STALE
(``stale_timeout_s`` and two periods after the last message, or after the last estimate's
stamp where it leads), then only the last before the next message: a day's gap is three
ticks, not 86,400 (a 1970 stamp, 1.7e9).
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterator
from typing import NamedTuple

import numpy as np

from .sources import Source
from ..core.estimate_record import Estimate, EstimateColumns
from ..core.estimator import TorqueEstimator

__all__ = ['ReplayBatch', 'ReplayEvent', 'replay_batches', 'replay_events']

_NEVER = 1 << 63


class ReplayEvent(NamedTuple):
    """One thing the node would do: publish an estimate, or tick its diagnostics timer."""

    log_ns: int  # when [ns]
    estimate: Estimate | None  # None: the diagnostics timer fires


class ReplayBatch(NamedTuple):
    """Estimates made one after the other, or a tick of the diagnostics timer."""

    log_ns: list[int]  # when each estimate is published [ns]; [the tick's time]
    estimates: EstimateColumns | None  # None: the diagnostics timer fires


def replay_batches(source: Source, core: TorqueEstimator, tick_period_ns: int | None = None,
                   progress: Callable[[float], None] | None = None,
                   gaps: list[int] | None = None) -> Iterator[ReplayBatch]:
    """
    Run a bag's input events through the core, in bag order, a batch of estimates at a time.

    The core takes the messages between two ticks of the timer at once
    (``TorqueEstimator.on_chunk``, identical to ``on_input`` per message), so at each tick
    it is exactly in the state the node's would be in.

    Parameters
    ----------
    source : Source
        Decoded input events (``sources.open_source``).
    core : TorqueEstimator
        The core, fed exactly as the node feeds it.
    tick_period_ns : int, optional
        Period of the node's diagnostics timer [ns]; None: no ticks.
    progress : callable, optional
        Called with the fraction of messages done after each chunk.
    gaps : list of int, optional
        Appended, for each gap in the log whose ticks were left out, how many were.

    Yields
    ------
    ReplayBatch
        Estimates and timer ticks, in time order.

    """
    meta = source.meta
    next_tick = meta.start_ns + tick_period_ns if tick_period_ns else _NEVER
    quiet_ns = round(core.config.stale_timeout_s * 1e9) + 2 * (tick_period_ns or 0)
    fed_ns = meta.start_ns  # the latest log time fed to the core
    total = max(meta.input_message_count, 1)
    done = 0
    for chunk in source.chunks():
        n = len(chunk)
        log_times = chunk.log_times
        # a tick fires before the first message logged at or after it
        reach = np.maximum.accumulate(log_times) if tick_period_ns else None
        start = 0
        while start < n:
            end = n if reach is None else max(int(np.searchsorted(reach, next_tick)), start)
            if end > start:
                part = slice(start, end)
                positions, estimates = core.on_chunk(
                    chunk.kinds[part], chunk.stamps[part], log_times[part],
                    chunk.values[part], chunk.torques[part], chunk.has_value[part],
                    chunk.has_torque[part], chunk.defects[part])
                if len(estimates):
                    yield ReplayBatch(log_times[part][positions].tolist(), estimates)
                if reach is not None:
                    fed_ns = max(fed_ns, int(reach[end - 1]))
                start = end
            if start < n:
                next_tick = yield from _ticks(next_tick, int(log_times[start]),
                                              _quiet_from(fed_ns, core), tick_period_ns or 0,
                                              quiet_ns, gaps)
        done += n
        if progress is not None:
            progress(min(done / total, 1.0))
    if tick_period_ns:
        yield from _ticks(next_tick, meta.end_ns, _quiet_from(fed_ns, core), tick_period_ns,
                          quiet_ns, gaps)


def _quiet_from(fed_ns: int, core: TorqueEstimator) -> int:
    """Return when the quiet began: the last log time fed, or a later stamp (a lead)."""
    last = core.last  # its stamp may lead the log time by up to max_stamp_lead_s
    return fed_ns if last is None else max(fed_ns, last.stamp_ns)


def _ticks(next_tick: int, until_ns: int, fed_ns: int, period_ns: int, quiet_ns: int,
           gaps: list[int] | None) -> Generator[ReplayBatch, None, int]:
    """Yield the timer's ticks up to ``until_ns``, a gap's quiet ones left out; the next."""
    left_out = 0  # (without a period, next_tick is _NEVER: no tick)
    while next_tick <= until_ns:
        if next_tick > fed_ns + quiet_ns and until_ns - next_tick >= period_ns:
            skip = (until_ns - next_tick) // period_ns  # to the last before until_ns
            next_tick += skip * period_ns
            left_out += skip
        yield ReplayBatch([next_tick], None)
        next_tick += period_ns
    if left_out and gaps is not None:
        gaps.append(left_out)
    return next_tick


def replay_events(source: Source, core: TorqueEstimator, tick_period_ns: int | None = None,
                  progress: Callable[[float], None] | None = None) -> Iterator[ReplayEvent]:
    """
    Run a bag's input events through the core, in bag order, one event at a time.

    `replay_batches`, unbatched.

    Parameters
    ----------
    source : Source
        Decoded input events (``sources.open_source``).
    core : TorqueEstimator
        The core, fed exactly as the node feeds it.
    tick_period_ns : int, optional
        Period of the node's diagnostics timer [ns]; None: no ticks.
    progress : callable, optional
        Called with the fraction of messages done after each chunk.

    Yields
    ------
    ReplayEvent
        Each estimate made, and each timer tick, in time order.

    """
    for log_ns, estimates in replay_batches(source, core, tick_period_ns, progress):
        if estimates is None:
            yield ReplayEvent(log_ns[0], None)
        else:
            yield from map(ReplayEvent, log_ns, estimates.rows())
