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

"""Plots of the evaluation bank: detection delay against fault size, attribution picture."""

from __future__ import annotations

from collections.abc import Sequence
import math
from pathlib import Path
from typing import Any

import numpy as np

from .bank import RunRecord
from .settings import ACCEPTED_ATTRIBUTIONS, ALL_FAMILIES, ATTRIBUTIONS, FAULTS
from ..plotting import pyplot

__all__ = ['write_bank_plots']

_FAULT = {f.name: f for f in FAULTS}
_JITTER = 0.012
"""Horizontal spread between families in the delay plot [fault-size units]."""


def write_bank_plots(records: Sequence[RunRecord], figures: dict[str, Any],
                     out_dir: Path) -> list[Path]:
    """
    Write ``delay_vs_fault_size.png`` and ``attribution.png``.

    Parameters
    ----------
    records : sequence of RunRecord
        The runs.
    figures : dict
        From `report.bank_figures`.
    out_dir : Path
        Folder (must exist).

    Returns
    -------
    list of Path
        The files written.

    """
    plt = pyplot()
    paths = [out_dir / 'delay_vs_fault_size.png', out_dir / 'attribution.png']
    fig = _delay_figure(plt, records, figures)
    fig.savefig(paths[0], dpi=110)
    plt.close(fig)
    fig = _attribution_figure(plt, figures)
    fig.savefig(paths[1], dpi=110)
    plt.close(fig)
    return paths


def _delay_figure(plt, records: Sequence[RunRecord], figures: dict[str, Any]):
    faulty = [r for r in records if r.truth_class != 'nominal']
    finite = [r.delay_s for r in faulty if math.isfinite(r.delay_s)]
    top = 1.15 * max(finite, default=1.0)  # where the runs not detected are drawn
    steps = [f.name for f in FAULTS
             if f.truth_class == 'valve_plate' and not f.ramp and not f.intermittent]
    run = {r.fault for r in faulty}  # a column per fault the bank ran (held out or not)
    others = [f.name for f in FAULTS if f.truth_class != 'nominal' and f.name not in steps
              and f.name in run]
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8), sharey=True,
                                      gridspec_kw={'width_ratios': [1, 1.4]})
    colours = plt.get_cmap('tab10')
    present = {r.family for r in records}
    families = [f for f in ALL_FAMILIES if f.name in present]  # the bank's or the held-out
    for k, family in enumerate(families):
        shift = (k - (len(families) - 1) / 2) * _JITTER
        for ax, names, position in ((left, steps, lambda n: _FAULT[n].size),
                                    (right, others, others.index)):
            runs = [r for r in faulty if r.family == family.name and r.fault in names]
            if not runs:
                continue
            x = np.array([position(r.fault) for r in runs], dtype=float)
            x += shift * (1.0 if ax is left else 10.0)
            y = np.array([r.delay_s if math.isfinite(r.delay_s) else top for r in runs])
            missed = ~np.isfinite([r.delay_s for r in runs])
            ax.scatter(x[~missed], y[~missed], s=14, color=colours(k),
                       label=family.name if ax is left else None)
            ax.scatter(x[missed], y[missed], s=24, marker='x', color=colours(k))
    p50 = figures['delay_p50_s']
    shown = [n for n in steps if n in p50 and math.isfinite(p50[n]['all'])]
    left.plot([_FAULT[n].size for n in shown], [p50[n]['all'] for n in shown], 'k-', lw=1,
              label='median, all families')
    for ax in (left, right):
        ax.axhline(top, color='0.6', lw=0.8, ls=':')
        ax.grid(alpha=0.3)
    left.scatter([], [], marker='x', color='0.3', label='not detected (drawn on top)')
    left.set_xlabel('valve-plate friction factor (step) [-]')
    left.set_ylabel('detection delay from onset [s]')
    left.legend(fontsize=7, loc='upper right')
    right.set_xticks(range(len(others)))
    right.set_xticklabels([n.replace('_', ' ') for n in others], rotation=20, fontsize=8)
    right.set_xlabel('other faults')
    fig.suptitle('Wear monitor: detection delay against fault size', fontsize=10)
    fig.tight_layout()
    return fig


def _attribution_figure(plt, figures: dict[str, Any]):
    conf = figures['confusion']
    faults = list(conf)
    counts = np.array([[conf[f][a] for a in ATTRIBUTIONS] for f in faults], dtype=float)
    share = counts / np.maximum(counts.sum(axis=1, keepdims=True), 1.0)
    fig, ax = plt.subplots(figsize=(7.5, 0.45 * len(faults) + 1.6))
    ax.imshow(share, cmap='Blues', vmin=0.0, vmax=1.0, aspect='auto')
    for i, fault in enumerate(faults):
        accepted = ACCEPTED_ATTRIBUTIONS[_FAULT[fault].truth_class] if fault in _FAULT \
            else frozenset()
        for j, attribution in enumerate(ATTRIBUTIONS):
            ax.text(j, i, f'{int(counts[i, j])}', ha='center', va='center', fontsize=8,
                    color='white' if share[i, j] > 0.6 else 'black')
            if attribution in accepted:
                ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, lw=1.5,
                                           ec='tab:green'))
    ax.set_xticks(range(len(ATTRIBUTIONS)))
    ax.set_xticklabels([a.replace('_', ' ') for a in ATTRIBUTIONS], fontsize=8)
    ax.set_yticks(range(len(faults)))
    ax.set_yticklabels([f.replace('_', ' ') for f in faults], fontsize=8)
    ax.set_xlabel('attribution at the end of the run (green: correct)')
    ax.set_title('Wear monitor: attribution by true fault (runs)', fontsize=10)
    fig.tight_layout()
    return fig
