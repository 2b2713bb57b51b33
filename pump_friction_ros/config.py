"""Parameters of the torque estimator: one spec for the node, the replay and the tests.

The node declares every parameter below with a ``ParameterDescriptor`` built from this spec
(description and range); the replay reads the same ROS 2 parameters file
(``torque_estimator: ros__parameters: ...``); both validate into the same frozen
`EstimatorConfig`, which the ROS-free core takes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import yaml

from .errors import ConfigError

__all__ = [
    'NODE_NAME',
    'PARAMETERS',
    'EstimatorConfig',
    'ParameterSpec',
    'config_from_mapping',
    'load_estimator_config',
]

NODE_NAME = 'torque_estimator'


@dataclass(frozen=True)
class ParameterSpec:
    """One node parameter: name, default (its type is the parameter's), range, text."""

    name: str
    default: Any
    description: str
    low: float | None = None
    high: float | None = None
    choices: tuple[str, ...] | None = None


_INF = math.inf
PARAMETERS: tuple[ParameterSpec, ...] = (
    ParameterSpec('pump_file', '', 'Pump parameter YAML; empty: the package\'s '
                  'config/pumps/hong_doh_2004.yaml.'),
    ParameterSpec('table_file', '', 'Friction table .npz built for that pump; empty: built on '
                  'first use and cached (~/.cache/pump_friction_ros).'),
    ParameterSpec('joint_name', 'pump_shaft', 'Joint of sensor_msgs/JointState whose velocity '
                  'is the shaft speed [rad/s] and effort the motor torque [N m].'),
    ParameterSpec('speed_source', 'joint_state', 'Shaft speed from joint_states (JointState) '
                  'or shaft_speed (std_msgs/Float64).', choices=('joint_state', 'float64')),
    ParameterSpec('torque_source', 'joint_state', 'Measured motor torque from joint_states '
                  '(JointState effort) or motor_torque (std_msgs/Float64).',
                  choices=('joint_state', 'float64')),
    ParameterSpec('pressure_source', 'difference', 'load_pressure (FluidPressure, p_A - p_B) '
                  'or ports: pressure_a and pressure_b, dp = a - b.',
                  choices=('difference', 'ports')),
    ParameterSpec('viscosity_source', 'parameter', 'Oil viscosity from oil_viscosity_m2_s, '
                  'or from oil_temperature (sensor_msgs/Temperature [degC]) via ASTM D341.',
                  choices=('parameter', 'temperature')),
    ParameterSpec('oil_viscosity_m2_s', 0.0, 'Oil kinematic viscosity [m^2/s] (1 cSt = 1e-6);'
                  ' 0: the pump file\'s.', 0.0, 1e-2),
    ParameterSpec('oil_viscosity_40c_m2_s', 46e-6, 'Viscosity at 40 degC [m^2/s] for the '
                  'temperature law (ISO VG 46: 46e-6).', 1e-7, 1e-2),
    ParameterSpec('oil_viscosity_100c_m2_s', 6.8e-6, 'Viscosity at 100 degC [m^2/s] for the '
                  'temperature law (ISO VG 46: 6.8e-6).', 1e-7, 1e-2),
    ParameterSpec('max_input_age_s', 0.05, 'An input older than this is stale: no estimate '
                  'is made [s].', 1e-4, 60.0),
    ParameterSpec('max_temperature_age_s', 5.0, 'Oil temperature older than this is stale '
                  '[s] (temperature sensors publish slowly).', 1e-3, 3600.0),
    ParameterSpec('rotor_inertia_kg_m2', 2.0e-4, 'Inertia of motor rotor, coupling and pump '
                  'rotating group [kg m^2].', 0.0, 10.0),
    ParameterSpec('accel_filter_time_constant_s', 0.01, 'Time constant of each of the two '
                  'low-pass stages of the speed derivative [s].', 1e-4, 10.0),
    ParameterSpec('drive_loss_torque_nm', 0.0, 'Constant drive loss opposing the motion '
                  '(seals, gears) [N m].', 0.0, 100.0),
    ParameterSpec('monitor_min_speed_rad_s', 20.0, 'The wear monitor learns only above this '
                  '|speed| [rad/s] (reversals and creep are skipped).', 0.0, 1e4),
    ParameterSpec('monitor_max_accel_rad_s2', 300.0, 'The wear monitor learns only from '
                  'near-steady samples, |filtered acceleration| below this [rad/s^2].', 0.0,
                  _INF),
    ParameterSpec('ewma_time_constant_s', 2.0, 'Time constant of the residual\'s EWMA [s].',
                  1e-3, 1e5),
    ParameterSpec('cusum_drift_nm', 0.1, 'CUSUM allowance k: friction residual tolerated '
                  'without accumulating [N m].', 0.0, 100.0),
    ParameterSpec('cusum_warn_nm_s', 1.5, 'CUSUM level (integral of residual beyond k) for '
                  'WARN [N m s].', 1e-6, 1e6),
    ParameterSpec('cusum_error_nm_s', 5.0, 'CUSUM level for ERROR [N m s].', 1e-6, 1e6),
    ParameterSpec('cusum_clear_ratio', 0.5, 'A level clears when the CUSUM falls below this '
                  'fraction of its threshold (hysteresis).', 0.0, 1.0),
    ParameterSpec('rls_forgetting_time_s', 30.0, 'Memory of the valve-plate scale estimate '
                  '(RLS forgetting factor exp(-dt / T)) [s].', 1.0, 1e7),
    ParameterSpec('rls_initial_std', 0.5, 'Prior standard deviation of the friction scale '
                  'factors [-].', 1e-3, 100.0),
    ParameterSpec('stale_timeout_s', 0.5, 'No estimate for this long: diagnostics STALE [s].',
                  1e-3, 3600.0),
    ParameterSpec('output_decimation', 10, 'Publish every N-th estimate (1 kHz in, 100 Hz '
                  'out with 10).', 1, 100000),
    ParameterSpec('diagnostics_rate_hz', 1.0, 'Rate of /diagnostics [Hz].', 0.01, 100.0),
    ParameterSpec('hardware_id', 'eha_pump', 'hardware_id of the diagnostic status.'),
    ParameterSpec('reliable_inputs', False, 'Subscribe with reliable QoS instead of the '
                  'sensor-data profile (best effort).'),
)


@dataclass(frozen=True)
class EstimatorConfig:
    """Validated estimator parameters (SI); field names are the parameter names."""

    pump_file: str = ''
    table_file: str = ''
    joint_name: str = 'pump_shaft'
    speed_source: str = 'joint_state'
    torque_source: str = 'joint_state'
    pressure_source: str = 'difference'
    viscosity_source: str = 'parameter'
    oil_viscosity_m2_s: float = 0.0
    oil_viscosity_40c_m2_s: float = 46e-6
    oil_viscosity_100c_m2_s: float = 6.8e-6
    max_input_age_s: float = 0.05
    max_temperature_age_s: float = 5.0
    rotor_inertia_kg_m2: float = 2.0e-4
    accel_filter_time_constant_s: float = 0.01
    drive_loss_torque_nm: float = 0.0
    monitor_min_speed_rad_s: float = 20.0
    monitor_max_accel_rad_s2: float = 300.0
    ewma_time_constant_s: float = 2.0
    cusum_drift_nm: float = 0.1
    cusum_warn_nm_s: float = 1.5
    cusum_error_nm_s: float = 5.0
    cusum_clear_ratio: float = 0.5
    rls_forgetting_time_s: float = 30.0
    rls_initial_std: float = 0.5
    stale_timeout_s: float = 0.5
    output_decimation: int = 10
    diagnostics_rate_hz: float = 1.0
    hardware_id: str = 'eha_pump'
    reliable_inputs: bool = False

    def __post_init__(self) -> None:
        if self.cusum_error_nm_s < self.cusum_warn_nm_s:
            raise ConfigError('cusum_error_nm_s must be >= cusum_warn_nm_s')
        if self.oil_viscosity_100c_m2_s >= self.oil_viscosity_40c_m2_s:
            raise ConfigError('oil_viscosity_100c_m2_s must be below oil_viscosity_40c_m2_s')


assert [f.name for f in fields(EstimatorConfig)] == [p.name for p in PARAMETERS]
assert all(getattr(EstimatorConfig, p.name) == p.default for p in PARAMETERS)


def _check(spec: ParameterSpec, value: Any, where: str) -> Any:
    """Return ``value`` converted to the type of ``spec.default``, or raise ConfigError."""
    name = f'{where}{spec.name}'
    kind = type(spec.default)
    if kind is bool:
        if not isinstance(value, bool):
            raise ConfigError(f'{name}: expected true or false, got {value!r}')
        return value
    if kind is str:
        if not isinstance(value, str):
            raise ConfigError(f'{name}: expected a string, got {value!r}')
        if spec.choices and value not in spec.choices:
            raise ConfigError(f'{name}: must be one of {", ".join(spec.choices)}, '
                              f'got {value!r}')
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f'{name}: expected a number, got {value!r}')
    if kind is int:
        if isinstance(value, float) and not value.is_integer():
            raise ConfigError(f'{name}: expected an integer, got {value!r}')
        value = int(value)
    else:
        value = float(value)
        if math.isnan(value):
            raise ConfigError(f'{name}: must not be NaN')
    if (spec.low is not None and value < spec.low) or \
            (spec.high is not None and value > spec.high):
        raise ConfigError(f'{name}: must be in [{spec.low:g}, {spec.high:g}], got {value!r}')
    return value


