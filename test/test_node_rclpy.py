"""The rclpy node: a publisher -> node -> subscriber round trip, parameters, diagnostics.

Real rclpy tests; they need a sourced ROS 2 Jazzy and skip with the reason otherwise.
"""

import time
from pathlib import Path

import pytest

rclpy = pytest.importorskip(
    'rclpy', reason='rclpy is not importable: source a ROS 2 Jazzy install to run node tests')

from builtin_interfaces.msg import Time  # noqa: E402
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from sensor_msgs.msg import FluidPressure, JointState  # noqa: E402
from std_msgs.msg import Float64, Header  # noqa: E402

from pump_friction_ros.config import load_estimator_config  # noqa: E402
from pump_friction_ros.errors import PumpFrictionError  # noqa: E402
from pump_friction_ros.node import TorqueEstimatorNode  # noqa: E402
from pump_friction_ros.ros_messages import level_from_msg  # noqa: E402
from pump_friction_ros.table import build_table  # noqa: E402

PARAMS = Path(__file__).resolve().parents[1] / 'config' / 'torque_estimator.yaml'
NS = 1_000_000_000


@pytest.fixture(scope='module')
def table_file(tmp_path_factory, paper_params):
    return str(build_table(paper_params).save(tmp_path_factory.mktemp('t') / 'table.npz'))


@pytest.fixture
def ros(table_file):
    """Start rclpy with the package's parameters file; yields a function making the node."""
    started = []

    def start(*overrides):
        args = ['--ros-args', '--params-file', str(PARAMS), '-p', f'table_file:={table_file}']
        for item in overrides:
            args += ['-p', item]
        rclpy.init(args=args)
        started.append(True)
        return TorqueEstimatorNode()

    yield start
    if started:
        rclpy.try_shutdown()


class Probe(Node):
    """Publishes the node's inputs and records its outputs."""

    def __init__(self):
        super().__init__('probe')
        self.joint = self.create_publisher(JointState, 'joint_states', 10)
        self.pressure = self.create_publisher(FluidPressure, 'load_pressure', 10)
        self.got = {}
        self.diagnostics = []
        for name in ('expected_torque', 'residual', 'friction_torque'):
            self.create_subscription(Float64, f'/torque_estimator/{name}',
                                     lambda msg, n=name: self.got.setdefault(n, msg.data), 10)
        self.create_subscription(DiagnosticArray, '/diagnostics',
                                 lambda msg: self.diagnostics.append(msg), 10)

    def send(self, stamp_ns, speed, torque, dp):
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


def test_published_inputs_come_back_as_the_cores_numbers(ros, paper_params):
    node = ros()
    probe = Probe()
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    ex.add_node(probe)
    try:
        assert spin_until(ex, lambda: probe.count_subscribers('joint_states') > 0)
        assert spin_until(ex, lambda: probe.count_subscribers('load_pressure') > 0)
        stamp = 10 * NS
        for _ in range(50):  # best-effort inputs: resend until one round trip lands
            probe.send(stamp, 500.0, 12.0, 120e5)
            stamp += 1_000_000
            if spin_until(ex, lambda: 'residual' in probe.got, 0.2):
                break
        expected = probe.got['expected_torque']
        reference = node.core.table.lookup(500.0, 120e5, 46e-6).input_nm + 0.05
        assert expected == pytest.approx(reference, abs=0.05)  # + J * filtered accel (~0)
        assert probe.got['residual'] == pytest.approx(12.0 - expected, abs=1e-9)
    finally:
        ex.shutdown()
        probe.destroy_node()
        node.destroy_node()


def test_parameters_come_from_the_yaml_file(ros, table_file):
    node = ros()
    try:
        expected = load_estimator_config(PARAMS)
        for name, value in expected.__dict__.items():
            if name != 'table_file':
                assert getattr(node.config, name) == value, name
        assert node.config.table_file == table_file
    finally:
        node.destroy_node()


def test_diagnostics_go_from_ok_to_alarm_on_a_simulated_wear_step(ros):
    node = ros('cusum_warn_nm_s:=0.02', 'cusum_error_nm_s:=0.05', 'diagnostics_rate_hz:=20.0',
               'monitor_max_accel_rad_s2:=1.0e9')
    probe = Probe()
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    ex.add_node(probe)
    try:
        assert spin_until(ex, lambda: probe.count_subscribers('joint_states') > 0)
        expected = node.core.table.lookup(400.0, 100e5, 46e-6).input_nm + 0.05
        levels = []

        def send(extra_nm):
            # stamped from the node's clock: diagnostics age estimates against that clock
            probe.send(node.get_clock().now().nanoseconds, 400.0, expected + extra_nm, 100e5)
            ex.spin_once(timeout_sec=0.002)
            levels.extend(level_from_msg(m.status[0].level) for m in probe.diagnostics)
            probe.diagnostics.clear()

        end = time.monotonic() + 10.0
        while 0 not in levels and time.monotonic() < end:  # OK before the wear step
            send(0.0)
        assert 0 in levels
        for _ in range(600):
            send(1.0)  # +1 N m of friction: a simulated wear step
        spin_until(ex, lambda: probe.diagnostics, 1.0)
        levels += [level_from_msg(m.status[0].level) for m in probe.diagnostics]
        assert levels[-1] in (level_from_msg(DiagnosticStatus.WARN),
                              level_from_msg(DiagnosticStatus.ERROR))
    finally:
        ex.shutdown()
        probe.destroy_node()
        node.destroy_node()


@pytest.mark.parametrize('override', ['output_decimation:=0', 'rotor_inertia_kg_m2:=heavy',
                                      'speed_source:=tachometer'])
def test_invalid_parameter_stops_start_up_with_one_clear_message(ros, override):
    with pytest.raises(PumpFrictionError, match=override.split(':=')[0]):
        ros(override)
