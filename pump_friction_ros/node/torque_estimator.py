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
ROS 2 node ``torque_estimator``: thin rclpy glue around the ROS-free `TorqueEstimator`.

Callbacks only convert messages to SI floats, call the core, and convert the results back.
See README, "torque_estimator", for topics and parameters, docs/monitor.md for diagnostics,
and docs/cpu_cost.md for why the node subscribes raw messages, publishes serialised Float64s
and keeps its QoS event handlers to the one that can fire.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
import math
from pathlib import Path
import sys
import time
import traceback
from typing import Any

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
import rclpy
from rclpy.clock import Clock
from rclpy.clock_type import ClockType
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.exceptions import (
    InvalidParameterTypeException,
    InvalidParameterValueException,
    ParameterException,
)
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
import rclpy.logging
from rclpy.node import Node
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    qos_policy_name_from_kind,
    qos_profile_sensor_data,
    QoSProfile,
    ReliabilityPolicy,
)
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import FluidPressure, JointState, Temperature
from std_msgs.msg import Float64, Header
from std_srvs.srv import Trigger

from .stop_signals import StopSignals
from ..core.baseline_store import baseline_path, BaselineStore
from ..core.estimate_record import Estimate
from ..core.estimator_setup import estimator_from_config
from ..core.inputs import (
    FLOAT64,
    FLUID_PRESSURE,
    INPUTS,
    inputs_for,
    InputSpec,
    JOINT_STATE,
    TEMPERATURE,
)
from ..core.node_parameters import config_from_mapping, NODE_NAME, PARAMETERS, ParameterSpec
from ..core.params_check import check_command_line
from ..errors import PumpFrictionError
from ..messages.cdr_message import MessageDecoder
from ..messages.conversions import (
    diagnostic_array,
    DIAGNOSTICS_QOS_DEPTH,
    float64_cdr,
    MessageTypes,
    OUTPUT_QOS_DEPTH,
    OUTPUT_TOPICS,
    outputs_of,
    RELIABLE_INPUT_QOS_DEPTH,
)

# what rclpy.init raises on a bad command line (the second: a RuntimeError, not the first)
_RCLError, _UnknownROSArgsError = _rclpy.RCLError, _rclpy.UnknownROSArgsError

_MESSAGE_CLASSES = {JOINT_STATE: JointState, FLOAT64: Float64, FLUID_PRESSURE: FluidPressure,
                    TEMPERATURE: Temperature}


def reliable_qos(depth: int) -> QoSProfile:
    """
    Return reliable, keep last ``depth``, volatile: the outputs' QoS, and reliable inputs'.

    The replay writes the same profile into its output bag (``bags.sinks.output_qos``).

    Parameters
    ----------
    depth : int
        History depth [messages].

    Returns
    -------
    QoSProfile
        Deadline, lifespan and liveliness stay at the middleware's defaults.

    """
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


def input_qos(reliable: bool) -> QoSProfile:
    """
    Return the QoS of the inputs: the sensor-data profile, or reliable with a deep history.

    Parameters
    ----------
    reliable : bool
        The ``reliable_inputs`` parameter.

    Returns
    -------
    QoSProfile
        Best effort, keep last 5 (``qos_profile_sensor_data``); or reliable, keep last
        ``RELIABLE_INPUT_QOS_DEPTH``, volatile.

    """
    return reliable_qos(RELIABLE_INPUT_QOS_DEPTH) if reliable else qos_profile_sensor_data


def _descriptor(spec: ParameterSpec) -> ParameterDescriptor:
    """Parameter descriptor (description, range, read-only) from the shared spec."""
    desc = ParameterDescriptor(description=spec.description, read_only=True)
    if spec.choices:
        desc.additional_constraints = 'one of: ' + ', '.join(spec.choices)
    if spec.low is None or spec.high is None:
        return desc
    if isinstance(spec.default, int) and math.isfinite(spec.high):  # (bools: no range)
        desc.integer_range = [IntegerRange(from_value=int(spec.low), to_value=int(spec.high),
                                           step=1)]
    elif isinstance(spec.default, float):  # [0, inf] too: rclpy compares with inf
        desc.floating_point_range = [FloatingPointRange(from_value=float(spec.low),
                                                        to_value=float(spec.high), step=0.0)]
    return desc