def config_from_mapping(values: dict[str, Any], where: str = '') -> EstimatorConfig:
    """Validate parameter values (any subset; the rest take their defaults).

    Parameters
    ----------
    values : dict
        Parameter name to value.
    where : str
        Prefix for error messages (e.g. the file name).

    Returns
    -------
    EstimatorConfig
        The validated configuration.

    Raises
    ------
    ConfigError
        One message naming the first unknown, mistyped or out-of-range parameter.
    """
    specs = {p.name: p for p in PARAMETERS}
    unknown = sorted(set(values) - set(specs) - {'use_sim_time'})
    if unknown:
        raise ConfigError(f'{where}unknown parameter(s): {", ".join(unknown)}')
    checked = {name: _check(specs[name], value, where) for name, value in values.items()
               if name in specs}
    return EstimatorConfig(**checked)


def load_estimator_config(path: str | Path | None) -> EstimatorConfig:
    """Read a ROS 2 parameters file (``torque_estimator: ros__parameters: {...}``).

    Sections ``/**`` (any node), ``torque_estimator``, ``/torque_estimator`` and
    ``/**/torque_estimator`` (the node in any namespace) are merged in that order.

    Parameters
    ----------
    path : str or Path or None
        The file; None gives the defaults.

    Returns
    -------
    EstimatorConfig
        The validated configuration.

    Raises
    ------
    ConfigError
        Missing file, invalid YAML, wrong layout, or an invalid parameter.
    """
    if path is None:
        return EstimatorConfig()
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text(encoding='utf-8'))
    except FileNotFoundError:
        raise ConfigError(f'parameters file not found: {path}') from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f'cannot read parameters file {path}: {exc}') from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        at = f' (line {mark.line + 1})' if mark else ''
        raise ConfigError(f'{path}: invalid YAML{at}') from None
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
    return config_from_mapping(merged, f'{path}: ')
