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

r"""
The command line's standard output: what it prints never stops what it writes.

A command prints its summary as it goes and writes its output files; a reader that goes
away (``| head -0``), a full device (``> /dev/full``) or a terminal that cannot show a
character (``PYTHONIOENCODING=ascii``, a file name in another encoding) made the print raise
and the command stop before its ``--out`` was written. `GuardedStdout` takes the failure:
the rest of the output goes to ``os.devnull``, the command finishes, and `finish` says
what was lost (a closed pipe is the reader's choice: nothing to say). Characters the stream
cannot encode are written escaped (``\xff``).
"""

from __future__ import annotations

import errno
import io
import os
from typing import Any, TextIO

__all__ = ['GuardedStdout', 'non_utf8_argument']


class GuardedStdout:
    """
    Standard output that takes a write failure instead of raising it.

    Parameters
    ----------
    stream : TextIO
        The stream to write to (``sys.stdout``).

    """

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream
        self.failure: OSError | None = None

    def write(self, text: str) -> int:
        """Write ``text``; on a failure the rest goes nowhere (returns its length)."""
        try:
            try:
                return self._stream.write(text)
            except UnicodeEncodeError:
                encoding = getattr(self._stream, 'encoding', None) or 'utf-8'
                return self._stream.write(
                    text.encode(encoding, 'backslashreplace').decode(encoding))
        except OSError as exc:
            self._lost(exc)
            return len(text)

    def flush(self) -> None:
        """Flush; a failure is kept, not raised."""
        try:
            self._stream.flush()
        except OSError as exc:
            self._lost(exc)

    def _lost(self, exc: OSError) -> None:
        """Send the rest (and what the buffer still holds) to os.devnull."""
        if self.failure is None:
            self.failure = exc
        try:
            fd = self._stream.fileno()
        except (OSError, ValueError, io.UnsupportedOperation):
            self._stream = open(os.devnull, 'w', encoding='utf-8')
            return
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, fd)  # the buffered rest flushes there, now and at exit
        finally:
            os.close(devnull)

    def finish(self) -> str:
        """
        Flush, and say what was lost.

        Returns
        -------
        str
            '' when all was written or the reader closed the pipe; else one line.

        """
        self.flush()
        if self.failure is None or self.failure.errno == errno.EPIPE:
            return ''
        why = self.failure.strerror or type(self.failure).__name__
        return f'standard output: {why}: the summary was not printed'

    def __getattr__(self, name: str) -> Any:
        """Everything else (encoding, isatty, fileno) as the stream has it."""
        return getattr(self._stream, name)


def non_utf8_argument(argv: list[str]) -> str:
    r"""
    Return the first argument that is not valid UTF-8, shown escaped; '' if none.

    Parameters
    ----------
    argv : list of str
        The arguments (Python decodes bytes that are not UTF-8 as lone surrogates).

    Returns
    -------
    str
        The argument, its undecodable bytes as ``\xff``.

    """
    for arg in argv:
        try:
            arg.encode('utf-8')
        except UnicodeEncodeError:
            raw = arg.encode('utf-8', 'surrogateescape')
            return raw.decode('utf-8', 'backslashreplace')
    return ''
