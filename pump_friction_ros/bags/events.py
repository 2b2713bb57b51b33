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
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
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
                   progress: Callable[[float], None] | None = None) -> Iterator[ReplayBatch]:
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

    Yields
    ------
    ReplayBatch
        Estimates and timer ticks, in time order.

    """
    meta = source.meta
    next_tick = meta.start_ns + tick_period_ns if tick_period_ns else _NEVER
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
                start = end
            if start < n:
                log_ns = int(log_times[start])
                while next_tick <= log_ns:
                    yield ReplayBatch([next_tick], None)
                    next_tick += tick_period_ns  # type: ignore[operator]
        done += n
        if progress is not None:
            progress(min(done / total, 1.0))
    while next_tick <= meta.end_ns:
        yield ReplayBatch([next_tick], None)
        next_tick += tick_period_ns  # type: ignore[operator]


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
