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
The two first-order-hold low-pass stages: their coefficients, and their array form, bit for bit.

Each stage is the exact discretisation of tau y' = x - y for an input linear between samples
(first-order hold): y_k = b y_k-1 + u_k, u_k = a x_k-1 + c (x_k - x_k-1), with
b = exp(-dt / tau), a = 1 - b, c = 1 - tau a / dt. `SpeedFilter` and `SettledResidual` run
it sample by sample in the node. On a chunk of a bag those loops were the replay's slowest
stage (about 1.7 us per joint state together); `run_two_stage` runs the same recursion over
arrays and gives the same floats:

- The input term u is elementwise arithmetic: the same IEEE operations, one element at a
  time.
- The recursion, over a run of samples of one spacing (one b), is scipy's ``lfilter`` with
  numerator [1] and denominator [1, -b]. Its direct form II transposed computes y_k = z + 1 u_k
  and z = 0 u_k - (-b) y_k, so y_k = b y_k-1 + u_k to the last bit; the per-sample code
  writes the sum in that grouping. Tested on numpy 1.26 / scipy 1.11 and the newest
  releases (``test_lowpass``).
- Runs of one sample spacing are what a simulated bag or a fixed-period driver gives.
  Stamps with jitter give runs of a sample or two, where ``lfilter``'s call would cost more
  than the loop: `run_two_stage` then returns None and the caller loops.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ['MIN_RUN', 'TwoStage', 'run_two_stage', 'stage_coefficients']

MIN_RUN = 64
"""Fewest samples per run of one spacing, on average, for the array form to be used."""


def stage_coefficients(dt_s: float, tau_s: float) -> tuple[float, float, float]:
    """
    Return (b, a, c) of one first-order-hold low-pass stage.

    Parameters
    ----------
    dt_s : float
        Sample spacing [s], > 0.
    tau_s : float
        Time constant [s], > 0.

    Returns
    -------
    tuple of float
        b = exp(-dt / tau), a = 1 - b, c = 1 - tau a / dt.

    """
    b = math.exp(-dt_s / tau_s)
    a = 1.0 - b
    return b, a, 1.0 - tau_s * a / dt_s


class TwoStage(NamedTuple):
    """Both stages after each sample, and the spacing and coefficients last used."""

    lp1: np.ndarray
    lp2: np.ndarray
    step_ns: int
    coefficients: tuple[float, float, float]


def run_two_stage(stamps_ns: np.ndarray, x: np.ndarray, start: np.ndarray, last_ns: int,
                  state: tuple[float, float, float], step_ns: int,
                  coefficients: tuple[float, float, float], tau_s: float
                  ) -> TwoStage | None:
    """
    Run both stages over a chunk: the per-sample recursion, bit for bit, or None.

    Parameters
    ----------
    stamps_ns : ndarray of int64
        Sample times [ns]; where ``start`` is False, later than the sample before.
    x : ndarray of float
        Input samples, finite.
    start : ndarray of bool
        Samples where the filter (re)starts at rest (both stages set to x).
    last_ns : int
        Time of the sample before the chunk [ns]: used when ``start[0]`` is False.
    state : tuple of float
        (lp1, lp2, x_prev) before the chunk: used when ``start[0]`` is False.
    step_ns : int
        Spacing of the last filtered sample before the chunk [ns] (-1: none).
    coefficients : tuple of float
        Its (b, a, c).
    tau_s : float
        Time constant of each stage [s].

    Returns
    -------
    TwoStage or None
        None when the runs of one spacing are shorter than `MIN_RUN` samples on average.

    """
    n = x.size
    prev_stamps = np.empty_like(stamps_ns)
    prev_stamps[1:] = stamps_ns[:-1]
    prev_stamps[:1] = last_ns
    steps = stamps_ns - prev_stamps
    filtered = ~start
    # runs: consecutive filtered samples of one spacing
    first = filtered.copy()
    first[1:] &= start[:-1] | (steps[1:] != steps[:-1])
    firsts = np.flatnonzero(first)
    if firsts.size > max(1, n // MIN_RUN):
        return None
    bounds = np.append(np.flatnonzero(start | first), n)
    ends = bounds[np.searchsorted(bounds, firsts, side='right')]
    from scipy.signal import lfilter

    lp1 = np.where(start, x, 0.0)
    lp2 = lp1.copy()
    x_prev = np.empty_like(x)
    x_prev[1:] = x[:-1]
    x_prev[:1] = state[2]
    for i0, i1 in zip(firsts.tolist(), ends.tolist(), strict=True):
        step = int(steps[i0])
        if step != step_ns:
            coefficients = stage_coefficients(step * 1e-9, tau_s)
            step_ns = step
        b, a, c = coefficients
        y1 = float(lp1[i0 - 1]) if i0 else state[0]
        y2 = float(lp2[i0 - 1]) if i0 else state[1]
        xp, xs = x_prev[i0:i1], x[i0:i1]
        out1 = lfilter([1.0], [1.0, -b], a * xp + c * (xs - xp), zi=[b * y1])[0]
        old1 = np.empty_like(out1)
        old1[0] = y1
        old1[1:] = out1[:-1]
        lp1[i0:i1] = out1
        lp2[i0:i1] = lfilter([1.0], [1.0, -b], a * old1 + c * (out1 - old1), zi=[b * y2])[0]
    return TwoStage(lp1, lp2, step_ns, coefficients)
