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
Entry point of ``pump_friction`` (console script): light on purpose.

The command line imports numpy, scipy and the rest before it can install its handlers (a
second or so); a Ctrl-C in that time is one line and exit code 130, as later, not a
traceback from the import. The Ctrl-C is noted by a handler of its own: a library may turn
the KeyboardInterrupt into another error on its way up (numpy 1.26 into an ImportError
"you should not try to import numpy from its source directory", measured on the Jazzy
environment 8 times in 8 at 1-8 ms).
"""

from __future__ import annotations

from collections.abc import Sequence
import os
import signal
import sys
from typing import Any

__all__ = ['main']


def main(argv: Sequence[str] | None = None) -> int:
    """
    Run ``pump_friction`` (``cli.main``) once its modules are imported.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        ``cli.main``'s exit code (a Ctrl-C during the imports exits 130 at once).

    """
    noted: list[int] = []

    def note(signum: int, frame: Any) -> None:
        noted.append(signum)
        raise KeyboardInterrupt

    # Python's own handler only (one a runner set, e.g. Ctrl-C ignored, is left alone)
    ours = signal.getsignal(signal.SIGINT) is signal.default_int_handler
    try:
        if ours:
            signal.signal(signal.SIGINT, note)
        from .cli import main as run
        if ours:  # cli.main installs its own (`interrupts.sigint_kept`) over Python's
            signal.signal(signal.SIGINT, signal.default_int_handler)
    except BaseException:
        if not noted:
            raise
        print('pump_friction: interrupted', file=sys.stderr, flush=True)
        # Out at once, nothing begun: not through the interpreter's exit, which dies of
        # SIGINT all the same (exit -2, measured 2 in 4 at 0.1 s) when the interrupt came in
        # code an extension module ran through PyRun_* (CPython then flags it unhandled).
        os._exit(130)
    return run(argv)


if __name__ == '__main__':
    sys.exit(main())
