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
Sources of decoded input chunks: the bag read here, or in a helper process one chunk ahead.

Both satisfy `Source`. The helper process is stopped by closing its pipe (it then ends on
its own), with every wait bounded and a kill after it, and it starts with default signal
handling: it must not depend on the handlers it inherits from its parent (rclpy's SIGTERM
handler in a ROS test process, Ctrl-C while the parent cleans up).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
import multiprocessing
from pathlib import Path
import signal
import sys
from typing import Any, Protocol, TYPE_CHECKING

from .reader import BagInputs, BagMeta, Chunk, ReadStats
from ..core.node_parameters import EstimatorConfig
from ..errors import BagError
from ..interrupts import sigint_held

if TYPE_CHECKING:  # (no ForkContext on Windows)
    from multiprocessing.context import DefaultContext, ForkContext

__all__ = ['InlineSource', 'ProcessSource', 'Source', 'child_signals', 'open_source',
           'process_context', 'sigint_held', 'start_helper', 'stop_process']

JOIN_TIMEOUT_S = 5.0
"""How long a helper process is given to end by itself before it is killed [s]."""


class Source(Protocol):
    """Decoded input events of one bag, in bag order."""

    meta: BagMeta

    def chunks(self) -> Iterator[Chunk]:
        """Yield the events, a chunk at a time."""

    def stats(self) -> ReadStats:
        """Return what reading found (complete once `chunks` is exhausted)."""

    def close(self) -> None:
        """Release the bag (and the helper process)."""


class InlineSource:
    """Reads and decodes the bag in this process."""

    def __init__(self, bag: str | Path, config: EstimatorConfig,
                 remaps: dict[str, str] | None) -> None:
        self._inputs = BagInputs(bag, config, remaps)
        self.meta = self._inputs.meta()

    def chunks(self) -> Iterator[Chunk]:
        """Yield the events, a chunk at a time."""
        yield from self._inputs.chunks()

    def stats(self) -> ReadStats:
        """Return what reading found."""
        return self._inputs.stats()

    def close(self) -> None:
        """Close the bag."""
        self._inputs.close()


def process_context() -> ForkContext | DefaultContext:
    """
    Return how helper and fleet processes start: forked, where the platform has fork.

    They are started under `interrupts.sigint_held` and rely on a forked child inheriting the
    blocked signals until it sets its own handlers (`child_signals`). Forkserver (Python
    3.14's default on Linux) and spawn start the child from another process, whose mask is
    not this thread's: a Ctrl-C in that instant would raise in the child. Elsewhere (macOS,
    Windows: no safe fork) the platform's default.

    Returns
    -------
    multiprocessing.context.ForkContext or DefaultContext
        The context to make pipes and processes with.

    """
    if sys.platform == 'linux' and 'fork' in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context('fork')
    return multiprocessing.get_context()


def child_signals() -> None:
    """In a helper process: default SIGTERM, and Ctrl-C left to the parent (it stops us)."""
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # started under `interrupts.sigint_held`: both signals blocked until now
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})


def start_helper(proc: Any, child_end: Any, on_failure: Callable[[], None]) -> None:
    """
    Start a helper process with Ctrl-C held back; on any exception (Ctrl-C) stop it again.

    Parameters
    ----------
    proc : multiprocessing.Process
        The helper, not started.
    child_end : Connection
        The helper's end of the pipe, closed here once the helper has it.
    on_failure : callable
        Stops the helper (closes the parent's end, bounded wait) if this is interrupted.

    """
    try:
        with sigint_held():
            proc.start()
        child_end.close()
    except BaseException:
        on_failure()
        raise


