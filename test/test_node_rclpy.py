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
The rclpy node: a publisher -> node -> subscriber round trip, parameters, diagnostics.

Real rclpy tests; they need a sourced ROS 2 Jazzy and skip with the reason otherwise.
"""

import os
from pathlib import Path
import subprocess
import sys
import time

import pytest

rclpy = pytest.importorskip(
    'rclpy', reason='rclpy is not importable: source a ROS 2 Jazzy install to run node tests')

# Imports that need a sourced ROS 2, after the skip above; flake8-import-order compares
# them with 'import pytest' across the code in between, hence I100.
from builtin_interfaces.msg import Time  # noqa: E402, I100
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus  # noqa: E402
from pump_friction_ros.bags.sinks import output_qos, output_topics  # noqa: E402
from pump_friction_ros.core.inputs import Defect, InputKind, INPUTS  # noqa: E402
from pump_friction_ros.core.node_parameters import load_estimator_config  # noqa: E402
from pump_friction_ros.errors import ConfigError, PumpFrictionError  # noqa: E402
from pump_friction_ros.messages.cdr_message import MessageDecoder  # noqa: E402
from pump_friction_ros.messages.conversions import input_sample, stamp_to_ns  # noqa: E402
from pump_friction_ros.node.torque_estimator import TorqueEstimatorNode  # noqa: E402
from pump_friction_ros.physics.model import PumpModel  # noqa: E402
from pump_friction_ros.table.friction_table import build_table  # noqa: E402
from rclpy.event_handler import QoSSubscriptionEventType  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import qos_profile_sensor_data  # noqa: E402
from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402
from sensor_msgs.msg import FluidPressure, JointState, Temperature  # noqa: E402
from std_msgs.msg import Float64, Header  # noqa: E402

from .conftest import level_from_msg  # noqa: E402, I100

PARAMS = Path(__file__).resolve().parents[1] / 'config' / 'torque_estimator.yaml'
SAMPLE_PARAMS = Path(__file__).resolve().parents[1] / 'bags' / 'eha_params.yaml'
NS = 1_000_000_000


@pytest.fixture(scope='module')
def table_file(tmp_path_factory, paper_params):
    return str(build_table(paper_params).save(tmp_path_factory.mktemp('t') / 'table.npz'))


@pytest.fixture
def ros(table_file):
    """Start rclpy with the package's parameters file; yields a function making the node."""
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
        # the full model's input torque + the bags' drive loss (eha_params.yaml); the speed
        # does not change, so the inertia term is 0
        reference = float(PumpModel(paper_params).evaluate(500.0, 120e5, 46e-6).input_nm[0])
        assert expected == pytest.approx(reference + 0.05, rel=5e-4)
        assert probe.got['residual'] == pytest.approx(12.0 - expected, abs=1e-9)
        assert node.received[InputKind.JOINT_STATE] > 0
        assert node.received[InputKind.LOAD_PRESSURE] > 0
        assert node.core.counts['rejected_undecodable'] == 0
    finally:
        ex.shutdown()
        probe.destroy_node()
        node.destroy_node()


def test_with_simulated_time_before_the_first_clock_stamped_inputs_are_not_future(ros):
    """use_sim_time and no /clock yet: the node's time reads 0, which judges no stamp."""
    node = ros('use_sim_time:=true')
    probe = Probe()
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    ex.add_node(probe)
    try:
        assert node.get_clock().now().nanoseconds == 0  # nobody publishes /clock here
        assert spin_until(ex, lambda: probe.count_subscribers('joint_states') > 0)
        assert spin_until(ex, lambda: probe.count_subscribers('load_pressure') > 0)
        stamp = 10 * NS  # a bag's stamps, 10 s ahead of a clock at 0
        for _ in range(50):
            probe.send(stamp, 500.0, 12.0, 120e5)
            stamp += 1_000_000
            if spin_until(ex, lambda: 'residual' in probe.got, 0.2):
                break
        assert 'residual' in probe.got
        assert node.core.counts['rejected_future_stamp'] == 0
    finally:
        ex.shutdown()
        probe.destroy_node()
        node.destroy_node()


