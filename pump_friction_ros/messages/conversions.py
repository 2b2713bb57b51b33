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
Messages <-> SI floats, for rclpy and rosbags message classes alike (no ROS import here).

rclpy messages and rosbags' message dataclasses have the same field names, so every
function here takes either. Message classes are passed in through `MessageTypes`, built
from rclpy's classes in the node or by `rosbags_types()` in the replay and the tests.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
import struct
from typing import Any

from ..core.diagnostics import DiagnosticSnapshot
from ..core.estimate_record import Estimate
from ..core.inputs import Defect, InputSpec

__all__ = [
    'DIAGNOSTICS_QOS_DEPTH',
    'OUTPUTS',
    'OUTPUT_QOS_DEPTH',
    'OUTPUT_TOPICS',
    'RELIABLE_INPUT_QOS_DEPTH',
    'MessageTypes',
    'diagnostic_array',
    'float64_cdr',
    'input_sample',
    'joint_sample',
    'level_to_msg',
    'outputs_of',
    'rosbags_types',
    'stamp_msg',
    'stamp_to_ns',
]

OUTPUTS = (
    ('expected_torque', 'expected_nm', False),
    ('friction_torque', 'friction_nm', False),
    ('efficiency', 'efficiency', True),
    ('residual', 'residual_nm', True),
    ('valve_plate_friction_scale', 'valve_plate_scale', False),
)
"""
The node's Float64 outputs: (topic, `Estimate` field, published only where finite).

Efficiency is undefined near zero speed or pressure and the residual needs a fresh measured
torque: a NaN is never published as if it were a value.
"""
OUTPUT_TOPICS = tuple(topic for topic, _, _ in OUTPUTS)
"""Private topics of the node (``~/<name>``), std_msgs/Float64 each."""

OUTPUT_QOS_DEPTH = 10
"""
History depth of the node's Float64 outputs [messages].

Every output of the node (these and /diagnostics) is published reliable, keep last,
volatile; the node's publishers and the replay's output bag (its ``offered_qos_profiles``)
are both made from these constants.
"""
DIAGNOSTICS_QOS_DEPTH = 10
"""History depth of /diagnostics [messages] (reliable, keep last, volatile)."""
RELIABLE_INPUT_QOS_DEPTH = 100
"""
History depth of the inputs with ``reliable_inputs: true`` [messages].

100 ms of a 1 kHz input: the node loses nothing while its executor is held up for less
than that (a reliable reader keeping only the last 10 would drop samples after 10 ms).
"""

_CDR_LE = b'\x00\x01\x00\x00'
_DOUBLE = struct.Struct('<d')


def outputs_of(estimate: Estimate) -> list[tuple[str, float]]:
    """
    Topic and value of each output an estimate publishes (`OUTPUTS`).

    Parameters
    ----------
    estimate : Estimate
        An estimate with ``publish`` set.

    Returns
    -------
    list of (str, float)
        (topic name from `OUTPUT_TOPICS`, value in SI), in `OUTPUTS` order; a value that
        may be undefined is left out where it is not finite.

    """
    out = []
    for topic, field_name, finite_only in OUTPUTS:
        value = getattr(estimate, field_name)
        if not finite_only or math.isfinite(value):
            out.append((topic, value))
    return out


def stamp_to_ns(stamp: Any) -> int | None:
    """
    Nanoseconds of a ``builtin_interfaces/Time``; None for an unset (zero) stamp.

    Parameters
    ----------
    stamp : builtin_interfaces/msg/Time
        ``sec`` and ``nanosec`` fields.

    Returns
    -------
    int or None
        Time [ns], or None when the stamp is zero (the caller uses its clock instead).

    """
    ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
    return ns if ns != 0 else None


def joint_sample(msg: Any, joint_name: str) -> tuple[float | None, float | None, Defect]:
    """
    Speed (velocity) and torque (effort) of one joint of a ``sensor_msgs/JointState``.

    The joint is found by name in every message (drivers may reorder joints or publish
    several). An empty ``velocity`` / ``effort`` array means "not filled"; an array that is
    neither empty nor as long as ``name`` makes the message malformed (sensor_msgs says
    all arrays have the size of ``name`` or are empty), and so does a message carrying
    neither speed nor torque, or naming the joint twice (neither can be taken for the shaft).

    Parameters
    ----------
    msg : sensor_msgs/msg/JointState
        The message.
    joint_name : str
        Name of the pump shaft's joint.

    Returns
    -------
    tuple
        (speed [rad/s] or None, torque [N m] or None, `Defect`); the values are None
        whenever the defect is not ``Defect.NONE``.

    """
    names = list(msg.name)
    if joint_name not in names:
        return None, None, Defect.MISSING_JOINT
    i, n = names.index(joint_name), len(names)
    velocity, effort = msg.velocity, msg.effort
    if any(len(a) not in (0, n) for a in (msg.position, velocity, effort)) \
            or names.count(joint_name) > 1:  # which of the two is the shaft: nobody can say
        return None, None, Defect.MALFORMED
    speed = float(velocity[i]) if len(velocity) else None
    torque = float(effort[i]) if len(effort) else None
    if speed is None and torque is None:
        return None, None, Defect.MALFORMED
    return speed, torque, Defect.NONE


