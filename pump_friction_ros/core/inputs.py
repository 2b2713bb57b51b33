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
The node's inputs in one table: topic, message type, value field, stamp rule, when used.

The node builds its subscriptions from `inputs_for`, the bag reader its topic list and the
replay its dispatch, so the three cannot drift apart. Every input reaches the ROS-free core
through one entry point, `TorqueEstimator.on_input(kind, stamp_ns, value, torque)`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum

from .node_parameters import (
    EstimatorConfig,
    PressureSource,
    SpeedSource,
    TorqueSource,
    ViscositySource,
)

__all__ = ['DEFECT_COUNTER', 'INPUTS', 'MAX_PRESSURE_PA', 'MAX_SPEED_RAD_S', 'MAX_TORQUE_NM',
           'TEMPERATURE_RANGE_C', 'Defect', 'InputKind', 'InputSpec', 'inputs_for']

JOINT_STATE = 'sensor_msgs/msg/JointState'
FLUID_PRESSURE = 'sensor_msgs/msg/FluidPressure'
FLOAT64 = 'std_msgs/msg/Float64'
TEMPERATURE = 'sensor_msgs/msg/Temperature'


class InputKind(IntEnum):
    """What a message carries into the core."""

    JOINT_STATE = 0  # shaft speed (velocity) and / or measured torque (effort) [rad/s, N m]
    SHAFT_SPEED = 1  # [rad/s]
    MOTOR_TORQUE = 2  # [N m]
    LOAD_PRESSURE = 3  # p_A - p_B [Pa]
    PRESSURE_A = 4  # [Pa]
    PRESSURE_B = 5  # [Pa]
    OIL_TEMPERATURE = 6  # [degC]


class Defect(IntEnum):
    """Why a message gave no sample; each is counted by the core as ``rejected_<name>``."""

    NONE = 0
    MISSING_JOINT = 1  # a JointState without the configured joint
    MALFORMED = 2  # a JointState whose arrays do not match its names, carry nothing, or
    #                name the joint twice (which one is the shaft?)
    UNDECODABLE = 3  # a bag message that does not deserialise


@dataclass(frozen=True)
class InputSpec:
    """
    One input topic of the node.

    ``topic`` is relative (the node subscribes it in its namespace; a bag holds it as
    ``/<topic>`` unless remapped). ``value_field`` names the message field holding the value
    (None: a JointState, read by joint name). With ``has_header`` the sample time is the
    header stamp (the receive time when the stamp is zero), else the receive time.
    """

    kind: InputKind
    topic: str
    msgtype: str
    value_field: str | None
    has_header: bool
    used: Callable[[EstimatorConfig], bool]


def _joint_used(c: EstimatorConfig) -> bool:
    return SpeedSource.JOINT_STATE in (c.speed_source, c.torque_source)


INPUTS: tuple[InputSpec, ...] = (
    InputSpec(InputKind.JOINT_STATE, 'joint_states', JOINT_STATE, None, True, _joint_used),
    InputSpec(InputKind.SHAFT_SPEED, 'shaft_speed', FLOAT64, 'data', False,
              lambda c: c.speed_source == SpeedSource.FLOAT64),
    InputSpec(InputKind.MOTOR_TORQUE, 'motor_torque', FLOAT64, 'data', False,
              lambda c: c.torque_source == TorqueSource.FLOAT64),
    InputSpec(InputKind.LOAD_PRESSURE, 'load_pressure', FLUID_PRESSURE, 'fluid_pressure', True,
              lambda c: c.pressure_source == PressureSource.DIFFERENCE),
    InputSpec(InputKind.PRESSURE_A, 'pressure_a', FLUID_PRESSURE, 'fluid_pressure', True,
              lambda c: c.pressure_source == PressureSource.PORTS),
    InputSpec(InputKind.PRESSURE_B, 'pressure_b', FLUID_PRESSURE, 'fluid_pressure', True,
              lambda c: c.pressure_source == PressureSource.PORTS),
    InputSpec(InputKind.OIL_TEMPERATURE, 'oil_temperature', TEMPERATURE, 'temperature', True,
              lambda c: c.viscosity_source == ViscositySource.TEMPERATURE),
)
"""Every input the node can take, in `InputKind` order."""

# Physical plausibility of the samples: beyond these a value is rejected and counted.
MAX_SPEED_RAD_S = 1.0e4
"""|speed| above this (95,000 rpm) is not a plausible measurement: rejected."""
MAX_PRESSURE_PA = 2.0e8
"""|pressure| above this (2,000 bar) is rejected."""
MAX_TORQUE_NM = 1.0e4
"""|torque| above this is rejected."""
TEMPERATURE_RANGE_C = (-60.0, 250.0)
"""Oil temperatures outside this range are rejected."""
DEFECT_COUNTER = {Defect.MISSING_JOINT: 'rejected_missing_joint',
                  Defect.MALFORMED: 'rejected_malformed',
                  Defect.UNDECODABLE: 'rejected_undecodable'}
"""The estimator's counter of each message defect."""


def inputs_for(config: EstimatorConfig) -> tuple[InputSpec, ...]:
    """
    Return the inputs the node subscribes with this configuration.

    Parameters
    ----------
    config : EstimatorConfig
        Node parameters (the ``*_source`` choices).

    Returns
    -------
    tuple of InputSpec
        In `InputKind` order.

    """
    return tuple(spec for spec in INPUTS if spec.used(config))
