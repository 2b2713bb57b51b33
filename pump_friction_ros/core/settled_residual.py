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
The residual the wear monitor takes: measured torque aligned with the model, in steady running.

The expected torque's inertia part is J times the derivative of the speed through two
first-order low-pass stages (``speed_filter``): the true J a delayed and smoothed by
those stages. The measured torque holds the true J a undelayed. Subtracting the two leaves
J (a - a_filtered), which at every acceleration onset is of the order of J a: 1-2.5 N m on
an EHA rotor of 5e-4 to 1e-3 kg m^2, and under a position loop's exponential approach
(a proportional to the remaining error, decaying with the loop's time constant T) a bias
of about J (2 tau / T) a that no acceleration gate removes.

Here the measured torque minus the *static* expected torque (theoretical + friction +
drive loss, no inertia) goes through the same two stages as the speed. The stages are
linear and time-invariant, so they commute with d/dt: LP(J d(omega)/dt) = J d(LP omega)/dt
= J a_filtered. The monitored residual

    r = LP(T_measured - T_static) - J a_filtered = LP(T_measured - T_static - J a)

is the true residual through the low-pass, with no inertia leak, whatever the motion (up to
the sampling: the stages see the torque samples linearly interpolated, the speed's
derivative piecewise constant; the difference is a transient of a sample period at a jerk).
That transient, and the start of the filters after a restart, decay as (1 + t/tau)
exp(-t/tau); the monitor takes a sample only where the running has been steady (above the
minimum speed, below the acceleration limit, torque fresh, filters running) for
``monitor_settle_s`` before it and ``monitor_lookahead_s`` after it (the filtered
acceleration needs a few milliseconds to see a jerk). The monitor's samples therefore come
``monitor_lookahead_s`` late, which is nothing against its windows of a quarter second.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from typing import Any

from .speed_filter import stage_coefficients

__all__ = ['SettledResidual']


class SettledResidual:
    """
    Low-pass (measured - static expected) torque, released where the running was steady.

    A sample is released to the monitor once the steady run that holds it began at least
    ``settle_s`` before it and has gone on for ``lookahead_s`` after it: the filtered
    acceleration lags a jerk by a few milliseconds, and the samples just after a jerk,
    which carry its sampling transient, are not taken before the gate has seen it.

    Parameters
    ----------
    tau_s : float
        Time constant of each of the two stages [s]: the speed filter's.
    max_gap_ns : int
        A longer gap between samples restarts the filter (as the speed filter's).
    settle_s : float
        Steady running needed before a sample [s].
    lookahead_s : float
        Steady running needed after a sample [s].

    """

    def __init__(self, tau_s: float, max_gap_ns: int, settle_s: float,
                 lookahead_s: float) -> None:
        self.tau_s = tau_s
        self.max_gap_ns = max_gap_ns
        self.settle_ns = round(settle_s * 1e9)
        self.lookahead_ns = round(lookahead_s * 1e9)
        self.pending: deque[tuple[int, float, Any]] = deque()
        self.reset()

    def reset(self) -> None:
        """Forget the state: the next sample restarts the filter."""
        self._lp1 = self._lp2 = self._x_prev = 0.0
        self._step_ns = -1
        self._coefficients = (0.0, 0.0, 0.0)
        self._last_ns: int | None = None
        self._restarts = -1
        self._steady_since_ns = 0
        self.pending.clear()

    def update(self, stamp_ns: int, restarts: int, diff_nm: float, steady: bool,
               payload: Any) -> tuple[int, float, Any] | None:
        """
        Take one sample; return the one now confirmed settled, if any.

        Parameters
        ----------
        stamp_ns : int
            Sample time [ns].
        restarts : int
            The speed filter's ``restarts`` after this sample: a change restarts this one.
        diff_nm : float
            Measured - static expected torque [N m]; NaN without a fresh measured torque.
        steady : bool
            Above the minimum speed and below the acceleration limit.
        payload : object
            What the monitor needs of this sample, handed back on release.

        Returns
        -------
        tuple or None
            (stamp [ns], LP(measured - static expected) [N m], payload) of the sample
            released by this one (at most one), or None.

        """
        last = self._last_ns
        pending = self.pending
        if diff_nm != diff_nm:  # no measured torque: the run ends here
            self._last_ns = None
            pending.clear()
            return None
        self._last_ns = stamp_ns
        if last is None or restarts != self._restarts or \
                not 0 < stamp_ns - last <= self.max_gap_ns:
            self._lp1 = self._lp2 = self._x_prev = diff_nm  # (re)start
            self._restarts = restarts
            self._steady_since_ns = stamp_ns
            pending.clear()
            return None
        step_ns = stamp_ns - last
        if step_ns != self._step_ns:
            self._coefficients = stage_coefficients(step_ns * 1e-9, self.tau_s)
            self._step_ns = step_ns
        b, a, c = self._coefficients
        lp1_old = self._lp1
        x_prev = self._x_prev
        self._lp1 = b * lp1_old + a * x_prev + c * (diff_nm - x_prev)
        self._lp2 = b * self._lp2 + a * lp1_old + c * (self._lp1 - lp1_old)
        self._x_prev = diff_nm
        if not steady:
            self._steady_since_ns = stamp_ns
            pending.clear()
            return None
        if stamp_ns - self._steady_since_ns >= self.settle_ns:
            pending.append((stamp_ns, self._lp2, payload))
        if pending and stamp_ns - pending[0][0] >= self.lookahead_ns:
            return pending.popleft()
        return None

    def update_many(self, stamps_ns: list[int], restarts: list[int], diffs_nm: list[float],
                    steady: list[bool], payloads: Sequence[list[Any]]
                    ) -> tuple[list[int], list[tuple[int, float, Any]]]:
        """
        Take many samples in order: `update` for each, in one loop (the chunk path).

        The same operations in the same order as `update`: results and state are identical.

        Parameters
        ----------
        stamps_ns : list of int
            Sample times [ns].
        restarts : list of int
            The speed filter's ``restarts`` after each sample.
        diffs_nm : list of float
            Measured - static expected torque [N m] (NaN: none).
        steady : list of bool
            Above the minimum speed and below the acceleration limit.
        payloads : sequence of list
            The payload's columns: sample i's payload is the tuple of their i-th items.

        Returns
        -------
        tuple of list
            The positions of the samples that released one, and what each released:
            (stamp, filtered difference, payload) where the payload of a sample of this
            call is its position (an int: the columns hold it), that of an earlier call's
            sample its tuple. Samples still pending at the end keep their tuples.

        """
        tau, max_gap = self.tau_s, self.max_gap_ns
        settle, lookahead = self.settle_ns, self.lookahead_ns
        lp1, lp2, x_prev = self._lp1, self._lp2, self._x_prev
        step_prev, (b, a, c) = self._step_ns, self._coefficients
        last, seen, since = self._last_ns, self._restarts, self._steady_since_ns
        pending = self.pending
        positions: list[int] = []
        released: list[tuple[int, float, Any]] = []
        samples = zip(stamps_ns, restarts, diffs_nm, steady, strict=True)
        for i, (stamp, count, x, ok) in enumerate(samples):
            if x != x:
                last = None
                pending.clear()
                continue
            prev, last = last, stamp
            if prev is None or count != seen or not 0 < stamp - prev <= max_gap:
                lp1 = lp2 = x_prev = x
                seen = count
                since = stamp
                pending.clear()
                continue
            step = stamp - prev
            if step != step_prev:
                b, a, c = stage_coefficients(step * 1e-9, tau)
                step_prev = step
            lp1_old = lp1
            lp1 = b * lp1_old + a * x_prev + c * (x - x_prev)
            lp2 = b * lp2 + a * lp1_old + c * (lp1 - lp1_old)
            x_prev = x
            if not ok:
                since = stamp
                pending.clear()
                continue
            if stamp - since >= settle:
                pending.append((stamp, lp2, i))
            if pending and stamp - pending[0][0] >= lookahead:
                positions.append(i)
                released.append(pending.popleft())
        for k, (stamp, lp, payload) in enumerate(pending):  # they outlive the columns
            if isinstance(payload, int):
                pending[k] = (stamp, lp, tuple(column[payload] for column in payloads))
        self._lp1, self._lp2, self._x_prev = lp1, lp2, x_prev
        self._step_ns, self._coefficients = step_prev, (b, a, c)
        self._last_ns, self._restarts, self._steady_since_ns = last, seen, since
        return positions, released