class TorqueEstimatorNode(Node):
    """
    Subscribes to shaft speed, pressure and motor torque; publishes the estimates.

    Parameters
    ----------
    command_line : sequence of str
        The node's command line (``sys.argv``): its parameters files and ``-p`` rules are
        checked as the replay checks them (``core.params_check``); empty: not checked.
    **node_kwargs
        rclpy ``Node`` arguments (``cli_args`` is checked with the command line).

    """

    def __init__(self, command_line: Sequence[str] = (), **node_kwargs: Any) -> None:
        try:  # rclpy's own parameters (use_sim_time:=1 is an integer, not a bool)
            super().__init__(NODE_NAME, **node_kwargs)
        except ParameterException as exc:
            raise PumpFrictionError(str(exc)) from None
        values = {}
        for spec in PARAMETERS:
            try:
                self.declare_parameter(spec.name, spec.default, _descriptor(spec))
            except (InvalidParameterValueException, InvalidParameterTypeException) as exc:
                raise PumpFrictionError(f'parameter {spec.name}: {exc}') from None
            values[spec.name] = self.get_parameter(spec.name).value
        # what rcl's merge of several files drops, and names no parameter takes (the
        # command line: rclpy keeps no list of its files)
        check_command_line([*command_line, *(node_kwargs.get('cli_args') or [])],
                           self.get_fully_qualified_name())
        self.config = config_from_mapping(values, 'parameter ',
                                          default_origin='a node parameter')
        self.core = estimator_from_config(self.config)
        name = self.get_fully_qualified_name()
        self.baseline = BaselineStore(baseline_path(self.config.baseline_file, name), self.core,
                                      f'node {name}')
        self.core.baseline = self.baseline  # its status goes into /diagnostics
        self._types = MessageTypes(Float64, Time, Header, KeyValue, DiagnosticStatus,
                                   DiagnosticArray)
        # messages received per input, indexed by `InputKind` (tests, the CPU benchmark)
        self.received = [0] * len(INPUTS)
        cfg = self.config

        # Every publisher, subscription and QoS event handler is one more entity that rclpy's
        # executor puts into the wait set it rebuilds for every message, which is most of
        # the node's CPU cost at 1 kHz (docs/cpu_cost.md). rclpy gives each publisher and
        # subscription two handlers by default (incompatible QoS, incompatible type).
        # Outputs: none. An incompatible subscriber is told by its own side (rclpy and
        # rclcpp subscriptions warn by default), so ours would only repeat it.
        quiet_publisher = PublisherEventCallbacks(use_default_callbacks=False)
        self._pub = {name: self.create_publisher(Float64, f'~/{name}',
                                                 reliable_qos(OUTPUT_QOS_DEPTH),
                                                 event_callbacks=quiet_publisher)
                     for name in OUTPUT_TOPICS}
        self._diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics',
                                               reliable_qos(DIAGNOSTICS_QOS_DEPTH),
                                               event_callbacks=quiet_publisher)

        # Inputs: one handler, incompatible QoS, and only where it can fire. A best-effort,
        # volatile subscription with the default deadline and liveliness (the sensor-data
        # profile) requests the least of every policy, so every publisher matches it; a
        # reliable one does not match a best-effort publisher, which then sends the node
        # nothing: that must be said. (An rmw without the event makes rclpy skip the handler,
        # `SubscriptionEventCallbacks.create_event_handlers` catches UnsupportedEventTypeError.)
        in_qos = input_qos(cfg.reliable_inputs)
        for inp in inputs_for(cfg):
            events = SubscriptionEventCallbacks(
                incompatible_qos=self._incompatible_qos_warning(inp.topic)
                if cfg.reliable_inputs else None,
                use_default_callbacks=False)
            sub = self.create_subscription(_MESSAGE_CLASSES[inp.msgtype], inp.topic,
                                           self._input_callback(inp), in_qos,
                                           event_callbacks=events, raw=True)
            if cfg.reliable_inputs and not sub.event_handlers:
                self.get_logger().info(f'the middleware reports no incompatible QoS on '
                                       f'{inp.topic}: a best-effort publisher goes unnoticed')
        self.create_service(Trigger, '~/reset_monitor', self._on_reset)
        # the baseline is saved from the diagnostics timer. It runs on the node's clock, as
        # the replay's does; simulated time that does not advance (no /clock, or paused)
        # stops it, so a steady timer stands in while it is silent (`_on_clock_watchdog`)
        period_s = 1.0 / cfg.diagnostics_rate_hz
        self.create_timer(period_s, self._on_diagnostics_timer)
        # a tick later than this, with the clock where it was, is a stopped clock
        self._silent_after_s = period_s + cfg.stale_timeout_s
        self._last_tick_s = time.monotonic()
        # the clock as the watchdog last read it, and when (steady time) it last moved: a
        # clock paused between two ticks stands still here, never at the last tick's value
        self._watched_ns, self._clock_moved_s = self._now_ns(), self._last_tick_s
        self.create_timer(period_s, self._on_clock_watchdog,
                          clock=Clock(clock_type=ClockType.STEADY_TIME))
        self._next_save_s = time.monotonic() + cfg.baseline_save_period_s
        self._status_name = f'{NODE_NAME}: {self.core.pump_name}'
        axis_cst = self.core.table.viscosity_axis_m2_s[[0, -1]] * 1e6
        self.get_logger().info(
            f'pump {self.core.pump_name}, table {self.core.table.metadata.get("source")} '
            f'(viscosity {axis_cst[0]:.3g}-{axis_cst[1]:.4g} cSt); '
            f'inputs: speed {cfg.speed_source}, torque {cfg.torque_source}, pressure '
            f'{cfg.pressure_source}, viscosity {cfg.viscosity_source}')
        if self.core.table_coverage:
            self.get_logger().warning(self.core.table_coverage)
        severity, line = self.baseline.load()
        getattr(self.get_logger(), severity)(line)

    # -- conversions at the edge ----------------------------------------------------------

    def _now_ns(self) -> int:
        return self.get_clock().now().nanoseconds

    def _publish(self, estimate: Estimate | None) -> None:
        if estimate is None or not estimate.publish:
            return
        pub = self._pub
        for name, value in outputs_of(estimate):
            pub[name].publish(float64_cdr(value))  # serialised: no message object to build

    # -- callbacks: message -> SI -> core -> message ----------------------------------------

    def _input_callback(self, spec: InputSpec) -> Callable[[bytes], None]:
        """Return the callback of one raw input subscription (serialised CDR in)."""
        cls = _MESSAGE_CLASSES[spec.msgtype]
        decode = MessageDecoder(spec, self.config.joint_name,
                                lambda raw: deserialize_message(raw, cls))
        core, kind, received, now_ns = self.core, spec.kind, self.received, self._now_ns

        def on_message(raw: bytes) -> None:
            received[kind] += 1
            stamp, value, torque, defect = decode(raw)
            if defect:
                core.on_defect(defect)
                return
            now = now_ns()  # 0: simulated time before the first /clock, not a time to judge
            self._publish(core.on_input(kind, stamp or now, value, torque, now or None))

        return on_message

    def _incompatible_qos_warning(self, topic: str) -> Callable[[Any], None]:
        """Return an incompatible-QoS event handler warning once per topic and policy."""
        warned: set[str] = set()

        def on_event(event: Any) -> None:
            try:
                policy = qos_policy_name_from_kind(event.last_policy_kind)
            except ValueError:
                policy = str(event.last_policy_kind)
            if policy in warned:
                return
            warned.add(policy)
            self.get_logger().warning(
                f'input {topic}: a publisher offers incompatible QoS ({policy}); nothing it '
                f'sends reaches this node (reliable_inputs is true: is it best effort?)')

        return on_event

    def _on_diagnostics_timer(self) -> None:
        self._last_tick_s = time.monotonic()
        self._publish_status('')

    def _on_clock_watchdog(self) -> None:
        """Publish STALE and save on while the node's clock stops the diagnostics timer."""
        steady_s, now = time.monotonic(), self._now_ns()
        if now != self._watched_ns:  # it moved (forward, or back: a jump), since last read
            self._watched_ns, self._clock_moved_s = now, steady_s
        silent_s = steady_s - max(self._last_tick_s, self._clock_moved_s)
        if silent_s < self._silent_after_s or not self.get_parameter('use_sim_time').value:
            return  # slower than real time it still ticks; a system clock never stops
        why = ('use_sim_time is true and no /clock has come' if now == 0 else
               f"the node's clock has not advanced for {steady_s - self._clock_moved_s:.0f} s"
               ' (use_sim_time is true: /clock stopped or paused)')
        self._publish_status(why)

    def _publish_status(self, clock_stopped: str) -> None:
        now = self._now_ns()
        status = self.core.diagnostics(now, clock_stopped)
        self._diag_pub.publish(diagnostic_array(self._types, status, now, self._status_name,
                                                self.config.hardware_id))
        if time.monotonic() >= self._next_save_s:
            self._next_save_s = time.monotonic() + self.config.baseline_save_period_s
            self.save_baseline()

    def save_baseline(self) -> None:
        """Save the baseline file if the monitor learnt anything new; a failure warns once."""
        warning = self.baseline.save()
        if warning:
            self.get_logger().warning(warning)

    def _on_reset(self, request: Trigger.Request, response: Trigger.Response
                  ) -> Trigger.Response:
        # after a repair: forget the learnt baseline, keep the old file as .bak, re-learn
        response.success, response.message = self.baseline.reset()
        (self.get_logger().info if response.success else self.get_logger().warning)(
            response.message)
        return response


