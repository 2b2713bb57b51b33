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
The node's baseline file: where it is, loading it at start, saving it, resetting it.

`BaselineStore` never raises for a file problem: each method returns the line to log and
the status for /diagnostics says it. A file it cannot use (unreadable, corrupt, another
version, learnt on another pump, table or parameters) it never overwrites: the monitor
learns in memory until `BaselineStore.reset` (the node's ``~/reset_monitor``) moves the
file aside as ``<name>.<UTC time>.bak`` and writes the new one. The file itself:
``baseline_file``; docs/node.md, "The healthy baseline file".
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any, TYPE_CHECKING

from .baseline_disk import archive_baseline
from .baseline_file import (
    baseline_document,
    load_baseline,
    read_baseline,
    restore_baseline,
    utc_now,
    write_baseline,
)
from ..errors import BaselineError, BaselineMismatchError, OutputError

if TYPE_CHECKING:
    from .estimator import TorqueEstimator

__all__ = ['BaselineStore', 'baseline_path', 'default_baseline_path']


def default_baseline_path(node_name: str) -> Path:
    """
    Return the node's baseline file when ``baseline_file`` is empty.

    Parameters
    ----------
    node_name : str
        The node's fully qualified name (``/eha1/torque_estimator``).

    Returns
    -------
    Path
        ``$ROS_HOME/pump_friction_ros/baselines/<namespace.name>.yaml`` (``ROS_HOME``
        defaulting to ``~/.ros``), e.g. ``eha1.torque_estimator.yaml``.

    """
    home = Path(os.environ.get('ROS_HOME') or Path.home() / '.ros').expanduser()
    name = '.'.join(part for part in node_name.split('/') if part) or 'torque_estimator'
    return home / 'pump_friction_ros' / 'baselines' / f'{name}.yaml'


def baseline_path(value: str, node_name: str) -> Path:
    """
    Resolve the ``baseline_file`` parameter to an absolute path (the file need not exist).

    Parameters
    ----------
    value : str
        The parameter: a path (``~`` expanded; relative: to the current directory), or
        empty for `default_baseline_path`.
    node_name : str
        The node's fully qualified name.

    Returns
    -------
    Path
        Absolute path.

    """
    if not value:
        return default_baseline_path(node_name)
    path = Path(value).expanduser()
    return Path(os.path.normpath(path if path.is_absolute() else Path.cwd() / path))


class BaselineStore:
    """
    One estimator's baseline file: load, save, reset, and its /diagnostics status.

    Never raises for a file problem: each method returns the line to log, and the status
    says it. A file that cannot be used (unreadable, corrupt, another version, another
    provenance) is never overwritten: the monitor learns in memory until `reset` moves the
    file aside (``.bak``) and writes the new one.

    Parameters
    ----------
    path : Path
        The file (absolute).
    core : TorqueEstimator
        The estimator whose monitor it holds.
    origin : str
        Who learns it, written in the file (``node /torque_estimator``).

    """

    def __init__(self, path: Path, core: TorqueEstimator, origin: str = '') -> None:
        self.path = path
        self.core = core
        self.origin = origin
        self.status = 'none yet: learning from scratch'
        self.note = 'no baseline yet (learning)'  # for the diagnostics message; '' when fine
        self.writable = True  # False while the file on disk is one this node cannot use
        self.errors = 0  # failed loads and saves
        self.created_utc = ''
        self.saved_utc = ''
        self._saved_samples = core.learnt[0]  # nothing new to save until it changes
        self._warned = ''

    def load(self) -> tuple[str, str]:
        """
        Load the file into the estimator, if there is one and it is usable.

        Returns
        -------
        tuple of str
            Severity (``info``, ``warning`` or ``error``) and the line to log.

        """
        try:
            if not self.path.exists():  # ENAMETOOLONG, EACCES on a folder: raised, not False
                return 'info', f'baseline file {self.path}: none yet, learning from scratch'
        except OSError as exc:
            self.errors += 1
            self.writable = False
            self.status = f'not used: {exc.strerror or exc}'
            self.note = 'baseline file not usable: learning in memory, nothing saved'
            return 'error', (f'baseline file {self.path}: {exc.strerror or exc}; learning in '
                             'memory, nothing is saved (set baseline_file to a path that can '
                             'be written)')
        try:
            document = read_baseline(self.path)
            restore_baseline(self.core, document, self.path)
        except BaselineError as exc:
            self.errors += 1
            self.writable = False
            mismatch = isinstance(exc, BaselineMismatchError)
            reason = ' '.join(str(exc).split())
            self.status = f'not used: {reason}'
            self.note = 'baseline file not used (' + \
                ('learnt on another pump, table or parameters' if mismatch else 'unreadable') \
                + '): learning afresh, call ~/reset_monitor to replace it'
            return ('warning' if mismatch else 'error',
                    f'baseline file not used: {reason}; learning afresh in memory, the file '
                    'is kept until ~/reset_monitor (or pump_friction reset-baseline) '
                    'replaces it')
        samples, first_ns, last_ns = self._loaded(document)
        span = f', stamps {first_ns * 1e-9:.3f} to {last_ns * 1e-9:.3f} s' \
            if first_ns is not None and last_ns is not None else ''
        return 'info', (f'baseline file {self.path}: loaded, learnt from {samples} monitored '
                        f'samples{span} since {self.created_utc}')

    @classmethod
    def opened(cls, path: Path, core: TorqueEstimator) -> BaselineStore:
        """
        Load a file that must be usable, read-only (the replay's ``--baseline``).

        Parameters
        ----------
        path : Path
            The file.
        core : TorqueEstimator
            The estimator to load it into.

        Returns
        -------
        BaselineStore
            Loaded; it never writes the file.

        Raises
        ------
        BaselineError
            As `load_baseline`.

        """
        baseline = cls(path, core)
        baseline._loaded(load_baseline(core, path))
        baseline.writable = False
        return baseline

    def _loaded(self, document: dict[str, Any]) -> tuple[int, int | None, int | None]:
        """Take a loaded document's times; return what the monitor has learnt."""
        learnt = self.core.learnt
        self._saved_samples = learnt[0]
        self.created_utc = str(document.get('created_utc', ''))
        self.saved_utc = str(document.get('updated_utc', ''))
        self.status, self.note = 'loaded', ''
        return learnt

    def save(self, force: bool = False) -> str:
        """
        Write the file if the monitor learnt anything since the last save.

        Parameters
        ----------
        force : bool
            Write even when nothing new was learnt.

        Returns
        -------
        str
            A warning to log: the first failure, or a failure for a new reason; else ''.

        """
        if not self.writable or (not force and self.core.learnt[0] == self._saved_samples):
            return ''
        samples = self.core.learnt[0]
        created = self.created_utc or utc_now()
        document = baseline_document(self.core, created, self.origin)
        try:
            write_baseline(self.path, document)
        except (OutputError, BaselineError) as exc:
            self.errors += 1
            reason = ' '.join(str(exc).split())
            self.status = f'not saved: {reason}'
            self.note = 'baseline not saved (see baseline_status)'
            if reason == self._warned:
                return ''
            self._warned = reason
            return f'{reason}; the monitor keeps learning in memory'
        self._saved_samples = samples
        self.created_utc, self.saved_utc = created, document['updated_utc']
        self.status, self.note, self._warned = 'saved', '', ''
        return ''

    def reset(self) -> tuple[bool, str]:
        """
        Forget what the monitor learnt (after a repair) and start a new baseline file.

        The old file is moved aside (`archive_baseline`) and the new, empty state written.

        Returns
        -------
        tuple
            Whether the new file was written, and a message for the service's response.

        """
        self.core.reset_monitor()
        self.created_utc = ''
        try:
            archived = archive_baseline(self.path)
        except OutputError as exc:
            self.errors += 1
            self.status = f'not saved: {exc}'
            self.note = 'baseline not saved (see baseline_status)'
            self.writable = False
            return False, (f'wear monitor reset, re-learning the healthy baseline in memory; '
                           f'{exc}, so it is not overwritten')
        self.writable = True
        self._warned = ''
        warning = self.save(force=True)
        kept = f'; the old one kept as {archived}' if archived else ''
        if warning or self.status != 'saved':
            return False, (f'wear monitor reset, re-learning the healthy baseline in memory; '
                           f'{self.status}{kept}')
        return True, (f'wear monitor reset: re-learning the healthy baseline (after a '
                      f'repair), new file {self.path}{kept}')

    def diagnostics(self) -> tuple[list[tuple[str, float | int | str]], str]:
        """
        Return the key-values and the message note for /diagnostics.

        Returns
        -------
        tuple
            Key-values (``baseline_file``, ``baseline_status``, ``baseline_samples``, the
            first and latest stamps learnt from [s], ``baseline_created_utc``,
            ``baseline_saved_utc``, ``baseline_errors``), and the note for the message
            (empty when the file is loaded or saved).

        """
        samples, first_ns, last_ns = self.core.learnt
        nan = math.nan
        return [('baseline_file', str(self.path)), ('baseline_status', self.status),
                ('baseline_samples', samples),
                ('baseline_first_stamp_s', nan if first_ns is None else first_ns * 1e-9),
                ('baseline_last_stamp_s', nan if last_ns is None else last_ns * 1e-9),
                ('baseline_created_utc', self.created_utc),
                ('baseline_saved_utc', self.saved_utc),
                ('baseline_errors', self.errors)], self.note
