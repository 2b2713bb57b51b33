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

"""A dependency-free progress bar on stderr, shown only when a job takes more than a moment."""

from __future__ import annotations

import sys
import time
from typing import TextIO

__all__ = ['ProgressBar']


class ProgressBar:
    """
    Progress bar drawn on a terminal after ``delay_s``; silent when not a terminal.

    Parameters
    ----------
    label : str
        Text before the bar.
    delay_s : float
        Nothing is drawn before this much time has passed [s].
    stream : file, optional
        Where to draw (default ``sys.stderr``).
    enabled : bool
        False for ``--quiet``.

    """

    def __init__(self, label: str, delay_s: float = 0.5, stream: TextIO | None = None,
                 enabled: bool = True) -> None:
        self.label = label
        self.delay_s = delay_s
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled and getattr(self.stream, 'isatty', lambda: False)()
        self._start = time.monotonic()
        self._drawn = False
        self._last = -1

    def __call__(self, fraction: float) -> None:
        """
        Report the fraction of the job done (0..1).

        Parameters
        ----------
        fraction : float
            Fraction done [-].

        """
        if not self.enabled or time.monotonic() - self._start < self.delay_s:
            return
        percent = int(100 * min(max(fraction, 0.0), 1.0))
        if percent == self._last:
            return
        self._last = percent
        filled = percent * 30 // 100
        self.stream.write(f'\r{self.label} [{"#" * filled}{"." * (30 - filled)}] {percent:3d}%')
        self.stream.flush()
        self._drawn = True

    def close(self) -> None:
        """End the bar's line, if one was drawn."""
        if self._drawn:
            self.stream.write('\n')
            self.stream.flush()
            self._drawn = False

    def __enter__(self) -> ProgressBar:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
