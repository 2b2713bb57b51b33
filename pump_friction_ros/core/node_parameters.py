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
Parameters of the torque estimator: one spec for the node, the replay and the tests.

The node declares every parameter below with a ``ParameterDescriptor`` built from this spec
(description and range); the replay reads the same ROS 2 parameters file
(``torque_estimator: ros__parameters: ...``); both validate into the same frozen
`EstimatorConfig`, which the ROS-free core takes.

Longer than 500 lines because it is the one list of every parameter, each with its default,
range and description: the node, the YAML file and the docs read them from here, and a
parameter split off into another module would be one more place to look for it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from enum import Enum
import math
from pathlib import Path
from typing import Any, TypeVar

from ..errors import ConfigError, quote
from ..paths import resolve_path
from ..yaml_files import number_as_float, read_yaml

_View = TypeVar('_View')

__all__ = [
    'BAG_PARAMS_FILE',
    'NODE_NAME',
    'PARAMETERS',
    'ROS_PARAMETERS',
    'EstimatorConfig',
    'ParameterSpec',
    'PressureSource',
    'SpeedSource',
    'TorqueSource',
    'ViscositySource',
    'checked_values',
    'config_from_mapping',
    'load_estimator_config',
    'quote',
    'settings_view',
]

NODE_NAME = 'torque_estimator'
BAG_PARAMS_FILE = 'node_params.yaml'
"""A ROS 2 params file inside a bag folder: the node parameters of the installation the bag
was recorded on. The replay reads it before any ``--params`` file (which override it)."""


class _Choice(str, Enum):
    """A choice parameter: an enum in the core, its plain string value to ROS and YAML."""

    _value_: str

    def __str__(self) -> str:
        return self.value

    def __format__(self, spec: str) -> str:
        return format(self.value, spec)


class SpeedSource(_Choice):
    """Where the shaft speed comes from."""

    JOINT_STATE = 'joint_state'
    FLOAT64 = 'float64'


class TorqueSource(_Choice):
    """Where the measured motor torque comes from."""

    JOINT_STATE = 'joint_state'
    FLOAT64 = 'float64'


class PressureSource(_Choice):
    """Load pressure difference as one signal, or as the two port pressures."""

    DIFFERENCE = 'difference'
    PORTS = 'ports'


class ViscositySource(_Choice):
    """Oil viscosity from a parameter, or from the oil temperature."""

    PARAMETER = 'parameter'
    TEMPERATURE = 'temperature'


_INF = math.inf


def _param(default: Any, description: str, low: float | None = None,
           high: float | None = None) -> Any:
    """Declare one parameter: its default, description and range, in one place."""
    return field(default=default, metadata={'description': description, 'low': low,
                                            'high': high})


