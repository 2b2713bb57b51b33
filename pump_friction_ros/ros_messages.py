"""Messages <-> SI floats, for rclpy and rosbags message classes alike (no ROS import here).

rclpy messages and rosbags' message dataclasses have the same field names, so every
function here takes either. Message classes are passed in through `MessageTypes`, built
from rclpy's classes in the node or by `rosbags_types()` in the replay and the tests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .estimator import DiagnosticSnapshot, Estimate

__all__ = [
    'OUTPUT_TOPICS',
    'MessageTypes',
    'diagnostic_array',
    'float64_message',
    'joint_sample',
    'level_from_msg',
    'level_to_msg',
    'outputs_of',
    'rosbags_types',
    'stamp_msg',
    'stamp_to_ns',
]

OUTPUT_TOPICS = ('expected_torque', 'friction_torque', 'efficiency', 'residual',
                 'valve_plate_friction_scale')
"""Private topics of the node (``~/<name>``), std_msgs/Float64 each."""


def outputs_of(estimate: Estimate) -> list[tuple[str, float]]:
    """Topic and value of each output an estimate publishes.

    Efficiency is published only where defined and the residual only with a fresh measured
    torque: a NaN is never published as if it were a value.

    Parameters
    ----------
    estimate : Estimate
        An estimate with ``publish`` set.

    Returns
    -------
    list of (str, float)
        (topic name from `OUTPUT_TOPICS`, value in SI).
    """
    out = [('expected_torque', estimate.expected_nm), ('friction_torque', estimate.friction_nm)]
    if math.isfinite(estimate.efficiency):
        out.append(('efficiency', estimate.efficiency))
    if math.isfinite(estimate.residual_nm):
        out.append(('residual', estimate.residual_nm))
    out.append(('valve_plate_friction_scale', estimate.valve_plate_scale))
    return out


def stamp_to_ns(stamp: Any) -> int | None:
    """Nanoseconds of a ``builtin_interfaces/Time``; None for an unset (zero) stamp.

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


def joint_sample(msg: Any, joint_name: str) -> tuple[float | None, float | None] | None:
    """Speed (velocity) and torque (effort) of one joint of a ``sensor_msgs/JointState``.

    The joint is found by name in every message (drivers may reorder joints or publish
    several). An empty or too short ``velocity`` / ``effort`` array means "not filled".

    Parameters
    ----------
    msg : sensor_msgs/msg/JointState
        The message.
    joint_name : str
        Name of the pump shaft's joint.

    Returns
    -------
    tuple or None
        (speed [rad/s] or None, torque [N m] or None); None when the joint is absent.
    """
    names = list(msg.name)
    if joint_name not in names:
        return None
    i = names.index(joint_name)
    velocity, effort = msg.velocity, msg.effort
    speed = float(velocity[i]) if len(velocity) > i else None
    torque = float(effort[i]) if len(effort) > i else None
    return speed, torque


def level_from_msg(level: Any) -> int:
    """DiagnosticStatus level as an int, from rclpy (bytes) or rosbags (int).

    Parameters
    ----------
    level : bytes or int
        ``DiagnosticStatus.level``.

    Returns
    -------
    int
        0 OK, 1 WARN, 2 ERROR, 3 STALE.
    """
    if isinstance(level, (bytes, bytearray)):
        return level[0]
    return int(level)


def level_to_msg(level: int, status_cls: Any) -> Any:
    """DiagnosticStatus level in the representation of ``status_cls``.

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


def float64_message(types: MessageTypes, value: float) -> Any:
    """``std_msgs/Float64`` holding ``value``."""
    return types.float64(data=float(value))


def diagnostic_array(types: MessageTypes, snapshot: DiagnosticSnapshot, stamp_ns: int,
                     name: str, hardware_id: str) -> Any:
    """``diagnostic_msgs/DiagnosticArray`` with one status for the pump.

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

