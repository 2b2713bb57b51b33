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
What a replay did: the summary a person reads, the fleet table's row, the alarm intervals.

`ReplaySummary` holds the counts, the intervals at WARN and ERROR, the final scales and what
reading found (messages read, those the metadata counts but the storage did not give, the
diagnostics ticks left out across gaps in the log); `LevelTracker` makes the intervals from
the level of each estimate.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math

from ..core.estimate_record import COUNTERS, Estimate
from ..core.monitor import ERROR, STALE, WARN

__all__ = ['SKIP_COUNTERS', 'LevelTracker', 'ReplaySummary']

# the counters of inputs skipped, rejected or clamped (the others count what was made)
SKIP_COUNTERS = tuple(k for k in COUNTERS
                      if k.startswith(('stale', 'rejected', 'clamped', 'stamp')))


@dataclass
class ReplaySummary:
    """What a replay did, for the printed summary and the fleet table."""

    bag: str
    label: str = ''  # the bag's name in a fleet (unique; see ``fleet.output_names``)
    storage: str = ''
    duration_s: float = 0.0
    span_ns: tuple[int, int] = (0, 0)  # log times of the first and the last message [ns]
    messages_read: dict[str, int] = field(default_factory=dict)
    unread: dict[str, int] = field(default_factory=dict)  # in the metadata, not the storage
    other_type: dict[str, int] = field(default_factory=dict)  # `ReadStats.other_type`
    estimates: int = 0
    published: int = 0
    counts: dict[str, int] = field(default_factory=dict)
    decoded_one_by_one: int = 0
    warn_intervals: list[tuple[float, float]] = field(default_factory=list)
    error_intervals: list[tuple[float, float]] = field(default_factory=list)
    final_level: int = 0
    final_valve_plate_scale: float = math.nan
    final_valve_plate_scale_std: float = math.nan
    final_other_scale: float = math.nan
    final_other_scale_std: float = math.nan
    attribution: str = ''  # what explains the torque at the end (the status message's words)
    elapsed_s: float = 0.0
    # the diagnostics timer's ticks left out in each gap of the log (`events.replay_batches`)
    diagnostics_gaps: list[int] = field(default_factory=list)
    diagnostics_ticks: int = 0  # /diagnostics written (an output bag), and how many STALE
    stale_ticks: int = 0
    stale_message: str = ''  # the latest STALE status's message
    outputs: dict[str, str] = field(default_factory=dict)
    error: str = ''
    estimates_list: list[Estimate] | None = None

    def count_status(self, level: int, message: str) -> None:
        """
        Count one /diagnostics status written, keeping the latest STALE one's message.

        Parameters
        ----------
        level : int
            Its level (``monitor.OK`` ... ``STALE``).
        message : str
            Its message.

        """
        self.diagnostics_ticks += 1
        if level == STALE:
            self.stale_ticks += 1
            self.stale_message = message

    def stale_note(self) -> str:
        """
        Say how many of the /diagnostics written were STALE, and why; '' if none.

        Returns
        -------
        str
            ``'/diagnostics STALE in 19 of 19 statuses (the latest: stale: ...)'``.

        """
        if not self.stale_ticks:
            return ''
        return (f'/diagnostics STALE in {self.stale_ticks} of {self.diagnostics_ticks} '
                f'statuses (the latest: {self.stale_message})')

    @property
    def alarm_onset_s(self) -> float:
        """Time of the first entry into WARN or ERROR, from the start of the bag [s]."""
        starts = [a for a, _ in self.warn_intervals + self.error_intervals]
        return min(starts) if starts else math.nan

    @property
    def alarm_s(self) -> float:
        """Time spent at WARN or ERROR [s]."""
        return sum(b - a for a, b in self.warn_intervals + self.error_intervals)

    def skipped(self) -> str:
        """
        Say which inputs were skipped or clamped, and how many: the non-zero counters.

        Returns
        -------
        str
            ``', skipped: stale_skips 3, rejected_non_finite 900'``, or '' if none.

        """
        items = ', '.join(f'{k} {n}' for k in SKIP_COUNTERS if (n := self.counts.get(k, 0)))
        notes = [note for note in (self.unread_note(), self.other_type_note()) if note]
        return (f', skipped: {items}' if items else '') + ''.join(f', {n}' for n in notes)

    def other_type_note(self) -> str:
        """
        Say how many messages on an input topic were of another type, and not read.

        Returns
        -------
        str
            ``'not read, of another type: /load_pressure (sensor_msgs/msg/Temperature)
            999 (...)'``, or '' if none.

        """
        if not self.other_type:
            return ''
        items = ', '.join(f'{key} {n}' for key, n in self.other_type.items())
        return (f'not read, of another type: {items} (the node subscribes to its own type '
                'only)')

    def unread_note(self) -> str:
        """
        Say how many messages the metadata counts that the storage did not give.

        Returns
        -------
        str
            ``'unread: /joint_states 1828 (...)'``, or '' if none.

        """
        if not self.unread:
            return ''
        items = ', '.join(f'{topic} {n}' for topic, n in self.unread.items())
        return (f'unread: {items} (counted in the metadata, not in the storage: truncated or '
                'corrupt; the estimates are of what was read)')

    def formatted(self) -> str:
        """
        Multi-line summary for a person.

        Returns
        -------
        str
            The summary.

        """
        if self.error:
            return f'{self.bag}: FAILED: {self.error}'

        def intervals(items: list[tuple[float, float]]) -> str:
            return ', '.join(f'{a:.1f}-{b:.1f} s' for a, b in items) or 'none'

        lines = [f'bag {self.bag} ({self.storage}): {self.duration_s:.1f} s',
                 '  messages read: ' + ', '.join(f'{t} {n}'
                                                 for t, n in self.messages_read.items()),
                 f'  estimates: {self.estimates} ({self.published} published)',
                 '  skipped: ' + ', '.join(f'{k} {self.counts.get(k, 0)}'
                                           for k in SKIP_COUNTERS),
                 f'  WARN: {intervals(self.warn_intervals)}',
                 f'  ERROR: {intervals(self.error_intervals)}',
                 f'  first alarm at {self.alarm_onset_s:.1f} s' if self.warn_intervals
                 or self.error_intervals else '  no alarm' if self.stale_ticks <
                 self.diagnostics_ticks or not self.stale_ticks
                 else '  no alarm from the monitor, but every /diagnostics status was STALE',
                 f'  final status: {self.attribution}',
                 f'  friction scales at the end: valve plate {self.final_valve_plate_scale:.3f}'
                 f' +- {1.96 * self.final_valve_plate_scale_std:.3f}, other components '
                 f'{self.final_other_scale:.3f} +- {1.96 * self.final_other_scale_std:.3f} '
                 '(95 %)',
                 f'  replayed in {self.elapsed_s:.2f} s']
        if self.other_type:  # after the messages read
            lines.insert(2, f'  {self.other_type_note()}')
        if self.unread:
            lines.insert(2, f'  {self.unread_note()}')
        if self.diagnostics_gaps:
            lines.insert(1, f'  gaps in the log: {len(self.diagnostics_gaps)}, in which '
                         f'{sum(self.diagnostics_gaps)} ticks of /diagnostics are left out '
                         '(the STALE status the node would repeat)')
        if self.stale_ticks:
            lines.insert(lines.index(f'  final status: {self.attribution}'),
                         f'  {self.stale_note()}')
        lines += [f'  {kind}: {path}' for kind, path in self.outputs.items()]
        return '\n'.join(lines)


class LevelTracker:
    """Intervals spent at WARN and at ERROR, from the level of each estimate."""

    def __init__(self) -> None:
        self.level = 0
        self.since_ns = 0
        self.warn: list[tuple[int, int]] = []
        self.error: list[tuple[int, int]] = []

    def update(self, level: int, stamp_ns: int) -> None:
        """
        Take the level of the estimate stamped ``stamp_ns``: an interval ends where it moves.

        Parameters
        ----------
        level : int
            The monitor's level (``monitor.OK``, ``WARN``, ``ERROR``, ``STALE``).
        stamp_ns : int
            The estimate's stamp [ns].

        """
        if level == self.level:
            return
        self._close(stamp_ns)
        self.level, self.since_ns = level, stamp_ns

    def _close(self, stamp_ns: int) -> None:
        if self.level == WARN:
            self.warn.append((self.since_ns, stamp_ns))
        elif self.level == ERROR:
            self.error.append((self.since_ns, stamp_ns))

    def finish(self, stamp_ns: int) -> None:
        """
        Close the interval still open at the end of the bag.

        Parameters
        ----------
        stamp_ns : int
            The last estimate's stamp [ns].

        """
        self._close(stamp_ns)
        self.level = 0
