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
Opening an input file that must be a regular file: never a pipe to wait on, never a device.

A named pipe given as a parameters or baseline file would block ``open()`` until something
writes to it (a node that never starts, a replay that never ends), and ``/dev/zero`` would
be read until memory runs out. `open_regular` opens without blocking and refuses anything
but a regular file, and `read_regular` reads at most a bound, with an `OSError` whose
``strerror`` says which, as every reader here already reports an unreadable file.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path
import stat
from typing import BinaryIO

__all__ = ['YAML_LIMIT_BYTES', 'open_regular', 'read_regular', 'special_kind']

YAML_LIMIT_BYTES = 64 << 20
"""The largest YAML file read [bytes]: pump, parameters and baseline files are kilobytes; a
file past this is not one of them, and parsing it would take minutes and gigabytes."""

_KINDS = ((stat.S_ISDIR, 'a directory'), (stat.S_ISFIFO, 'a named pipe'),
          (stat.S_ISCHR, 'a character device'), (stat.S_ISBLK, 'a block device'),
          (stat.S_ISSOCK, 'a socket'))


def special_kind(path: Path) -> str:
    """
    Return what a path is when it is neither a regular file nor a folder, else ''.

    Parameters
    ----------
    path : Path
        The path; a link is followed (a dangling link, or nothing there: '').

    Returns
    -------
    str
        ``a named pipe``, ``a character device`` (``/dev/null``), ...; '' for a regular
        file, a folder or nothing.

    """
    try:
        mode = path.stat().st_mode
    except OSError:
        return ''
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return ''
    return next((name for test, name in _KINDS if test(mode)), 'not a regular file')


def open_regular(path: Path) -> BinaryIO:
    """
    Open a regular file for reading, without waiting on a named pipe.

    Parameters
    ----------
    path : Path
        The file.

    Returns
    -------
    BinaryIO
        The open file, positioned at its start (blocking reads, as any file).

    Raises
    ------
    OSError
        The file cannot be opened, or is not a regular file (``strerror`` says what it is).

    """
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, 'O_CLOEXEC', 0))
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = next((name for test, name in _KINDS if test(mode)), 'not a regular file')
            raise OSError(errno.EINVAL, f'{kind}, not a regular file', str(path))
        os.set_blocking(fd, True)
        return os.fdopen(fd, 'rb')
    except BaseException:
        os.close(fd)
        raise


def read_regular(path: Path, limit_bytes: int) -> bytes:
    """
    Read a whole regular file of at most ``limit_bytes``.

    Parameters
    ----------
    path : Path
        The file.
    limit_bytes : int
        The most it may hold [bytes].

    Returns
    -------
    bytes
        Its content.

    Raises
    ------
    OSError
        As `open_regular`, or the file is larger than ``limit_bytes``.

    """
    with open_regular(path) as handle:
        data = handle.read(limit_bytes + 1)
    if len(data) > limit_bytes:
        raise OSError(errno.EFBIG, f'larger than {limit_bytes >> 20} MiB, not a file this '
                      'package reads', str(path))
    return data
