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
launch_testing: the node starts from its parameters file, answers, and shuts down cleanly.

Needs a sourced ROS 2 Jazzy (launch_testing, rclpy); skipped with the reason otherwise.
"""

import atexit
import os
from pathlib import Path
import shutil
import sys
import tempfile
import time
import unittest

import pytest

pytest.importorskip('launch_testing',
                    reason='launch_testing is not importable: source ROS 2 Jazzy')
rclpy = pytest.importorskip('rclpy', reason='rclpy is not importable: source ROS 2 Jazzy')

# Imports that need a sourced ROS 2, after the skip above; flake8-import-order compares
# them with 'import pytest' across the code in between, hence I100.
from builtin_interfaces.msg import Time  # noqa: E402, I100
import launch  # noqa: E402
import launch_testing  # noqa: E402
import launch_testing.actions  # noqa: E402
import launch_testing.asserts  # noqa: E402
from sensor_msgs.msg import FluidPressure, JointState  # noqa: E402
from std_msgs.msg import Float64, Header  # noqa: E402

PARAMS = Path(__file__).resolve().parents[1] / 'config' / 'torque_estimator.yaml'
ROS_HOME = tempfile.mkdtemp(prefix='pump_friction_ros_launch_test_')
atexit.register(shutil.rmtree, ROS_HOME, ignore_errors=True)


@pytest.mark.launch_test
def generate_test_description():
    # The node's start-up line comes from its rclpy logger, which rcutils writes to stderr
    # (RCUTILS_LOGGING_USE_STDOUT 0 or unset), unbuffered with RCUTILS_LOGGING_BUFFERED_STREAM
    # 0 (1 would ask for line buffering): pinned here whatever the calling shell has set.
    # Its own ROS_HOME: the node's default baseline file (under ROS_HOME) is not the one of a
    # torque_estimator on this machine (conftest.py gives the tests their own DDS domain).
    env = dict(os.environ, RCUTILS_LOGGING_USE_STDOUT='0', RCUTILS_LOGGING_BUFFERED_STREAM='0',
               PYTHONUNBUFFERED='1', ROS_HOME=ROS_HOME)
    node = launch.actions.ExecuteProcess(
        cmd=[sys.executable, '-m', 'pump_friction_ros.node', '--ros-args',
             '--params-file', str(PARAMS)],
        env=env, output='screen')
    return launch.LaunchDescription([node, launch_testing.actions.ReadyToTest()]), {
        'estimator': node}


STARTED = 'pump hong_doh_2004'  # in the node's first log line (rclpy logger, on stderr)


class TestTorqueEstimatorRuns(unittest.TestCase):

    # launch_testing 3.4.3 (io_handler.py, ActiveIoHandler.waitFor): stream='stderr' is the
    # default; it is spelled out because the stream must be the one the logger writes to.

    def test_starts_with_the_papers_pump(self, proc_output, estimator):
        proc_output.assertWaitFor(STARTED, process=estimator, timeout=60, stream='stderr')

    def test_answers_joint_states_with_an_expected_torque(self, proc_output, estimator):
        proc_output.assertWaitFor(STARTED, process=estimator, timeout=60, stream='stderr')
        rclpy.init()
        node = rclpy.create_node('launch_probe')
        got = []
        try:
            node.create_subscription(Float64, '/torque_estimator/expected_torque',
                                     lambda m: got.append(m.data), 10)
            joint = node.create_publisher(JointState, 'joint_states', 10)
            pressure = node.create_publisher(FluidPressure, 'load_pressure', 10)
            end = time.monotonic() + 20.0
            k = 0
            while not got and time.monotonic() < end:
                header = Header(stamp=Time(sec=100, nanosec=k * 1_000_000), frame_id='')
                pressure.publish(FluidPressure(header=header, fluid_pressure=100e5,
                                               variance=0.0))
                joint.publish(JointState(header=header, name=['pump_shaft'], position=[0.0],
                                         velocity=[300.0], effort=[9.0]))
                k += 1
                rclpy.spin_once(node, timeout_sec=0.05)
            self.assertTrue(got, 'no expected_torque received')
            self.assertGreater(got[0], 7.0)  # 100 bar: 7.8 N m theoretical + friction
        finally:
            node.destroy_node()
            rclpy.shutdown()


@launch_testing.post_shutdown_test()
class TestShutdown(unittest.TestCase):

    def test_exit_code_is_clean(self, proc_info):
        launch_testing.asserts.assertExitCodes(proc_info)
