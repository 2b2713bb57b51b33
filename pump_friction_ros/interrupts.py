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
Ctrl-C and SIGTERM for the command line: never lost, one line, exit 130 or 143.

A stop is noted by the handlers `sigint_kept` (the command) and `sigterm_kept` (a fleet's
worker) install, raised again by `raise_if_interrupted` where a finaliser swallowed it, and
held back by `sigint_held` while outputs move into place (`staging`). `note_committed`
records the outputs already in place, so that the line of an interrupted command says
which are complete.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
import os
from pathlib import Path
import signal
import sys
import threading
from types import FrameType
from typing import Any

__all__ = ['committed_outputs', 'note_committed', 'raise_if_interrupted', 'sigint_held',
           'sigint_ignored', 'sigint_kept', 'sigterm_kept', 'stop_signal']

_SIGINT_SEEN: list[int] = []  # Ctrl-Cs received through `sigint_kept`'s handler
_COMMITTED: list[str] = []  # outputs this command has put in place (`note_committed`)


def _note_and_raise(signum: int, frame: object) -> None:
    """Note the Ctrl-C, then raise KeyboardInterrupt as Python's own handler does."""
    _SIGINT_SEEN.append(signum)
    raise KeyboardInterrupt


def sigint_kept() -> None:
    """
    Never lose a Ctrl-C, even one that Python swallows; called once as a command starts.

    Python raises KeyboardInterrupt wherever the main thread is. In a finaliser (the
    ``__del__`` of a pipe's end collected at that instant, say) it only prints "Exception
    ignored" and goes on, and the command ran to its end and committed its outputs, exit 0
    (CI on f314839). From here on the SIGINT handler notes the signal before raising it, a
    KeyboardInterrupt that a finaliser swallowed is not printed, and `raise_if_interrupted`
    raises it again where the command checks: between batches and before any output is
    committed (`commit_all`). A handler not Python's default (Ctrl-C ignored by a runner in
    the background, say) is left alone. SIGTERM (``kill``, a supervisor stopping the
    command), whose default would kill the process with its staged outputs left behind, is
    taken the same way: a stop that discards them (`stop_signal` says which came).
    """
    _SIGINT_SEEN.clear()
    _COMMITTED.clear()
    if threading.current_thread() is threading.main_thread():
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            signal.signal(signal.SIGINT, _note_and_raise)
        if signal.getsignal(signal.SIGTERM) == signal.SIG_DFL:
            signal.signal(signal.SIGTERM, _note_and_raise)
    _quiet_swallowed_stops()


def note_committed(target: str | Path) -> None:
    """
    Note an output put in place, complete: a Ctrl-C after it cannot take it back.

    Parameters
    ----------
    target : str or Path
        The output, as the command line named it.

    """
    _COMMITTED.append(str(target))


def committed_outputs() -> list[str]:
    """
    Return the outputs this command has put in place so far (`note_committed`).

    Returns
    -------
    list of str
        In the order they were committed.

    """
    return list(_COMMITTED)


def _default_sigterm_in_child() -> None:
    """In a forked child, give SIGTERM back its default if it was `sigint_kept`'s."""
    if signal.getsignal(signal.SIGTERM) is _note_and_raise:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


# A process forked by a command (a process pool's worker, a helper) must not inherit the
# command's SIGTERM-as-Ctrl-C: its parent stops it with SIGTERM (a pool's terminate), and
# a KeyboardInterrupt there is an error of one task, after which it would go on. Those that
# stop on SIGTERM in their own way set their handler as they start (`sigterm_kept`).
os.register_at_fork(after_in_child=_default_sigterm_in_child)


def stop_signal() -> int | None:
    """
    Return the first stop signal `sigint_kept`'s handlers received (SIGINT, SIGTERM), if any.

    Returns
    -------
    int or None
        The signal number, or None (no signal noted: a KeyboardInterrupt of another origin).

    """
    return _SIGINT_SEEN[0] if _SIGINT_SEEN else None


def _note_and_exit(signum: int, frame: object) -> None:
    """Note the SIGTERM, then exit as its default does (status 128 + 15), unwinding."""
    _SIGINT_SEEN.append(signum)
    raise SystemExit(128 + signum)


