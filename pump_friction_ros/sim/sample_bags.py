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

"""Sample bags: simulated EHA duty cycles written as rosbag2 bags (sqlite3 and mcap)."""

from __future__ import annotations

from pathlib import Path
import sqlite3
from typing import Any

import numpy as np

from .duty_cycle import DutyCycle, simulate_duty_cycle, SimulatedRun, wear_step
from ..core.node_parameters import BAG_PARAMS_FILE, EstimatorConfig
from ..errors import BagError
from ..physics.pump_parameters import load_pump
from ..staging import StagedOutputs
from ..table.table_files import cached_table

__all__ = ['SAMPLE_BAGS', 'SAMPLE_PARAMS_FILE', 'make_sample_bags', 'sample_params_text',
           'write_run']

SAMPLE_DURATION_S = 75.0
WEAR_START_S, WEAR_RAMP_S, WEAR_SCALE = 25.0, 5.0, 1.6
SAMPLE_BAGS = {
    # name: (storage, valve-plate wear?)
    'eha_nominal': ('sqlite3', False),
    'eha_valve_plate_wear': ('mcap', True),
}
JOINT_NAME = EstimatorConfig().joint_name


def write_run(run: SimulatedRun, path: Path, storage: str, joint_name: str = JOINT_NAME,
              start_ns: int = 1_700_000_000 * 1_000_000_000, compress: bool = True) -> Path:
    """
    Write a simulated run as a bag: JointState (speed, torque) and FluidPressure.

    Both are stamped in their headers; the log time equals the stamp. Compressed with zstd
    (sqlite3: file compression; mcap: chunk compression) to keep the bag small.

    Parameters
    ----------
    run : SimulatedRun
        The signals.
    path : Path
        Bag directory to create (must not exist).
    storage : {'sqlite3', 'mcap'}
        Storage plugin.
    joint_name : str
        Name of the shaft joint.
    start_ns : int
        Time of the first sample [ns].
    compress : bool
        Compress with zstd.

    Returns
    -------
    Path
        The bag.

    """
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores

    ts = get_typestore(Stores.ROS2_JAZZY)
    t = ts.types
    header_t, time_t = t['std_msgs/msg/Header'], t['builtin_interfaces/msg/Time']
    joint_t, pressure_t = t['sensor_msgs/msg/JointState'], t['sensor_msgs/msg/FluidPressure']
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    writer = Writer(path, version=9, storage_plugin=plugin)
    if compress:
        writer.set_compression(CompressionMode.STORAGE if storage == 'mcap'
                               else CompressionMode.FILE, CompressionFormat.ZSTD)
    joint_ns = start_ns + np.round(run.t_s * 1e9).astype(np.int64)
    press_ns = start_ns + np.round(run.pressure_t_s * 1e9).astype(np.int64)
    events = sorted([(int(ns), 0, i) for i, ns in enumerate(press_ns)]
                    + [(int(ns), 1, i) for i, ns in enumerate(joint_ns)])
    empty = np.zeros(0)

    def header(ns: int, frame: str) -> Any:  # a std_msgs/msg/Header of the typestore
        return header_t(stamp=time_t(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000),
                        frame_id=frame)

    with writer:
        joints = writer.add_connection('/joint_states', 'sensor_msgs/msg/JointState',
                                       typestore=ts)
        pressure = writer.add_connection('/load_pressure', 'sensor_msgs/msg/FluidPressure',
                                         typestore=ts)
        for ns, kind, i in events:
            if kind == 0:
                msg = pressure_t(header=header(ns, 'pump'),
                                 fluid_pressure=float(run.pressure_diff_pa[i]), variance=0.0)
                writer.write(pressure, ns, ts.serialize_cdr(msg, 'sensor_msgs/msg/FluidPressure'))
            else:
                msg = joint_t(header=header(ns, ''), name=[joint_name], position=empty,
                              velocity=np.array([run.speed_rad_s[i]]),
                              effort=np.array([run.torque_nm[i]]))
                writer.write(joints, ns, ts.serialize_cdr(msg, 'sensor_msgs/msg/JointState'))
    return path


SAMPLE_PARAMS_FILE = 'eha_params.yaml'


