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
Pump parameter sets: loading, validation and hashing of the YAML files in ``config/pumps``.

Every value is SI. The YAML files say, value by value, where each number comes from
(Hong & Doh 2004 table, figure or text; or how it was fixed when the paper leaves it open).

Each value is declared once: its dataclass field carries how it is read and its physical
range (`_number`, `_length`, ...), and `pump_from_mapping` reads every section from those
declarations; only checks across fields are written out. Longer than 500 lines because the
ranges' reasons, the field declarations and that one reader are kept together.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields, is_dataclass
import hashlib
from itertools import pairwise
import json
import math
from pathlib import Path
from typing import Any, get_type_hints, overload

import numpy as np

from ..errors import ConfigError, quote
from ..paths import config_dir, default_pump_file, resolve_path
from ..yaml_files import number_as_float, read_yaml

__all__ = [
    'Bearing',
    'Curve',
    'Geometry',
    'Oil',
    'Operation',
    'Piston',
    'PistonFriction',
    'PumpParams',
    'ValvePlate',
    'barrel_effective_area_m2',
    'config_dir',
    'default_pump_file',
    'load_pump',
    'pump_from_mapping',
]

JOINT_SLIDING_FRAMES = ('barrel', 'flange')

# Physical ranges of pump-file values (SI). None is from the paper: they keep a file inside
# what an axial piston pump can be, so that a slip (a unit, a sign, 1e-320) is refused with
# the field's name instead of giving infinite or NaN torques.
MIN_LENGTH_M = 1e-4
"""0.1 mm: no dimension of a pump's moving parts is smaller (bores of the smallest units,
~0.5 cc/rev, are ~4 mm; ball joints ~1 mm)."""
FILM_CLEARANCE_RANGE_M = (1e-7, 1e-3)
"""0.1 um to 1 mm: below the roughness of lapped valve plates (Ra ~ 0.1 um) there is no
film to shear, which the Couette term assumes; above 1 mm the plate no longer seals (the
paper's 10 um and the effective 1.07 um lie well inside)."""
MIN_PISTON_MASS_KG = 1e-5
"""10 mg: a steel piston of the smallest bore (1 mm x 2 mm) weighs ~12 mg."""
VISCOSITY_RANGE_M2_S = (1e-7, 1e-2)
"""0.1 cSt (below any hydraulic fluid: water is 1 cSt) to 10,000 cSt (cold gear oil)."""
MIN_INCLINATION_RAD = math.radians(1.0)
"""1 deg: bent-axis units run at 15-45 deg; near 0 the stroke vanishes."""


# Each pump-file value is declared once, as a dataclass field whose metadata say how it is read
# and its physical range; `pump_from_mapping` reads every section from these declarations.
Meta = dict[str, Any]


def _number(low: float | None = None, high: float | None = None, *,
            low_inclusive: bool = False) -> Meta:
    """Declare a finite number in (low, high] ([low, high] with ``low_inclusive``)."""
    return {'read': 'number', 'low': low, 'high': high, 'low_inclusive': low_inclusive}


def _length(high_m: float) -> Meta:
    """Declare a length in [`MIN_LENGTH_M`, high_m] [m]."""
    return _number(MIN_LENGTH_M, high_m, low_inclusive=True)


def _zero_to(high: float) -> Meta:
    """Declare a non-negative number in [0, high]."""
    return _number(0.0, high, low_inclusive=True)


def _integer(low: int) -> Meta:
    """Declare an integer >= low."""
    return {'read': 'integer', 'low': low}


def _text(choices: tuple[str, ...] | None = None) -> Meta:
    """Declare a string, one of ``choices`` if given."""
    return {'read': 'text', 'choices': choices}


def _curve(x_key: str) -> Meta:
    """Declare a measured coefficient curve in [0, 1], its abscissa under ``x_key``."""
    return {'read': 'curve', 'x_key': x_key}


@dataclass(frozen=True)
class Curve:
    """
    A piecewise-linear curve y(x), held constant beyond its end points.

    Used for the friction coefficients the paper gives as measured curves (Figs. 6, 7, 9).
    """

    x: tuple[float, ...]
    y: tuple[float, ...]

    @overload
    def __call__(self, x: float) -> float:
        ...

    @overload
    def __call__(self, x: np.ndarray) -> np.ndarray:
        ...

    def __call__(self, x: np.ndarray | float) -> np.ndarray | float:
        """
        Evaluate the curve (linear between points, constant outside).

        Parameters
        ----------
        x : float or ndarray
            Abscissa, in the unit of the curve's ``x`` [-].

        Returns
        -------
        float or ndarray
            Ordinate [-], a float for a float.

        """
        return np.interp(x, self.x, self.y)


