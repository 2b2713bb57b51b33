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

"""PNG figures: the model in the manner of Hong & Doh (2004) Figs. 3, 10-17, 19; replays."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .config import EstimatorConfig
from .model import COMPONENTS, PumpModel
from .paper import MEASURED_EFFICIENCY_136_BAR
from .units import BAR_TO_PA, pa_to_bar, RPM_TO_RAD_S

__all__ = ['write_model_figures', 'write_replay_figures']

_LABELS = {'valve_plate': 'valve plate', 'bearing': 'shaft bearing',
           'spherical_joints': 'spherical joints', 'piston_heads': 'piston heads'}


def _pyplot():
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    return plt


def write_model_figures(model: PumpModel, out_dir: Path) -> list[Path]:
    """
    Write the model's figures as PNG files.

    Parameters
    ----------
    model : PumpModel
        The pump model.
    out_dir : Path
        Folder to write into (created if missing).

    Returns
    -------
    list of Path
        The files written.

    """
    plt = _pyplot()
    out_dir.mkdir(parents=True, exist_ok=True)
    name = model.params.name
    deg = np.degrees(model.phi)
    written: list[Path] = []

    def save(fig, stem: str) -> None:
        fig.suptitle(f'{fig._suptitle.get_text()}  [{name}]' if fig._suptitle else name,
                     fontsize=10)
        fig.tight_layout()
        path = out_dir / f'{stem}.png'
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)

    # Fig. 3: head velocity and piston angular velocity at 10,000 rpm
    wf = model.evaluate(10000 * RPM_TO_RAD_S, 300 * BAR_TO_PA, waveforms=True).waveforms
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    ax1.plot(deg, wf.head_velocity_m_s[0])
    ax1.set(xlabel='shaft angle [deg]', ylabel="head velocity V'_A [m/s]",
            title='(a) piston head velocity')
    for k, label in enumerate(('x (radial)', 'y (tangential)', 'z (barrel axis)')):
        ax2.plot(deg, wf.piston_omega_rad_s[0, :, k], label=label)
    ax2.plot(deg, np.linalg.norm(wf.piston_omega_rad_s[0], axis=-1), 'k--', label='|w|')
    ax2.set(xlabel='shaft angle [deg]', ylabel='angular velocity [rad/s]',
            title='(b) piston angular velocity rel. barrel')
    ax2.legend(fontsize=8)
    fig.suptitle('Fig. 3: piston kinematics, 10,000 rpm')
    save(fig, 'fig03_kinematics')

    # Figs. 10-14: forces and piston friction torques over the shaft angle, 300 bar
    rpms = np.array([500.0, 4000.0, 10000.0])
    wf = model.evaluate(rpms * RPM_TO_RAD_S, 300 * BAR_TO_PA, waveforms=True).waveforms
    for stem, title, data, ylabel in (
            ('fig10_head_force', 'Fig. 10: head reaction F_A (piston 0), 300 bar',
             wf.head_force_n, '|F_A| [N]'),
            ('fig11_joint_force', 'Fig. 11: joint reaction F_B (piston 0), 300 bar',
             wf.joint_force_n, '|F_B| [N]'),
            ('fig13_joint_torque', 'Fig. 13: spherical-joint friction torque, 300 bar',
             wf.spherical_joints_nm, 'T_f^j [N m]'),
            ('fig14_head_torque', 'Fig. 14: piston-head friction torque, 300 bar',
             wf.piston_heads_nm, 'T_f^h [N m]')):
        fig, ax = plt.subplots(figsize=(6.5, 4))
        for i, rpm in enumerate(rpms):
            ax.plot(deg, data[i], label=f'{rpm:,.0f} rpm')
        ax.set(xlabel='shaft angle [deg]', ylabel=ylabel)
        ax.legend(fontsize=8)
        fig.suptitle(title)
        save(fig, stem)

    # Fig. 12: chamber pressure
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.plot(deg, pa_to_bar(wf.chamber_pressure_pa[0]))
    ax.set(xlabel='piston phase angle [deg]', ylabel='chamber pressure [bar]')
    fig.suptitle('Fig. 12: chamber pressure, 300 bar')
    save(fig, 'fig12_chamber_pressure')

    # Figs. 15-17: components and totals over speed, 300 bar
    rpm_axis = np.linspace(0.0, 10000.0, 41)
    res = model.evaluate(rpm_axis * RPM_TO_RAD_S, 300 * BAR_TO_PA)
    for stem, comp, fig_no in (('fig15_valve_plate', 'valve_plate', 15),
                               ('fig16_bearing', 'bearing', 16)):
        fig, ax = plt.subplots(figsize=(6.5, 4))
        ax.plot(rpm_axis, res.magnitudes_nm[comp])
        ax.set(xlabel='shaft speed [rpm]', ylabel='friction torque [N m]')
        fig.suptitle(f'Fig. {fig_no}: {_LABELS[comp]} friction, 300 bar')
        save(fig, stem)
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.stackplot(rpm_axis, *[res.magnitudes_nm[c] for c in COMPONENTS],
                 labels=[_LABELS[c] for c in COMPONENTS])
    ax2 = ax.twinx()
    ax2.plot(rpm_axis, res.input_nm, 'k', label='input torque')
    ax2.axhline(float(res.theoretical_nm[0]), color='k', ls=':', label='theoretical')
    ax.set(xlabel='shaft speed [rpm]', ylabel='friction torque [N m]')
    ax2.set(ylabel='input torque [N m]')
    ax.legend(loc='upper left', fontsize=8)
    ax2.legend(loc='lower right', fontsize=8)
    fig.suptitle('Fig. 17: friction components and input torque, 300 bar')
    save(fig, 'fig17_input_torque')

    # Fig. 19: efficiency map over speed x pressure, with the paper's measured points
    rpm_grid = np.linspace(250.0, 10000.0, 40)
    bar_grid = np.linspace(10.0, 350.0, 35)
    sp, pr = np.meshgrid(rpm_grid, bar_grid)
    res = model.evaluate(sp * RPM_TO_RAD_S, pr * BAR_TO_PA)
    eff = res.efficiency.reshape(sp.shape)
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    cs = ax.contourf(sp, pr, 100.0 * eff, levels=np.arange(50, 101, 2.5), cmap='viridis',
                     extend='min')
    ax.contour(sp, pr, 100.0 * eff, levels=[80, 85, 90, 95], colors='w', linewidths=0.7)
    fig.colorbar(cs, ax=ax, label='torque efficiency [%]')
    for rpm, measured in MEASURED_EFFICIENCY_136_BAR.items():
        ax.plot(rpm, 136.0, 'rx')
        ax.annotate(f'measured {100 * measured:.0f} %', (rpm, 136.0), color='r', fontsize=8,
                    xytext=(4, 4), textcoords='offset points')
    ax.set(xlabel='shaft speed [rpm]', ylabel='pressure difference [bar]')
    fig.suptitle('Fig. 19: torque efficiency map')
    save(fig, 'fig19_efficiency_map')
    return written


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
    plt = _pyplot()
    d = {k: np.asarray(v, dtype=float) for k, v in series.items()}
    t = d['time_s']
    level = d['level']
    monitored = d['monitored'] > 0.5
    written = []

    def shade(ax) -> None:
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

    def save(fig, heading: str, stem: str) -> None:
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
        ax.fill_between(t, scale - 1.96 * std, scale + 1.96 * std, color=colour, alpha=0.2,
                        label='95 % band')
    ax.axhline(1.0, color='k', ls=':', lw=0.8)
    shade(ax)
    learnt = d['vp_scale_std'] < 0.5 * config.scale_prior_std  # past the start-up
    both = np.concatenate([d['vp_scale'][learnt], d['other_scale'][learnt], [1.0]])
    ax.set(xlabel='time [s]', ylabel='scale [-] (1 = as modelled)',
           ylim=(min(0.8, float(both.min()) - 0.1), max(1.2, float(both.max()) + 0.1)))
    ax.legend(fontsize=8, loc='upper left')
    save(fig, 'Friction scales (attribution filter)', 'friction_scales')
    return written