@dataclass(frozen=True)
class EstimatorConfig:
    """
    Validated estimator parameters (SI); field names are the ROS parameter names.

    Each field is the one declaration of its parameter: default, description and range
    (the node's ``ParameterDescriptor`` and the README table are made from it).
    """

    pump_file: str = _param('', 'Pump parameter YAML: a path (relative: to the current '
                            'directory), a package://pump_friction_ros/... path or a shipped '
                            'set name (hong_doh_2004_consistent); empty: hong_doh_2004.')
    table_file: str = _param('', 'Friction table .npz built for that pump (a path or '
                             'package:// path); empty: built on first use and cached '
                             '(~/.cache/pump_friction_ros).')
    joint_name: str = _param('pump_shaft', 'Joint of sensor_msgs/JointState whose velocity '
                             'is the shaft speed [rad/s] and effort the motor torque [N m].')
    speed_source: SpeedSource = _param(
        SpeedSource.JOINT_STATE, 'Shaft speed from joint_states (JointState) or shaft_speed '
        '(std_msgs/Float64).')
    torque_source: TorqueSource = _param(
        TorqueSource.JOINT_STATE, 'Measured motor torque from joint_states (JointState '
        'effort) or motor_torque (std_msgs/Float64).')
    pressure_source: PressureSource = _param(
        PressureSource.DIFFERENCE, 'load_pressure (FluidPressure, p_A - p_B) or ports: '
        'pressure_a and pressure_b, dp = a - b.')
    viscosity_source: ViscositySource = _param(
        ViscositySource.PARAMETER, 'Oil viscosity from oil_viscosity_m2_s, or from '
        'oil_temperature (sensor_msgs/Temperature [degC]) via ASTM D341.')
    oil_viscosity_m2_s: float = _param(0.0, 'Oil kinematic viscosity [m^2/s] (1 cSt = 1e-6); '
                                       "0: the pump file's.", 0.0, 1e-2)
    oil_viscosity_40c_m2_s: float = _param(46e-6, 'Viscosity at 40 degC [m^2/s] for the '
                                           'temperature law (ISO VG 46: 46e-6).', 1e-7, 1e-2)
    oil_viscosity_100c_m2_s: float = _param(6.8e-6, 'Viscosity at 100 degC [m^2/s] for the '
                                            'temperature law (ISO VG 46: 6.8e-6).', 1e-7, 1e-2)
    cold_start_viscosity_m2_s: float = _param(
        1.0e-3, "Pump maker's cold-start limit of the oil viscosity [m^2/s] (1000 cSt for axial "
        'piston units): the friction table covers the oil from its viscosity at 250 degC up to '
        'this, and oil_viscosity_m2_s; beyond, /diagnostics says the oil is outside the table.',
        1e-5, 1e-2)
    max_input_age_s: float = _param(0.05, 'An input older than this is stale: no estimate is '
                                    'made [s].', 1e-4, 60.0)
    max_stamp_lead_s: float = _param(
        1.0, 'A header stamp more than this ahead of the receive time is rejected, so that '
        'one sample from a clock gone wrong cannot hold the later ones hostage [s].', 1e-3,
        3600.0)
    stamp_resync_samples: int = _param(
        20, 'After this many out-of-order samples of one input in a row, its clock is taken '
        'as restarted: that sample is accepted (counted in stamp_resyncs).', 1, 1000000)
    max_temperature_age_s: float = _param(5.0, 'Oil temperature older than this is stale [s] '
                                          '(temperature sensors publish slowly).', 1e-3, 3600.0)
    rotor_inertia_kg_m2: float = _param(2.0e-4, 'Inertia of motor rotor, coupling and pump '
                                        'rotating group [kg m^2].', 0.0, 10.0)
    accel_filter_time_constant_s: float = _param(
        0.01, 'Time constant of each of the two low-pass stages of the speed derivative [s].',
        1e-4, 10.0)
    drive_loss_torque_nm: float = _param(0.0, 'Constant drive loss opposing the motion '
                                         '(seals, gears) [N m].', 0.0, 100.0)
    monitor_min_speed_rad_s: float = _param(20.0, 'The wear monitor learns only above this '
                                            '|speed| [rad/s] (reversals and creep are '
                                            'skipped).', 0.0, 1e4)
    monitor_max_accel_rad_s2: float = _param(
        1000.0, 'The wear monitor learns only below this |filtered acceleration| [rad/s^2] '
        '(the inertia torque, 0.2 N m there at 2e-4 kg m^2, must be known well).', 0.0, _INF)
    ewma_time_constant_s: float = _param(2.0, "Time constant of the residual's EWMA [s].",
                                         1e-3, 1e5)
    cusum_drift_nm: float = _param(
        0.025, 'CUSUM allowance k: change from the healthy baseline (per cause, at a typical '
        'operating point) tolerated without accumulating [N m].', 0.0, 100.0)
    cusum_baseline_sigmas: float = _param(
        2.0, "The healthy baseline's own prediction uncertainty at a window's operating point, "
        'in standard deviations, is taken off the change before the CUSUM accumulates it '
        '(a point commissioning never saw is not a fault) [-].', 0.0, 10.0)
    cusum_warn_nm_s: float = _param(0.6, 'CUSUM level (integral of the change beyond k) for '
                                    'WARN [N m s].', 1e-6, 1e6)
    cusum_error_nm_s: float = _param(5.0, 'CUSUM level for ERROR [N m s].', 1e-6, 1e6)
    cusum_clear_ratio: float = _param(0.5, 'A level clears when the CUSUM falls below this '
                                      'fraction of its threshold (hysteresis).', 0.0, 1.0)
    monitor_settle_s: float = _param(
        0.05, 'The wear monitor takes a sample only after this much steady running (above the '
        'minimum speed, below the acceleration limit, torque fresh): the filters have '
        'forgotten the last transient [s].', 0.0, 60.0)
    monitor_lookahead_s: float = _param(
        0.02, 'A sample is monitored only once the steady running has gone on this long after '
        'it: the filtered acceleration sees a jerk a few milliseconds late [s].', 0.0, 10.0)
    baseline_learn_s: float = _param(
        30.0, 'Monitored running that teaches the healthy baseline (commissioning); no alarm '
        'until it is learnt [s].', 1.0, 1e7)
    baseline_settle_time_constant_s: float = _param(
        900.0, 'Slowest settling the commissioning waits for once it has seen the pump '
        'change (an oil warm-up without temperature input): the drift between its halves, '
        'extrapolated over this time constant, must stay below half the CUSUM allowance [s]; '
        '0: the drift alone.', 0.0, 1e6)
    warm_up_pause_s: float = _param(
        120.0, 'viscosity_source parameter: after a pause in monitored running longer than '
        "this (a restart too: the baseline file keeps the last window's time) the oil may be "
        'colder than at commissioning: the change from the baseline is not judged until it '
        "settles (the commissioning's check on it; docs/monitor.md) [s]; 0: never held.",
        0.0, 1e6)
    oil_temperature_band_c: float = _param(
        0.0, "viscosity_source parameter: the oil temperature's swing from commissioning "
        '[K]; its friction change (oil_viscosity_40c/100c law, times the friction levels '
        'the baseline learnt) is not a change of the pump, '
        "hides one as small, and widens a scale's interval by what it moves the reading "
        '(docs/monitor.md); 0: none.', 0.0, 100.0)
    torque_constant_drift_per_k: float = _param(
        0.0, "Drift of the drive's torque constant with temperature taken as normal [1/K] "
        '(NdFeB: 1.2e-3); times the temperature change from commissioning (topic, else the '
        'band) times the torque, on its side, it is not a change of the pump, and hides one '
        'as large (docs/monitor.md); 0: none, the drive compensates.', 0.0, 0.1)
    torque_constant_drift_max_per_k: float = _param(
        1.5e-3, "Temperature topic: the largest drift of the drive's torque constant the "
        'monitor learns (a change that the torque reading high as the oil warms explains '
        'better than any step is followed, not alarmed) [1/K] (NdFeB 0.8-1.3e-3; ferrite '
        '2e-3); 0: never.', 0.0, 0.1)
    attribution_window_s: float = _param(
        0.25, 'Monitored running averaged into one measurement of the baseline and the '
        'isolation [s].', 0.01, 60.0)
    scale_prior_std: float = _param(0.5, 'Prior standard deviation of the friction levels '
                                    'against the model in the baseline fit [-].', 1e-3, 100.0)
    offset_prior_std_nm: float = _param(
        0.3, 'Prior standard deviation of an extra drive loss and of a torque offset in the '
        'baseline fit [N m].', 1e-4, 100.0)
    torque_gain_prior_std: float = _param(
        0.1, 'Prior standard deviation of the gain error of the measured torque against the '
        'theoretical one (torque constant, pressure sensor) in the baseline fit [-].', 1e-4,
        10.0)
    inertia_prior_std_kg_m2: float = _param(
        2.0e-4, 'Prior standard deviation of the error of the effective rotor inertia in the '
        'baseline fit (data-sheet rotor and coupling, and the drive sampling current and '
        'encoder apart) [kg m^2].', 1e-9, 10.0)
    attribution_z: float = _param(
        3.0, 'A single cause explains the change when its likelihood-ratio statistic reaches '
        'z^2 and leads the runner-up by z^2 [standard deviations].', 0.5, 20.0)
    identifiability_correlation: float = _param(
        0.98, "|cosine| of two causes' signatures over the points seen from which the duty "
        'cycle cannot tell them apart [-].', 0.1, 1.0)
    isolation_memory_s: float = _param(
        120.0, 'Memory of the isolation: older windows since the change weigh exp(-age / '
        'this) [s of monitored running].', 1.0, 1e7)
    isolation_episode_lack_of_fit: float = _param(
        4.0, 'A change comes and goes where the best single cause fits every window since '
        'it this many times worse than the windows that show it (lack of fit, x noise) and '
        'those come in runs (runs test at attribution_z); the verdict then reads those '
        '(docs/monitor.md) [-].', 1.5, 1e6)
    scale_systematic_std: float = _param(
        0.05, 'Floor of the standard deviation of a reported friction scale: model error '
        'that does not average away [-].', 0.0, 10.0)
    level_systematic_std: float = _param(
        0.15, 'Relative standard deviation of the healthy friction levels the baseline '
        'learnt from model error, added in quadrature to the std of the fit: the pump is not its '
        'model, and where the shapes of the valve plate and of the other friction are nearly '
        'collinear, their split moves with the error of those shapes; the interval of a '
        'change relative to the level carries it, times the change (docs/monitor.md) [-].',
        0.0, 1.0)
    stale_timeout_s: float = _param(0.5, 'No estimate for this long: diagnostics STALE [s].',
                                    1e-3, 3600.0)
    output_decimation: int = _param(10, 'Publish every N-th estimate (1 kHz in, 100 Hz out '
                                    'with 10).', 1, 100000)
    diagnostics_rate_hz: float = _param(1.0, 'Rate of /diagnostics [Hz].', 0.01, 100.0)
    hardware_id: str = _param('eha_pump', 'hardware_id of the diagnostic status.')
    reliable_inputs: bool = _param(False, 'Subscribe with reliable QoS instead of the '
                                   'sensor-data profile (best effort).')
    baseline_file: str = _param(
        '', "File of the wear monitor's learnt healthy baseline, loaded at start, saved "
        'periodically, on ~/reset_monitor and at shutdown (relative: to the current '
        'directory); empty: $ROS_HOME/pump_friction_ros/baselines/<namespace.node name>.yaml, '
        'ROS_HOME defaulting to ~/.ros.')
    baseline_save_period_s: float = _param(
        60.0, 'Period of saving the baseline file while the monitor learns [s].', 1.0,
        86400.0)

    def __post_init__(self) -> None:
        for f in fields(self):  # choices given as strings (tests, YAML) become their enum
            kind = type(f.default)
            if issubclass(kind, _Choice) and not isinstance(getattr(self, f.name), kind):
                object.__setattr__(self, f.name, _SPECS[f.name].convert(getattr(self, f.name),
                                                                        ''))
        if self.cusum_error_nm_s < self.cusum_warn_nm_s:
            raise ConfigError('cusum_error_nm_s must be >= cusum_warn_nm_s')
        if self.oil_viscosity_100c_m2_s >= self.oil_viscosity_40c_m2_s:
            raise ConfigError('oil_viscosity_100c_m2_s must be below oil_viscosity_40c_m2_s')

    def viscosity_m2_s(self, pump_file_viscosity_m2_s: float) -> float:
        """
        Return the oil viscosity the parameters set: ``oil_viscosity_m2_s``, 0 the pump file's.

        Parameters
        ----------
        pump_file_viscosity_m2_s : float
            The pump file's oil viscosity [m^2/s].

        Returns
        -------
        float
            Kinematic viscosity [m^2/s].

        """
        return self.oil_viscosity_m2_s or pump_file_viscosity_m2_s


