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

"""Stop signals noted from the first instant of the node process, before any heavy import."""

from __future__ import annotations

import signal
from typing import Any

__all__ = ['StopSignals']


class StopSignals:
    """
    SIGINT and SIGTERM noted, never raised: the node stops through rclpy's own handler.

    rclpy's signal handler (installed by ``rclpy.init``) shuts the context down on SIGINT and
    SIGTERM, which ends the executor's spin with ``ExternalShutdownException``, and then
    calls the handler that was there before it: this one. Python's default SIGINT handler
    would raise ``KeyboardInterrupt`` wherever the main thread is; a second Ctrl-C (a
    terminal sends one to the process group, launch forwards another) would then cut
    ``destroy_node`` short with a traceback and exit code -2. Here every signal is only
    recorded, so the clean-up always runs to its end.
    """

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.received: list[str] = []
        self._previous: dict[int, Any] = {}

    def __call__(self, signum: int, frame: Any) -> None:
        """Note the signal (the Python-level handler)."""
        self.received.append(signal.Signals(signum).name)

    def __enter__(self) -> StopSignals:
        """Install this handler for SIGINT and SIGTERM."""
        for sig in self.SIGNALS:
            self._previous[sig] = signal.signal(sig, self)
        return self

    def __exit__(self, *exc: object) -> None:
        """Restore the handlers, or ignore both signals if one came (the process stops)."""
        for sig, handler in self._previous.items():
            # A stopping process ignores further stop signals, to its very end: CPython
            # resets Python-level handlers to SIG_DFL at finalisation (SIG_IGN it keeps), and
            # a signal then, while the middleware tears down, would kill it with -2.
            signal.signal(sig, signal.SIG_IGN if self.received else handler)
