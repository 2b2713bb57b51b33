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

"""tools/check_ros_pins.py: a ros-* wheel at another version than Jazzy's fails the run."""

import importlib.metadata
import importlib.util
from pathlib import Path

import pytest

_SPEC = importlib.util.spec_from_file_location(
    'check_ros_pins', Path(__file__).resolve().parents[1] / 'tools' / 'check_ros_pins.py')
check_ros_pins = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(check_ros_pins)


class Dist:

    def __init__(self, name, version):
        self.metadata = {'Name': name}
        self.version = version


@pytest.mark.parametrize('installed, ok', [
    ([('ros-rclpy', '7.1.6'), ('ros_std_msgs', '5.3.6'), ('numpy', '2.0')], True),
    ([('ros-rclpy', '9.1.2')], False),  # Kilted's
    ([('ros-rclpy', '7.1.6'), ('ros-made-up-package', '1.0')], False),  # not pinned
    ([('numpy', '2.0')], False),  # no ROS at all: the node tests would skip
])
def test_only_jazzys_pinned_versions_pass(monkeypatch, capsys, installed, ok):
    monkeypatch.setattr(importlib.metadata, 'distributions',
                        lambda: [Dist(n, v) for n, v in installed])
    assert (check_ros_pins.main() == 0) == ok
    out = capsys.readouterr()
    if not ok:
        assert out.err.count('\n') == 1  # one line
