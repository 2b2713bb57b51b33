"""ROS 2 node ``torque_estimator``: thin rclpy glue around the ROS-free `TorqueEstimator`.

Callbacks only convert messages to SI floats (``ros_messages``), call the core, and convert
the results back. See README, "torque_estimator", for topics, parameters and diagnostics.
"""

from __future__ import annotations

import math
import sys

import rclpy
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from sensor_msgs.msg import FluidPressure, JointState, Temperature
from std_msgs.msg import Float64, Header
from std_srvs.srv import Trigger

from .config import NODE_NAME, PARAMETERS, ParameterSpec, config_from_mapping
from .errors import PumpFrictionError
from .estimator import Estimate, estimator_from_config
from .ros_messages import (
    OUTPUT_TOPICS,
    MessageTypes,
    diagnostic_array,
    float64_message,
    joint_sample,
    outputs_of,
    stamp_to_ns,
)

OUTPUT_QOS_DEPTH = 10
DIAGNOSTICS_QOS_DEPTH = 10


def _descriptor(spec: ParameterSpec) -> ParameterDescriptor:
    """Parameter descriptor (description, range, read-only) from the shared spec."""
    desc = ParameterDescriptor(description=spec.description, read_only=True)
    if spec.choices:
        desc.additional_constraints = 'one of: ' + ', '.join(spec.choices)
    finite = spec.low is not None and spec.high is not None and math.isfinite(spec.high)
    if finite and isinstance(spec.default, int):  # (bool parameters have no range)
        desc.integer_range = [IntegerRange(from_value=int(spec.low), to_value=int(spec.high),
                                           step=1)]
    elif finite and isinstance(spec.default, float):
        desc.floating_point_range = [FloatingPointRange(from_value=float(spec.low),
                                                        to_value=float(spec.high), step=0.0)]
    return desc


class TorqueEstimatorNode(Node):
    """Subscribes to shaft speed, pressure and motor torque; publishes the estimates."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(NODE_NAME, **node_kwargs)
        values = {}
        for spec in PARAMETERS:
            try:
                self.declare_parameter(spec.name, spec.default, _descriptor(spec))
            except (InvalidParameterValueException, InvalidParameterTypeException) as exc:
                raise PumpFrictionError(f'parameter {spec.name}: {exc}') from None
            values[spec.name] = self.get_parameter(spec.name).value
        self.config = config_from_mapping(values, 'parameter ')
        self.core = estimator_from_config(self.config)
        self._types = MessageTypes(Float64, Time, Header, KeyValue, DiagnosticStatus,
                                   DiagnosticArray)
        cfg = self.config

        in_qos = (QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
                  if cfg.reliable_inputs else qos_profile_sensor_data)
        out_qos = QoSProfile(depth=OUTPUT_QOS_DEPTH, reliability=ReliabilityPolicy.RELIABLE)
        self._pub = {name: self.create_publisher(Float64, f'~/{name}', out_qos)
                     for name in OUTPUT_TOPICS}
        self._diag_pub = self.create_publisher(
            DiagnosticArray, '/diagnostics',
            QoSProfile(depth=DIAGNOSTICS_QOS_DEPTH, reliability=ReliabilityPolicy.RELIABLE))

        subscribe = self.create_subscription
        if 'joint_state' in (cfg.speed_source, cfg.torque_source):
            subscribe(JointState, 'joint_states', self._on_joint_state, in_qos)
        if cfg.speed_source == 'float64':
            subscribe(Float64, 'shaft_speed', self._on_shaft_speed, in_qos)
        if cfg.torque_source == 'float64':
            subscribe(Float64, 'motor_torque', self._on_motor_torque, in_qos)
        if cfg.pressure_source == 'difference':
            subscribe(FluidPressure, 'load_pressure', self._on_load_pressure, in_qos)
        else:
            subscribe(FluidPressure, 'pressure_a', self._on_pressure_a, in_qos)
            subscribe(FluidPressure, 'pressure_b', self._on_pressure_b, in_qos)
        if cfg.viscosity_source == 'temperature':
            subscribe(Temperature, 'oil_temperature', self._on_temperature, in_qos)
        self.create_service(Trigger, '~/reset_monitor', self._on_reset)
        self.create_timer(1.0 / cfg.diagnostics_rate_hz, self._on_diagnostics_timer)
        self._status_name = f'{NODE_NAME}: {self.core.pump_name}'
        self.get_logger().info(
            f'pump {self.core.pump_name}, table {self.core.table.metadata.get("source")}; '
            f'inputs: speed {cfg.speed_source}, torque {cfg.torque_source}, pressure '
            f'{cfg.pressure_source}, viscosity {cfg.viscosity_source}')

    # -- conversions at the edge ----------------------------------------------------------

    def _now_ns(self) -> int:
        return self.get_clock().now().nanoseconds

    def _stamp_ns(self, msg) -> int:
        stamp = stamp_to_ns(msg.header.stamp)
        return self._now_ns() if stamp is None else stamp

    def _publish(self, estimate: Estimate | None) -> None:
        if estimate is None or not estimate.publish:
            return
        for name, value in outputs_of(estimate):
            self._pub[name].publish(float64_message(self._types, value))

    # -- callbacks: message -> SI -> core -> message ----------------------------------------

    def _on_joint_state(self, msg: JointState) -> None:
        sample = joint_sample(msg, self.config.joint_name)
        if sample is not None:
            self._publish(self.core.on_joint_state(self._stamp_ns(msg), *sample))

    def _on_shaft_speed(self, msg: Float64) -> None:
        self._publish(self.core.on_speed(self._now_ns(), msg.data))

    def _on_motor_torque(self, msg: Float64) -> None:
        self.core.on_torque(self._now_ns(), msg.data)

    def _on_load_pressure(self, msg: FluidPressure) -> None:
        self.core.on_pressure(self._stamp_ns(msg), msg.fluid_pressure)

    def _on_pressure_a(self, msg: FluidPressure) -> None:
        self.core.on_port_pressure('a', self._stamp_ns(msg), msg.fluid_pressure)

    def _on_pressure_b(self, msg: FluidPressure) -> None:
        self.core.on_port_pressure('b', self._stamp_ns(msg), msg.fluid_pressure)

    def _on_temperature(self, msg: Temperature) -> None:
        self.core.on_temperature(self._stamp_ns(msg), msg.temperature)

    def _on_diagnostics_timer(self) -> None:
        now = self._now_ns()
        self._diag_pub.publish(diagnostic_array(self._types, self.core.diagnostics(now), now,
                                                self._status_name, self.config.hardware_id))

    def _on_reset(self, request: Trigger.Request, response: Trigger.Response):
        self.core.monitor.reset()
        response.success = True
        response.message = 'wear monitor reset: friction as modelled, no alarm'
        return response


def main(args: list[str] | None = None) -> int:
    """Run the node (console script ``torque_estimator``).

    Parameters
    ----------
    args : list of str, optional
        Command-line arguments for rclpy.

    Returns
    -------
    int
        0 on a normal shutdown, 1 when the parameters, pump file or table are invalid.
    """
    rclpy.init(args=args)
    node = None
    try:
        node = TorqueEstimatorNode()
        rclpy.spin(node)
    except PumpFrictionError as exc:
        print(f'{NODE_NAME}: cannot start: {exc}', file=sys.stderr)
        return 1
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
