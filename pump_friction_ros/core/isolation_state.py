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
The fault isolation's learning state as plain values, and read back (``attribution``).

A restart must not forget the change under way: the node writes the isolation's sums with
the monitor's (``monitor_state``), and a state written by an older release loads too. The
sums that came later (the oil band's, the drift's age-weighted ones, the friction bias, the
episodes) start from the next window where a file lacks them; a state written before the
spherical joints were a cause of their own (six causes) gets the joints' sums as zeros.

"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .baseline import read_count, read_sums
from .change_episodes import ChangeEpisodes
from .change_stats import ChangeStats
from .drift_nuisance import DriftNuisance
from .friction_bias import FrictionBias

__all__ = ['IsolationSums', 'isolation_state', 'read_isolation_state']

_PER_CAUSE = (('g', 'b', 'g1', 'g2', 'b1', 'bv', 'bv1'), ('x', 'x1'), ('g', 'b', 'g1', 'g2', 'b1'))
"""The per-cause sums of the isolation's state, its drift's and its episodes'."""


@dataclass
class IsolationSums:
    """What an isolation state holds: its change statistics and their companions."""

    stats: ChangeStats
    drift: DriftNuisance
    bias: FrictionBias
    episodes: ChangeEpisodes


def isolation_state(sums: IsolationSums) -> dict[str, object]:
    """
    Return the sums as plain values.

    Parameters
    ----------
    sums : IsolationSums
        The isolation's.

    Returns
    -------
    dict
        JSON-ready values, read back by `read_isolation_state`.

    """
    st = sums.stats
    return {'g': st.g.tolist(), 'b': st.b.tolist(), 'c': float(st.c),
            'count': float(st.count), 'windows': int(st.windows),
            'g1': st.g1.tolist(), 'g2': st.g2.tolist(),
            'b1': st.b1.tolist(), 'bv': st.bv.tolist(), 'bv1': st.bv1.tolist(),
            'drift': sums.drift.state(), 'bias': sums.bias.state(),
            'episodes': sums.episodes.state()}


def read_isolation_state(state: dict[str, object], like: IsolationSums) -> IsolationSums:
    """
    Read an `isolation_state` result back, into new sums shaped and set as `like`.

    Parameters
    ----------
    state : dict
        An `isolation_state` result, of this release or an older one.
    like : IsolationSums
        The isolation's present sums: their number of causes, the causes' least change,
        the bias's prior and the episodes' settings are kept.

    Returns
    -------
    IsolationSums
        All read: the caller replaces its sums together.

    Raises
    ------
    ValueError
        Missing or malformed sums.

    """
    n, lowest = like.stats.b.size, like.stats.lowest
    state = _widened(state, n)
    (g, b), (c, count) = read_sums(state, {'g': (n, n), 'b': (n,)}, ('c', 'count'),
                                   'isolation', grams=('g',))
    # sums that came later: a file without them, from the next window on (the oil
    # band's: no band until now; the bias's: none while a change under way lasts)
    (g1, g2, b1), _ = read_sums(state, {'g1': (n,), 'g2': (n,), 'b1': (n,)}, (),
                                'isolation') if 'g1' in state else ([np.zeros(n)] * 3, [])
    (bv, bv1), _ = read_sums(state, {'bv': (n,), 'bv1': (n,)}, (), 'isolation') \
        if 'bv' in state else ([np.zeros(n)] * 2, [])
    windows = read_count(state, 'windows', 'isolation')
    drift, bias = DriftNuisance(n), FrictionBias()
    if 'drift' in state:
        drift.load(state['drift'])  # type: ignore[arg-type]
        if 'x1' not in state['drift']:  # type: ignore[operator]
            # without the drift's age-weighted sum the line's do not fit together (it
            # named the wrong friction): the windows count as of one age, as its zeros
            g1, g2, b1, bv1 = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    if 'bias' in state:
        bias.load(state['bias'])  # type: ignore[arg-type]
    else:
        bias.usable = not windows
    bias.prior_precision = like.bias.prior_precision  # the monitor's
    episodes = ChangeEpisodes(n, like.episodes.ratio, like.episodes.z, lowest)
    if 'episodes' in state:  # else (a file from before them) from the next window on
        episodes.load(state['episodes'])  # type: ignore[arg-type]
    stats = ChangeStats(n, lowest)
    stats.g, stats.b, stats.c, stats.count, stats.windows = g, b, c, count, windows
    stats.g1, stats.g2, stats.b1, stats.bv, stats.bv1 = g1, g2, b1, bv, bv1
    return IsolationSums(stats, drift, bias, episodes)


def _widened(state: dict[str, object], n: int) -> dict[str, object]:
    """
    Return an isolation state written before the spherical joints were a cause, widened.

    Its per-cause sums (`_PER_CAUSE`) get the joints' (the last cause's) as zeros: their
    signature counts from the next window on, every other sum as it was. A state whose
    ``g`` is not n - 1 wide is returned as it is (`read_isolation_state` judges it).

    """
    g = state.get('g')
    if not (isinstance(g, list) and len(g) == n - 1):
        return state

    def widen(value: object) -> object:
        if not (isinstance(value, list) and len(value) == n - 1):
            return value
        if all(isinstance(row, list) for row in value):  # a matrix: a row and a column
            return [[*row, 0.0] for row in value] + [[0.0] * n]
        return [*value, 0.0]

    top, drift, episodes = _PER_CAUSE
    out = {key: widen(value) if key in top else value for key, value in state.items()}
    for key, keys in (('drift', drift), ('episodes', episodes)):
        part = out.get(key)
        if isinstance(part, dict):
            out[key] = {k: widen(v) if k in keys else v for k, v in part.items()}
    return out