@dataclass(frozen=True)
class Geometry:
    """Kinematic geometry of the bent-axis pump (Table 1, Fig. 2(a))."""

    n_pistons: int = field(metadata=_integer(3))
    bore_diameter_m: float = field(metadata=_length(0.5))
    inclination_rad: float = field(metadata=_number(MIN_INCLINATION_RAD, math.radians(60.0),
                                                    low_inclusive=True))
    joint_pitch_radius_m: float = field(metadata=_length(0.5))
    bore_pitch_radius_m: float = field(metadata=_length(0.5))
    rod_length_m: float = field(metadata=_length(1.0))
    joint_ball_radius_m: float = field(metadata=_length(0.1))
    head_radius_m: float = field(metadata=_length(0.25))

    @property
    def piston_area_m2(self) -> float:
        """Piston head area A_p [m^2]."""
        return math.pi / 4.0 * self.bore_diameter_m**2

    @property
    def stroke_m(self) -> float:
        """
        Piston stroke of the Fig. 2 geometry, 2 R_S sin(delta) [m].

        Exact for axes that intersect in the drive-flange plane, whatever the rod length
        and bore pitch radius (the bore-axis position at shaft angles 0 and pi differs by
        exactly this amount; see ``kinematics.head_position``).
        """
        return 2.0 * self.joint_pitch_radius_m * math.sin(self.inclination_rad)

    @property
    def displacement_m3(self) -> float:
        """Geometric displacement per revolution V_g = N A_p stroke [m^3]."""
        return self.n_pistons * self.piston_area_m2 * self.stroke_m


@dataclass(frozen=True)
class Piston:
    """Mass properties of one piston (axisymmetric rigid body)."""

    mass_kg: float = field(metadata=_number(MIN_PISTON_MASS_KG, 10.0, low_inclusive=True))
    joint_to_cg_m: float = field(metadata=_zero_to(1.0))
    inertia_axial_kg_m2: float = field(metadata=_zero_to(1.0))
    inertia_transverse_kg_m2: float = field(metadata=_zero_to(1.0))


@dataclass(frozen=True)
class ValvePlate:
    """Valve-plate geometry (Fig. 2(b)) and friction data (Figs. 6, 7)."""

    land_inner_radius_m: float = field(metadata=_length(0.5))
    port_inner_radius_m: float = field(metadata=_length(0.5))
    port_outer_radius_m: float = field(metadata=_length(0.5))
    land_outer_radius_m: float = field(metadata=_length(0.5))
    film_clearance_m: float = field(metadata=_number(*FILM_CLEARANCE_RANGE_M, low_inclusive=True))
    # x: |shaft speed| [rad/s]
    coulomb_coefficient: Curve = field(metadata=_curve('speed_rad_s'))

    @property
    def friction_radius_m(self) -> float:
        """Friction radius of eq. (9): the mean of R_o and R_i [m]."""
        return 0.5 * (self.land_outer_radius_m + self.land_inner_radius_m)

    @property
    def bridge_angle_rad(self) -> float:
        """
        Angular width of the land between the two kidney ports [rad].

        Derived from Fig. 2(b): kidneys of radial width r_o - r_i with round ends, and a
        zero-overlap bridge as wide as the kidney at the port pitch radius (r_o + r_i)/2.
        """
        half_width = 0.5 * (self.port_outer_radius_m - self.port_inner_radius_m)
        pitch = 0.5 * (self.port_outer_radius_m + self.port_inner_radius_m)
        return 2.0 * math.asin(half_width / pitch)


@dataclass(frozen=True)
class Bearing:
    """Shaft-bearing coefficients of Palmgren's eq. (10), in its catalogue units."""

    f0: float = field(metadata=_number(0.0, 100.0))
    f1: float = field(metadata=_zero_to(1.0))
    a: float = field(metadata=_number(0.0, 3.0))
    b: float = field(metadata=_number(0.0, 3.0))
    mean_diameter_m: float = field(metadata=_length(1.0))