def sigterm_kept() -> None:
    """
    Never lose a SIGTERM in a worker process; called once as the worker starts.

    The fleet's parent stops its workers with SIGTERM (after a Ctrl-C, say), and a worker
    exits by unwinding, which discards its staged outputs. Raised in a finaliser (a NumPy
    ``NpzFile.__del__`` collected at that instant, say: CI on e782729) the exit only prints
    "Exception ignored" and the worker goes on. As `sigint_kept` does for Ctrl-C: the
    handler notes the signal before raising, a stop that a finaliser swallowed is not
    printed, and `raise_if_interrupted` raises at the worker's next check (between batches,
    before any output is committed).
    """
    _SIGINT_SEEN.clear()
    signal.signal(signal.SIGTERM, _note_and_exit)
    _quiet_swallowed_stops()


def _quiet_swallowed_stops() -> None:
    """Print no "Exception ignored" for a Ctrl-C or SIGTERM noted: it is raised again."""
    if getattr(sys.unraisablehook, '_previous', None) is None:  # installed once
        previous = sys.unraisablehook

        def quiet(unraisable: sys.UnraisableHookArgs) -> None:
            if not (_SIGINT_SEEN and isinstance(unraisable.exc_value,
                                                (KeyboardInterrupt, SystemExit))):
                previous(unraisable)

        quiet._previous = previous  # type: ignore[attr-defined]
        sys.unraisablehook = quiet


def raise_if_interrupted() -> None:
    """
    Raise KeyboardInterrupt if a Ctrl-C (or a worker's SIGTERM) came and was swallowed.

    Raises
    ------
    KeyboardInterrupt
        A Ctrl-C was received since the command started.

    """
    if _SIGINT_SEEN:
        raise KeyboardInterrupt


@contextmanager
def sigint_held() -> Iterator[None]:
    """
    Hold Ctrl-C back for a moment that must not be cut in two; deliver it afterwards.

    Used while outputs are staged or moved into place (all or none), while a run cleans up
    after a failure or a first Ctrl-C, and while a helper process starts: the signal is
    blocked in this thread, which a child inherits (so a Ctrl-C in the instant between its
    start and its own handler setup cannot raise KeyboardInterrupt in it), and in the main
    thread Python's handler is swapped for one that only notes the signal (another thread
    may receive it). A Ctrl-C noted meanwhile is handed to the previous handler at the end.
    SIGTERM (the fleet's stop of a worker, `sigterm_kept`; the command's own, `sigint_kept`)
    is blocked and noted likewise, and delivered at the end: a worker stopped mid-commit
    exits once its output is in place, not between the old one's removal and the new one's
    rename.
    """
    noted: list[int] = []
    swapped: dict[int, Callable[[int, FrameType | None], Any]] = {}
    if threading.current_thread() is threading.main_thread():
        for stop in (signal.SIGINT, signal.SIGTERM):
            previous = signal.getsignal(stop)
            # a handler set from Python (not SIG_DFL, SIG_IGN, or None: not from Python)
            # runs in this thread whichever thread the signal reached (numpy's BLAS
            # threads, which the mask below does not cover): it only notes the signal now
            if callable(previous):
                swapped[stop] = previous
                signal.signal(stop, lambda signum, _: noted.append(signum))
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        for restored, handler in swapped.items():
            signal.signal(restored, handler)
        for came in dict.fromkeys(noted):  # once each, in the order they came
            if came in swapped:
                swapped[came](came, None)  # e.g. raises KeyboardInterrupt now


def sigint_ignored() -> None:
    """
    Ignore Ctrl-C from now on, in a process on its way out after the first one.

    A second Ctrl-C (an impatient user, or one noted during the clean-up and handed on)
    may be pending when the first is caught: Python raises it at the next bytecode, in
    the report or on the way out of ``main``, and the process dies of SIGINT instead of
    exiting 130. Setting the handler runs a pending one first: that only retries. A SIGTERM
    taken by `sigint_kept` is ignored likewise.
    """
    for signum in (signal.SIGINT, signal.SIGTERM):
        while True:
            try:
                if signum == signal.SIGINT or signal.getsignal(signum) is _note_and_raise:
                    signal.signal(signum, signal.SIG_IGN)
                break
            except KeyboardInterrupt:
                continue