def stop_process(proc: Any, timeout_s: float = JOIN_TIMEOUT_S) -> None:
    """
    Wait for a helper process to end, bounded: terminate, then kill it if it does not.

    Parameters
    ----------
    proc : multiprocessing.Process
        The process (already told to stop, e.g. by closing its pipe).
    timeout_s : float
        Time allowed for each step [s].

    """
    if proc.pid is None:  # never started
        return
    proc.join(timeout_s)
    if proc.is_alive():
        proc.terminate()
        proc.join(timeout_s)
    if proc.is_alive():
        proc.kill()
        proc.join(timeout_s)


def _reader_process(conn: Any, parent_end: Any, bag: str, config: EstimatorConfig,
                    remaps: dict[str, str] | None) -> None:
    """Read and batch-decode the bag; send the chunks down the pipe until it is closed."""
    child_signals()
    parent_end.close()  # our inherited copy: the parent closing its end must reach us
    try:
        with BagInputs(bag, config, remaps) as inputs:
            conn.send(('meta', inputs.meta()))
            for chunk in inputs.chunks():
                conn.send(('chunk', chunk))
            conn.send(('done', inputs.stats()))
    except (BrokenPipeError, EOFError, OSError) as exc:
        if isinstance(exc, (BrokenPipeError, EOFError)):
            return  # the parent stopped listening: nothing more to do
        _send_error(conn, f'bag {bag}: {type(exc).__name__}: {exc}')
    except BagError as exc:
        _send_error(conn, str(exc))
    except Exception as exc:  # e.g. a log time beyond int64, a sqlite timestamp of text
        _send_error(conn, f'bag {bag}: unreadable ({type(exc).__name__}: {exc})')
    finally:
        conn.close()


def _send_error(conn: Any, message: str) -> None:
    try:
        conn.send(('error', message))
    except (BrokenPipeError, OSError):
        pass


class ProcessSource:
    """Reads and decodes the bag in a helper process, one chunk ahead of the core."""

    def __init__(self, bag: str | Path, config: EstimatorConfig,
                 remaps: dict[str, str] | None) -> None:
        ctx = process_context()
        self._conn, child = ctx.Pipe(duplex=False)
        self._proc = ctx.Process(target=_reader_process,
                                 args=(child, self._conn, str(bag), config, remaps),
                                 daemon=True)
        start_helper(self._proc, child, self.close)
        self._stats = ReadStats()
        try:
            kind, payload = self._receive()
        except BaseException:  # Ctrl-C while the bag opens: stop the reader too
            self.close()
            raise
        if kind != 'meta':
            self.close()
            raise BagError(f'bag reader: unexpected {kind}')
        self.meta: BagMeta = payload

    def _receive(self) -> tuple[str, Any]:
        try:
            kind, payload = self._conn.recv()
        except (EOFError, OSError) as exc:
            self.close()
            raise BagError('the bag reader process died') from exc
        if kind == 'error':
            self.close()
            raise BagError(payload)
        return kind, payload

    def chunks(self) -> Iterator[Chunk]:
        """Yield the events, a chunk at a time."""
        while True:
            kind, payload = self._receive()
            if kind == 'done':
                self._stats = payload
                return
            yield payload

    def stats(self) -> ReadStats:
        """Return what reading found."""
        return self._stats

    def close(self) -> None:
        """Stop the helper: close the pipe (it ends on its own), bounded wait, then kill."""
        self._conn.close()
        stop_process(self._proc)


def open_source(bag: str | Path, config: EstimatorConfig, remaps: dict[str, str] | None,
                pipeline: bool | None = None) -> Source:
    """
    Open a bag as a source of decoded input events.

    Parameters
    ----------
    bag : str or Path
        The bag.
    config : EstimatorConfig
        Node parameters (topics, joint).
    remaps : dict, optional
        Topic remappings.
    pipeline : bool, optional
        Read in a helper process (default: yes, unless this process is daemonic, e.g. a
        Dask or pool worker, which may not have children).

    Returns
    -------
    Source
        The source; close it when done.

    """
    if pipeline is None:
        pipeline = not multiprocessing.current_process().daemon
    return (ProcessSource if pipeline else InlineSource)(bag, config, remaps)
