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
Filtered shaft acceleration: two first-order low-pass stages and the derivative of the second.

Each stage is the exact discretisation of tau y' = x - y for an input linear between samples
(first-order hold): y_k = b y_k-1 + a x_k-1 + c (x_k - x_k-1), with b = exp(-dt / tau),
a = 1 - b, c = 1 - tau a / dt. A ramp then lags by exactly tau per stage at any sample
spacing, and (lp1 - lp2) / tau is the slope of lp2. The estimator runs the scalar form
(`SpeedFilter`) sample by sample; the calibration runs the array form (`filter_two_stage`,
`lowpass.run_two_stage`) over a record. Both are the same recursion (tested equal).
"""

from __future__ import annotations

from typing import cast

import numpy as np

from .lowpass import run_two_stage, stage_coefficients, TwoStage

__all__ = ['SpeedFilter', 'filter_two_stage', 'stage_coefficients']  # the last: lowpass's


class SpeedFilter:
    """
    Two low-pass stages of the shaft speed and the filtered acceleration, sample by sample.

    Parameters
    ----------
    tau_s : float
        Time constant of each stage [s].
    max_gap_ns : int
        A gap longer than this between samples restarts the filter (no derivative across);
        so does a step back in time (the source's clock restarted, see the estimator's
        ``stamp_resync_samples``).

    """

    def __init__(self, tau_s: float, max_gap_ns: int) -> None:
        self.tau_s = tau_s
        self.max_gap_ns = max_gap_ns
        self.reset()

    def reset(self) -> None:
        """Forget the state: the next sample restarts the filter at rest."""
        self._lp1 = self._lp2 = self._x_prev = 0.0
        self._step_ns = -1
        self._coefficients = (0.0, 0.0, 0.0)
        self._last_ns: int | None = None
        self.accel_rad_s2 = 0.0
        self.restarts = 0
        """(Re)starts so far: a filter that follows this one (``settled_residual``) restarts
        with it."""

    def update(self, stamp_ns: int, speed_rad_s: float) -> float:
        """
        Take one speed sample and return the filtered acceleration.

        Stamps normally increase; a gap above ``max_gap_ns`` or a step that is not forward
        (a clock restart) restarts the filter at rest on this sample.

        Parameters
        ----------
        stamp_ns : int
            Sample time [ns].
        speed_rad_s : float
            Shaft speed [rad/s].

        Returns
        -------
        float
            Filtered acceleration [rad/s^2]; 0 at a (re)start.

        """
        last = self._last_ns
        self._last_ns = stamp_ns
        if last is None or not 0 < stamp_ns - last <= self.max_gap_ns:
            self._lp1 = self._lp2 = self._x_prev = speed_rad_s  # (re)start at rest
            self.accel_rad_s2 = 0.0
            self.restarts += 1
            return 0.0
        step_ns = stamp_ns - last
        if step_ns != self._step_ns:  # evenly spaced samples: coefficients once
            self._coefficients = stage_coefficients(step_ns * 1e-9, self.tau_s)
            self._step_ns = step_ns
        b, a, c = self._coefficients
        lp1_old = self._lp1
        x_prev = self._x_prev
        self._lp1 = b * lp1_old + (a * x_prev + c * (speed_rad_s - x_prev))
        self._lp2 = b * self._lp2 + (a * lp1_old + c * (self._lp1 - lp1_old))
        self._x_prev = speed_rad_s
        self.accel_rad_s2 = (self._lp1 - self._lp2) / self.tau_s
        return self.accel_rad_s2

    def update_many(self, stamps_ns: np.ndarray, speeds_rad_s: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
        """
        Take many speed samples in order: `update` for each (the chunk path).

        The same operations in the same order as `update`, so the results and the state
        left behind are identical to calling it sample by sample (``test_speed_filter``,
        ``test_lowpass``): over arrays (`lowpass.run_two_stage`) where the samples come
        evenly spaced, else in one loop.

        Parameters
        ----------
        stamps_ns : ndarray of int64
            Sample times [ns].
        speeds_rad_s : ndarray of float
            Shaft speeds [rad/s].

        Returns
        -------
        tuple of ndarray
            Filtered acceleration after each sample [rad/s^2], and `restarts` after each.

        """
        stamps = np.asarray(stamps_ns, dtype=np.int64)
        x = np.asarray(speeds_rad_s, dtype=float)
        if not stamps.size:
            return np.zeros(0), np.zeros(0, dtype=np.int64)
        last = self._last_ns
        steps = np.diff(stamps, prepend=stamps[0] if last is None else last)
        start = (steps <= 0) | (steps > self.max_gap_ns)
        if last is None:
            start[0] = True
        run = run_two_stage(stamps, x, start, 0 if last is None else last,
                            (self._lp1, self._lp2, self._x_prev), self._step_ns,
                            self._coefficients, self.tau_s)
        if run is None:
            looped, restarts = self._loop(stamps.tolist(), x.tolist())
            return np.array(looped), np.array(restarts, dtype=np.int64)
        accel = np.where(start, 0.0, (run.lp1 - run.lp2) / self.tau_s)
        counts = self.restarts + np.cumsum(start)
        self.restarts = int(counts[-1])
        self._last_ns = int(stamps[-1])
        self._step_ns, self._coefficients = run.step_ns, run.coefficients
        self._lp1, self._lp2 = float(run.lp1[-1]), float(run.lp2[-1])
        self._x_prev, self.accel_rad_s2 = float(x[-1]), float(accel[-1])
        return accel, counts

    def _loop(self, stamps_ns: list[int], speeds_rad_s: list[float]
              ) -> tuple[list[float], list[int]]:
        """`update` for each sample in one loop: `update_many` where the spacing varies."""
        tau, max_gap = self.tau_s, self.max_gap_ns
        restarts = self.restarts
        counts: list[int] = []
        count = counts.append
        last, step_prev = self._last_ns, self._step_ns
        lp1, lp2, x_prev, accel = self._lp1, self._lp2, self._x_prev, self.accel_rad_s2
        b, a, c = self._coefficients
        out: list[float] = []
        append = out.append
        for stamp, x in zip(stamps_ns, speeds_rad_s, strict=True):
            if last is None or not 0 < stamp - last <= max_gap:
                lp1 = lp2 = x_prev = x  # (re)start at rest
                accel = 0.0
                restarts += 1
            else:
                step = stamp - last
                if step != step_prev:
                    b, a, c = stage_coefficients(step * 1e-9, tau)
                    step_prev = step
                lp1_old = lp1
                lp1 = b * lp1_old + (a * x_prev + c * (x - x_prev))
                lp2 = b * lp2 + (a * lp1_old + c * (lp1 - lp1_old))
                x_prev = x
                accel = (lp1 - lp2) / tau
            last = stamp
            append(accel)
            count(restarts)
        self.restarts = restarts
        self._last_ns, self._step_ns = last, step_prev
        self._lp1, self._lp2, self._x_prev, self.accel_rad_s2 = lp1, lp2, x_prev, accel
        self._coefficients = (b, a, c)
        return out, counts


def filter_two_stage(x: np.ndarray, dt_s: float, tau_s: float) -> np.ndarray:
    """
    Apply the two low-pass stages to an evenly sampled record, starting at rest on x[0].

    Parameters
    ----------
    x : ndarray
        Samples, evenly spaced in time.
    dt_s : float
        Sample spacing [s].
    tau_s : float
        Time constant of each stage [s].

    Returns
    -------
    ndarray
        The output of the second stage (same unit as ``x``).

    """
    y = np.asarray(x, dtype=float)
    step_ns = max(1, round(dt_s * 1e9))  # the coefficients are dt_s's, given for this step
    start = np.zeros(y.size, dtype=bool)
    start[:1] = True
    run = run_two_stage(np.arange(y.size, dtype=np.int64) * step_ns, y, start, 0,
                        (0.0, 0.0, 0.0), step_ns, stage_coefficients(dt_s, tau_s), tau_s)
    return cast(TwoStage, run).lp2  # one spacing: one run, never left to the loop
