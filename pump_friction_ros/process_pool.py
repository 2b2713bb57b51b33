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
Map a function over items in worker processes, stopping the workers when the caller stops.

``ProcessPoolExecutor`` used as a context manager waits, on the way out of an exception
(a Ctrl-C, a SIGTERM taken as one, a worker killed), for every item already handed to it:
`pool.map` hands them all at once, so a stopped evaluation bank would run to its end. Here
the workers are terminated instead, and they ignore Ctrl-C themselves (the terminal sends
it to the whole process group: the parent alone decides how to stop).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from concurrent.futures import ProcessPoolExecutor
import signal
from typing import TypeVar

__all__ = ['process_map']

_T = TypeVar('_T')
_R = TypeVar('_R')

_JOIN_S = 5.0  # how long a terminated worker is waited for before it is killed [s]


def _worker_start() -> None:
    """Ignore Ctrl-C and take SIGTERM by default: the parent stops a worker (terminate)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def process_map(function: Callable[[_T], _R], items: Iterable[_T], workers: int,
                on_result: Callable[[int], None] | None = None) -> list[_R]:
    """
    Return ``[function(item) for item in items]``, computed in ``workers`` processes.

    Parameters
    ----------
    function : callable
        A picklable function of one item.
    items : iterable
        Its arguments.
    workers : int
        Processes (>= 1).
    on_result : callable, optional
        Called with the number of results so far after each one (a progress bar).

    Returns
    -------
    list
        The results, in the order of ``items``.

    Raises
    ------
    BaseException
        Whatever a call or the caller raised (KeyboardInterrupt included): the workers
        are terminated first, without waiting for the items not yet done.

    """
    pool = ProcessPoolExecutor(max_workers=workers, initializer=_worker_start)
    results: list[_R] = []
    try:
        for result in pool.map(function, items):
            results.append(result)
            if on_result is not None:
                on_result(len(results))
    except BaseException:
        _terminate(pool)
        raise
    pool.shutdown()
    return results


def _terminate(pool: ProcessPoolExecutor) -> None:
    """Stop a pool's workers now, dropping what they were doing and what was queued."""
    processes = list((getattr(pool, '_processes', None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        process.terminate()
    for process in processes:
        process.join(_JOIN_S)
        if process.is_alive():
            process.kill()
            process.join(_JOIN_S)
