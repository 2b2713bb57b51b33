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

"""Pump parameter files: validation errors name the field; the hash follows values only."""

import copy

from pump_friction_ros.errors import ConfigError
from pump_friction_ros.physics.pump_parameters import load_pump, pump_from_mapping
from pump_friction_ros.yaml_files import read_yaml
import pytest
import yaml

from .conftest import CONSISTENT_PUMP, PAPER_PUMP


@pytest.fixture
def raw():
    return yaml.safe_load(PAPER_PUMP.read_text())


def test_both_shipped_parameter_sets_load_and_differ(paper_params, consistent_params):
    assert paper_params.name == 'hong_doh_2004'
    assert consistent_params.name == 'hong_doh_2004_consistent'
    assert paper_params.sha256 != consistent_params.sha256
    assert paper_params.geometry == consistent_params.geometry


def test_default_pump_is_the_papers(paper_params):
    assert load_pump().sha256 == paper_params.sha256


def test_hash_ignores_comments_but_not_values(tmp_path, paper_params):
    text = PAPER_PUMP.read_text()
    commented = tmp_path / 'c.yaml'
    commented.write_text('# another comment\n' + text.replace('# Table 1', '# table one'))
    assert load_pump(commented).sha256 == paper_params.sha256
    changed = tmp_path / 'v.yaml'
    changed.write_text(text.replace('mass_kg: 3.2e-3', 'mass_kg: 3.3e-3'))
    assert load_pump(changed).sha256 != paper_params.sha256


def test_yaml_1_1_exponent_without_sign_is_read_as_a_number(raw):
    raw['oil']['viscosity_m2_s'] = '46e-6'
    raw['operation']['efficiency_min_pressure_pa'] = '5e5'
    params = pump_from_mapping(raw)
    assert params.oil.viscosity_m2_s == 46e-6
    assert params.operation.efficiency_min_pressure_pa == 5e5


@pytest.mark.parametrize(('section', 'key', 'value', 'message'), [
    ('geometry', 'rod_length_m', None, 'geometry.rod_length_m: missing'),
    ('geometry', 'n_pistons', 4.5, 'geometry.n_pistons: expected an integer'),
    ('geometry', 'bore_diameter_m', 'wide', 'geometry.bore_diameter_m: expected a number'),
    ('geometry', 'bore_diameter_m', -9.5e-3, 'geometry.bore_diameter_m: must be >= 0.0001'),
    ('geometry', 'rod_length_m', 0.015, 'rod_length_m: must exceed'),
    ('piston', 'mass_kg', float('nan'), 'piston.mass_kg: must be finite'),
    ('piston', 'mass_kg', True, 'piston.mass_kg: expected a number'),
    ('valve_plate', 'port_inner_radius_m', 5e-3, 'R_i < r_i < r_o < R_o'),
    ('oil', 'viscosity_m2_s', 0.0, 'oil.viscosity_m2_s: must be >= 1e-07'),
    ('valve_plate', 'film_clearance_m', 1e-320, 'film_clearance_m: must be >= 1e-07'),
    ('valve_plate', 'film_clearance_m', 0.01, 'film_clearance_m: must be <= 0.001'),
    ('geometry', 'n_pistons', 10**9, 'n_pistons: 1000000000 bores of 0.0095 m do not fit'),
    ('geometry', 'n_pistons', 7, 'n_pistons: 7 bores of 0.0095 m do not fit'),
    ('geometry', 'inclination_rad', 1e-300, 'inclination_rad: must be >= 0.0174533'),
    ('piston', 'mass_kg', 1e-300, 'mass_kg: must be >= 1e-05'),
    ('bearing', 'mean_diameter_m', 1e-320, 'mean_diameter_m: must be >= 0.0001'),
    ('piston_friction', 'joint_sliding_frame', 'shaft', 'must be one of barrel, flange'),
    ('bearing', 'f0', -1, 'bearing.f0: must be > 0'),
    # integers too large for a float: refused by range, not an OverflowError
    ('piston', 'mass_kg', 10**400, 'piston.mass_kg: must be finite, got 1000'),
    ('geometry', 'n_pistons', 10**400, 'geometry.n_pistons: must be <= 2\\*\\*53'),
])
def test_invalid_field_is_refused_with_one_message_naming_it(raw, section, key, value, message):
    if value is None:
        del raw[section][key]
    else:
        raw[section][key] = value
    with pytest.raises(ConfigError, match=message.replace('(', r'\(')):
        pump_from_mapping(raw, 'pump.yaml')


def test_unknown_key_is_refused(raw):
    raw['geometry']['rod_lenght_m'] = 0.05
    with pytest.raises(ConfigError, match=r'unknown key.*rod_lenght_m'):
        pump_from_mapping(raw)