def input_sample(spec: InputSpec, msg: Any, joint_name: str
                 ) -> tuple[float | None, float | None, Defect]:
    """
    Return the sample one input message carries, in SI (what `TorqueEstimator.on_input` takes).

    Parameters
    ----------
    spec : InputSpec
        The input (``inputs.INPUTS``) the message arrived on.
    msg : message
        The message (rclpy's or rosbags').
    joint_name : str
        JointState: the pump shaft's joint.

    Returns
    -------
    tuple
        (value or None, torque [N m] or None, `Defect`).

    """
    if spec.value_field is None:
        return joint_sample(msg, joint_name)
    return float(getattr(msg, spec.value_field)), None, Defect.NONE


def level_to_msg(level: int, status_cls: Any) -> Any:
    """
    Return the DiagnosticStatus level in the representation of ``status_cls``.

    rclpy's ``DiagnosticStatus`` holds its level constants as bytes (``bytes([1])``),
    rosbags' as ints; the class's own ``OK`` constant tells which.

    Parameters
    ----------
    level : int
        0 OK, 1 WARN, 2 ERROR, 3 STALE.
    status_cls : type
        ``diagnostic_msgs/msg/DiagnosticStatus`` of rclpy or of rosbags.

    Returns
    -------
    bytes or int
        The level for that class.

    """
    if not 0 <= level <= 3:
        raise ValueError(f'diagnostic level must be 0..3, got {level}')
    return bytes([level]) if isinstance(status_cls.OK, (bytes, bytearray)) else level


@dataclass(frozen=True)
class MessageTypes:
    """The message classes the conversions build (rclpy's or rosbags')."""

    float64: type
    time: type
    header: type
    key_value: type
    diagnostic_status: type
    diagnostic_array: type


def rosbags_types(typestore: Any) -> MessageTypes:
    """Message classes of a rosbags typestore (``get_typestore(Stores.ROS2_JAZZY)``)."""
    t = typestore.types
    return MessageTypes(t['std_msgs/msg/Float64'], t['builtin_interfaces/msg/Time'],
                        t['std_msgs/msg/Header'], t['diagnostic_msgs/msg/KeyValue'],
                        t['diagnostic_msgs/msg/DiagnosticStatus'],
                        t['diagnostic_msgs/msg/DiagnosticArray'])


def stamp_msg(types: MessageTypes, ns: int) -> Any:
    """``builtin_interfaces/Time`` for a time in nanoseconds (>= 0)."""
    sec, nanosec = divmod(int(ns), 1_000_000_000)
    return types.time(sec=sec, nanosec=nanosec)


def float64_cdr(value: float) -> bytes:
    """
    Return the CDR (little-endian) bytes of a ``std_msgs/Float64``.

    What rosbags and the middleware serialise: the node publishes these bytes (rclpy's
    ``Publisher.publish`` takes serialised bytes) and the replay writes them to its bag.

    Parameters
    ----------
    value : float
        The data field.

    Returns
    -------
    bytes
        Encapsulation header and the double.

    """
    return _CDR_LE + _DOUBLE.pack(value)


def diagnostic_array(types: MessageTypes, snapshot: DiagnosticSnapshot, stamp_ns: int,
                     name: str, hardware_id: str) -> Any:
    """
    ``diagnostic_msgs/DiagnosticArray`` with one status for the pump.

    Parameters
    ----------
    types : MessageTypes
        Message classes.
    snapshot : DiagnosticSnapshot
        Level, message and key-values from `TorqueEstimator.diagnostics`.
    stamp_ns : int
        Header stamp [ns].
    name : str
        Status name (``torque_estimator: <pump name>``).
    hardware_id : str
        ``hardware_id`` of the status.

    Returns
    -------
    DiagnosticArray
        The message.

    """
    status = types.diagnostic_status(
        level=level_to_msg(snapshot.level, types.diagnostic_status), name=name,
        message=snapshot.message, hardware_id=hardware_id,
        values=[types.key_value(key=k, value=v) for k, v in snapshot.values])
    header = types.header(stamp=stamp_msg(types, stamp_ns), frame_id='')
    return types.diagnostic_array(header=header, status=[status])