def settings_view(config: EstimatorConfig, cls: type[_View]) -> _View:
    """
    Return the settings dataclass ``cls`` filled from the same-named node parameters.

    A filter takes the few parameters it uses, as a small frozen dataclass whose fields are
    named after them; each parameter stays declared once, here (default, range, text).

    Parameters
    ----------
    config : EstimatorConfig
        The node parameters.
    cls : type
        A dataclass whose fields are all `EstimatorConfig` fields.

    Returns
    -------
    object
        An instance of ``cls``.

    """
    return cls(**{f.name: getattr(config, f.name) for f in fields(cls)})  # type: ignore[arg-type]


@dataclass(frozen=True)
class ParameterSpec:
    """
    One node parameter as ROS sees it, made from its `EstimatorConfig` field.

    ``default`` is the ROS value (a choice's string); ``choices`` lists a choice's values.
    """

    name: str
    default: Any
    description: str
    low: float | None = None
    high: float | None = None
    choices: tuple[str, ...] | None = None
    enum: type[_Choice] | None = None

    def convert(self, value: Any, where: str, ros_types: bool = False) -> Any:
        """
        Return ``value`` converted to the parameter's type, or raise ConfigError.

        With ``ros_types`` (a parameters file), a number must be of the declared type as
        rclpy holds it: the node refuses ``1`` for a double and ``2.0`` for an integer.
        """
        if ros_types and not isinstance(value, bool) and isinstance(value, (int, float)) \
                and isinstance(self.default, (int, float)) \
                and not isinstance(self.default, bool) \
                and isinstance(value, float) != isinstance(self.default, float):
            want, write = ('a double', f'{value}.0') if isinstance(self.default, float) \
                else ('an integer', f'{value:g}')
            raise ConfigError(f'{where}{self.name}: expected {want}, got {quote(value)}: the '
                              f'node refuses it (ROS 2 parameters keep their type), write '
                              f'{write}')
        return _check(self, value, where)


