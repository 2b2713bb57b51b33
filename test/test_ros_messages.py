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

"""Message conversion at the node's edge, against rosbags' Jazzy message classes."""

import math
from types import SimpleNamespace

import numpy as np
from pump_friction_ros.core.estimator import TorqueEstimator
from pump_friction_ros.core.inputs import Defect, InputKind
from pump_friction_ros.core.node_parameters import EstimatorConfig
from pump_friction_ros.messages.conversions import (
    diagnostic_array,
    float64_cdr,
    joint_sample,
    level_to_msg,
    outputs_of,
    rosbags_types,
    stamp_msg,
    stamp_to_ns,
)
from pump_friction_ros.table.friction_table import build_table
import pytest

from .conftest import level_from_msg

try:
    from rosbags.typesys import get_typestore, Stores
except ImportError:  # a ROS shell without pip's rosbags: skip, do not break collection
    pytestmark = pytest.mark.skip(reason='rosbags is not installed (pip install rosbags)')

STORE = get_typestore(Stores.ROS2_JAZZY) if 'get_typestore' in globals() else None
T = STORE.types if STORE is not None else {}


def roundtrip(msg, msgtype):
    return STORE.deserialize_cdr(STORE.serialize_cdr(msg, msgtype), msgtype)


def joint_state(names, velocity, effort, sec=5, nanosec=250):
    header = T['std_msgs/msg/Header'](stamp=T['builtin_interfaces/msg/Time'](sec=sec,
                                                                             nanosec=nanosec),
                                      frame_id='')
    return T['sensor_msgs/msg/JointState'](
        header=header, name=names, position=np.zeros(len(names)),
        velocity=np.array(velocity, dtype=np.float64), effort=np.array(effort, dtype=np.float64))


def test_joint_found_by_name_among_several_after_a_cdr_round_trip():
    msg = roundtrip(joint_state(['wheel', 'pump_shaft'], [1.0, 523.5], [0.2, 12.25]),
                    'sensor_msgs/msg/JointState')
    assert joint_sample(msg, 'pump_shaft') == (523.5, 12.25, Defect.NONE)
    assert joint_sample(msg, 'wheel') == (1.0, 0.2, Defect.NONE)
    assert stamp_to_ns(msg.header.stamp) == 5_000_000_250


def test_unfilled_arrays_and_missing_joint():
    msg = joint_state(['pump_shaft'], [300.0], [])
    assert joint_sample(msg, 'pump_shaft') == (300.0, None, Defect.NONE)
    msg = joint_state(['pump_shaft'], [], [4.0])
    assert joint_sample(msg, 'pump_shaft') == (None, 4.0, Defect.NONE)
    assert joint_sample(msg, 'other') == (None, None, Defect.MISSING_JOINT)


def test_a_joint_named_twice_is_malformed_not_one_of_the_two_taken():
    msg = joint_state(['pump_shaft', 'wheel', 'pump_shaft'], [300.0, 1.0, 310.0],
                      [4.0, 0.2, 4.5])
    assert joint_sample(msg, 'pump_shaft') == (None, None, Defect.MALFORMED)
    assert joint_sample(msg, 'wheel') == (1.0, 0.2, Defect.NONE)  # named once: still read


def test_rclpy_style_array_fields_work_too():
    import array
    msg = SimpleNamespace(name=['pump_shaft'], position=array.array('d'),
                          velocity=array.array('d', [7.5]), effort=array.array('d'))
    assert joint_sample(msg, 'pump_shaft') == (7.5, None, Defect.NONE)


def test_zero_stamp_means_unset():
    assert stamp_to_ns(T['builtin_interfaces/msg/Time'](sec=0, nanosec=0)) is None


def test_fluid_pressure_and_temperature_fields_round_trip():
    header = T['std_msgs/msg/Header'](stamp=T['builtin_interfaces/msg/Time'](sec=1, nanosec=2),
                                      frame_id='')
    p = roundtrip(T['sensor_msgs/msg/FluidPressure'](header=header, fluid_pressure=1.36e7,
                                                     variance=0.0),
                  'sensor_msgs/msg/FluidPressure')
    assert p.fluid_pressure == 1.36e7
    t = roundtrip(T['sensor_msgs/msg/Temperature'](header=header, temperature=48.5,
                                                   variance=0.0), 'sensor_msgs/msg/Temperature')
    assert t.temperature == 48.5


def test_levels_convert_for_rosbags_ints_and_rclpy_bytes():
    rosbags_status = T['diagnostic_msgs/msg/DiagnosticStatus']
    rclpy_like = SimpleNamespace(OK=b'\x00', WARN=b'\x01', ERROR=b'\x02', STALE=b'\x03')
    for level in range(4):
        assert level_to_msg(level, rosbags_status) == level
        assert level_to_msg(level, rclpy_like) == bytes([level])
        assert level_from_msg(level_to_msg(level, rclpy_like)) == level
        assert level_from_msg(level_to_msg(level, rosbags_status)) == level
    assert level_to_msg(1, rclpy_like) == rclpy_like.WARN
    assert level_to_msg(2, rosbags_status) == rosbags_status.ERROR
    with pytest.raises(ValueError, match=r'0\.\.3'):
        level_to_msg(4, rosbags_status)


@pytest.fixture(scope='module')
def estimator(paper_params):
    est = TorqueEstimator(EstimatorConfig(oil_viscosity_m2_s=46e-6), build_table(paper_params),
                          46e-6, 'hong_doh_2004')
    est.on_input(InputKind.LOAD_PRESSURE, 0, 120e5)
    est.on_input(InputKind.MOTOR_TORQUE, 0, 11.0)
    est.on_input(InputKind.SHAFT_SPEED, 1_000, 500.0)
    return est


def test_diagnostic_array_serialises_with_units_in_keys(estimator):
    types = rosbags_types(STORE)
    msg = diagnostic_array(types, estimator.diagnostics(2_000_000), 2_000_000_123,
                           'torque_estimator: hong_doh_2004', 'eha_pump')
    back = roundtrip(msg, 'diagnostic_msgs/msg/DiagnosticArray')
    status = back.status[0]
    assert status.level == 0 and status.hardware_id == 'eha_pump'
    assert status.name == 'torque_estimator: hong_doh_2004'
    values = {kv.key: kv.value for kv in status.values}
    assert float(values['level']) == 0
    assert float(values['residual_nm']) == pytest.approx(estimator.last.residual_nm)
    assert back.header.stamp.sec == 2 and back.header.stamp.nanosec == 123


def test_outputs_skip_undefined_values(estimator):
    est = estimator.last
    topics = dict(outputs_of(est))
    assert topics['expected_torque'] == est.expected_nm
    assert topics['residual'] == est.residual_nm
    assert 'efficiency' in topics
    stale_torque = est._replace(residual_nm=math.nan, efficiency=math.nan)
    assert set(dict(outputs_of(stale_torque))) == {'expected_torque', 'friction_torque',
                                                   'valve_plate_friction_scale'}


def test_float64_and_stamp_builders_round_trip():
    types = rosbags_types(STORE)
    msg = STORE.deserialize_cdr(float64_cdr(2.5), 'std_msgs/msg/Float64')  # what the node sends
    assert msg.data == 2.5
    stamp = stamp_msg(types, 3_000_000_007)
    assert (stamp.sec, stamp.nanosec) == (3, 7)
