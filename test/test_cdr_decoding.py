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

"""The node's one-message CDR decoder against rosbags' deserialiser and the node's conversion."""

import struct

import numpy as np
import pytest

try:
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import get_typestore, Stores
except ImportError:  # a ROS shell without pip's rosbags: skip, do not break collection
    pytestmark = pytest.mark.skip(reason='rosbags is not installed (pip install rosbags)')

from pump_friction_ros.core.inputs import Defect, InputKind, INPUTS  # noqa: I100 (after try)
from pump_friction_ros.core.node_parameters import EstimatorConfig
from pump_friction_ros.messages.cdr import TopicDecoder
from pump_friction_ros.messages.cdr_message import MessageDecoder
from pump_friction_ros.messages.conversions import float64_cdr, input_sample, stamp_to_ns
from pump_friction_ros.sim.sample_bags import make_sample_bags

STORE = get_typestore(Stores.ROS2_JAZZY) if 'get_typestore' in globals() else None
T = STORE.types if STORE is not None else {}
JOINT = 'pump_shaft'
SPEC = {spec.kind: spec for spec in INPUTS}


def header(sec=5, nanosec=250, frame_id=''):
    stamp = T['builtin_interfaces/msg/Time'](sec=sec, nanosec=nanosec)
    return T['std_msgs/msg/Header'](stamp=stamp, frame_id=frame_id)


def joint_state(names, velocity, effort, position=None, **stamp):
    return T['sensor_msgs/msg/JointState'](
        header=header(**stamp), name=names,
        position=np.zeros(len(names)) if position is None else np.array(position, float),
        velocity=np.array(velocity, dtype=np.float64), effort=np.array(effort, dtype=np.float64))


def raw_of(msg, msgtype, little_endian=True):
    return bytes(STORE.serialize_cdr(msg, msgtype, little_endian=little_endian))


def reference(spec, raw):
    """Decode as the node did before it subscribed raw: deserialise, then `input_sample`."""
    msg = STORE.deserialize_cdr(raw, spec.msgtype)
    value, torque, defect = input_sample(spec, msg, JOINT)
    stamp = stamp_to_ns(msg.header.stamp) if spec.has_header else None
    return (None, None, None, defect) if defect else (stamp, value, torque, defect)


def decoder(kind):
    spec = SPEC[kind]
    return MessageDecoder(spec, JOINT, lambda raw: STORE.deserialize_cdr(raw, spec.msgtype))


JOINT_STATES = [
    joint_state([JOINT], [300.0], [9.5]),
    joint_state([JOINT], [301.0], [9.25], sec=6),  # same layout: the cached path
    joint_state(['wheel', JOINT], [1.0, 523.5], [0.2, 12.25]),
    joint_state([JOINT, 'wheel'], [523.5, 1.0], [12.25, 0.2]),  # same length, reordered
    joint_state([JOINT], [300.0], []),  # no effort
    joint_state([JOINT], [], [4.0]),  # no velocity: the same length as the one before
    joint_state([JOINT], [], [], position=[0.0]),  # neither: malformed
    joint_state([JOINT, 'wheel'], [1.0], [2.0, 3.0]),  # an array of the wrong length
    joint_state(['wheel'], [1.0], [2.0]),  # joint missing
    joint_state([JOINT, 'wheel', JOINT], [1.0, 2.0, 3.0], [4.0, 5.0, 6.0]),  # named twice
    joint_state([JOINT], [300.0], [9.5], sec=0, nanosec=0),  # unset stamp
    joint_state([JOINT], [-250.0], [-3.0], frame_id='pump_frame'),
    joint_state([JOINT], [300.0], [9.5]),  # back to the first layout
]


def test_joint_states_decode_as_the_node_converted_them():
    decode = decoder(InputKind.JOINT_STATE)
    for msg in JOINT_STATES:
        raw = raw_of(msg, 'sensor_msgs/msg/JointState')
        assert decode(raw) == reference(SPEC[InputKind.JOINT_STATE], raw), msg.name
    assert decode.fallbacks == 0  # every one of them by the parser


def test_a_joint_named_twice_is_malformed_by_the_parser_and_its_cache():
    decode = decoder(InputKind.JOINT_STATE)
    twice = joint_state([JOINT, 'wheel', JOINT], [1.0, 2.0, 3.0], [4.0, 5.0, 6.0])
    raw = raw_of(twice, 'sensor_msgs/msg/JointState')
    for _ in range(2):  # the second through the cached layout
        assert decode(raw) == (None, None, None, Defect.MALFORMED)
    assert decode.fallbacks == 0


def test_parser_and_deserialiser_give_the_same_sample_defects_included():
    """Big-endian CDR goes through the deserialiser: it must answer as the parser does."""
    parser, fallback = decoder(InputKind.JOINT_STATE), decoder(InputKind.JOINT_STATE)
    for msg in JOINT_STATES:
        little = raw_of(msg, 'sensor_msgs/msg/JointState')
        big = raw_of(msg, 'sensor_msgs/msg/JointState', little_endian=False)
        assert parser(little) == fallback(big), msg.name
    assert (parser.fallbacks, fallback.fallbacks) == (0, len(JOINT_STATES))


def test_rmw_padding_is_read_by_the_parser_one_by_one():
    """Fast DDS's serialize_message: 12 bytes, not all zero, after empty double arrays."""
    decode = decoder(InputKind.JOINT_STATE)
    for msg in (joint_state(['wheel', JOINT], [1.0, -523.5], [], position=[]),
                joint_state(['wheel'], [1.0], [], position=[])):
        raw = raw_of(msg, 'sensor_msgs/msg/JointState')
        for tail in (bytes(12), bytes(8) + b'S' + bytes(3)):  # learnt, then cached
            assert decode(raw + tail) == decode(raw) == reference(
                SPEC[InputKind.JOINT_STATE], raw)
    raw = raw_of(JOINT_STATES[0], 'sensor_msgs/msg/JointState')
    assert decode(raw + bytes(33))[3] == Defect.UNDECODABLE  # beyond any alignment
    assert decode.fallbacks == 1