def _spec_of(f: Any) -> ParameterSpec:
    default = f.default
    enum = type(default) if isinstance(default, _Choice) else None
    return ParameterSpec(
        f.name, default.value if enum else default, f.metadata['description'],
        f.metadata['low'], f.metadata['high'],
        tuple(m.value for m in enum) if enum else None, enum)


PARAMETERS: tuple[ParameterSpec, ...] = tuple(_spec_of(f) for f in fields(EstimatorConfig))
"""Every parameter of the node, in declaration order (made from `EstimatorConfig`)."""
_SPECS = {p.name: p for p in PARAMETERS}


def _check(spec: ParameterSpec, value: Any, where: str) -> Any:
    """Return ``value`` converted to the parameter's type, or raise ConfigError."""
    name = f'{where}{spec.name}'
    kind = type(spec.default)
    if kind is bool:
        if not isinstance(value, bool):
            raise ConfigError(f'{name}: expected true or false, got {quote(value)}')
        return value
    if kind is str:
        if not isinstance(value, str):
            raise ConfigError(f'{name}: expected a string, got {quote(value)}')
        if spec.enum is not None and spec.choices is not None:
            if value not in spec.choices:
                raise ConfigError(f'{name}: must be one of {", ".join(spec.choices)}, '
                                  f'got {quote(value)}')
            return spec.enum(value)
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f'{name}: expected a number, got {quote(value)}')
    given = value
    if kind is int:
        if isinstance(value, float) and not value.is_integer():
            raise ConfigError(f'{name}: expected an integer, got {quote(value)}')
        value = int(value)
    else:
        value = number_as_float(value)
        if math.isnan(value):
            raise ConfigError(f'{name}: must not be NaN')
    low = -math.inf if spec.low is None else spec.low
    high = math.inf if spec.high is None else spec.high
    if not low <= value <= high:
        raise ConfigError(f'{name}: must be in [{low:g}, {high:g}], got {quote(given)}')
    return value


