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
The node's healthy baseline file: loaded at start, saved periodically and at shutdown, reset.

Real rclpy tests; they skip with the reason where rclpy is missing.
"""

import json
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

import pytest

rclpy = pytest.importorskip(
    'rclpy', reason='rclpy is not importable: source a ROS 2 Jazzy install to run node tests')

# Imports that need a sourced ROS 2, after the skip above (I100: see test_node_rclpy.py).
from builtin_interfaces.msg import Time  # noqa: E402, I100
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from pump_friction_ros.core.baseline_file import (  # noqa: E402
    baseline_document,
    read_baseline,
    write_baseline,
)
from pump_friction_ros.core.estimator_setup import estimator_from_config  # noqa: E402
from pump_friction_ros.core.inputs import InputKind as K  # noqa: E402
from pump_friction_ros.core.node_parameters import load_estimator_config  # noqa: E402
from pump_friction_ros.node.torque_estimator import TorqueEstimatorNode  # noqa: E402
from pump_friction_ros.table.friction_table import build_table  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from sensor_msgs.msg import FluidPressure, JointState, Temperature  # noqa: E402
from std_msgs.msg import Header  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402

from .test_baseline_file import feed, N_MONITORED  # noqa: E402, I100

REPO = Path(__file__).resolve().parents[1]
PARAMS = REPO / 'config' / 'torque_estimator.yaml'
SAMPLE_PARAMS = REPO / 'bags' / 'eha_params.yaml'
NS = 1_000_000_000


@pytest.fixture(scope='module')
def table_file(tmp_path_factory, paper_params):
    return str(build_table(paper_params).save(tmp_path_factory.mktemp('t') / 'table.npz'))


@pytest.fixture
def ros(table_file):
    """Start rclpy with the sample parameters; yields a function making the node."""
    started = []

    def start(*overrides):
        args = ['--ros-args', '--params-file', str(PARAMS), '--params-file', str(SAMPLE_PARAMS),
                '-p', f'table_file:={table_file}']
        for item in overrides:
            args += ['-p', item]
        rclpy.init(args=args)
        started.append(True)
        return TorqueEstimatorNode()

    yield start
    if started:
        rclpy.try_shutdown()


def learnt_file(path, table_file, **changes):
    """Write a baseline learnt by a core with the node's parameters (and ``changes``)."""
    config = load_estimator_config([PARAMS, SAMPLE_PARAMS])
    config = config.__class__(**{**config.__dict__, 'table_file': table_file, **changes})
    core = feed(estimator_from_config(config))
    write_baseline(path, baseline_document(core, origin='test'))
    return core


class Probe(Node):
    """Publishes the node's inputs, records /diagnostics, calls ~/reset_monitor."""

    def __init__(self):
        super().__init__('probe')
        self.joint = self.create_publisher(JointState, 'joint_states', 10)
        self.pressure = self.create_publisher(FluidPressure, 'load_pressure', 10)
        self.diagnostics = []
        self.create_subscription(DiagnosticArray, '/diagnostics', self.diagnostics.append, 10)
        self.reset = self.create_client(Trigger, '/torque_estimator/reset_monitor')

    def send(self, stamp_ns, speed=400.0, torque=10.0, dp=100e5):
        sec, nanosec = divmod(stamp_ns, NS)
        header = Header(stamp=Time(sec=sec, nanosec=nanosec), frame_id='')
        self.pressure.publish(FluidPressure(header=header, fluid_pressure=dp, variance=0.0))
        self.joint.publish(JointState(header=header, name=['pump_shaft'], position=[0.0],
                                      velocity=[speed], effort=[torque]))


def spin_until(executor, condition, timeout_s=10.0):
    end = time.monotonic() + timeout_s
    while time.monotonic() < end and not condition():
        executor.spin_once(timeout_sec=0.05)
    return condition()


def status_values(probe):
    msg = probe.diagnostics[-1].status[0]
    return msg.message, {kv.key: kv.value for kv in msg.values}


def session(node):
    probe = Probe()
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    ex.add_node(probe)
    return probe, ex


def close(node, probe, ex):
    ex.shutdown()
    probe.destroy_node()
    node.destroy_node()


