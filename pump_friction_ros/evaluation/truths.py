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
The truths a bank run's readings are held to, where they are not the fault's factor itself.

The monitor publishes each friction cause's change from its healthy baseline (1: as at
commissioning). Where commissioning completed after a fault's onset, the baseline holds the
fault, in part or whole, and the change the monitor can see is the factor over the one the
baseline holds (`commissioned_factor`; ``bank.valve_plate_truth``). The isolation's
estimate of a change weighs its windows by a memory, so a change that comes and goes is held
to the factor its memory holds (`memory_weighted_factor`, `memory_weighted_since`).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np

__all__ = ['commissioned_factor', 'commissioned_since', 'memory_weighted_factor',
           'memory_weighted_since']


def commissioned_factor(t_s: np.ndarray, factor: np.ndarray, signature_nm: np.ndarray,
                        dt_s: float, learn_s: float, learnt_s: float) -> float:
    """
    Return the friction factor a baseline learnt at ``learnt_s`` holds.

    The monitor publishes a cause's change from its healthy baseline (1: as at
    commissioning). A baseline completed after the fault's onset holds the fault, in part or
    whole: commissioning's fit is over its last ``baseline_learn_s`` of monitored running
    (both halves, ``commissioning``), a least-squares level, so the level it holds is the
    s^2-weighted mean of the factor there (s the cause's healthy friction magnitude), and
    the truth a scale is held to is the factor at the end over it. (A step inside that
    stretch makes the halves disagree and commissioning start again, so the stretch
    rarely straddles one.) The samples are those of running at the true speed and
    acceleration (the simulation's gate): the monitor also leaves out ``monitor_settle_s``
    after each acceleration and short windows, so its stretch of learnt running reaches a
    little further back in time than this one; for a ramp the truth is then a little high.

    Parameters
    ----------
    t_s : ndarray
        Times of the running samples [s], increasing.
    factor : ndarray
        The fault's factor at them [-].
    signature_nm : ndarray
        The cause's healthy friction magnitude at them [N m].
    dt_s : float
        Sample period [s].
    learn_s : float
        ``baseline_learn_s`` [s of monitored running].
    learnt_s : float
        When the baseline was complete [s].

    Returns
    -------
    float
        The weighted factor (1 where no sample is taken before ``learnt_s``).

    """
    end = int(np.searchsorted(t_s, learnt_s, side='right'))
    start = max(0, end - max(1, round(learn_s / dt_s)))
    held = factor[start:end]
    if held.size and (held == held[0]).all():  # (exactly: a baseline learnt before the onset)
        return float(held[0])
    weight = signature_nm[start:end] ** 2
    total = float(np.sum(weight))
    return float(np.dot(weight, held)) / total if total > 0.0 else 1.0


def commissioned_since(factor: np.ndarray | float, t_s: np.ndarray, signature_nm: np.ndarray,
                       running: np.ndarray, learn_s: float) -> Callable[[float], float] | None:
    """
    Return `commissioned_factor` over the running samples, or None for a steady factor.

    Parameters
    ----------
    factor : ndarray or float
        The fault's valve-plate factor per sample, or one for all [-].
    t_s : ndarray
        Sample times [s], evenly spaced.
    signature_nm : ndarray
        The healthy valve-plate friction per sample [N m].
    running : ndarray of bool
        Samples the monitor takes.
    learn_s : float
        ``baseline_learn_s`` [s].

    Returns
    -------
    callable or None
        The factor a baseline learnt at a stamp [s] holds; None where it never changes.

    """
    if np.ndim(factor) == 0 or not running.any():
        return None
    dt = float(t_s[1] - t_s[0])
    return partial(commissioned_factor, t_s[running], np.asarray(factor)[running],
                   np.abs(signature_nm[running]), dt, learn_s)


def memory_weighted_factor(factor: np.ndarray, signature_nm: np.ndarray, taken: np.ndarray,
                           dt_s: float, memory_s: float) -> float:
    """
    Return the friction factor the isolation's memory holds at the end of a run.

    The isolation estimates a cause's change as sum s d / sum s^2 over its windows, older
    ones weighted by exp(-age / memory) in monitored running (``attribution``). With
    d = (f - 1) s that is the s^2- and memory-weighted mean of f: the truth an intermittent
    fault's estimate can be held to (the factor at the end is on or off by chance).

    Parameters
    ----------
    factor : ndarray
        The fault's factor per sample [-].
    signature_nm : ndarray
        The cause's healthy friction magnitude per sample [N m].
    taken : ndarray of bool
        Samples the monitor takes (running, after the onset).
    dt_s : float
        Sample period [s].
    memory_s : float
        ``isolation_memory_s`` [s of monitored running].

    Returns
    -------
    float
        The weighted factor (the factor at the end where no sample is taken).

    """
    if not taken.any():
        return float(factor[-1])
    age = (np.count_nonzero(taken) - np.cumsum(taken)[taken]) * dt_s
    weight = np.exp(-age / memory_s) * signature_nm[taken] ** 2
    return float(np.sum(weight * factor[taken]) / np.sum(weight))


def memory_weighted_since(t_s: np.ndarray, factor: np.ndarray, signature_nm: np.ndarray,
                          dt_s: float, memory_s: float, start_s: float) -> float:
    """
    Return `memory_weighted_factor` over the samples taken from ``start_s`` on.

    The isolation's sums start afresh when both CUSUMs are back at zero (``attribution``):
    an intermittent fault whose change cleared between its episodes is estimated from the
    change under way at the end only, the monitor's ``change_start_s`` on.

    Parameters
    ----------
    t_s : ndarray
        Times of the samples the monitor takes after the onset [s] (at least one).
    factor, signature_nm : ndarray
        The fault's factor [-] and the cause's healthy friction magnitude [N m] at them.
    dt_s : float
        Sample period [s].
    memory_s : float
        ``isolation_memory_s`` [s of monitored running].
    start_s : float
        Where the change under way began [s] (-inf: the onset).

    Returns
    -------
    float
        The weighted factor (the last given sample's where none is from ``start_s`` on).

    """
    return memory_weighted_factor(factor, signature_nm, t_s >= start_s, dt_s, memory_s)
