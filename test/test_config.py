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

"""Node parameters declared once: the dataclass, the ROS spec, the shipped YAML and the README."""

from dataclasses import fields
from enum import Enum
import math
from pathlib import Path
import re

import numpy as np
from pump_friction_ros.core.node_parameters import (
    config_from_mapping,
    EstimatorConfig,
    load_estimator_config,
    NODE_NAME,
    PARAMETERS,
)
from pump_friction_ros.errors import ConfigError
import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
SHIPPED = REPO / 'config' / 'torque_estimator.yaml'
FIELDS = {f.name: f for f in fields(EstimatorConfig)}
CHOICES = [p for p in PARAMETERS if p.choices]
RANGED = [p for p in PARAMETERS if p.low is not None]
ROS_TYPES = {bool, int, float, str}  # what a ROS 2 parameter can hold here


def shipped_parameters():
    return yaml.safe_load(SHIPPED.read_text())[f'/**/{NODE_NAME}']['ros__parameters']


def test_every_parameter_has_a_one_line_description():
    for p in PARAMETERS:
        assert p.description.strip() and '\n' not in p.description, p.name


@pytest.mark.parametrize('spec', PARAMETERS, ids=[p.name for p in PARAMETERS])
def test_ros_default_is_the_dataclass_default_as_a_plain_ros_type(spec):
    default = FIELDS[spec.name].default
    if isinstance(default, Enum):
        assert spec.default == default.value and spec.enum is type(default)
    else:
        assert spec.default == default and spec.enum is None
    # exactly a ROS type: a float declared with an int default would make the node declare
    # an integer parameter and refuse 0.5 from a parameters file
    assert type(spec.default) in ROS_TYPES
    assert type(default).__name__ == FIELDS[spec.name].type or isinstance(default, Enum)


@pytest.mark.parametrize('spec', CHOICES, ids=[p.name for p in CHOICES])
def test_choices_are_the_enum_values_and_strings_become_enum_members(spec):
    assert spec.choices == tuple(member.value for member in spec.enum)
    for member in spec.enum:
        value = getattr(config_from_mapping({spec.name: member.value}), spec.name)
        assert value is member and str(value) == member.value
        assert getattr(EstimatorConfig(**{spec.name: member.value}), spec.name) is member


@pytest.mark.parametrize('spec', CHOICES, ids=[p.name for p in CHOICES])
@pytest.mark.parametrize('value', ['Joint_State', 'bogus', '', 1, None])
def test_other_choice_values_are_refused_with_one_line(spec, value):
    with pytest.raises(ConfigError) as info:
        config_from_mapping({spec.name: value}, 'params.yaml: ')
    text = str(info.value)
    assert text.startswith(f'params.yaml: {spec.name}: ') and '\n' not in text
    if isinstance(value, str):
        assert all(choice in text for choice in spec.choices)


def _outside(spec):
    """Values just outside the range (the nearest representable ones)."""
    if type(spec.default) is int:
        return [spec.low - 1] + ([] if math.isinf(spec.high) else [spec.high + 1])
    below = float(np.nextafter(spec.low, -math.inf))
    return [below] + ([] if math.isinf(spec.high) else [float(np.nextafter(spec.high,
                                                                           math.inf))])


@pytest.mark.parametrize('spec', RANGED, ids=[p.name for p in RANGED])
def test_range_ends_are_accepted_and_values_beyond_refused_with_one_line(spec):
    for end in (spec.low, spec.high):
        if not math.isinf(end):
            assert spec.convert(type(spec.default)(end), '') == end
    # and integers too large for a float (a params file can hold 400 digits): refused by the
    # range, not an OverflowError
    huge = [sign * 10**400 for sign, end in ((1, spec.high), (-1, spec.low))
            if not math.isinf(end)]
    for value in [*_outside(spec), *huge]:
        with pytest.raises(ConfigError, match=rf'^{spec.name}: must be in \[') as info:
            config_from_mapping({spec.name: value})
        assert '\n' not in str(info.value)
    if type(spec.default) is float:
        with pytest.raises(ConfigError, match='NaN'):
            config_from_mapping({spec.name: math.nan})


@pytest.mark.parametrize(('name', 'value', 'message'), [
    ('reliable_inputs', 1, 'expected true or false'),
    ('output_decimation', 2.5, 'expected an integer'),
    ('output_decimation', True, 'expected a number'),
    ('max_input_age_s', '0.05', 'expected a number'),
    ('joint_name', 3, 'expected a string'),
    ('max_imput_age_s', 0.05, 'unknown parameter'),
])
def test_mistyped_and_unknown_parameters_are_refused_with_one_line(name, value, message):
    with pytest.raises(ConfigError, match=message) as info:
        config_from_mapping({name: value})
    assert name in str(info.value) and '\n' not in str(info.value)


def test_whole_numbers_convert_to_the_parameter_type():
    config = config_from_mapping({'output_decimation': 4.0, 'max_input_age_s': 1})
    assert type(config.output_decimation) is int and type(config.max_input_age_s) is float


def test_shipped_parameters_file_names_exactly_the_declared_parameters():
    values = shipped_parameters()
    assert set(values) == set(FIELDS)  # none unknown, none missing
    for name, value in values.items():  # as the node would declare them: same ROS type
        assert type(value) is type(next(p for p in PARAMETERS if p.name == name).default), \
            name
    assert load_estimator_config(SHIPPED).joint_name == values['joint_name']


def test_shipped_parameters_are_the_declared_defaults():
    defaults = {p.name: p.default for p in PARAMETERS}
    assert shipped_parameters() == defaults  # a deployment's own values go in its own file


def test_every_value_in_the_shipped_parameters_file_has_a_comment():
    lines = SHIPPED.read_text().splitlines()
    start = lines.index('  ros__parameters:') + 1
    for line in lines[start:]:
        if line.strip():
            assert re.match(r'^    \w+: .*\S\s+# \S', line), line


def test_zero_viscosity_means_the_pump_files():
    assert EstimatorConfig(oil_viscosity_m2_s=0.0).viscosity_m2_s(46e-6) == 46e-6
    assert EstimatorConfig(oil_viscosity_m2_s=68e-6).viscosity_m2_s(46e-6) == 68e-6


@pytest.mark.parametrize('view', ['MonitorSettings', 'AttributionSettings'])
def test_each_filter_takes_named_node_parameters_only(view):
    from pump_friction_ros.core import attribution, monitor
    from pump_friction_ros.core.node_parameters import settings_view

    cls = getattr(monitor, view, None) or getattr(attribution, view)
    assert {f.name for f in fields(cls)} < set(FIELDS)  # a few of them, each declared once
    config = EstimatorConfig(cusum_drift_nm=0.123, attribution_z=3.5)
    got = settings_view(config, cls)
    for f in fields(cls):
        assert getattr(got, f.name) == getattr(config, f.name)
