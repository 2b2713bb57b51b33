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
What the wear monitor has learnt, as plain values: the node keeps it across restarts.

(With the monitor's settings and trace records, `MonitorSettings` and `MonitorTrace`.)

`MonitorPersistence` is the part of ``monitor.WearMonitor`` that writes its state out and
reads it back (the node's ``baseline_file``, docs/node.md): the baseline's sums and
whether it is complete, the CUSUM sums, the level and the EWMA, the isolation's sums; not
the open window (a fraction of a second). A state of another layout or a malformed one is
refused and changes nothing.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import NamedTuple, TYPE_CHECKING

import numpy as np

from .attribution import DETECTED_CAUSES
from .baseline import read_count, read_sums
from .oil_follow import followed

if TYPE_CHECKING:
    from .attribution import FaultIsolation
    from .baseline import Baseline, BaselineLearner
    from .commissioning import Commissioning
    from .gain_follow import GainFollow
    from .last_alarm import LastAlarm
    from .oil_follow import OilFollow
    from .warm_up_hold import WarmUpHold

__all__ = ['ERROR', 'OK', 'WARN', 'MonitorPersistence', 'MonitorSettings', 'MonitorTrace']

OK, WARN, ERROR = 0, 1, 2


class MonitorTrace(NamedTuple):
    """The monitor's state after each of many samples (`WearMonitor.update_many`)."""

    level: list[int]
    cusum_pos_nm_s: list[float]
    cusum_neg_nm_s: list[float]
    valve_plate_scale: list[float]  # `WearMonitor.theta_vp`
    other_scale: list[float]  # `WearMonitor.theta_rest`
    valve_plate_scale_std: list[float]
    other_scale_std: list[float]


@dataclass(frozen=True)
class MonitorSettings:
    """The node parameters of the detection (declared in ``node_parameters``)."""

    ewma_time_constant_s: float
    cusum_drift_nm: float
    cusum_baseline_sigmas: float
    cusum_warn_nm_s: float
    cusum_error_nm_s: float
    cusum_clear_ratio: float
    baseline_learn_s: float
    baseline_settle_time_constant_s: float
    torque_constant_drift_max_per_k: float
    warm_up_pause_s: float


class MonitorPersistence:
    """The wear monitor's `state_dict` / `load_state_dict` (a mixin of ``WearMonitor``)."""

    STATE_VERSION = 3
    """Version of `state_dict`'s layout; `load_state_dict` refuses others (3: the baseline
    learns the rotor inertia)."""

    commissioning: Commissioning
    isolation: FaultIsolation
    baseline: Baseline | None
    samples: int
    windows: int
    ewma_nm: float
    alarm_onset_s: float
    change_start_s: float
    last_alarm: LastAlarm
    level: int
    cusum_pos_nm_s: float
    cusum_neg_nm_s: float
    theta_vp: float
    theta_rest: float
    valve_plate_scale_std: float
    rest_scale_std: float
    _var: float
    _pos: np.ndarray
    _neg: np.ndarray
    _allowance_nm_s: float
    _gain_allowance_nm_s: float
    _allowance_s: float
    _recent_s2: np.ndarray
    _recent_s: float

    _follow: OilFollow | None
    _gain_follow: GainFollow | None
    _hold: WarmUpHold | None

    @property
    def learner(self) -> BaselineLearner:
        """Return the commissioning's sums (all of its stationary windows)."""
        return self.commissioning.learner

    @property
    def fit(self) -> Baseline:
        """Return the commissioning's fit so far (the baseline, once complete)."""
        return self.commissioning.fit

    def _set_signatures(self) -> None:
        raise NotImplementedError

    def _open(self, sign: float) -> None:
        raise NotImplementedError

    def _publish_fit(self) -> None:
        raise NotImplementedError

    def state_dict(self) -> dict[str, object]:
        """
        Return what the monitor has learnt, as plain JSON-able values (persisted by the node).

        The baseline's sums (and whether it is complete), the CUSUM sums, level and EWMA,
        the last alarm (``last_alarm``), the isolation's sums, and how far the friction
        baseline followed the oil (``oil_follow``, where the viscosity is assumed) or the
        torque measurement's drift learnt with the oil temperature (``gain_follow``, where
        it is measured); not the open window (a fraction of a second).

        Returns
        -------
        dict
            ``version`` and the learnt state; `load_state_dict` restores it exactly.

        """
        return {'version': self.STATE_VERSION, 'samples': self.samples,
                'windows': self.windows, 'commissioning': self.commissioning.state(),
                'baseline_complete': self.baseline is not None,
                'ewma_nm': float(self.ewma_nm), 'ewma_var_nm2': float(self._var),
                'cusum_pos_nm_s': self._pos.tolist(), 'cusum_neg_nm_s': self._neg.tolist(),
                'level': int(self.level), 'alarm_onset_s': float(self.alarm_onset_s),
                'change_start_s': float(self.change_start_s),
                'last_alarm': self.last_alarm.state(), 'isolation': self.isolation.state(),
                'allowance_nm_s': float(self._allowance_nm_s),
                'gain_allowance_nm_s': float(self._gain_allowance_nm_s),
                'allowance_s': float(self._allowance_s),
                'recent_signature_s2': self._recent_s2.tolist(),
                'recent_running_s': float(self._recent_s),
                **({'oil_follow': self._follow.state()} if self._follow is not None else {}),
                **({'gain_follow': self._gain_follow.state()}
                   if self._gain_follow is not None else {}),
                **({'warm_up_hold': self._hold.state()} if self._hold is not None else {})}

    def load_state_dict(self, state: dict[str, object]) -> None:
        """
        Restore what `state_dict` returned.

        Parameters
        ----------
        state : dict
            A `state_dict` result (e.g. read back from the node's baseline file).

        Raises
        ------
        ValueError
            A state of another version, or missing or malformed entries (the monitor is
            then left as it was).

        """
        if not isinstance(state, dict) or state.get('version') != self.STATE_VERSION:
            version = state.get('version') if isinstance(state, dict) else None
            raise ValueError(f'monitor state version {version!r}, expected '
                             f'{self.STATE_VERSION}')
        saved = self.state_dict()
        try:
            self._load(state)
        # a hand-edited file: the wrong kind of value (a list where a mapping goes), a
        # number past a double's range (10**400) or an infinite count (.inf)
        except (KeyError, TypeError, ValueError, IndexError, AttributeError,
                ArithmeticError) as exc:
            self._load(saved)
            raise ValueError(f'malformed monitor state: {exc}') from None

    def _load(self, state: dict[str, object]) -> None:
        self.commissioning.load(state['commissioning'])  # type: ignore[arg-type]
        self.isolation.load(state['isolation'])  # type: ignore[arg-type]
        self.samples = read_count(state, 'samples', 'monitor')
        self.windows = read_count(state, 'windows', 'monitor')
        complete = state['baseline_complete']
        if not isinstance(complete, bool):
            raise ValueError(f'baseline_complete {complete!r}: not true or false')
        self.baseline = self.fit if complete else None
        if self._follow is not None:  # came later: a file without it has followed nothing
            self._follow.reset()
            if self.baseline is not None and 'oil_follow' in state:
                self._follow.load(state['oil_follow'])  # type: ignore[arg-type]
                self.baseline = followed(self.baseline, self._follow.factors)
        if self._gain_follow is not None:  # came later too: a file without it learnt none
            self._gain_follow.reset()
            if self.baseline is not None and 'gain_follow' in state:
                self._gain_follow.load(state['gain_follow'])  # type: ignore[arg-type]
        if self._hold is not None:  # came later too: a file without it saw no oil move,
            self._hold.forget()  # and how long ago its last window was is not known
            if 'warm_up_hold' in state:
                self._hold.load(state['warm_up_hold'])  # type: ignore[arg-type]
            elif self.baseline is not None:
                self._hold.arm('after a restart from a baseline file without its time')
        ewma, var, onset = (float(state[key]) for key in (  # type: ignore[arg-type]
            'ewma_nm', 'ewma_var_nm2', 'alarm_onset_s'))
        pos = np.asarray(state['cusum_pos_nm_s'], dtype=float)
        neg = np.asarray(state['cusum_neg_nm_s'], dtype=float)
        if pos.shape != (len(DETECTED_CAUSES),) or neg.shape != pos.shape or not (
                np.all(np.isfinite(pos)) and np.all(np.isfinite(neg))
                and math.isfinite(ewma) and math.isfinite(var)):
            raise ValueError('monitor sums of the wrong shape or not finite')
        if var < 0.0 or np.any(pos < 0.0) or np.any(neg < 0.0):
            raise ValueError('monitor variance or CUSUM sums negative')
        # the oil allowance's sums came later: a file without them starts them afresh
        allowance = [float(state.get(key, 0.0))  # type: ignore[arg-type]
                     for key in ('allowance_nm_s', 'gain_allowance_nm_s', 'allowance_s')]
        if not all(math.isfinite(x) and x >= 0.0 for x in allowance):
            raise ValueError('monitor allowance sums negative or not finite')
        self._allowance_nm_s, self._gain_allowance_nm_s, self._allowance_s = allowance
        # so did the recent points' signature sums: without them, commissioning's points
        n = len(DETECTED_CAUSES)
        s2, running = np.zeros((n, n)), 0.0
        if 'recent_running_s' in state or 'recent_signature_s2' in state:  # both, or refused
            (s2,), (running,) = read_sums(state, {'recent_signature_s2': (n, n)},
                                          ('recent_running_s',), 'recent signature')
        # a forgotten sum of outer products: symmetric, its diagonal >= 0, Cauchy-Schwarz
        rms = np.sqrt(np.maximum(np.diag(s2), 0.0))
        if np.any(np.diag(s2) < 0.0) or np.any(s2 != s2.T) or np.any(
                np.abs(s2) > (1.0 + 1e-9) * np.outer(rms, rms)):
            raise ValueError('recent signature sums not a sum of products')
        self._recent_s2, self._recent_s = s2, running
        self._set_signatures()
        self.ewma_nm, self._var, self.alarm_onset_s = ewma, var, onset
        # came later: from a file without it, a change under way is dated from the next
        # window; a start without the isolation's windows (or not finite) dates nothing
        start = float(state.get('change_start_s', math.nan))  # type: ignore[arg-type]
        held = math.isfinite(start) and self.isolation.stats.windows > 0
        self.change_start_s = start if held else math.nan
        self._pos, self._neg = pos, neg
        self.cusum_pos_nm_s, self.cusum_neg_nm_s = float(pos.max()), float(neg.max())
        level = state['level']  # an integer as written: 1.7, '2' or true are not levels
        if isinstance(level, bool) or not isinstance(level, int) or \
                level not in (OK, WARN, ERROR):
            raise ValueError(f'monitor level {level!r}')
        self.level = level
        if 'last_alarm' in state:  # came later: a file without it has kept none
            self.last_alarm.load(state['last_alarm'])  # type: ignore[arg-type]
        else:
            self.last_alarm.clear()
        self._open(0.0)
        self._publish_fit()
