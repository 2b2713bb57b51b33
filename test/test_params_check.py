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
The node's command-line check, ROS-free: which sections apply, what is refused.

The rclpy side (a node refusing to start) is in test_node_rclpy.py.
"""

from pathlib import Path

from pump_friction_ros.core.params_check import (
    check_command_line,
    parameter_sources,
    section_applies,
)
from pump_friction_ros.errors import ConfigError
import pytest

CONFIG = Path(__file__).resolve().parents[1] / 'config' / 'torque_estimator.yaml'


@pytest.mark.parametrize('section, fqn, applies', [
    ('/**', '/torque_estimator', True),
    ('/**', '/eha1/left/torque_estimator', True),
    ('torque_estimator', '/torque_estimator', True),  # no slash: from the root
    ('torque_estimator', '/eha1/torque_estimator', False),
    ('/**/torque_estimator', '/torque_estimator', True),
    ('/**/torque_estimator', '/eha1/left/torque_estimator', True),
    ('/*/torque_estimator', '/torque_estimator', False),  # exactly one token
    ('/*/torque_estimator', '/eha1/torque_estimator', True),
    ('/eha1/*', '/eha1/torque_estimator', True),
    ('/eha1/*', '/eha2/torque_estimator', False),
    ('/torque_estimator_2', '/torque_estimator', False),
    ('/torque.estimator', '/torque_estimator', False),  # a dot is a dot, not any character
])
def test_sections_apply_as_rclpy_matches_node_names(section, fqn, applies):
    assert section_applies(section, fqn) is applies


def test_only_ros_args_blocks_count_and_options_with_values_are_skipped():
    args = ['prog', '--params-file', 'not_ros.yaml', '--ros-args', '-r', '--params-file',
            '--params-file', 'a.yaml', '-p', 'x:=1', '--', '--params-file', 'after.yaml',
            '--ros-args', '--param', 'y:=2', '--params-file', 'b.yaml']
    assert parameter_sources(args) == (['a.yaml', 'b.yaml'], ['x:=1', 'y:=2'])


def _file(tmp_path, text):
    path = tmp_path / 'p.yaml'
    path.write_text(text)
    return ['--ros-args', '--params-file', str(CONFIG), '--params-file', str(path)]


def test_a_nested_name_in_the_nodes_section_is_refused_flattened(tmp_path):
    args = _file(tmp_path, 'torque_estimator:\n  ros__parameters:\n    monitor:\n'
                           '      cusum_warn: 1.0\n')
    with pytest.raises(ConfigError, match=r"unknown parameter.*'monitor\.cusum_warn'"):
        check_command_line(args, '/torque_estimator')


def test_another_namespaces_section_and_another_nodes_rule_are_not_checked(tmp_path):
    args = _file(tmp_path, '/eha2/torque_estimator:\n  ros__parameters:\n    joint_nam: x\n')
    check_command_line([*args, '-p', 'other_node:joint_nam:=x'], '/eha1/torque_estimator')
    with pytest.raises(ConfigError, match='unknown parameter'):
        check_command_line(args, '/eha2/torque_estimator')


def test_the_shipped_file_and_the_ros_parameters_pass(tmp_path):
    args = _file(tmp_path, '/**:\n  ros__parameters:\n    use_sim_time: true\n'
                           '    start_type_description_service: false\n')
    check_command_line([*args, '-p', 'use_sim_time:=true'], '/torque_estimator')
