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

"""PNG plots of a replay: torque, residual and CUSUM, efficiency, friction scales."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..core.node_parameters import EstimatorConfig
from ..plotting import pyplot

__all__ = ['write_replay_figures']


def write_replay_figures(series: dict[str, list[float]], out_dir: Path, title: str,
                         config: EstimatorConfig) -> list[Path]:
    """
    PNG plots of a replay, as a hydraulics engineer reads them.

    ``torque.png``: measured and expected motor torque, and the raw residual below.
    ``residual.png``: the friction-direction residual of the monitored samples (the others
    grey), the CUSUM sums against their thresholds, the alarm intervals. ``efficiency.png``:
    measured and model torque efficiency, pump and motor mode apart. ``friction_scales.png``:
    valve-plate and other-friction scales with their 95 % bands.

    Parameters
    ----------
    series : dict of list
        One row per published estimate (``bags.replay._Series``).
    out_dir : Path
        Folder to write into (must exist).
    title : str
        Bag name for the titles.
    config : EstimatorConfig
        The node parameters (CUSUM thresholds).

    Returns
    -------
    list of Path
        The files written.

    """
    plt = pyplot()
    d = {k: np.asarray(v, dtype=float) for k, v in series.items()}
    t = d['time_s']
    level = d['level']
    monitored = d['monitored'] > 0.5
    written = []

    def shade(ax: Any) -> None:
        for value, colour, label in ((1, 'gold', 'WARN'), (2, 'tomato', 'ERROR')):
            mask = level == value
            if mask.any():
                ax.fill_between(t, 0, 1, where=mask, color=colour, alpha=0.3, label=label,
                                transform=ax.get_xaxis_transform(), step='post')

    def robust_limits(values: np.ndarray, pad: float = 0.15) -> tuple[float, float]:
        v = values[np.isfinite(values)]
        if not v.size:
            return -1.0, 1.0
        lo, hi = np.percentile(v, [1.0, 99.0])
        span = max(hi - lo, 1e-3)
        return lo - pad * span, hi + pad * span

    def save(fig: Any, heading: str, stem: str) -> None:
        fig.suptitle(f'{heading}  [{title}]', fontsize=10)
        fig.tight_layout()
        path = out_dir / f'{stem}.png'
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)

    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(10, 6), sharex=True,
                                  gridspec_kw={'height_ratios': [2, 1]})
    ax.plot(t, d['expected_nm'], lw=0.8, color='C1', label='expected (model)')
    ax.plot(t, d['measured_nm'], lw=0.5, color='C0', alpha=0.7, label='measured')
    ax.set(ylabel='motor torque [N m]')
    ax.legend(fontsize=8, loc='upper right')
    ax2.plot(t, d['measured_nm'] - d['expected_nm'], lw=0.4, color='k')
    ax2.set(xlabel='time [s]', ylabel='measured - expected [N m]',
            ylim=robust_limits(d['measured_nm'] - d['expected_nm']))
    save(fig, 'Measured and expected motor torque', 'torque')

    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    r = d['friction_residual_nm']
    ax.plot(t[~monitored], r[~monitored], '.', ms=1, color='0.75',
            label='not monitored (slow or accelerating)')
    ax.plot(t[monitored], r[monitored], '.', ms=1.5, color='k', label='monitored')
    ax.axhline(config.cusum_drift_nm, color='C2', ls='--', lw=0.8,
               label=f'CUSUM allowance k = {config.cusum_drift_nm:g} N m')
    ax.axhline(-config.cusum_drift_nm, color='C2', ls='--', lw=0.8)
    ax.axhline(0.0, color='k', lw=0.5)
    shade(ax)
    ax.set(ylabel='friction-direction residual [N m]',
           ylim=robust_limits(r[monitored] if monitored.any() else r))
    ax.legend(fontsize=7, loc='upper left', markerscale=5)
    ax2.plot(t, d['cusum_pos_nm_s'], color='C3', label='S+ (more torque than modelled)')
    ax2.plot(t, d['cusum_neg_nm_s'], color='C0', label='S- (less)')
    ax2.axhline(config.cusum_warn_nm_s, color='goldenrod', ls='--', lw=1, label='WARN')
    ax2.axhline(config.cusum_error_nm_s, color='tomato', ls='--', lw=1, label='ERROR')
    shade(ax2)
    ax2.set(xlabel='time [s]', ylabel='CUSUM [N m s]')
    ax2.legend(fontsize=7, loc='upper left')
    save(fig, 'Friction-direction residual, CUSUM and alarms', 'residual')

    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    pump = d['pump_mode'] > 0.5
    for ax, mask, name in ((axes[0], pump, 'pump mode'), (axes[1], ~pump, 'motor mode')):
        sel = mask & monitored
        ax.plot(t[sel], 100.0 * d['measured_efficiency'][sel], '.', ms=1.5, color='k',
                label='measured (monitored samples)')
        ax.plot(t[mask], 100.0 * d['efficiency'][mask], '.', ms=1, color='C1',
                label='model')
        shade(ax)
        ax.set(xlabel='time [s]', title=name, ylim=(0, 100))
        ax.legend(fontsize=7, loc='lower left', markerscale=5)
    axes[0].set(ylabel='torque efficiency [%]')
    save(fig, 'Torque efficiency: measured and modelled', 'efficiency')

    fig, ax = plt.subplots(figsize=(10, 4))
    for key, colour, label in (('vp', 'C3', 'valve plate'), ('other', 'C0',
                                                             'other components')):
        scale, std = d[f'{key}_scale'], d[f'{key}_scale_std']
        ax.plot(t, scale, color=colour, label=f'{label} friction scale')
        band = np.clip([scale - 1.96 * std, scale + 1.96 * std], -1e3, 1e3)  # std inf: no end
        ax.fill_between(t, band[0], band[1], color=colour, alpha=0.2, label='95 % band')
    ax.axhline(1.0, color='k', ls=':', lw=0.8)
    shade(ax)
    learnt = d['vp_scale_std'] < 0.5 * config.scale_prior_std  # past the start-up
    both = np.concatenate([d['vp_scale'][learnt], d['other_scale'][learnt], [1.0]])
    ax.set(xlabel='time [s]', ylabel='scale [-] (1 = as at commissioning)',
           ylim=(min(0.8, float(both.min()) - 0.1), max(1.2, float(both.max()) + 0.1)))
    ax.legend(fontsize=8, loc='upper left')
    save(fig, 'Friction scales relative to the healthy baseline', 'friction_scales')
    return written