def _spin(executor: SingleThreadedExecutor, node: Node) -> None:
    """
    Execute callbacks until the context shuts down, surviving a callback's error.

    Any peer can send a request that makes one of rclpy's own callbacks raise: Jazzy's
    parameter service builds ``Parameter.from_parameter_msg`` outside its ``try``
    (``rclpy/parameter_service.py``), so a ``ParameterValue`` of an unknown type raises
    ``ValueError`` out of ``spin_once``, and ``Executor.spin`` would end the node. Here that
    request is dropped (its client gets no response) and the node goes on. The error is
    logged the 1st, 2nd, 4th, 8th... time, with where it was raised and the count, so a
    peer repeating it cannot flood the log. A shutdown (the context no longer ok, a signal
    waking the wait) still ends the loop.

    Parameters
    ----------
    executor : SingleThreadedExecutor
        The executor the node was added to.
    node : Node
        The node, for its logger.

    """
    failures = 0
    while executor.context.ok():
        try:
            executor.spin_once()
        except ExternalShutdownException:
            raise
        except Exception as exc:
            if not executor.context.ok():
                raise  # the shutdown's own error: run() tells it from a real one
            failures += 1
            if failures & (failures - 1):  # logged at 1, 2, 4, 8...
                continue
            why = ' '.join(str(exc).split()) or 'no message'
            frames = traceback.extract_tb(exc.__traceback__)
            where = f' at {Path(frames[-1].filename).name}:{frames[-1].lineno}' if frames else ''
            node.get_logger().error(
                f'a callback raised {type(exc).__name__}{where}: {why}; what it was handling '
                f'is dropped and the node goes on ({failures} such error(s) so far)')


