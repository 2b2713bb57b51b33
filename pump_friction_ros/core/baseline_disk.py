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
The baseline file on disk: written atomically, through links, moved aside on a reset.

`replace_file` writes a temporary file in the same folder, flushes and fsyncs it, renames it
over the file (``os.replace``) and fsyncs the folder, so a crash or power cut leaves the old
file or the new one, never half of one. A file that is a symbolic link (to a persistent
volume) stays one: the file it names is written and moved aside. /dev/null, a named pipe or
a socket is never replaced. ``baseline_file`` makes the content; docs/node.md, "The healthy
baseline file".
"""

from __future__ import annotations

import os
from pathlib import Path
import stat
import tempfile
import time

from ..errors import OutputError
from ..input_files import special_kind
from ..paths import created_file_mode
from ..staging import remove_empty_folders

__all__ = ['archive_baseline', 'replace_file', 'writable_folder']


def replace_file(path: Path, text: str) -> None:
    """
    Write ``text`` to ``path`` atomically: the old file, or the new one, never half of one.

    On any failure the temporary file is removed and ``path`` is left as it was. An
    existing file's permissions are kept; a new one gets a new file's (the umask's).

    Parameters
    ----------
    path : Path
        The baseline file; its folder is made when missing.
    text : str
        The whole content.

    Raises
    ------
    OutputError
        The folder or file cannot be written, or it is not a regular file (one line, with
        the reason).

    """
    _refuse_special(path)
    real = _through_links(path)
    try:
        real.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f'.{real.name}.', suffix='.tmp', dir=real.parent)
        try:
            with os.fdopen(fd, 'w', encoding='utf-8') as handle:
                os.fchmod(handle.fileno(), stat.S_IMODE(real.stat().st_mode)
                          if real.is_file() else created_file_mode())
                handle.write(text)
                handle.flush()
                os.fsync(handle.fileno())
            os.replace(tmp, real)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        _fsync_folder(real.parent)
    except OSError as exc:
        raise OutputError(f'cannot write baseline file {path}: '
                          f'{exc.strerror or type(exc).__name__}') from None


def writable_folder(path: Path) -> None:
    """
    Check that `replace_file` can write ``path``: its folder made, a file made in it.

    The folders made for the check and the file are removed again: a run that fails later
    leaves nothing behind (`replace_file` makes them when it writes).

    Parameters
    ----------
    path : Path
        The baseline file to be written.

    Raises
    ------
    OutputError
        It cannot (one line, with the reason, as `replace_file` would say it).

    """
    _refuse_special(path)
    real = _through_links(path)
    missing = [folder for folder in (real.parent, *real.parent.parents) if not folder.exists()]
    try:
        real.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f'.{real.name}.', suffix='.probe', dir=real.parent)
        os.close(fd)
        os.unlink(tmp)
    except OSError as exc:
        raise OutputError(f'cannot write baseline file {path}: '
                          f'{exc.strerror or type(exc).__name__}') from None
    finally:
        remove_empty_folders(missing)


def _through_links(path: Path) -> Path:
    """
    Return the file a symbolic link names (itself if it is none), to write in its place.

    A baseline file kept elsewhere (a persistent volume) through a link stays there: a
    rename onto the link would replace the link with a plain file.

    """
    return Path(os.path.realpath(path)) if path.is_symlink() else path


def _refuse_special(path: Path) -> None:
    """Refuse to replace /dev/null or a named pipe with a baseline file (`OutputError`)."""
    special = special_kind(path)
    if special:
        raise OutputError(f'cannot write baseline file {path}: it is {special}, not a '
                          'regular file: not replaced')


def _fsync_folder(folder: Path) -> None:
    """Make the rename durable (a power cut after it keeps the new file); best effort."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def archive_baseline(path: Path) -> Path | None:
    """
    Move a baseline file aside as ``<name>.<UTC time>.bak``, so that it is re-learnt.

    Parameters
    ----------
    path : Path
        The file.

    Returns
    -------
    Path or None
        Where it went; None when there was no file.

    Raises
    ------
    OutputError
        It is a folder or not a regular file, or cannot be moved (one line, with the
        reason).

    """
    given, path = path, _through_links(path)  # the linked file is moved; the link stays
    if path.is_dir():
        raise OutputError(f'baseline file {given} is a folder: not moved aside')
    if path.exists() and not path.is_file():  # a reset must never replace /dev/null
        raise OutputError(f'baseline file {given} is not a regular file (a device, a named '
                          'pipe or a socket): not moved aside')
    stamp = time.strftime('%Y%m%dT%H%M%SZ', time.gmtime())
    target = path.with_name(f'{path.name}.{stamp}.bak')
    n = 1
    while target.exists():
        n += 1
        target = path.with_name(f'{path.name}.{stamp}-{n}.bak')
    try:
        os.replace(path, target)
    except FileNotFoundError as exc:
        if path.exists():  # it is there, the rename cannot move it (a special file system)
            raise OutputError(f'cannot move baseline file {given} aside: {exc.strerror}'
                              ) from None
        return None
    except OSError as exc:
        raise OutputError(f'cannot move baseline file {given} aside: '
                          f'{exc.strerror or type(exc).__name__}') from None
    return target
