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
Outputs written atomically: staged under a temporary name beside the target, then moved.

Every output of the command line (replay bags, CSV and plots; calibrated pump files and
reports; tables) goes through `Staged`: the target is checked (an existing output is
replaced only with ``force``, and only if it is of the same kind), its folder is made, and
the output is written under a hidden temporary name in that folder and renamed into place
by `Staged.commit`. A failed or interrupted run calls `Staged.discard`, which removes the
temporary output and the folders the staging made, so nothing that looks complete is left.
Errors are one line naming the target, never a temporary name.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
import os
from pathlib import Path
import shutil
import signal
import sys
import tempfile
import threading
from types import FrameType
from typing import Any

from .errors import OutputError, UsageError
from .input_files import special_kind

__all__ = ['Staged', 'StagedOutputs', 'commit_all', 'committed_outputs', 'discard_all',
           'looks_like_bag', 'looks_like_plots', 'note_committed', 'raise_if_interrupted',
           'refuse_at_inputs', 'remove_empty_folders', 'sigint_held', 'sigint_ignored',
           'sigint_kept', 'sigterm_kept', 'stop_signal']

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


def looks_like_bag(path: Path) -> bool:
    """Whether an existing folder is a rosbag2 bag (``metadata.yaml`` in it)."""
    return (path / 'metadata.yaml').is_file()


def looks_like_plots(path: Path) -> bool:
    """Whether an existing folder holds only PNG files (an earlier run's plots)."""
    return all(p.is_file() and p.suffix == '.png' for p in path.iterdir())