@dataclass(frozen=True)
class PistonFriction:
    """Friction of the spherical joints and piston heads (Fig. 9, eqs. 3-5)."""

    # x: sliding speed [m/s]
    joint_coefficient: Curve = field(metadata=_curve('sliding_speed_m_s'))
    head_coefficient: Curve = field(metadata=_curve('sliding_speed_m_s'))
    joint_sliding_frame: str = field(metadata=_text(JOINT_SLIDING_FRAMES))


@dataclass(frozen=True)
class Oil:
    """Hydraulic oil properties."""

    density_kg_m3: float = field(metadata=_number(100.0, 3000.0))
    viscosity_m2_s: float = field(metadata=_number(*VISCOSITY_RANGE_M2_S, low_inclusive=True))


@dataclass(frozen=True)
class Operation:
    """Operating conventions: charge pressure, zero-speed smoothing, efficiency domain."""

    charge_pressure_pa: float = field(metadata=_zero_to(1e7))
    zero_speed_threshold_rad_s: float = field(metadata=_number(0.0, 100.0))
    efficiency_min_speed_rad_s: float = field(metadata=_number(0.0, 1e4))
    efficiency_min_pressure_pa: float = field(metadata=_number(0.0, 2e8))


@dataclass(frozen=True)
class PumpParams:
    """A complete, validated pump parameter set (SI units throughout)."""

    name: str = field(metadata=_text())
    description: str = field(metadata=_text())
    geometry: Geometry
    piston: Piston
    valve_plate: ValvePlate
    bearing: Bearing
    piston_friction: PistonFriction
    oil: Oil
    operation: Operation
    source: str = field(default='', compare=False)

    @property
    def sha256(self) -> str:
        """Hash of the parameter values (not of the file text: comments do not count)."""
        values = asdict(self)
        values.pop('source')
        canonical = json.dumps(values, sort_keys=True, separators=(',', ':'))
        return hashlib.sha256(canonical.encode()).hexdigest()


# ---------------------------------------------------------------------------------------
# Loading and validation
# ---------------------------------------------------------------------------------------


_MAX_EXACT_INT = 2**53  # the largest integer float arithmetic holds exactly


def _as_number(value: Any) -> float | None:
    """
    Return ``value`` as a float, or None if it is not a number.

    PyYAML follows YAML 1.1, where ``5.0e5`` (no exponent sign) is a string; such plain
    numeric strings are accepted as numbers. Booleans are not numbers.
    """
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return number_as_float(value)  # (a 400-digit integer: inf, refused as not finite)
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            return None
    return None