@pytest.mark.parametrize(('curve', 'mutate', 'message'), [
    ('joint_coefficient', lambda c: c.update(coefficient=[0.1]), 'lengths differ'),
    ('joint_coefficient', lambda c: c.update(sliding_speed_m_s=[0, 2, 1, 3, 4, 5]), 'increase'),
    ('head_coefficient', lambda c: c.update(coefficient=[1.5]), r'\[0.0, 1.0\]'),
    ('head_coefficient', lambda c: c.update(coefficient=[]), 'non-empty'),
])
def test_invalid_friction_curve_is_refused(raw, curve, mutate, message):
    mutate(raw['piston_friction'][curve])
    with pytest.raises(ConfigError, match=message):
        pump_from_mapping(raw)


def test_unreadable_files_give_clear_errors(tmp_path):
    with pytest.raises(ConfigError, match='not found'):
        load_pump(tmp_path / 'missing.yaml')
    bad = tmp_path / 'bad.yaml'
    bad.write_text('geometry: [1, 2\n')
    with pytest.raises(ConfigError, match=r'invalid YAML \(line'):
        load_pump(bad)
    scalar = tmp_path / 'scalar.yaml'
    scalar.write_text('42\n')
    with pytest.raises(ConfigError, match='expected a mapping'):
        load_pump(scalar)


def test_a_key_given_twice_in_a_pump_file_is_refused_naming_it_and_its_line(tmp_path):
    text = PAPER_PUMP.read_text()
    assert text.count('film_clearance_m:') == 1
    twice = tmp_path / 'twice.yaml'
    twice.write_text(text.replace('film_clearance_m:', 'film_clearance_m: 12.0e-6\n'
                                  '  film_clearance_m:', 1))
    with pytest.raises(ConfigError) as err:
        load_pump(twice)
    message = str(err.value)
    assert "key 'film_clearance_m' given twice" in message and '\n' not in message
    line = text[:text.index('film_clearance_m:')].count('\n') + 2  # the second one's
    assert f'(line {line},' in message
    merged = tmp_path / 'merged.yaml'  # a merge key's values may be overridden, as YAML means
    merged.write_text('base: &e {a: 1, b: 2}\nuse: {<<: *e, b: 3}\n')
    assert read_yaml(merged, 'pump file')['use'] == {'a': 1, 'b': 3}


def test_consistent_set_only_changes_documented_values(raw):
    other = yaml.safe_load(CONSISTENT_PUMP.read_text())
    differ = {(s, k) for s in raw if isinstance(raw[s], dict)
              for k in raw[s] if raw[s][k] != other[s][k]}
    assert differ == {('piston', 'mass_kg'), ('piston', 'joint_to_cg_m'),
                      ('piston', 'inertia_axial_kg_m2'), ('piston', 'inertia_transverse_kg_m2'),
                      ('valve_plate', 'film_clearance_m'), ('bearing', 'mean_diameter_m'),
                      ('piston_friction', 'joint_sliding_frame')}
    assert copy.deepcopy(raw) == raw


def test_absurd_yaml_is_refused_in_one_line(tmp_path):
    huge = tmp_path / 'huge.yaml'
    huge.write_text(PAPER_PUMP.read_text().replace('n_pistons: 5 ', 'n_pistons: ' + '9' * 5000))
    with pytest.raises(ConfigError, match='a number too long'):
        load_pump(huge)
    deep = tmp_path / 'deep.yaml'
    deep.write_text('name: ' + '[' * 100000 + ']' * 100000 + '\n')
    with pytest.raises(ConfigError, match='invalid YAML'):
        load_pump(deep)


def test_a_huge_integer_is_quoted_without_printing_it():
    from pump_friction_ros.errors import quote
    assert quote(10**5000) == 'an integer too long to print'
    assert quote('x' * 10**6) == repr('x' * 60) + '...'


def _numeric_keys(raw):
    return [(section, key) for section, values in raw.items() if isinstance(values, dict)
            and section != 'provenance'
            for key, value in values.items() if isinstance(value, (int, float))
            and not isinstance(value, bool)]


@pytest.mark.parametrize('value', [1e30, -1.0, 'fast', None])
def test_every_number_of_the_file_has_a_range_and_a_type(raw, value):
    """No pump value is 1e30 (any unit), negative, text or missing: each is refused by name."""
    keys = _numeric_keys(raw)
    assert len(keys) == 27  # every number of the seven sections (curves apart)
    for section, key in keys:
        broken = copy.deepcopy(raw)
        if value is None:
            del broken[section][key]
        else:
            broken[section][key] = value
        with pytest.raises(ConfigError, match=rf'{section}\.{key}: '):
            pump_from_mapping(broken, 'pump.yaml')
