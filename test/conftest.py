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

"""Shared fixtures: the two shipped pump parameter sets and their models; ROS isolation."""

import atexit
import os
from pathlib import Path
import shutil
import tempfile

from pump_friction_ros.physics.model import PumpModel
from pump_friction_ros.physics.pump_parameters import load_pump
import pytest

# The rclpy tests talk DDS: on this machine only, in a domain of this run's own (two runs at
# once, or the robot a shell was set up for, must not hear each other: the tests publish
# joint states and start nodes named torque_estimator), logs in a temporary folder. Set
# before any test module imports rclpy, overriding the shell's: its domain is never used.
_SHELL_DOMAIN = os.environ.get('ROS_DOMAIN_ID', '0')
_DOMAIN = os.getpid() % 100 + 1
if str(_DOMAIN) == _SHELL_DOMAIN:
    _DOMAIN = _DOMAIN % 100 + 1
os.environ['ROS_DOMAIN_ID'] = str(_DOMAIN)
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.pop('ROS_STATIC_PEERS', None)
if 'ROS_LOG_DIR' not in os.environ:
    os.environ['ROS_LOG_DIR'] = tempfile.mkdtemp(prefix='pump_friction_ros_log_')
    atexit.register(shutil.rmtree, os.environ['ROS_LOG_DIR'], ignore_errors=True)

REPO = Path(__file__).resolve().parents[1]
PAPER_PUMP = REPO / 'config' / 'pumps' / 'hong_doh_2004.yaml'
CONSISTENT_PUMP = REPO / 'config' / 'pumps' / 'hong_doh_2004_consistent.yaml'


@pytest.fixture(autouse=True)
def _own_ros_home(tmp_path_factory, monkeypatch):
    """Each test its own ROS_HOME: a node's default baseline file never outlives its test."""
    monkeypatch.setenv('ROS_HOME', str(tmp_path_factory.mktemp('ros_home')))


@pytest.fixture(scope='session')
def paper_params():
    return load_pump(PAPER_PUMP)


@pytest.fixture(scope='session')
def consistent_params():
    return load_pump(CONSISTENT_PUMP)


@pytest.fixture(scope='session')
def paper_model(paper_params):
    return PumpModel(paper_params)


@pytest.fixture(scope='session')
def consistent_model(consistent_params):
    return PumpModel(consistent_params)


def pytest_configure(config):
    # markers the ament linters and launch_testing register themselves when ROS is sourced
    for marker in ('flake8', 'pep257', 'copyright', 'linter', 'launch_test', 'rostest'):
        config.addinivalue_line('markers', f'{marker}: ament / launch_testing marker')


def level_from_msg(level):
    """Return a DiagnosticStatus level as an int, from rclpy (bytes) or rosbags (int)."""
    return level[0] if isinstance(level, (bytes, bytearray)) else int(level)


@pytest.fixture(scope='module')
def env(tmp_path_factory):
    """Environment of ``pump_friction`` subprocesses: a private table cache per module."""
    values = dict(os.environ)
    values['XDG_CACHE_HOME'] = str(tmp_path_factory.mktemp('cache'))
    values['PYTHONPATH'] = os.pathsep.join(filter(None, [str(REPO),
                                                         values.get('PYTHONPATH', '')]))
    return values
