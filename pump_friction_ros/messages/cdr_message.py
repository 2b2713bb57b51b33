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
Decoding of one input message at a time from raw CDR: the live node's raw subscriptions.

The node subscribes raw (serialised) messages and decodes them here, which costs less than
rclpy building a Python message object per message; the layout parser is the batch decoder's
(``cdr``), so the node and the replay read the same bytes the same way.
"""

from __future__ import annotations

from collections.abc import Callable
import struct
from typing import Any

from .cdr import (
    align,
    CDR_LE,
    check_end,
    header_end,
    joint_layout,
    JointLayout,
    LayoutError,
)
from .conversions import input_sample, stamp_to_ns
from ..core.inputs import Defect, FLOAT64, InputSpec, JOINT_STATE

__all__ = ['MessageDecoder']

_STAMP = struct.Struct('<iI')
_DOUBLE = struct.Struct('<d')


class MessageDecoder:
    """
    Decodes one input topic's raw CDR messages one at a time (the node's raw subscriptions).

    The layout of the last JointState parsed is kept: a message of the same length whose
    layout-defining bytes (frame_id, joint names, array lengths) equal that one's is read
    with two unpacks; any other is parsed again (`joint_layout`). A payload the parser does
    not take (big-endian CDR, a layout it does not know) is deserialised by ``deserialize``
    and converted by `ros_messages.input_sample`, so both paths give the same sample.

    Parameters
    ----------
    spec : InputSpec
        The input (message type, value field, stamp rule).
    joint_name : str
        JointState: the pump shaft's joint.
    deserialize : callable
        ``deserialize(raw)`` returns the message object (rclpy's ``deserialize_message``
        in the node, rosbags' ``deserialize_cdr`` in the tests).

    """

    def __init__(self, spec: InputSpec, joint_name: str,
                 deserialize: Callable[[bytes], Any]) -> None:
        self.spec = spec
        self.joint = joint_name
        self.deserialize = deserialize
        self.fallbacks = 0
        self._length = -1
        self._checks: tuple[tuple[int, int, bytes], ...] = ()
        self._layout: JointLayout | None = None
        self._decode = {JOINT_STATE: self._joint_state, FLOAT64: self._float64}.get(
            spec.msgtype, self._header_and_double)

    def __call__(self, raw: bytes) -> tuple[int | None, float | None, float | None, Defect]:
        """
        Decode one message.

        Parameters
        ----------
        raw : bytes
            The serialised message, with its encapsulation header.

        Returns
        -------
        tuple
            (header stamp [ns] or None when zero or absent, value or None, torque [N m] or
            None, `Defect`), the values in SI as `ros_messages.input_sample` gives them.

        """
        try:
            if raw[:2] != CDR_LE:
                raise LayoutError('not little-endian CDR')
            return self._decode(raw)
        except (LayoutError, UnicodeDecodeError, struct.error):
            return self._slow(raw)

    def _stamp(self, raw: bytes) -> int | None:
        sec, nanosec = _STAMP.unpack_from(raw, 4)
        return (sec * 1_000_000_000 + nanosec) or None

    def _float64(self, raw: bytes) -> tuple[None, float, None, Defect]:
        if len(raw) != 12:
            check_end(raw, 8, FLOAT64)
        return None, _DOUBLE.unpack_from(raw, 4)[0], None, Defect.NONE

    def _header_and_double(self, raw: bytes) -> tuple[int | None, float, None, Defect]:
        first_double = align(header_end(raw), 8)
        if 4 + first_double + 16 != len(raw):
            check_end(raw, first_double + 16, self.spec.msgtype)
        return self._stamp(raw), _DOUBLE.unpack_from(raw, 4 + first_double)[0], None, \
            Defect.NONE

    def _joint_state(self, raw: bytes
                     ) -> tuple[int | None, float | None, float | None, Defect]:
        layout = self._layout
        if layout is None or len(raw) != self._length:
            layout = self._learn(raw)
        else:
            for a, b, ref in self._checks:
                if raw[a:b] != ref:
                    layout = self._learn(raw)
                    break
        if layout.defect:
            return None, None, None, layout.defect
        velocity = None if layout.velocity is None \
            else _DOUBLE.unpack_from(raw, 4 + layout.velocity)[0]
        effort = None if layout.effort is None \
            else _DOUBLE.unpack_from(raw, 4 + layout.effort)[0]
        sec, nanosec = _STAMP.unpack_from(raw, 4)
        return (sec * 1_000_000_000 + nanosec) or None, velocity, effort, Defect.NONE

    def _learn(self, raw: bytes) -> JointLayout:
        """Parse a JointState layout and keep it, with the bytes that must match it."""
        layout = joint_layout(raw, self.joint)
        spans = [(12, 4 + layout.names_end)] + [(4 + at, 8 + at)
                                                for at in layout.array_count_offsets]
        self._checks = tuple((a, b, raw[a:b]) for a, b in spans)
        self._length = len(raw)
        self._layout = layout
        return layout

    def _slow(self, raw: bytes) -> tuple[int | None, float | None, float | None, Defect]:
        """Deserialise with ``deserialize`` and convert with the node's message function."""
        self.fallbacks += 1
        try:
            msg = self.deserialize(raw)
        except Exception:
            return None, None, None, Defect.UNDECODABLE
        value, torque, defect = input_sample(self.spec, msg, self.joint)
        if defect:
            return None, None, None, defect  # as the parser returns a defect
        stamp = stamp_to_ns(msg.header.stamp) if self.spec.has_header else None
        return stamp, value, torque, defect