def _reason(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def remove_empty_folders(folders: list[Path]) -> None:
    """
    Remove the folders given that are empty, deepest first (errors ignored).

    Parameters
    ----------
    folders : list of Path
        Folders this run created.

    """
    for folder in sorted(folders, key=lambda p: len(p.parts), reverse=True):
        try:
            folder.rmdir()
        except OSError:
            pass  # not empty (another output is in it) or already gone


def _make_folder(folder: Path, target: Path) -> list[Path]:
    """Make ``folder`` and its missing parents; return those made, outermost first."""
    missing = []
    for parent in (folder, *folder.parents):
        if parent.is_dir():
            break
        if parent.exists() or parent.is_symlink():
            raise OutputError(f'cannot create the output {target}: {parent} is not a folder')
        missing.append(parent)
    made: list[Path] = []
    try:
        for parent in reversed(missing):
            parent.mkdir()
            made.append(parent)
    except OSError as exc:
        remove_empty_folders(made)
        raise OutputError(f'cannot create the output {target}: cannot make the folder '
                          f'{parent} ({_reason(exc)})') from None
    return made


def refuse_at_inputs(flag: str, target: str | Path, inputs: Iterable[str | Path]) -> None:
    """
    Refuse an output at an input, inside one (a bag's folder) or around one.

    ``--force`` would otherwise replace the data the command reads: a bag's
    ``metadata.yaml``, a bench CSV, or a folder holding them.

    Parameters
    ----------
    flag : str
        The output's option, for the message (``--out``).
    target : str or Path
        The output.
    inputs : iterable of str or Path
        The command's input files and bags.

    Raises
    ------
    UsageError
        ``target`` is an input, is in one, or holds one.

    """
    where = Path(target).expanduser().resolve()
    for given in inputs:
        source = Path(given).expanduser().resolve()
        if where == source or source in where.parents or where in source.parents:
            raise UsageError(f'{flag} {target}: an output cannot be at, in or around the '
                             f'input {given}')


class Staged:
    """
    An output path written under a temporary name and moved into place by `commit`.

    Parameters
    ----------
    target : Path
        Where the output goes.
    force : bool
        Replace an existing output of the same kind.
    is_dir : bool
        The output is a folder (plots, a report, a bag) rather than a file.
    create : bool
        Make the (empty) staged folder now; False for a folder its writer creates (a bag).
    looks_like : callable, optional
        For a folder: whether an existing one is an earlier output of this kind, which
        ``force`` may replace (an empty folder always may). Without it any folder may be.

    Raises
    ------
    OutputError
        The target exists (without ``force``), is of another kind, or cannot be made.

    """

    def __init__(self, target: str | Path, force: bool, is_dir: bool, *, create: bool = True,
                 looks_like: Callable[[Path], bool] | None = None) -> None:
        target = Path(target)
        self.target = target  # as given, for the messages; ``where``, absolute, for the work
        where = Path(os.path.abspath(target))
        here = Path.cwd()
        if where == here or where in here.parents:  # '.', '..', '/': not an output's name
            raise OutputError(f'cannot create the output {target}: it is the current folder '
                              'or one above it; name a folder or file below it')
        self._where = where
        if where.exists() or where.is_symlink():  # (a dangling link too: something is there)
            if not force:
                raise OutputError(f'output exists: {target} (remove it, choose another path, '
                                  'or pass --force)')
            special = special_kind(where)
            if special:  # /dev/null, a named pipe: never replaced by a file
                raise OutputError(f'output {target} is {special}, not a '
                                  f'{"folder" if is_dir else "regular file"}: not replaced')
            if where.is_dir() != is_dir:
                want, found = ('a folder', 'a file') if is_dir else ('a file', 'a folder')
                raise OutputError(f'output {target} is {found}, expected {want}: not '
                                  'replaced')
            if is_dir and looks_like is not None and any(where.iterdir()) and \
                    not looks_like(where):
                raise OutputError(f'output {target} is a folder that does not look like an '
                                  'earlier output of this kind: not replaced (remove it '
                                  'yourself or choose another path)')
        self._made = _make_folder(where.parent, target)
        try:
            self._tmp_parent = Path(tempfile.mkdtemp(prefix=f'.{where.name}.partial-',
                                                     dir=where.parent))
        except OSError as exc:
            remove_empty_folders(self._made)
            raise OutputError(f'cannot create the output {target}: cannot write in '
                              f'{target.parent} ({_reason(exc)})') from None
        self.path = self._tmp_parent / where.name
        if is_dir and create:
            self.path.mkdir()

    def commit(self) -> None:
        """Move the output into place (replacing an old one) and remove the staging folder."""
        where = self._where
        try:
            if where.is_dir() and not where.is_symlink():
                shutil.rmtree(where)
            elif where.exists() or where.is_symlink():
                where.unlink()
            os.replace(self.path, where)
        except OSError as exc:
            self.discard()
            raise OutputError(f'cannot write the output {self.target}: {_reason(exc)}') \
                from None
        shutil.rmtree(self._tmp_parent, ignore_errors=True)
        self._made = []
        note_committed(self.target)

    def discard(self) -> None:
        """Remove the staged output and the folders made for it (if left empty)."""
        shutil.rmtree(self._tmp_parent, ignore_errors=True)
        remove_empty_folders(self._made)


def commit_all(staged: list[Staged]) -> None:
    """
    Commit several staged outputs, with Ctrl-C held back until all are in place.

    If one fails, the ones not yet committed are discarded.

    Parameters
    ----------
    staged : list of Staged
        The outputs, all written.

    """
    with sigint_held():
        raise_if_interrupted()  # one swallowed by a finaliser: nothing goes into place
        for k, item in enumerate(staged):
            try:
                item.commit()
            except BaseException:
                discard_all(staged[k + 1:])
                raise


def discard_all(staged: list[Staged]) -> None:
    """
    Discard several staged outputs (after a failure or an interrupt).

    Parameters
    ----------
    staged : list of Staged
        The outputs.

    """
    for item in reversed(staged):
        item.discard()


class StagedOutputs:
    """
    The outputs of one run: staged together, committed together, discarded together.

    `add` stages an output and records it with Ctrl-C held back, so that an interrupt can
    never leave a staging folder that `discard` does not know of.
    """

    def __init__(self) -> None:
        self.items: list[Staged] = []

    def add(self, target: str | Path, force: bool, is_dir: bool, **kwargs) -> Staged:
        """
        Stage one output (see `Staged` for the arguments).

        Returns
        -------
        Staged
            The staged output; write to its ``path``.

        """
        with sigint_held():
            item = Staged(target, force, is_dir, **kwargs)
            self.items.append(item)
        return item

    def commit(self) -> None:
        """Move every output into place (`commit_all`)."""
        commit_all(self.items)

    def discard(self) -> None:
        """Remove every staged output and the folders made for them (Ctrl-C held back)."""
        with sigint_held():
            discard_all(self.items)