def test_the_node_loads_its_baseline_file_at_start(ros, table_file, tmp_path):
    path = tmp_path / 'baseline.yaml'
    core = learnt_file(path, table_file)
    node = ros(f'baseline_file:={path}', 'diagnostics_rate_hz:=20.0')
    probe, ex = session(node)
    try:
        assert node.core.learnt == core.learnt
        assert json.dumps(node.core.monitor.state_dict()) == \
            json.dumps(core.monitor.state_dict())
        assert spin_until(ex, lambda: probe.diagnostics)
        _, values = status_values(probe)
        assert values['baseline_file'] == str(path)
        assert values['baseline_status'] == 'loaded'
        assert values['baseline_samples'] == str(N_MONITORED)
    finally:
        close(node, probe, ex)


def test_reset_service_keeps_the_old_file_and_writes_a_new_one(ros, table_file, tmp_path):
    path = tmp_path / 'baseline.yaml'
    learnt_file(path, table_file)
    old = path.read_bytes()
    node = ros(f'baseline_file:={path}')
    probe, ex = session(node)
    try:
        assert node.core.learnt[0] == N_MONITORED
        assert probe.reset.wait_for_service(timeout_sec=10.0)
        future = probe.reset.call_async(Trigger.Request())
        assert spin_until(ex, future.done)
        response = future.result()
        assert response.success, response.message
        assert 're-learning the healthy baseline' in response.message
        backups = list(tmp_path.glob('baseline.yaml.*.bak'))
        assert len(backups) == 1 and backups[0].read_bytes() == old
        assert str(backups[0]) in response.message
        assert read_baseline(path)['learnt']['samples'] == 0
        assert node.core.learnt == (0, None, None)
    finally:
        close(node, probe, ex)


def test_the_baseline_is_saved_periodically_once_something_is_learnt(ros, tmp_path):
    path = tmp_path / 'baseline.yaml'
    node = ros(f'baseline_file:={path}', 'baseline_save_period_s:=1.0',
               'diagnostics_rate_hz:=20.0')
    probe, ex = session(node)
    try:
        assert spin_until(ex, lambda: len(probe.diagnostics) >= 25)  # > 1 s, nothing learnt
        assert not path.exists()
        message, values = status_values(probe)
        assert values['baseline_status'].startswith('none yet')
        assert 'no baseline yet' in message
        assert spin_until(ex, lambda: probe.count_subscribers('joint_states') > 0)
        sent = 0
        end = time.monotonic() + 20.0
        while not path.exists() and time.monotonic() < end:
            probe.send(node.get_clock().now().nanoseconds)
            sent += 1
            ex.spin_once(timeout_sec=0.002)
        assert path.exists()
        doc = read_baseline(path)
        assert 0 < doc['learnt']['samples'] <= sent
        assert doc['provenance']['parameters']['drive_loss_torque_nm'] == 0.05
        assert doc['about']['origin'] == 'node /torque_estimator'
        assert node.baseline.status == 'saved'
    finally:
        close(node, probe, ex)


def test_a_node_with_the_temperature_topic_saves_what_it_judged_after_its_baseline(
        ros, table_file, tmp_path):
    # With the oil temperature, the torque drift's term enters each window's change from
    # the baseline; it once made the state numpy floats, and every save was refused.
    path = tmp_path / 'baseline.yaml'
    config = load_estimator_config([PARAMS, SAMPLE_PARAMS])
    config = config.__class__(**{**config.__dict__, 'table_file': table_file,
                                 'viscosity_source': 'temperature'})
    core = estimator_from_config(config)
    t0 = 1_700_000_000 * NS
    for k in range(round(1.5 * config.baseline_learn_s * 1000)):  # 1 kHz of steady running
        stamp = t0 + k * 1_000_000
        if k % 100 == 0:
            core.on_input(K.OIL_TEMPERATURE, stamp, 40.0)
        core.on_input(K.LOAD_PRESSURE, stamp, 100e5)
        core.on_input(K.JOINT_STATE, stamp, 400.0, 10.0)
    assert not core.monitor.learning  # a complete baseline, learnt at 40 degC
    # written as plain numbers whatever the core's types: what is tested is the node's save
    document = json.loads(json.dumps(baseline_document(core, origin='test'), default=float))
    write_baseline(path, document)
    node = ros(f'baseline_file:={path}', 'viscosity_source:=temperature',
               'baseline_save_period_s:=1.0', 'diagnostics_rate_hz:=20.0')
    probe, ex = session(node)
    oil = probe.create_publisher(Temperature, 'oil_temperature', 10)
    try:
        assert node.baseline.status == 'loaded'
        assert spin_until(ex, lambda: probe.count_subscribers('oil_temperature') > 0)
        judged = node.core.monitor.windows
        end = time.monotonic() + 20.0
        while time.monotonic() < end and not (
                node.core.monitor.windows > judged + 3 and node.baseline.status == 'saved'):
            stamp = node.get_clock().now().nanoseconds
            sec, nanosec = divmod(stamp, NS)
            oil.publish(Temperature(header=Header(stamp=Time(sec=sec, nanosec=nanosec)),
                                    temperature=42.0, variance=0.0))
            probe.send(stamp)
            ex.spin_once(timeout_sec=0.002)
        assert node.core.monitor.windows > judged + 3, 'no window judged after the baseline'
        assert node.baseline.status == 'saved', node.baseline.status
        saved = read_baseline(path)
        assert saved['learnt']['samples'] > core.learnt[0]  # what it ran since is kept
        assert saved['monitor_state']['ewma_nm'] != 0.0
    finally:
        close(node, probe, ex)