_PATH_PARAMETERS = {'pump_file': True, 'table_file': False}  # name: may name a pump set


def config_from_mapping(values: dict[str, Any], where: str = '',
                        origins: dict[str, str] | None = None, default_origin: str = ''
                        ) -> EstimatorConfig:
    """
    Validate parameter values (any subset; the rest take their declared defaults).

    File parameters (``pump_file``, ``table_file``) are resolved to absolute paths and
    must exist (``paths.resolve_path``: a relative path resolves against the current
    directory, as the node's must; ``package://`` paths and shipped pump set names work).

    Parameters
    ----------
    values : dict
        Parameter name to value.
    where : str
        Prefix for error messages (e.g. the file name).
    origins : dict, optional
        Parameter name to where its value came from (e.g. ``params file x.yaml``), for the
        file parameters' error messages.
    default_origin : str
        Where the values without an entry in ``origins`` came from.

    Returns
    -------
    EstimatorConfig
        The validated configuration.

    Raises
    ------
    ConfigError
        One message naming the first unknown, mistyped or out-of-range parameter, or a file
        parameter naming no file.

    """
    return _resolved(checked_values(values, where), origins or {}, default_origin)


ROS_PARAMETERS = frozenset({'use_sim_time', 'start_type_description_service'})
"""Parameters rclpy declares on every node: allowed beside the estimator's, not checked."""