def run(args: list[str] | None, stop: StopSignals) -> int:
    """
    Run the node until a stop signal or a shutdown; ``stop`` is already installed.

    Parameters
    ----------
    args : list of str, optional
        Command-line arguments for rclpy.
    stop : StopSignals
        The stop-signal handler, installed before this module was imported.

    Returns
    -------
    int
        0 on a normal shutdown (SIGINT, SIGTERM, or the context shut down elsewhere), 1 when
        the parameters, pump file or table are invalid.

    """
    if stop.received:  # while Python imported rclpy and the messages: nothing to undo
        print(f'{NODE_NAME}: stopping on {stop.received[0]} during start-up', file=sys.stderr)
        return 0
    try:
        rclpy.init(args=args)
    except (_RCLError, _UnknownROSArgsError) as exc:  # the command line: a params file that
        # does not parse, a bad remap, an unknown --ros-args flag (--params-files)
        why = ' '.join(str(exc).split())
        if isinstance(exc, _UnknownROSArgsError):  # its text is the list of them
            why = f'unknown --ros-args argument(s) {why}'
        print(f'{NODE_NAME}: cannot start: {why}', file=sys.stderr)
        return 1
    # Made before the node: an executor made after a signal has shut the context down
    # fails in its constructor (and then in its __del__, with a traceback on stderr).
    executor = SingleThreadedExecutor()
    node = None
    refused = False
    try:
        if not stop.received:  # else a signal came before rclpy's handler was there
            node = TorqueEstimatorNode(sys.argv if args is None else args)
            executor.add_node(node)
            _spin(executor, node)
    except PumpFrictionError as exc:
        print(f'{NODE_NAME}: cannot start: {exc}', file=sys.stderr)
        refused = True  # that line is the whole story: no 'stopping on' after it
        return 1
    except ExternalShutdownException:
        pass
    except Exception:
        # The context went away under the start-up (a signal: rclpy's handler shuts it
        # down in its own thread, and an rcl call can fail on it before Python has run
        # our handler), or a real error, which is raised.
        if not stop.received and rclpy.ok():
            raise
    finally:
        why = stop.received[0] if stop.received else 'context shut down'
        logger = node.get_logger().name if node is not None else NODE_NAME
        unsaved = _save_baseline_at_exit(node)
        executor.shutdown()
        if node is not None:
            node.destroy_node()
        # after destroy_node: the lines go to the console, not to /rosout (whose
        # publisher died with the context)
        if unsaved:
            rclpy.logging.get_logger(logger).warning(unsaved)
        if not refused:
            rclpy.logging.get_logger(logger).info(f'stopping on {why}')
        rclpy.try_shutdown()
    return 0


def _save_baseline_at_exit(node: TorqueEstimatorNode | None) -> str:
    """Save what the monitor learnt since the last save; return a warning, never raise."""
    if node is None:
        return ''
    try:
        return node.baseline.save()
    except Exception as exc:  # the clean-up must run to its end
        return f'baseline file not saved at shutdown: {type(exc).__name__}: {exc}'