def test_layout_change_of_the_same_length_is_not_read_with_the_old_offsets():
    decode = decoder(InputKind.JOINT_STATE)
    a = raw_of(joint_state([JOINT], [], [4.0], position=[]), 'sensor_msgs/msg/JointState')
    b = raw_of(joint_state([JOINT], [], [], position=[4.0]), 'sensor_msgs/msg/JointState')
    assert len(a) == len(b)  # the effort of one sits where the position of the other does
    assert decode(a)[1:] == (None, 4.0, Defect.NONE)
    assert decode(b) == (None, None, None, Defect.MALFORMED)
    assert decode(a)[1:] == (None, 4.0, Defect.NONE)


@pytest.mark.parametrize('kind, msgtype, field, value', [
    (InputKind.LOAD_PRESSURE, 'sensor_msgs/msg/FluidPressure', 'fluid_pressure', 1.36e7),
    (InputKind.PRESSURE_A, 'sensor_msgs/msg/FluidPressure', 'fluid_pressure', -2.0e5),
    (InputKind.OIL_TEMPERATURE, 'sensor_msgs/msg/Temperature', 'temperature', 48.5),
])
def test_header_and_double_messages_decode_for_any_frame_id(kind, msgtype, field, value):
    decode = decoder(kind)
    for frame_id in ('', 'p', 'abc', 'pressure_sensor_frame'):
        msg = T[msgtype](header=header(frame_id=frame_id), **{field: value}, variance=0.5)
        raw = raw_of(msg, msgtype)
        assert decode(raw) == reference(SPEC[kind], raw) == (5_000_000_250, value, None,
                                                             Defect.NONE)
    assert decode.fallbacks == 0


def test_float64_decodes_and_matches_rosbags_serialisation():
    raw = raw_of(T['std_msgs/msg/Float64'](data=523.5), 'std_msgs/msg/Float64')
    assert raw == float64_cdr(523.5)
    for kind in (InputKind.SHAFT_SPEED, InputKind.MOTOR_TORQUE):
        assert decoder(kind)(raw) == (None, 523.5, None, Defect.NONE)


def test_big_endian_cdr_goes_through_the_deserialiser():
    decode = decoder(InputKind.JOINT_STATE)
    msg = joint_state(['wheel', JOINT], [1.0, 523.5], [0.2, 12.25])
    raw = raw_of(msg, 'sensor_msgs/msg/JointState', little_endian=False)
    assert raw[:2] == b'\x00\x00'
    assert decode(raw) == (5_000_000_250, 523.5, 12.25, Defect.NONE)
    assert decode.fallbacks == 1


@pytest.mark.parametrize('cut', [3, 10, 30, -1])
def test_truncated_payloads_are_undecodable_not_errors(cut):
    decode = decoder(InputKind.JOINT_STATE)
    raw = raw_of(joint_state([JOINT], [300.0], [9.5]), 'sensor_msgs/msg/JointState')
    decode(raw)  # learn the layout first
    assert decode(raw[:cut])[3] == Defect.UNDECODABLE
    pressure = decoder(InputKind.LOAD_PRESSURE)
    raw = raw_of(T['sensor_msgs/msg/FluidPressure'](header=header(), fluid_pressure=1.0,
                                                    variance=0.0),
                 'sensor_msgs/msg/FluidPressure')
    assert pressure(raw[:cut])[3] == Defect.UNDECODABLE


def test_a_corrupt_name_count_cannot_make_it_read_past_the_end():
    decode = decoder(InputKind.JOINT_STATE)
    raw = bytearray(raw_of(joint_state([JOINT], [300.0], [9.5]), 'sensor_msgs/msg/JointState'))
    struct.pack_into('<I', raw, 4 + 12 + 4, 0x7FFFFFFF)  # the name count, after frame_id ''
    assert decode(bytes(raw))[3] == Defect.UNDECODABLE


def test_sample_bags_decode_one_by_one_as_in_batches(tmp_path, monkeypatch):
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path / 'cache'))
    config = EstimatorConfig()
    for bag in make_sample_bags(tmp_path / 'bags', seed=5, duration_s=1.0):
        with Reader(bag) as reader:
            for conn in reader.connections:
                spec = next(s for s in INPUTS if '/' + s.topic == conn.topic)
                items = list(reader.messages(connections=[conn]))
                raws = [bytes(raw) for _, _, raw in items]
                batch = TopicDecoder(spec, config.joint_name, STORE).decode(
                    raws, [t for _, t, _ in items])
                one = decoder(spec.kind)
                for i, raw in enumerate(raws):
                    stamp, value, torque, defect = one(raw)
                    # the independent reference: rosbags' deserialiser + the node's conversion
                    msg = STORE.deserialize_cdr(raw, spec.msgtype)
                    assert (value, torque, defect) == input_sample(spec, msg, config.joint_name)
                    assert stamp == (stamp_to_ns(msg.header.stamp) if spec.has_header else None)
                    assert (stamp, defect) == (int(batch.stamps[i]), batch.defects[i])
                    assert value == (batch.values[i] if batch.has_value[i] else None)
                    assert torque == (batch.torques[i] if batch.has_torque[i] else None)
                assert one.fallbacks == 0
