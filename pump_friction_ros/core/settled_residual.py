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
from typing import Any, NamedTuple

import numpy as np

from .lowpass import run_two_stage, stage_coefficients

__all__ = ['Released', 'SettledResidual', 'release_settled']


class Released(NamedTuple):
    """
    The samples the settle gate released during a chunk, in release order.

    The first ``len(carried)`` were queued in an earlier chunk: their payloads are the
    tuples in ``carried`` and their ``sources`` are -1. The payload of each other one is
    its position in the chunk, ``sources``.
    """

    positions: np.ndarray
    """Chunk positions of the samples that released them."""
    stamps_ns: np.ndarray
    """Their times [ns]."""
    filtered_nm: np.ndarray
    """Their filtered difference LP(measured - static expected) [N m]."""
    sources: np.ndarray
    """Their chunk positions (-1: queued in an earlier chunk)."""
    carried: list[Any]
    """Payloads of those queued in an earlier chunk."""


def release_settled(stamps_ns: np.ndarray, opportunity: np.ndarray, queued: np.ndarray,
                    values: np.ndarray, carried: list[tuple[int, float, Any]],
                    lookahead_ns: int
                    ) -> tuple[Released, list[tuple[int, float, Any]], np.ndarray] | None:
    """
    Release a chunk's settled samples, first in first out, over arrays: `update`'s queue.

    Each sample that may release one releases at most the oldest queued sample, once it is
    ``lookahead_ns`` old. So the k-th queued sample of a steady run leaves at the sample
    d_k = max(f_k, d_k-1 + 1), f_k being the first sample far enough after it: a running
    maximum of f_k - k (numpy's ``maximum.accumulate``, offset per run).

    Parameters
    ----------
    stamps_ns : ndarray of int64
        Sample times [ns] (samples with a measured torque only).
    opportunity : ndarray of bool
        Samples that may release one (filtered and steady); every other sample empties
        the queue.
    queued : ndarray of bool
        Opportunities that join the queue (settled long enough), before their own release
        check.
    values : ndarray of float
        Filtered difference after each sample [N m].
    carried : list of tuple
        The queue before the chunk: (stamp [ns], filtered difference [N m], payload).
    lookahead_ns : int
        Steady running needed after a queued sample before it is released [ns].

    Returns
    -------
    tuple or None
        The releases (positions and sources in these arrays); the carried samples still
        queued at the end; the positions of this chunk's samples still queued at the end,
        if the last sample may release. None where the stamps of the opportunities go back
        (a clock restart between runs): the loop handles that.

    """
    opp = np.flatnonzero(opportunity)
    opp_stamps = stamps_ns[opp]
    if opp.size > 1 and bool(np.any(opp_stamps[1:] < opp_stamps[:-1])):
        return None
    empty = np.zeros(0, dtype=np.int64)
    new_run = np.ones(opp.size, dtype=bool)  # runs of consecutive opportunities
    new_run[1:] = opp[1:] != opp[:-1] + 1
    run_of_opp = np.cumsum(new_run) - 1
    run_last = np.append(np.flatnonzero(new_run)[1:], opp.size) - 1
    carry = carried if opp.size and opp[0] == 0 else []
    mine = np.flatnonzero(queued)
    m = len(carry) + mine.size
    if not m:
        return Released(empty, empty, np.zeros(0), empty, []), [], empty
    elem_stamps = np.concatenate((np.array([s for s, _, _ in carry], dtype=np.int64),
                                  stamps_ns[mine]))
    elem_opp = np.concatenate((np.zeros(len(carry), dtype=np.int64),
                               np.searchsorted(opp, mine)))
    runs = run_of_opp[elem_opp]
    first = np.maximum(np.searchsorted(opp_stamps, elem_stamps + lookahead_ns), elem_opp)
    first = np.minimum(first, run_last[runs] + 1)
    run_start = np.flatnonzero(np.concatenate(([True], runs[1:] != runs[:-1])))
    k = np.arange(m) - np.repeat(run_start, np.diff(np.append(run_start, m)))
    offset = runs * (4 * (opp.size + m + 1))
    leave = np.maximum.accumulate(first - k + offset) - offset + k
    out = leave <= run_last[runs]
    at_end = ~out & (run_last[runs] == opp.size - 1) & (opp[-1] == stamps_ns.size - 1)
    n_carry = len(carry)
    n_out_carry = int(np.count_nonzero(out[:n_carry]))
    sources = np.concatenate((np.full(n_carry, -1, dtype=np.int64), mine))
    elem_values = np.concatenate((np.array([v for _, v, _ in carry], dtype=float),
                                  values[mine]))
    released = Released(opp[leave[out]], elem_stamps[out], elem_values[out], sources[out],
                        [p for _, _, p in carry[:n_out_carry]])
    left = [c for c, end in zip(carry, at_end[:n_carry].tolist(), strict=True) if end]
    return released, left, mine[at_end[n_carry:]]


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
        self._lp1 = b * lp1_old + (a * x_prev + c * (diff_nm - x_prev))
        self._lp2 = b * self._lp2 + (a * lp1_old + c * (self._lp1 - lp1_old))
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

    def update_many(self, stamps_ns: np.ndarray, restarts: np.ndarray, diffs_nm: np.ndarray,
                    steady: np.ndarray, payloads: Sequence[np.ndarray]) -> Released:
        """
        Take many samples in order: `update` for each (the chunk path).

        The same operations in the same order as `update`: results and state are identical
        (``test_chunk_path``, ``test_lowpass``). Over arrays where the samples come evenly
        spaced (`lowpass.run_two_stage`, `release_settled`), else in one loop.

        Parameters
        ----------
        stamps_ns : ndarray of int64
            Sample times [ns].
        restarts : ndarray of int64
            The speed filter's ``restarts`` after each sample.
        diffs_nm : ndarray of float
            Measured - static expected torque [N m] (NaN: none).
        steady : ndarray of bool
            Above the minimum speed and below the acceleration limit.
        payloads : sequence of ndarray
            The payload's columns: sample i's payload is the tuple of their i-th items.

        Returns
        -------
        Released
            The samples released during the chunk, in order.

        """
        stamps = np.asarray(stamps_ns, dtype=np.int64)
        counts = np.asarray(restarts, dtype=np.int64)
        diffs = np.asarray(diffs_nm, dtype=float)
        ok = np.asarray(steady, dtype=bool)
        released = self._arrays(stamps, counts, diffs, ok, payloads) if stamps.size else None
        if released is not None:
            return released
        positions, out = self._loop(stamps.tolist(), counts.tolist(), diffs.tolist(),
                                    ok.tolist(), payloads)
        carried = [payload for _, _, payload in out if not isinstance(payload, int)]
        return Released(np.array(positions, dtype=np.int64),
                        np.array([stamp for stamp, _, _ in out], dtype=np.int64),
                        np.array([value for _, value, _ in out], dtype=float),
                        np.array([-1] * len(carried) + [p for _, _, p in out[len(carried):]],
                                 dtype=np.int64), carried)

    def _arrays(self, stamps: np.ndarray, counts: np.ndarray, diffs: np.ndarray,
                ok: np.ndarray, payloads: Sequence[np.ndarray]) -> Released | None:
        """`update_many` over arrays; None (nothing changed) where the loop must do it."""
        n = stamps.size
        valid = diffs == diffs
        where = np.flatnonzero(valid)
        if not where.size:
            return None
        after_nan = np.zeros(n, dtype=bool)  # the sample before was NaN: a run ends there
        after_nan[1:] = ~valid[:-1]
        v_stamps, v_counts, x = stamps[where], counts[where], diffs[where]
        last = self._last_ns
        prev_stamps = np.diff(v_stamps, prepend=v_stamps[0] if last is None else last)
        prev_counts = np.diff(v_counts, prepend=self._restarts)
        start = after_nan[where] | (prev_counts != 0) | (prev_stamps <= 0) | \
            (prev_stamps > self.max_gap_ns)
        if last is None or where[0] != 0:
            start[0] = True
        run = run_two_stage(v_stamps, x, start, 0 if last is None else last,
                            (self._lp1, self._lp2, self._x_prev), self._step_ns,
                            self._coefficients, self.tau_s)
        if run is None:
            return None
        v_ok = ok[where]
        resets = start | ~v_ok
        opportunity = ~resets
        reset_at = np.flatnonzero(resets)
        latest = np.searchsorted(reset_at, np.arange(where.size), side='right') - 1
        since_at = np.append(v_stamps[reset_at], self._steady_since_ns)  # -1: before
        since = since_at[latest]
        queued = opportunity & (v_stamps - since >= self.settle_ns)
        gate = release_settled(v_stamps, opportunity, queued, run.lp2, list(self.pending),
                               self.lookahead_ns)
        if gate is None:
            return None
        released, carried_left, still = gate
        # the state `update` leaves: the last valid sample's, the queue as it stands
        self._lp1, self._lp2, self._x_prev = float(run.lp1[-1]), float(run.lp2[-1]), float(x[-1])
        self._step_ns, self._coefficients = run.step_ns, run.coefficients
        self._last_ns = int(stamps[-1]) if valid[-1] else None
        starts = np.flatnonzero(start)
        if starts.size:
            self._restarts = int(v_counts[starts[-1]])
        if reset_at.size:
            self._steady_since_ns = int(v_stamps[reset_at[-1]])
        pending = self.pending
        pending.clear()
        if valid[-1]:
            pending.extend(carried_left)
            positions = where[still]
            values = run.lp2[still].tolist()
            columns = [np.asarray(column)[positions].tolist() for column in payloads]
            pending.extend(zip(stamps[positions].tolist(), values, zip(*columns, strict=True),
                               strict=True))
        sources = np.where(released.sources >= 0, where[released.sources], -1)
        return released._replace(positions=where[released.positions], sources=sources)

    def _loop(self, stamps_ns: list[int], restarts: list[int], diffs_nm: list[float],
              steady: list[bool], payloads: Sequence[Any]
              ) -> tuple[list[int], list[tuple[int, float, Any]]]:
        """
        `update` for each sample in one loop: `update_many` where the spacing varies.

        Returns the positions of the samples that released one, and what each released:
        (stamp, filtered difference, payload) where the payload of a sample of this call is
        its position (an int: the columns hold it), that of an earlier call's sample its
        tuple. Samples still pending at the end keep their tuples.
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
            lp1 = b * lp1_old + (a * x_prev + c * (x - x_prev))
            lp2 = b * lp2 + (a * lp1_old + c * (lp1 - lp1_old))
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
                pending[k] = (stamp, lp, tuple(float(column[payload]) for column in payloads))
        self._lp1, self._lp2, self._x_prev = lp1, lp2, x_prev
        self._step_ns, self._coefficients = step_prev, (b, a, c)
        self._last_ns, self._restarts, self._steady_since_ns = last, seen, since
        return positions, released
