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
import tempfile
from typing import TextIO

from .errors import OutputError, UsageError
from .input_files import special_kind
from .interrupts import note_committed, raise_if_interrupted, sigint_held

__all__ = ['NamedErrorsFile', 'Staged', 'StagedOutputs', 'cannot_write', 'commit_all',
           'discard_all', 'looks_like_bag', 'looks_like_plots', 'refuse_at_inputs',
           'remove_empty_folders']


def looks_like_bag(path: Path) -> bool:
    """Whether an existing folder is a rosbag2 bag (``metadata.yaml`` in it)."""
    return (path / 'metadata.yaml').is_file()


def looks_like_plots(path: Path) -> bool:
    """Whether an existing folder holds only PNG files (an earlier run's plots)."""
    return all(p.is_file() and p.suffix == '.png' for p in path.iterdir())


def _reason(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def cannot_write(name: str, exc: BaseException) -> str:
    """
    Return the one line for an output that could not be written: its name and the reason.

    Parameters
    ----------
    name : str
        The output as the command line named it (``--csv out/e.csv``).
    exc : BaseException
        The error: an OSError says its reason without the errno, another its text.

    Returns
    -------
    str
        ``cannot write the output <name>: <reason>``.

    """
    reason = _reason(exc) if isinstance(exc, OSError) else str(exc) or type(exc).__name__
    return f'cannot write the output {name}: {reason}'


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
    flag : str, optional
        The option that named it (``--csv``), for the messages of `writing`.

    Raises
    ------
    OutputError
        The target exists (without ``force``), is of another kind, or cannot be made.

    """

    def __init__(self, target: str | Path, force: bool, is_dir: bool, *, create: bool = True,
                 looks_like: Callable[[Path], bool] | None = None, flag: str = '') -> None:
        target = Path(target)
        self.target = target  # as given, for the messages; ``where``, absolute, for the work
        self.flag = flag
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

    @contextmanager
    def writing(self) -> Iterator[None]:
        """
        Turn an OSError while the output is written (a full disk) into one line naming it.

        A write's error names no file (``[Errno 28] No space left on device``) or the
        staging file; the line names the option and the output as given.

        Yields
        ------
        None
            The block that writes into ``path``.

        Raises
        ------
        OutputError
            The block raised an OSError.

        """
        try:
            yield
        except OSError as exc:
            raise OutputError(cannot_write(self.name, exc)) from None

    @property
    def name(self) -> str:
        """Return the output as the messages name it: the option and the target as given."""
        return f'{self.flag} {self.target}' if self.flag else str(self.target)

    def open_text(self) -> NamedErrorsFile:
        """
        Open the staged file for text, its write and close errors named as `writing` does.

        Returns
        -------
        NamedErrorsFile
            The file (newline='': the csv module's own line ends).

        """
        with self.writing():
            file = open(self.path, 'w', newline='', encoding='utf-8')
        return NamedErrorsFile(file, self)

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


class NamedErrorsFile:
    """A text file whose write and close errors are `Staged.writing`'s one line."""

    def __init__(self, file: TextIO, staged: Staged) -> None:
        self._file = file
        self._staged = staged

    def write(self, text: str) -> int:
        """Write ``text`` (`Staged.writing`'s error on failure)."""
        with self._staged.writing():
            return self._file.write(text)

    def close(self) -> None:
        """Flush and close the file (`Staged.writing`'s error on failure)."""
        with self._staged.writing():  # (closed even when the flush fails)
            self._file.close()

    def __enter__(self) -> NamedErrorsFile:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


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
