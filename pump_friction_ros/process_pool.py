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

``concurrent.futures.ProcessPoolExecutor`` used as a context manager waits, on the way out
of an exception (a Ctrl-C, a SIGTERM taken as one, a failed item), for every item already
handed to it: its ``map`` hands them all out at once, so a stopped evaluation bank ran on
to its end; and killing its workers races its own thread (CPython 3.11 then raises
InvalidStateError there). ``multiprocessing.Pool`` used as a context manager terminates its
workers on the way out instead. The workers ignore Ctrl-C (the terminal sends it to the
whole process group: the parent alone decides how to stop) and take SIGTERM by default.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
import multiprocessing
import signal
from typing import TypeVar

__all__ = ['process_map']

_T = TypeVar('_T')
_R = TypeVar('_R')


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
    results: list[_R] = []
    with multiprocessing.get_context().Pool(workers, initializer=_worker_start) as pool:
        for result in pool.imap(function, items):  # (the exit terminates the workers)
            results.append(result)
            if on_result is not None:
                on_result(len(results))
        pool.close()
        pool.join()  # waited for: their CPU time counts in os.times()'s children
    return results