def checked_values(values: dict[str, Any], where: str, ros_types: bool = False
                   ) -> dict[str, Any]:
    """
    Return parameter values converted to their parameters' types.

    Parameters
    ----------
    values : dict
        Parameter name to value, as read (``ROS_PARAMETERS`` are left out of the result).
    where : str
        Prefix for error messages (e.g. the file name).
    ros_types : bool
        Refuse what rclpy would refuse (an integer for a double, a string for a number).

    Returns
    -------
    dict
        The estimator's parameters among them, each of its declared type.

    Raises
    ------
    ConfigError
        One message naming the unknown parameters, or the first mistyped or out-of-range
        one.

    """
    unknown = sorted(map(str, set(values) - set(_SPECS) - ROS_PARAMETERS))
    if unknown:
        raise ConfigError(f'{where}unknown parameter(s): '
                          f'{", ".join(quote(u) for u in unknown)}')
    return {name: _SPECS[name].convert(value, where, ros_types)
            for name, value in values.items() if name in _SPECS}


def _resolved(checked: dict[str, Any], origins: dict[str, str], default_origin: str
              ) -> EstimatorConfig:
    """Resolve the file parameters of checked values and build the configuration."""
    for name, pump_set in _PATH_PARAMETERS.items():
        if checked.get(name):
            origin = origins.get(name, default_origin)
            checked[name] = str(resolve_path(checked[name], name, origin=origin,
                                             pump_set=pump_set))
    return EstimatorConfig(**checked)


def _read_params_file(path: Path) -> dict[str, Any]:
    """Return the merged ``ros__parameters`` of one file's sections for this node."""
    data = read_yaml(path, 'parameters file', unique_keys=False)  # the later wins, as in ROS 2
    if not isinstance(data, dict):
        raise ConfigError(f'{path}: expected "{NODE_NAME}: ros__parameters: ..."')
    merged: dict[str, Any] = {}
    keys = ('/**', NODE_NAME, f'/{NODE_NAME}', f'/**/{NODE_NAME}')
    for node in keys:
        section = data.get(node)
        if section is None:
            continue
        if not isinstance(section, dict) or not isinstance(section.get('ros__parameters'),
                                                           dict):
            raise ConfigError(f'{path}: {node}: expected a ros__parameters mapping')
        merged.update(section['ros__parameters'])
    if not merged and not any(k in data for k in keys):
        raise ConfigError(f'{path}: no "{NODE_NAME}" or "/**" section')
    return merged


def load_estimator_config(paths: str | Path | Sequence[str | Path] | None
                          ) -> EstimatorConfig:
    """
    Read ROS 2 parameters files (``torque_estimator: ros__parameters: {...}``), as ROS does.

    Parameters not in any file keep their declared defaults (`EstimatorConfig`, which the
    node declares and ``config/torque_estimator.yaml`` repeats); with several files a later
    file overrides an earlier one, parameter by parameter (``--params-file A --params-file
    B``). Within a file, sections ``/**`` (any node), ``torque_estimator``,
    ``/torque_estimator`` and ``/**/torque_estimator`` (the node in any namespace) are
    merged in that order.

    Parameters
    ----------
    paths : str or Path or sequence of them, or None
        The file(s); None or an empty sequence gives the defaults.

    Returns
    -------
    EstimatorConfig
        The validated configuration, file parameters resolved to absolute paths.

    Raises
    ------
    ConfigError
        Missing file, invalid YAML, wrong layout, or an invalid parameter (named with its
        file).

    """
    if paths is None:
        return EstimatorConfig()
    if isinstance(paths, (str, Path)):
        paths = [paths]
    merged: dict[str, Any] = {}
    origins: dict[str, str] = {}
    for path in map(Path, paths):
        # errors name the file; numbers of the node's types, or the node would refuse it
        values = checked_values(_read_params_file(path), f'{path}: ', ros_types=True)
        merged.update(values)
        origins.update(dict.fromkeys(values, f'params file {path}'))
    return _resolved(merged, origins, '')
