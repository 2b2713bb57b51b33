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
The last alarm, kept after it cleared: when, how high, and what it was named.

The monitor's level follows its CUSUMs: an alarm clears when they drain below
``cusum_clear_ratio`` of the threshold. A fault that comes and goes (a valve plate that
tilts under some loads) drains them in its off episodes, and its alarm clears with the
verdict that named it; a maintenance engineer looking at the status then sees "torque as the
healthy baseline" and nothing of the valve plate named minutes before. So the monitor keeps
its last alarm: the close of the window that raised it, the close of the one that cleared
it (NaN while it lasts), the highest level, and the verdict, its words and the valve-plate
scale +- std at its height: the window where its CUSUM was highest (the latest of them at
the cap). Not its last window: as the sums drain after a fault went off, the scales'
memory fills with healthy windows (a valve plate x1.8 read 0.97 there). /diagnostics
publishes it (``last_alarm_*``), the status message at OK says it, and the state file keeps
it across restarts; a reset (a repair) forgets it with the baseline. An alarm that ended
because the baseline followed it did not clear, and says what it was taken for: without
temperature topic the oil thinning (``oil_follow``: a fall of friction), with it the torque
measurement drifting with the oil temperature (``gain_follow``, the drift learnt).
The stamps are the inputs' (a clock restarted since can put the clearing before the onset).
"""

from __future__ import annotations

import math

from .monitor_state import ERROR, OK, WARN

__all__ = ['FOLLOWED', 'LastAlarm']

FOLLOWED = {'oil': 'taken for the oil thinning (friction baseline followed)',
            'drift': "taken for the torque measurement's drift with the oil temperature "
                     '(drift learnt)'}
"""What an alarm the baseline followed was taken for: `LastAlarm.followed`'s values."""


class LastAlarm:
    """The monitor's last alarm, under way or cleared."""

    def __init__(self) -> None:
        self.clear()

    def clear(self) -> None:
        """Forget the last alarm (none since)."""
        self.onset_s = math.nan
        """Close of the window that raised it [s]; NaN: no alarm since the reset."""
        self.cleared_s = math.nan
        """Close of the window it cleared (or was followed) on [s]; NaN while it lasts."""
        self.followed = ''
        """'' (cleared, or under way), or the `FOLLOWED` key of what the baseline followed
        when it ended."""
        self.level = OK
        """The highest level it reached (WARN or ERROR; OK: none)."""
        self.cusum_nm_s = 0.0
        """Its highest CUSUM, max(S+, S-) [N m s]: its height."""
        self.verdict = ''
        """`attribution.Verdict` value at its height."""
        self.words = ''
        """That verdict's words (the status message's)."""
        self.valve_plate_scale = math.nan
        """Valve-plate scale at its height [-]."""
        self.valve_plate_scale_std = math.nan
        """Its std [-]."""

    def during(self, onset_s: float, level: int, cusum_nm_s: float, verdict: str, words: str,
               valve_plate_scale: float, valve_plate_scale_std: float) -> None:
        """
        Take a window in alarm.

        Parameters
        ----------
        onset_s : float
            The alarm's onset (``WearMonitor.alarm_onset_s``) [s]; where none is under way
            (`active`), a new last alarm starts.
        level : int
            WARN or ERROR.
        cusum_nm_s : float
            max(S+, S-) [N m s]: at or above the highest so far, the reading is taken.
        verdict : str
            The isolation's verdict (`attribution.Verdict` value).
        words : str
            Its words.
        valve_plate_scale, valve_plate_scale_std : float
            The valve-plate scale and its std [-].

        """
        if not self.active:
            self.onset_s, self.level, self.cusum_nm_s = onset_s, level, -math.inf
            self.cleared_s, self.followed = math.nan, ''
        self.level = max(self.level, level)
        if cusum_nm_s >= self.cusum_nm_s:
            self.cusum_nm_s, self.verdict, self.words = cusum_nm_s, verdict, words
            self.valve_plate_scale, self.valve_plate_scale_std = \
                valve_plate_scale, valve_plate_scale_std

    def end(self, t_s: float, followed: str = '') -> None:
        """
        End the alarm under way, if one is, at ``t_s`` [s].

        Parameters
        ----------
        t_s : float
            Close of the window that cleared it, or that the baseline followed it on [s].
        followed : str
            '' (cleared), or what the baseline followed instead of alarming (a `FOLLOWED`
            key).

        """
        if self.active:
            self.cleared_s, self.followed = t_s, followed

    @property
    def active(self) -> bool:
        """Return whether the alarm is under way (raised, not cleared)."""
        return self.level != OK and math.isnan(self.cleared_s)

    @property
    def verdict_under_way(self) -> str:
        """Return the verdict at the height of the alarm under way ('' where none is)."""
        return self.verdict if self.active else ''

    def note(self) -> str:
        """Return the cleared last alarm in words for the status message, or ''."""
        if self.level == OK or self.active:
            return ''
        name = 'ERROR' if self.level == ERROR else 'WARN'
        how = FOLLOWED[self.followed] if self.followed else 'cleared'
        return f'last alarm {name} {self.onset_s:.1f}-{self.cleared_s:.1f} s, {how}: {self.words}'

    def state(self) -> dict[str, object]:
        """Return the last alarm as plain values."""
        return {'onset_s': float(self.onset_s), 'cleared_s': float(self.cleared_s),
                'followed': self.followed, 'level': int(self.level),
                'cusum_nm_s': float(self.cusum_nm_s), 'verdict': self.verdict,
                'words': self.words,
                'valve_plate_scale': float(self.valve_plate_scale),
                'valve_plate_scale_std': float(self.valve_plate_scale_std)}

    def load(self, state: dict[str, object]) -> None:
        """
        Restore what `state` returned.

        Parameters
        ----------
        state : dict
            A `state` result.

        Raises
        ------
        ValueError
            A level that is not OK, WARN or ERROR, text that is not text, an alarm without
            a finite onset or with an infinite clearing (NaN: under way), ``followed`` not
            '' or a `FOLLOWED` key (nor a bool: the oil's or none, as files wrote it before).

        """
        level, followed = state['level'], state.get('followed', '')
        if type(followed) is bool:  # a file of 3b1f855-671d6f4: the oil follow, the only one
            followed = 'oil' if followed else ''
        onset, cleared, cusum, scale, std = (float(state[key]) for key in (  # type: ignore
            'onset_s', 'cleared_s', 'cusum_nm_s', 'valve_plate_scale', 'valve_plate_scale_std'))
        verdict, words = state['verdict'], state['words']
        if level not in (OK, WARN, ERROR) or type(level) is not int or \
                not isinstance(verdict, str) or not isinstance(words, str) or \
                not (followed == '' or followed in FOLLOWED):
            raise ValueError(f'last alarm: level {level!r}, its words or followed {followed!r}')
        if level != OK and not (math.isfinite(onset) and not math.isinf(cleared)):
            raise ValueError(f'last alarm: onset {onset!r}, cleared {cleared!r}')
        self.onset_s, self.cleared_s, self.level, self.cusum_nm_s = onset, cleared, level, cusum
        self.followed, self.verdict, self.words = followed, verdict, words
        self.valve_plate_scale, self.valve_plate_scale_std = scale, std