class _Section:
    """Typed access to one mapping of the YAML file, with errors that name the field."""

    def __init__(self, mapping: Any, path: str, where: str) -> None:
        if not isinstance(mapping, dict):
            raise ConfigError(f'{where}: {path or "top level"}: expected a mapping')
        self._mapping = mapping
        self._path = path
        self._where = where
        self._used: set[str] = set()

    def _name(self, key: str) -> str:
        return f'{self._path}.{key}' if self._path else key

    def _error(self, key: str, message: str) -> ConfigError:
        return ConfigError(f'{self._where}: {self._name(key)}: {message}')

    def raw(self, key: str) -> Any:
        if key not in self._mapping:
            raise self._error(key, 'missing')
        self._used.add(key)
        return self._mapping[key]

    def section(self, key: str) -> _Section:
        return _Section(self.raw(key), self._name(key), self._where)

    def number(self, key: str, *, low: float | None = None, high: float | None = None,
               low_inclusive: bool = False) -> float:
        value = _as_number(self.raw(key))
        if value is None:
            raise self._error(key, f'expected a number, got {quote(self._mapping[key])}')
        if not math.isfinite(value):
            raise self._error(key, f'must be finite, got {quote(self._mapping[key])}')
        if low is not None and (value < low or (value == low and not low_inclusive)):
            relation = '>=' if low_inclusive else '>'
            raise self._error(key, f'must be {relation} {low:g}, got {value:g}')
        if high is not None and value > high:
            raise self._error(key, f'must be <= {high:g}, got {value:g}')
        return value

    def integer(self, key: str, *, low: int) -> int:
        value: object = self.raw(key)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self._error(key, f'expected an integer, got {quote(value)}')
        if value < low:
            raise self._error(key, f'must be >= {low}, got {quote(value)}')
        if value > _MAX_EXACT_INT:  # beyond, float arithmetic on it is not exact (or fails)
            raise self._error(key, f'must be <= 2**53, got {quote(value)}')
        return value

    def text(self, key: str, choices: tuple[str, ...] | None = None) -> str:
        value = self.raw(key)
        if not isinstance(value, str):
            raise self._error(key, f'expected a string, got {quote(value)}')
        if choices is not None and value not in choices:
            raise self._error(key, f'must be one of {", ".join(choices)}, got {quote(value)}')
        return value

    def curve(self, key: str, x_key: str, *, low: float = 0.0, high: float = 1.0) -> Curve:
        sub = self.section(key)
        xs = sub.raw(x_key)
        ys = sub.raw('coefficient')
        name = self._name(key)
        for label, seq in (('abscissa', xs), ('coefficient', ys)):
            if not isinstance(seq, list) or not seq:
                raise ConfigError(f'{self._where}: {name}: {label} must be a non-empty list')
            if any((n := _as_number(v)) is None or not math.isfinite(n) for v in seq):
                raise ConfigError(f'{self._where}: {name}: {label} must hold finite numbers')
        xs, ys = [_as_number(v) for v in xs], [_as_number(v) for v in ys]
        if len(xs) != len(ys):
            raise ConfigError(f'{self._where}: {name}: abscissa and coefficient lengths differ'
                              f' ({len(xs)} vs {len(ys)})')
        if any(b <= a for a, b in pairwise(xs)) or xs[0] < 0:
            raise ConfigError(f'{self._where}: {name}: abscissa must start >= 0 and increase')
        if any(not low <= v <= high for v in ys):
            raise ConfigError(f'{self._where}: {name}: coefficients must lie in [{low}, {high}]')
        sub.finish()
        return Curve(tuple(float(v) for v in xs), tuple(float(v) for v in ys))

    def finish(self) -> None:
        unknown = sorted(set(self._mapping) - self._used)
        if unknown:
            raise ConfigError(f'{self._where}: {self._path or "top level"}: unknown key(s) '
                              f'{", ".join(quote(k) for k in unknown)}')


def barrel_effective_area_m2(geom: Geometry, vp: ValvePlate) -> float:
    """
    Net area A_b pressing the barrel on the valve plate per chamber, eq. (9).

    A_b = A_p - pi/(2N) [(R_o^2 - r_o^2)/ln(R_o/r_o) - (R_i^2 - r_i^2)/ln(R_i/r_i)]: the
    piston area minus the lift of the radial pressure field under the lands. A property of
    the pump's geometry, so it lives here: the file check needs it, the friction uses it.

    Parameters
    ----------
    geom : Geometry
        Pump geometry (piston area, number of pistons).
    vp : ValvePlate
        Valve-plate radii.

    Returns
    -------
    float
        A_b [m^2].

    """
    r_in, p_in = vp.land_inner_radius_m, vp.port_inner_radius_m
    p_out, r_out = vp.port_outer_radius_m, vp.land_outer_radius_m
    outer = (r_out**2 - p_out**2) / math.log(r_out / p_out)
    inner = (r_in**2 - p_in**2) / math.log(r_in / p_in)
    return geom.piston_area_m2 - math.pi / (2.0 * geom.n_pistons) * (outer - inner)


def _read_fields(cls: Any, section: _Section) -> dict[str, Any]:
    """Read the fields of dataclass ``cls`` that carry a declaration (`_number` & co.)."""
    values: dict[str, Any] = {}
    for item in fields(cls):
        meta = item.metadata
        read = meta.get('read')
        if read == 'number':
            values[item.name] = section.number(item.name, low=meta['low'], high=meta['high'],
                                               low_inclusive=meta['low_inclusive'])
        elif read == 'integer':
            values[item.name] = section.integer(item.name, low=meta['low'])
        elif read == 'text':
            values[item.name] = section.text(item.name, meta['choices'])
        elif read == 'curve':
            values[item.name] = section.curve(item.name, meta['x_key'])
    return values