def sample_params_text(cycle: DutyCycle, pump_file: str | None = None) -> str:
    """
    Return the node parameters of the simulated pump, as a ROS 2 params file.

    The values the sample bags were simulated with that are not the node's defaults travel
    with the bags (``bags/eha_params.yaml``): replay them with ``--params`` this file.

    Parameters
    ----------
    cycle : DutyCycle
        The simulation's settings (oil viscosity, drive loss, rotor inertia).
    pump_file : str, optional
        The pump file simulated, when not the default (written as an absolute path).

    Returns
    -------
    str
        The file's text.

    """
    lines = [
        '# Node parameters of the pump simulated in the sample bags (pump_friction',
        '# make-sample-bags, sim.duty_cycle.DutyCycle): give it after the defaults, e.g.',
        '#   pump_friction replay bags/eha_nominal --params bags/eha_params.yaml',
        '#   ros2 launch pump_friction_ros torque_estimator.launch.py params_file:=<this file>',
        '/**/torque_estimator:',
        '  ros__parameters:',
    ]
    if pump_file:
        lines.append(f'    pump_file: {Path(pump_file).resolve()}')
    lines += [
        f'    oil_viscosity_m2_s: {cycle.viscosity_m2_s!r}  # the simulated oil '
        f'({cycle.viscosity_m2_s * 1e6:g} cSt)',
        f'    drive_loss_torque_nm: {cycle.drive_loss_torque_nm!r}  # the simulated drive loss',
        f'    rotor_inertia_kg_m2: {cycle.rotor_inertia_kg_m2!r}  # the simulated rotor',
    ]
    return '\n'.join(lines) + '\n'


def make_sample_bags(out_dir: str | Path, seed: int = 0, pump_file: str | None = None,
                     duration_s: float = SAMPLE_DURATION_S) -> list[Path]:
    """
    Write ``eha_nominal`` (sqlite3) and ``eha_valve_plate_wear`` (mcap) into ``out_dir``.

    A positioning duty cycle with speed reversals and a load-following pressure, joint
    states at 1 kHz and pressure at 500 Hz; the measured torque is the model's (via the
    pump's friction table) plus rotor inertia, a 0.05 N m drive loss and noise. In the wear
    bag the valve-plate friction rises to 1.6x from 25 s to 30 s.

    Parameters
    ----------
    out_dir : str or Path
        Folder for the bags (created); the bags themselves must not exist. They are
        written under temporary names and moved into place together at the end
        (``staging``): an interrupted or failed run leaves none.
    seed : int
        Random seed: the same seed gives the same signals.
    pump_file : str, optional
        Pump parameter YAML (default: the paper's pump).
    duration_s : float
        Length of each bag [s].

    Returns
    -------
    list of Path
        The bags written; the node parameters of the simulated pump
        (`sample_params_text`) are in each bag folder (``node_params.yaml``, read by the
        replay) and beside them (``eha_params.yaml``, for ``ros2 launch ... params_file:=``).

    """
    from rosbags.rosbag2 import WriterError

    out_dir = Path(out_dir)
    targets = [out_dir / name for name in SAMPLE_BAGS] + [out_dir / SAMPLE_PARAMS_FILE]
    for target in targets:
        if target.exists():
            raise BagError(f'output exists: {target} (remove it or choose another --out)')
    outputs = StagedOutputs()  # checked and made first; moved into place together at the end
    try:
        bags = [outputs.add(out_dir / name, False, True, create=False) for name in SAMPLE_BAGS]
        params = outputs.add(out_dir / SAMPLE_PARAMS_FILE, False, False)
        table = cached_table(load_pump(pump_file))
        cycle = DutyCycle(duration_s=duration_s)
        text = sample_params_text(cycle, pump_file)
        for k, (staged, (storage, worn)) in enumerate(zip(bags, SAMPLE_BAGS.values(),
                                                          strict=True)):
            wear = wear_step(WEAR_START_S, WEAR_SCALE, WEAR_RAMP_S) if worn else None
            run = simulate_duty_cycle(table, cycle, seed=seed * 1000 + k, wear=wear)
            try:  # a full disk: sqlite3's error, or the MCAP writer's OSError
                write_run(run, staged.path, storage)
                # the simulated installation's parameters travel with each bag
                (staged.path / BAG_PARAMS_FILE).write_text(text)
            except (OSError, sqlite3.Error, WriterError) as exc:
                raise BagError(f'cannot write the sample bag {staged.target}: {exc}') from exc
        try:
            params.path.write_text(text)
        except OSError as exc:
            raise BagError(f'cannot write {params.target}: {exc}') from exc
        outputs.commit()
    except BaseException:
        outputs.discard()
        raise
    return [staged.target for staged in bags]
