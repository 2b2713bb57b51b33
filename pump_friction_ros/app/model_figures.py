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

"""PNG figures of the model in the manner of Hong & Doh (2004) Figs. 3, 10-17, 19."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..physics.model import COMPONENTS, PumpModel
from ..physics.paper import MEASURED_EFFICIENCY_136_BAR
from ..physics.units import BAR_TO_PA, pa_to_bar, RPM_TO_RAD_S
from ..plotting import pyplot

__all__ = ['write_model_figures']

_LABELS = {'valve_plate': 'valve plate', 'bearing': 'shaft bearing',
           'spherical_joints': 'spherical joints', 'piston_heads': 'piston heads'}


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
    plt = pyplot()
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