def _check_geometry(g: Geometry, where: str) -> None:
    offset = 2.0 * g.joint_pitch_radius_m
    if g.rod_length_m <= offset:
        raise ConfigError(f'{where}: geometry.rod_length_m: must exceed 2 x joint_pitch_radius_m'
                          f' ({offset:g} m) for the piston to stay in its bore')
    # the bores must not cut into each other: centres 2 R_C sin(pi / N) apart on the pitch
    # circle, more than a bore diameter (this also bounds N: 1e9 pistons fit no barrel)
    spacing = 2.0 * g.bore_pitch_radius_m * math.sin(math.pi / g.n_pistons)
    if spacing <= g.bore_diameter_m:
        raise ConfigError(f'{where}: geometry.n_pistons: {quote(g.n_pistons)} bores of '
                          f'{g.bore_diameter_m:g} m do not fit on the bore pitch circle'
                          f' of radius {g.bore_pitch_radius_m:g} m (adjacent centres '
                          f'{spacing:.3g} m apart)')


def _check_piston(piston: Piston, sections: dict[str, Any], where: str) -> None:
    if piston.joint_to_cg_m > sections['geometry'].rod_length_m:
        raise ConfigError(f'{where}: piston.joint_to_cg_m: must not exceed geometry.rod_length_m')


def _check_valve_plate(vp: ValvePlate, sections: dict[str, Any], where: str) -> None:
    radii = (vp.land_inner_radius_m, vp.port_inner_radius_m, vp.port_outer_radius_m,
             vp.land_outer_radius_m)
    if not all(a < b for a, b in pairwise(radii)):
        raise ConfigError(f'{where}: valve_plate: radii must satisfy R_i < r_i < r_o < R_o')
    area = barrel_effective_area_m2(sections['geometry'], vp)
    if area <= 0.0:  # the film's pressure field outweighs the pistons: the barrel lifts off
        raise ConfigError(f'{where}: valve_plate: the pressure field under the lands lifts '
                          f'more than the piston area presses (A_b = {area:.3g} m^2 <= 0, '
                          'eq. 9): the barrel would lift off; check the radii against '
                          'geometry.bore_diameter_m and n_pistons')


# What one field's range cannot say: checks across fields, run after their section is read.
_SECTION_CHECKS: dict[str, Any] = {
    'geometry': lambda g, sections, where: _check_geometry(g, where),
    'piston': _check_piston,
    'valve_plate': _check_valve_plate,
}


def pump_from_mapping(data: Any, where: str = '<mapping>') -> PumpParams:
    """
    Build a validated `PumpParams` from the parsed YAML mapping.

    Each value is read as its dataclass field declares it (type and physical range), section
    by section in `PumpParams` order; checks across fields follow their section.

    Parameters
    ----------
    data : dict
        Parsed content of a pump parameter file.
    where : str
        Name of the source, used in error messages.

    Returns
    -------
    PumpParams
        The validated parameter set.

    Raises
    ------
    ConfigError
        One clear message naming the first missing, mistyped or non-physical field.

    """
    top = _Section(data, '', where)
    values = _read_fields(PumpParams, top)
    types = get_type_hints(PumpParams)
    sections: dict[str, Any] = {}
    for item in fields(PumpParams):
        cls: Any = types[item.name]
        is_section: bool = is_dataclass(cls)  # (a bool: no narrowing of cls)
        if not is_section:
            continue
        section = top.section(item.name)
        sections[item.name] = cls(**_read_fields(cls, section))
        section.finish()
        check = _SECTION_CHECKS.get(item.name)
        if check is not None:
            check(sections[item.name], sections, where)
    if 'provenance' in data:  # written by `pump_friction calibrate`; not a parameter
        if not isinstance(top.raw('provenance'), dict):
            raise ConfigError(f'{where}: provenance: expected a mapping')
    top.finish()
    return PumpParams(**values, **sections, source=where)


def load_pump(path: str | Path | None = None) -> PumpParams:
    """
    Load and validate a pump parameter file.

    Parameters
    ----------
    path : str or Path, optional
        YAML file, ``package://pump_friction_ros/...`` path or shipped set name
        (``hong_doh_2004_consistent``; see ``paths.resolve_path``). Default: the paper's
        pump, ``config/pumps/hong_doh_2004.yaml``.

    Returns
    -------
    PumpParams
        The validated parameter set.

    Raises
    ------
    ConfigError
        When the file is missing, is not valid YAML, or any field is invalid.

    """
    path = default_pump_file() if path is None or str(path) == '' else \
        resolve_path(path, 'pump file', pump_set=True)
    return pump_from_mapping(read_yaml(path, 'pump file'), str(path))
