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
Node parameters: one source of defaults, params files merged as ROS does, file parameters.

The node declares `config.PARAMETERS` (made from `EstimatorConfig`), the replay starts
from `EstimatorConfig()`, and ``config/torque_estimator.yaml`` repeats the same values, so a
partial params file or a ``-p`` override changes only what it names. What is specific to
the sample bags' simulated pump lives in ``bags/eha_params.yaml``.
"""

import argparse
import math
from pathlib import Path

from pump_friction_ros.core.node_parameters import (
    EstimatorConfig,
    load_estimator_config,
    PARAMETERS,
)
from pump_friction_ros.errors import ConfigError
from pump_friction_ros.paths import config_dir
from pump_friction_ros.sim.duty_cycle import DutyCycle
from pump_friction_ros.sim.sample_bags import sample_params_text
from pump_friction_ros.yaml_files import read_yaml, SafeDumper
import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
SHIPPED = REPO / 'config' / 'torque_estimator.yaml'
SAMPLE_PARAMS = REPO / 'bags' / 'eha_params.yaml'


def params_file(path, **values):
    path.write_text(yaml.safe_dump({'/**/torque_estimator': {'ros__parameters': values}}))
    return path


def test_shipped_params_file_declared_defaults_and_replay_defaults_agree():
    raw = yaml.safe_load(SHIPPED.read_text())['/**/torque_estimator']['ros__parameters']
    assert list(raw) == [p.name for p in PARAMETERS]  # every parameter, in declared order
    defaults = EstimatorConfig()
    for spec in PARAMETERS:  # what the node declares ...
        assert raw[spec.name] == spec.default, spec.name  # ... is what the file says
        value = getattr(defaults, spec.name)  # ... and what the replay starts from
        assert (value.value if spec.enum else value) == spec.default, spec.name
    assert load_estimator_config(SHIPPED) == defaults
    from pump_friction_ros.app.data_commands import estimator_config
    assert estimator_config(argparse.Namespace(params=None)) == defaults  # replay, no flag


def test_the_sample_bags_bring_their_simulated_pump_with_them():
    assert SAMPLE_PARAMS.read_text() == sample_params_text(DutyCycle())
    config = load_estimator_config([SHIPPED, SAMPLE_PARAMS])
    cycle = DutyCycle()
    assert config.oil_viscosity_m2_s == cycle.viscosity_m2_s == 46e-6
    assert config.drive_loss_torque_nm == cycle.drive_loss_torque_nm == 0.05
    assert config.rotor_inertia_kg_m2 == cycle.rotor_inertia_kg_m2


def test_a_partial_params_file_changes_only_what_it_names(tmp_path):
    one = params_file(tmp_path / 'one.yaml', hardware_id='pump_7')
    assert load_estimator_config(one) == EstimatorConfig(hardware_id='pump_7')
    both = load_estimator_config([SAMPLE_PARAMS, one])
    assert both.hardware_id == 'pump_7' and both.oil_viscosity_m2_s == 46e-6


def test_later_params_files_override_earlier_ones_parameter_by_parameter(tmp_path):
    a = params_file(tmp_path / 'a.yaml', hardware_id='a', cusum_drift_nm=0.3)
    b = params_file(tmp_path / 'b.yaml', hardware_id='b')
    config = load_estimator_config([a, b])
    assert config.hardware_id == 'b' and config.cusum_drift_nm == 0.3
    bad = params_file(tmp_path / 'bad.yaml', cusum_drift_nm='high')
    with pytest.raises(ConfigError, match=r'bad\.yaml: cusum_drift_nm: expected a number'):
        load_estimator_config([a, bad])


def test_a_parameter_given_twice_in_one_file_takes_the_later_as_ros_2_does(tmp_path):
    # rcl_yaml_param_parser's parse.c overwrites the earlier value ("Overwriting,
    # deallocate original"); a pump file refuses the same (test_params)
    path = tmp_path / 'twice.yaml'
    path.write_text('torque_estimator:\n  ros__parameters:\n    hardware_id: first\n'
                    '    cusum_drift_nm: 0.3\n    hardware_id: second\n')
    config = load_estimator_config(path)
    assert (config.hardware_id, config.cusum_drift_nm) == ('second', 0.3)


def test_a_plain_exponent_without_a_dot_is_a_number_as_ros_2_reads_it(tmp_path):
    # rcl_yaml_param_parser takes an unquoted 1e-2 as a double (strtod); YAML 1.1, PyYAML's,
    # reads it as the string '1e-2' and the file ros2 launch accepts was refused
    path = tmp_path / 'exp.yaml'
    path.write_text('torque_estimator:\n  ros__parameters:\n    cusum_drift_nm: 3e-2\n'
                    '    warm_up_pause_s: 2E2\n    stale_timeout_s: .5e0\n')
    config = load_estimator_config(path)
    assert (config.cusum_drift_nm, config.warm_up_pause_s, config.stale_timeout_s) == (
        0.03, 200.0, 0.5)
    quoted = tmp_path / 'quoted.yaml'  # quoted, a string in ROS 2 too
    quoted.write_text("torque_estimator:\n  ros__parameters:\n    cusum_drift_nm: '3e-2'\n")
    with pytest.raises(ConfigError, match=r"cusum_drift_nm: expected a number, got '3e-2'"):
        load_estimator_config(quoted)


def test_a_string_that_would_read_as_a_number_is_written_quoted_and_reads_back(tmp_path):
    # the loader reads a plain 1e5 as ROS 2 does, a number: the files this package writes
    # (the baseline file, with the node's hardware_id in its provenance) quote such a string
    doc = {'hardware_id': '1e5', 'other': '2E-3', 'gain': 1e-05, 'std': math.inf, 'n': 3}
    path = tmp_path / 'round.yaml'
    path.write_text(yaml.dump(doc, Dumper=SafeDumper))
    assert read_yaml(path, 'file') == doc
    # a file written before (a plain 1e5 string) reads as written where only we write it
    path.write_text(yaml.dump(doc, Dumper=yaml.SafeDumper))
    assert read_yaml(path, 'baseline file', ros_numbers=False) == doc
    assert read_yaml(path, 'parameters file')['hardware_id'] == 1e5  # as ROS 2 would


def test_relative_pump_file_resolves_against_the_current_directory_and_says_so(
        tmp_path, monkeypatch):
    (tmp_path / 'out').mkdir()
    pump = tmp_path / 'out' / 'my_pump.yaml'
    pump.write_text((config_dir() / 'pumps' / 'hong_doh_2004.yaml').read_text())
    params = params_file(tmp_path / 'out' / 'my_params.yaml', pump_file='out/my_pump.yaml')
    monkeypatch.chdir(tmp_path)
    assert load_estimator_config(params).pump_file == str(pump)  # absolute from here on
    elsewhere = tmp_path / 'elsewhere'
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    with pytest.raises(ConfigError) as info:
        load_estimator_config(params)
    message = str(info.value)
    assert 'pump_file' in message and str(params) in message and str(elsewhere) in message
    assert 'current directory' in message and '\n' not in message


@pytest.mark.parametrize('value', [
    'hong_doh_2004_consistent',
    'package://pump_friction_ros/config/pumps/hong_doh_2004_consistent.yaml',
])
def test_pump_file_may_name_a_shipped_set_or_a_package_path(tmp_path, value):
    config = load_estimator_config(params_file(tmp_path / 'p.yaml', pump_file=value))
    assert config.pump_file == str(config_dir() / 'pumps' / 'hong_doh_2004_consistent.yaml')
    from pump_friction_ros.physics.pump_parameters import load_pump
    assert load_pump(value).name == 'hong_doh_2004_consistent'


@pytest.mark.parametrize(('value', 'message'), [
    ('hong_doh_2005', 'no such shipped pump set; shipped: hong_doh_2004, '
                      'hong_doh_2004_consistent'),
    ('package://pump_friction_ros/config/pumps/none.yaml', 'not found'),
    ('package://', 'expected package://<package>/<path>'),
    ('package://no_such_package_x/config/p.yaml', 'package not found'),
])
def test_bad_pump_file_values_are_named(tmp_path, value, message):
    with pytest.raises(ConfigError, match=message.replace('(', r'\(')):
        load_estimator_config(params_file(tmp_path / 'p.yaml', pump_file=value))


@pytest.mark.parametrize('name', ['pump_file', 'table_file'])
def test_an_unknown_package_in_a_file_parameter_names_the_parameter(tmp_path, name):
    from pump_friction_ros.core.estimator_setup import estimator_from_config
    value = 'package://no_such_package_x/config/p.yaml'
    with pytest.raises(ConfigError) as info:
        estimator_from_config(load_estimator_config(
            params_file(tmp_path / 'p.yaml', **{name: value})))
    message = str(info.value)
    assert message.startswith(f"{name} '{value}' (from ") and 'package not found' in message
    assert '\n' not in message


def test_the_nodes_file_parameters_resolve_against_its_directory_and_say_so(tmp_path,
                                                                            monkeypatch):
    """What TorqueEstimatorNode does with its declared values (no rclpy needed)."""
    from pump_friction_ros.core.node_parameters import config_from_mapping
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError) as info:
        config_from_mapping({'pump_file': 'out/my_pump.yaml'}, 'parameter ',
                            default_origin='a node parameter')
    message = str(info.value)
    assert message.startswith("pump_file 'out/my_pump.yaml' (from a node parameter) not found")
    assert str(tmp_path) in message and 'current directory' in message
    config = config_from_mapping({'pump_file': 'hong_doh_2004_consistent'}, 'parameter ')
    assert Path(config.pump_file).is_absolute()


def test_the_issues_partial_params_file_on_the_healthy_sample_bag_raises_no_alarm(
        tmp_path, capsys):
    """The issue's exact mistake: a one-parameter file; the bag's own parameters still hold."""
    from pump_friction_ros.app.cli import main
    one = tmp_path / 'one.yaml'
    one.write_text('/**/torque_estimator:\n  ros__parameters:\n    hardware_id: pump_7\n')
    assert main(['replay', str(REPO / 'bags' / 'eha_nominal'), '--params', str(one),
                 '--quiet']) == 0
    out = capsys.readouterr().out
    assert f'node parameters from {REPO / "bags" / "eha_nominal" / "node_params.yaml"}' in out
    assert 'no alarm' in out and 'torque as the healthy baseline' in out


def test_each_sample_bag_carries_the_node_parameters_of_its_simulated_pump():
    for bag in ('eha_nominal', 'eha_valve_plate_wear'):
        assert (REPO / 'bags' / bag / 'node_params.yaml').read_text() == \
            SAMPLE_PARAMS.read_text()


def test_a_bags_node_params_that_is_not_a_file_is_an_error_not_the_defaults(tmp_path, capsys):
    """A folder where the bag's parameters belong: the replay must not run on defaults."""
    import shutil

    from pump_friction_ros.app.cli import main
    bag = tmp_path / 'bag'
    shutil.copytree(REPO / 'bags' / 'eha_nominal', bag)
    (bag / 'node_params.yaml').unlink()
    (bag / 'node_params.yaml').mkdir()
    assert main(['replay', str(bag), '--quiet']) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and f'{bag / "node_params.yaml"}' in err