def test_with_simulated_time_and_no_clock_diagnostics_go_on_stale_and_say_why(ros):
    node = ros('use_sim_time:=true', 'diagnostics_rate_hz:=10.0')
    probe = Probe()
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    ex.add_node(probe)
    try:
        assert node.get_clock().now().nanoseconds == 0  # nobody publishes /clock here
        assert spin_until(ex, lambda: len(probe.diagnostics) >= 2, 8.0), \
            'no /diagnostics without /clock'
        status = probe.diagnostics[-1].status[0]
        assert level_from_msg(status.level) == level_from_msg(DiagnosticStatus.STALE)
        assert status.message.startswith('stale: use_sim_time is true and no /clock has come')
    finally:
        ex.shutdown()
        probe.destroy_node()
        node.destroy_node()


def test_simulated_time_slower_than_real_time_is_not_said_to_stand_still(ros):
    from rosgraph_msgs.msg import Clock
    node = ros('use_sim_time:=true', 'diagnostics_rate_hz:=10.0')
    probe = Probe()
    clock = probe.create_publisher(Clock, '/clock', 10)
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    ex.add_node(probe)
    try:
        sim_ns = 100 * NS
        end = time.monotonic() + 4.0
        while time.monotonic() < end:  # a bag played at 0.1x: 10 ms of /clock each 100 ms
            sim_ns += 10_000_000
            clock.publish(Clock(clock=Time(sec=sim_ns // NS, nanosec=sim_ns % NS)))
            spin_until(ex, lambda: False, 0.1)
        messages = [m.status[0].message for m in probe.diagnostics]
        assert messages, 'no /diagnostics in 4 s of a slow clock'
        assert not [m for m in messages if 'has not advanced' in m or 'no /clock' in m]
    finally:
        ex.shutdown()
        probe.destroy_node()
        node.destroy_node()


@pytest.mark.parametrize('jump_back_s', [0.0, 900.0], ids=['paused', 'jumped-back-then-paused'])
def test_a_clock_paused_between_two_diagnostics_ticks_goes_on_stale_and_says_why(ros, jump_back_s):
    """ros2 bag play paused (space), mid-period: the clock stands still off any tick's value."""
    from rosgraph_msgs.msg import Clock
    node = ros('use_sim_time:=true', 'diagnostics_rate_hz:=10.0')
    probe = Probe()
    clock = probe.create_publisher(Clock, '/clock', 10)
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    ex.add_node(probe)

    def tick(ns):
        clock.publish(Clock(clock=Time(sec=ns // NS, nanosec=ns % NS)))
        spin_until(ex, lambda: False, 0.01)

    try:
        sim_ns = 1000 * NS
        end = time.monotonic() + 2.0
        while time.monotonic() < end:  # about real-time rate: 10 ms of /clock each 10 ms
            sim_ns += 10_000_000
            tick(sim_ns)
        tick(sim_ns - int(jump_back_s * NS) + 3_000_000)  # 3 ms on (or back), then pause
        running = len(probe.diagnostics)
        assert running >= 2, 'the diagnostics timer did not tick on a running /clock'
        spin_until(ex, lambda: False, 3.0)
        messages = [m.status[0].message for m in probe.diagnostics[running:]]
        stale = [m for m in messages if m.startswith('stale: ') and 'has not advanced' in m]
        assert stale, f'no STALE in 3 s of a paused clock: {messages}'
        assert '/clock stopped or paused' in stale[-1]
    finally:
        ex.shutdown()
        probe.destroy_node()
        node.destroy_node()


@pytest.mark.parametrize('section, line, refused', [
    ('/**/torque_estimator', 'output_decimation: 20.0', 'output_decimation'),  # rcl drops it
    ('/**/torque_estimator', 'max_input_age_s: "0.1"', 'max_input_age_s'),
    ('/**/torque_estimator', 'reliable_inputs: 1', 'reliable_inputs'),
    ('/**/torque_estimator', 'joint_name: [a, b]', 'joint_name'),
    ('torque_estimator', 'joint_nam: motor_shaft', 'joint_nam'),  # rclpy ignores it
    ('/**', 'output_decimation: 20.0', 'output_decimation'),
    ('/**', 'frame_id: base_link', None),  # a shared section: another node's parameter
    ('/other_node', 'joint_nam: motor_shaft', None),  # not this node's section
    ('/**/torque_estimator', 'output_decimation: 20', None),  # a good override
])
def test_a_second_params_file_the_node_would_ignore_stops_it_naming_the_parameter(
        table_file, tmp_path, section, line, refused):
    later = tmp_path / 'site.yaml'
    later.write_text(f'{section}:\n  ros__parameters:\n    {line}\n')
    args = ['--ros-args', '--params-file', str(PARAMS), '--params-file', str(SAMPLE_PARAMS),
            '--params-file', str(later), '-p', f'table_file:={table_file}']
    rclpy.init(args=args)
    try:
        if refused is None:
            node = TorqueEstimatorNode(args)
            if line.startswith('output_decimation'):
                assert node.config.output_decimation == 20
            node.destroy_node()
        else:
            with pytest.raises(PumpFrictionError, match=refused) as info:
                TorqueEstimatorNode(args)  # by rclpy (one file) or by the check, naming it
            assert '\n' not in str(info.value)
            assert isinstance(info.value, ConfigError) <= (str(later) in str(info.value))
    finally:
        rclpy.try_shutdown()


def test_a_misspelt_p_rule_stops_the_node_naming_it(table_file):
    args = ['--ros-args', '--params-file', str(PARAMS), '-p', f'table_file:={table_file}',
            '-p', 'joint_nam:=motor_shaft']
    rclpy.init(args=args)
    try:
        with pytest.raises(ConfigError, match='joint_nam:=motor_shaft: unknown parameter'):
            TorqueEstimatorNode(args)
    finally:
        rclpy.try_shutdown()


def test_parameters_come_from_the_yaml_file(ros, table_file):
    node = ros()
    try:
        expected = load_estimator_config([PARAMS, SAMPLE_PARAMS])  # later files override
        for name, value in expected.__dict__.items():
            if name != 'table_file':
                assert getattr(node.config, name) == value, name
        assert node.config.table_file == table_file
    finally:
        node.destroy_node()


def test_diagnostics_go_from_ok_to_alarm_on_a_simulated_wear_step(ros):
    node = ros('cusum_warn_nm_s:=0.02', 'cusum_error_nm_s:=0.05', 'diagnostics_rate_hz:=20.0',
               'monitor_max_accel_rad_s2:=1.0e9', 'baseline_learn_s:=1.0')
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

        end = time.monotonic() + 20.0
        while (0 not in levels or node.core.monitor.learning) and time.monotonic() < end:
            send(0.0)  # OK, and the healthy baseline learnt, before the wear step
        assert 0 in levels and not node.core.monitor.learning
        end = time.monotonic() + 20.0
        while node.core.monitor.level == 0 and time.monotonic() < end:
            send(1.0)  # +1 N m of friction: a simulated wear step
        assert node.core.monitor.level != 0, 'no alarm within 20 s of the wear step'
        # the next status that reports it: one published before the level changed may still
        # be on its way (seen on a loaded machine)
        alarm = (level_from_msg(DiagnosticStatus.WARN), level_from_msg(DiagnosticStatus.ERROR))
        spin_until(ex, lambda: any(level_from_msg(m.status[0].level) in alarm
                                   for m in probe.diagnostics), 2.0)
        levels += [level_from_msg(m.status[0].level) for m in probe.diagnostics]
        assert levels[-1] in alarm
    finally:
        ex.shutdown()
        probe.destroy_node()
        node.destroy_node()


def test_every_ranged_parameter_is_described_with_its_range_and_read_only(ros):
    """`ros2 param describe` shows the spec's range, [0, inf] included."""
    from pump_friction_ros.core.node_parameters import PARAMETERS
    node = ros()
    try:
        for spec in PARAMETERS:
            desc = node.describe_parameter(spec.name)
            assert desc.read_only and desc.description == spec.description, spec.name
            if spec.low is None or isinstance(spec.default, (bool, str)):
                continue
            ranges = (desc.floating_point_range if isinstance(spec.default, float)
                      else desc.integer_range)
            assert len(ranges) == 1, spec.name
            assert (ranges[0].from_value, ranges[0].to_value) == (spec.low, spec.high)
    finally:
        node.destroy_node()


@pytest.mark.parametrize('override', ['output_decimation:=0', 'rotor_inertia_kg_m2:=heavy',
                                      'speed_source:=tachometer'])
def test_invalid_parameter_stops_start_up_with_one_clear_message(ros, override):
    with pytest.raises(PumpFrictionError, match=override.split(':=')[0]):
        ros(override)


@pytest.mark.parametrize(('line', 'words'), [
    ('max_input_age_s: 1', 'expected a double, got 1: the node refuses it'),
    ('drive_loss_torque_nm: 0', 'expected a double, got 0'),
    ('output_decimation: 2.0', 'expected an integer, got 2.0'),
])
def test_a_number_of_the_wrong_type_is_refused_by_the_node_and_by_the_replay_alike(
        table_file, tmp_path, line, words):
    params = tmp_path / 'params.yaml'
    params.write_text(f'/**/torque_estimator:\n  ros__parameters:\n    {line}\n')
    name = line.split(':')[0]
    with pytest.raises(ConfigError, match=words):  # the replay's reading of the file
        load_estimator_config([PARAMS, params])
    # rclpy's, in the node (the file alone: after a file giving the integer, rcl keeps the
    # integer and drops a double quietly)
    rclpy.init(args=['--ros-args', '--params-file', str(params), '-p',
                     f'table_file:={table_file}'])
    try:
        with pytest.raises(PumpFrictionError, match=name):
            TorqueEstimatorNode()
    finally:
        rclpy.try_shutdown()


def _stamped(sec=5, nanosec=250, frame_id=''):
    return Header(stamp=Time(sec=sec, nanosec=nanosec), frame_id=frame_id)


RAW_CASES = [
    (InputKind.JOINT_STATE, JointState(header=_stamped(), name=['pump_shaft'], position=[0.0],
                                       velocity=[300.0], effort=[9.5])),
    (InputKind.JOINT_STATE, JointState(header=_stamped(frame_id='eha'),
                                       name=['wheel', 'pump_shaft'], position=[],
                                       velocity=[1.0, -523.5], effort=[])),
    (InputKind.JOINT_STATE, JointState(header=_stamped(), name=['wheel'], velocity=[1.0])),
    (InputKind.LOAD_PRESSURE, FluidPressure(header=_stamped(frame_id='p'),
                                            fluid_pressure=1.36e7, variance=0.0)),
    (InputKind.OIL_TEMPERATURE, Temperature(header=_stamped(sec=0, nanosec=0),
                                            temperature=48.5, variance=0.0)),
    (InputKind.SHAFT_SPEED, Float64(data=523.5)),
]


def _sample_of(spec, msg):
    """Return the independent reference: rclpy's message through the node's conversion."""
    value, torque, defect = input_sample(spec, msg, 'pump_shaft')
    stamp = stamp_to_ns(msg.header.stamp) if spec.has_header else None
    return (None, None, None, defect) if defect else (stamp, value, torque, Defect.NONE)


@pytest.mark.parametrize('kind, msg', RAW_CASES)
def test_raw_decoding_reads_this_middlewares_serialisation(kind, msg):
    """serialize_message: Fast DDS pads JointStates with empty arrays (92 B for 80 B)."""
    spec = next(s for s in INPUTS if s.kind == kind)
    raw = serialize_message(msg)  # the rmw's own serialisation
    decode = MessageDecoder(spec, 'pump_shaft', lambda b: deserialize_message(b, type(msg)))
    assert decode(raw) == _sample_of(spec, msg)
    assert decode.fallbacks == 0  # read by the parser, not by the deserialiser


def test_raw_subscription_bytes_are_read_by_the_parser(ros):
    """Decode what a raw subscription receives over the wire, for every case above."""
    node = ros()
    probe = Node('raw_probe')
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    ex.add_node(probe)
    try:
        for i, (kind, msg) in enumerate(RAW_CASES):
            got = []
            topic = f'raw_case_{i}'
            probe.create_subscription(type(msg), topic, got.append, 10, raw=True)
            pub = node.create_publisher(type(msg), topic, 10)
            assert spin_until(ex, lambda p=pub: p.get_subscription_count() > 0)
            for _ in range(50):
                pub.publish(msg)
                if spin_until(ex, lambda g=got: g, 0.2):
                    break
            assert got and isinstance(got[0], bytes), kind
            spec = next(s for s in INPUTS if s.kind == kind)
            cls = type(msg)
            decode = MessageDecoder(spec, 'pump_shaft', lambda b, c=cls: deserialize_message(b, c))
            assert decode(got[0]) == _sample_of(spec, msg), (kind, msg)
            assert decode.fallbacks == 0, (kind, len(got[0]))
    finally:
        ex.shutdown()
        probe.destroy_node()
        node.destroy_node()


def test_qos_event_handlers_only_where_they_can_fire(ros):
    node = ros()
    try:
        publishers = [*node._pub.values(), node._diag_pub]
        assert len(publishers) == 6
        assert all(pub.event_handlers == [] for pub in publishers)
        assert [len(sub.event_handlers) for sub in node.subscriptions] == [0, 0]  # best effort
    finally:
        node.destroy_node()
    rclpy.try_shutdown()
    node = ros('reliable_inputs:=true')
    try:
        handlers = [h for sub in node.subscriptions for h in sub.event_handlers]
        assert len(handlers) == 2
        assert all(h.event_type ==
                   QoSSubscriptionEventType.RCL_SUBSCRIPTION_REQUESTED_INCOMPATIBLE_QOS
                   for h in handlers)
    finally:
        node.destroy_node()


def test_a_best_effort_publisher_is_warned_about_once_with_reliable_inputs(ros):
    node = ros('reliable_inputs:=true')
    warnings = []

    class Logger:

        def warning(self, message):
            warnings.append(message)

    node.get_logger = Logger  # the handler looks the logger up when it fires
    probe = Node('best_effort_probe')
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    ex.add_node(probe)
    try:
        probe.create_publisher(JointState, 'joint_states', qos_profile_sensor_data)
        assert spin_until(ex, lambda: warnings, 15.0), 'no incompatible-QoS warning'
        probe.create_publisher(JointState, 'joint_states', qos_profile_sensor_data)
        spin_until(ex, lambda: len(warnings) > 1, 2.0)
        assert len(warnings) == 1  # once per topic and policy
        assert 'joint_states' in warnings[0] and 'RELIABILITY' in warnings[0]
    finally:
        ex.shutdown()
        probe.destroy_node()
        node.destroy_node()


def test_outputs_offer_the_qos_the_output_bag_records(ros):
    pytest.importorskip('rosbags', reason='rosbags is not installed (pip install rosbags)')
    node = ros()
    probe = Node('qos_probe')
    try:
        publishers = {pub.topic_name: pub for pub in [*node._pub.values(), node._diag_pub]}
        for topic, _, depth in output_topics():
            mine, bag = publishers[topic].qos_profile, output_qos(depth)
            assert (mine.history.name, mine.depth, mine.reliability.name, mine.durability.name,
                    mine.liveliness.name) == (bag.history.name, bag.depth, bag.reliability.name,
                                              bag.durability.name, bag.liveliness.name)
            assert mine.deadline.nanoseconds == mine.lifespan.nanoseconds == 0
            assert bag.deadline.sec == bag.lifespan.sec == 0
            end, offered = time.monotonic() + 10.0, []
            while not offered and time.monotonic() < end:  # the graph, as ros2 bag records it
                offered = [i.qos_profile for i in probe.get_publishers_info_by_topic(topic)
                           if i.node_name == 'torque_estimator']
                time.sleep(0.05)
            assert [(q.reliability.name, q.durability.name) for q in offered] == [
                ('RELIABLE', 'VOLATILE')]
    finally:
        probe.destroy_node()
        node.destroy_node()


def test_cpu_benchmark_runs_end_to_end(table_file):
    """A short run of the benchmark (figures are for docs/cpu_cost.md's longer runs: untested)."""
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([str(PARAMS.parents[1]), env.get('PYTHONPATH', '')])
    done = subprocess.run(
        [sys.executable, '-m', 'pump_friction_ros.node.measure_cpu', '--qos', 'reliable', '--runs',
         '1', '--window-s', '2', '--settle-s', '0.5', '--start-timeout-s', '60',
         '--estimator-param', f'table_file:={table_file}'],
        env=env, capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr[-2000:]
    assert 'estimator / bare, CPU per input message:' in done.stdout
    assert 'reliable: estimator / bare = ' in done.stdout