def test_without_a_path_the_file_is_under_ros_home_named_after_the_node(ros):
    node = ros()
    try:
        assert node.baseline.path == Path(os.environ['ROS_HOME']) / 'pump_friction_ros' / \
            'baselines' / 'torque_estimator.yaml'
        assert node.baseline.status.startswith('none yet')
    finally:
        node.destroy_node()


def test_a_file_of_other_parameters_is_not_used_and_the_status_says_so(ros, table_file,
                                                                       tmp_path):
    path = tmp_path / 'baseline.yaml'
    learnt_file(path, table_file)
    old = path.read_bytes()
    node = ros(f'baseline_file:={path}', 'drive_loss_torque_nm:=0.1',
               'diagnostics_rate_hz:=20.0')
    probe, ex = session(node)
    try:
        assert node.core.learnt[0] == 0
        assert spin_until(ex, lambda: probe.diagnostics)
        message, values = status_values(probe)
        assert 'baseline file not used' in message
        assert values['baseline_status'].startswith('not used: ')
        assert 'drive_loss_torque_nm (file 0.05, now 0.1)' in values['baseline_status']
        assert values['baseline_errors'] == '1'
        node.save_baseline()
        assert path.read_bytes() == old
    finally:
        close(node, probe, ex)


def test_the_node_saves_what_it_learnt_when_stopped(table_file, tmp_path):
    """SIGINT to a node process that learnt: the file holds it, one 'stopping' line."""
    path = tmp_path / 'baseline.yaml'
    env = dict(os.environ, RCUTILS_LOGGING_BUFFERED_STREAM='0', PYTHONUNBUFFERED='1',
               ROS_LOG_DIR=str(tmp_path / 'log'))
    env['PYTHONPATH'] = os.pathsep.join([str(REPO), env.get('PYTHONPATH', '')])
    proc = subprocess.Popen(
        [sys.executable, '-m', 'pump_friction_ros.node', '--ros-args', '--params-file',
         str(PARAMS), '--params-file', str(SAMPLE_PARAMS), '-p', f'table_file:={table_file}',
         '-p', f'baseline_file:={path}'],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    rclpy.init()
    probe = Probe()
    ex = SingleThreadedExecutor()
    ex.add_node(probe)
    try:
        assert spin_until(ex, lambda: probe.count_subscribers('joint_states') > 0, 60.0)
        assert spin_until(ex, lambda: probe.count_subscribers('load_pressure') > 0, 10.0)
        end = time.monotonic() + 2.0
        while time.monotonic() < end:
            probe.send(time.time_ns())
            ex.spin_once(timeout_sec=0.002)
        assert not path.exists()  # baseline_save_period_s is 60 s: the stop writes it
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
        ex.shutdown()
        probe.destroy_node()
        rclpy.try_shutdown()
    text = err.decode(errors='replace')
    assert proc.returncode == 0, text
    assert 'Traceback' not in text
    assert len([line for line in text.splitlines() if 'stopping on SIGINT' in line]) == 1
    assert read_baseline(path)['learnt']['samples'] > 0, text
