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
Decoding of the node's input messages from raw CDR: in batches (the replay), one by one (the node).

The input messages have a fixed layout in practice (same frame_id, same joint names, same
array lengths), so the raw payloads of a topic are grouped by length, the field offsets
are derived once per group from its first message by a small CDR layout parser, the
layout-defining bytes (frame_id, names, array lengths) are checked to be identical across
the group, and the numbers are read with numpy. A message that does not fit (another
layout, big-endian CDR) is decoded by rosbags' own deserialiser and the node's conversion
(`ros_messages.input_sample`) instead; both paths give the same samples (tested). Every
length read from a payload is checked against the bytes left, so a corrupted count cannot
make the parser loop or read past the end: such a message is undecodable, and counted.
Strings are checked as rosbags checks them (NUL terminator, UTF-8). After the last field a
payload may carry up to `MAX_TRAILING_PADDING` bytes of padding, whose values CDR leaves
unspecified: Fast DDS's ``rmw_serialize`` (rclpy's ``serialize_message``) sizes its buffer by
an estimate that counts 8-byte alignment for every empty ``double[]``, so a JointState with
empty position and effort comes back 12 bytes longer than the wire message (92 B for 80 B),
and those bytes are not always zero (measured: one was 0x53). rclpy's deserialiser reads
such a message; rosbags' refuses more than 3 trailing bytes, so it is read by this parser
alone. A longer tail makes the payload one the parser does not take.

``cdr_message.MessageDecoder`` does the same for one message at a time (the live node), with
the layout parser here: the node and the replay read the same bytes the same way.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any

import numpy as np

from .conversions import input_sample, stamp_to_ns
from ..core.inputs import Defect, FLOAT64, InputSpec, JOINT_STATE

__all__ = ['CDR_LE', 'MAX_TRAILING_PADDING', 'Decoded', 'JointLayout', 'LayoutError',
           'TopicDecoder', 'align', 'check_end', 'header_end', 'joint_layout']


MAX_TRAILING_PADDING = 32
"""
Bytes of any value accepted after a payload's last field [bytes].

Fast DDS's size estimate adds at most 7 bytes of 8-byte alignment for each of JointState's
three ``double[]`` and at most 7 at the end: 28 < 32 (measured: 12 with two empty arrays).
"""


CDR_LE = b'\x00\x01'  # encapsulation of little-endian plain CDR


class LayoutError(ValueError):
    """A payload that does not parse as the expected message."""


def align(pos: int, size: int) -> int:
    """Return ``pos`` rounded up to a multiple of ``size`` (CDR alignment) [bytes]."""
    return pos + (-pos % size)


def check_end(raw: bytes, payload_end: int, what: str) -> None:
    """
    Check that nothing but padding follows the last field (payload offset ``payload_end``).

    Parameters
    ----------
    raw : bytes
        The serialised message, with its 4-byte encapsulation header.
    payload_end : int
        Payload offset just after the last field.
    what : str
        The message type, for the error.

    Raises
    ------
    LayoutError
        The payload is shorter, or followed by more than `MAX_TRAILING_PADDING` bytes.

    """
    extra = len(raw) - 4 - payload_end
    if extra < 0 or extra > MAX_TRAILING_PADDING:
        raise LayoutError(f'{what} length mismatch')


def _u32(raw: bytes, pos: int) -> int:
    """Little-endian uint32 at payload offset ``pos`` (raw offset pos + 4), bounds-checked."""
    if 8 + pos > len(raw):
        raise LayoutError('truncated')
    return int.from_bytes(raw[4 + pos:8 + pos], 'little')


def _string(raw: bytes, pos: int, what: str) -> tuple[str, int]:
    """
    Read the CDR string whose length field is at payload offset ``pos``.

    Refused as rosbags refuses it: a length of zero or beyond the payload, no NUL
    terminator, or not UTF-8 (a message rosbags cannot deserialise must not be read here).

    Parameters
    ----------
    raw : bytes
        The serialised message, with its 4-byte encapsulation header.
    pos : int
        Payload offset of the string's length field.
    what : str
        Name of the field, for the error.

    Returns
    -------
    tuple
        (the string, payload offset just after its terminator).

    Raises
    ------
    LayoutError
        The string is not one rosbags would read.

    """
    length = _u32(raw, pos)
    end = pos + 4 + length
    if length == 0 or 4 + end > len(raw):
        raise LayoutError(f'{what} length beyond the payload')
    if raw[3 + end] != 0:
        raise LayoutError(f'{what} without its NUL terminator')
    try:
        return raw[8 + pos:3 + end].decode(), end
    except UnicodeDecodeError as exc:
        raise LayoutError(f'{what} is not UTF-8') from exc


def header_end(raw: bytes) -> int:
    """Return the payload offset after std_msgs/Header (stamp, frame_id); LayoutError if bad."""
    return _string(raw, 8, 'frame_id')[1]  # payload offsets: 0 sec, 4 nanosec, 8 frame_id


@dataclass(frozen=True)
class JointLayout:
    """Where the numbers of one JointState layout are (payload offsets)."""

    header_end: int
    names_end: int
    payload_end: int  # just after the effort array; padding may follow
    array_count_offsets: tuple[int, int, int]  # position, velocity, effort length fields
    index: int  # of the joint, -1 when absent
    velocity: int | None  # offset of the joint's velocity, None when the array is empty
    effort: int | None
    defect: Defect


def joint_layout(raw: bytes, joint: str) -> JointLayout:
    """
    Parse the layout of a little-endian CDR ``sensor_msgs/JointState`` payload.

    Parameters
    ----------
    raw : bytes
        The serialised message, with its 4-byte encapsulation header.
    joint : str
        Name of the pump shaft's joint.

    Returns
    -------
    JointLayout
        Offsets, and the defect (`ros_messages.joint_sample`'s rules) of this layout.

    Raises
    ------
    LayoutError
        A count or length beyond the payload, a string rosbags would refuse, or bytes left
        over beyond `MAX_TRAILING_PADDING`.

    """
    end = header_end(raw)
    pos = align(end, 4)
    count = _u32(raw, pos)
    pos += 4
    if count > (len(raw) - 4 - pos) // 5:  # each name takes at least 5 bytes
        raise LayoutError('name count beyond the payload')
    names = []
    for _ in range(count):
        name, end = _string(raw, pos, 'name')
        names.append(name)
        pos = align(end, 4)
    names_end = pos
    index = names.index(joint) if joint in names else -1
    counts, firsts, length_at = [], [], []
    for _ in range(3):  # position, velocity, effort
        pos = align(pos, 4)
        length_at.append(pos)
        n = _u32(raw, pos)
        pos += 4
        if n:
            pos = align(pos, 8)
        if 4 + pos + 8 * n > len(raw):
            raise LayoutError('array length beyond the payload')
        counts.append(n)
        firsts.append(pos)
        pos += 8 * n
    check_end(raw, pos, 'JointState')
    velocity = effort = None
    if index < 0:
        defect = Defect.MISSING_JOINT
    elif any(n not in (0, count) for n in counts) or not (counts[1] or counts[2]) \
            or names.count(joint) > 1:
        defect = Defect.MALFORMED
    else:
        defect = Defect.NONE
        velocity = firsts[1] + 8 * index if counts[1] else None
        effort = firsts[2] + 8 * index if counts[2] else None
    return JointLayout(end, names_end, pos, (length_at[0], length_at[1], length_at[2]), index,
                       velocity, effort, defect)


def _column(rows: np.ndarray, offset: int, dtype: str) -> np.ndarray:
    size = np.dtype(dtype).itemsize
    return np.ascontiguousarray(rows[:, offset:offset + size]).view(dtype).ravel()


@dataclass
class Decoded:
    """Samples of a batch of messages of one topic (parallel arrays)."""

    stamps: np.ndarray  # int64 [ns]: header stamp, else the log time
    values: np.ndarray  # float64; meaningful where has_value
    torques: np.ndarray  # float64; JointState effort where has_torque
    has_value: np.ndarray  # bool
    has_torque: np.ndarray  # bool
    defects: np.ndarray  # int8, `Defect`


class TopicDecoder:
    """
    Decodes one input topic's raw messages in batches; rosbags for irregular ones.

    Parameters
    ----------
    spec : InputSpec
        The input (message type, value field, stamp rule).
    joint_name : str
        JointState: the pump shaft's joint.
    typestore : rosbags Typestore
        The ROS 2 Jazzy typestore (for the fallback).

    """

    def __init__(self, spec: InputSpec, joint_name: str, typestore: Any) -> None:
        self.spec = spec
        self.msgtype = spec.msgtype
        self.joint = joint_name
        self.typestore = typestore
        self.fallbacks = 0

    def decode(self, raws: list[bytes], log_times: list[int]) -> Decoded:
        """
        Decode messages given with their log times [ns].

        Parameters
        ----------
        raws : list of bytes
            Serialised messages.
        log_times : list of int
            Their log (receive) times [ns].

        Returns
        -------
        Decoded
            One sample or defect per message.

        """
        n = len(raws)
        out = Decoded(np.array(log_times, dtype=np.int64), np.full(n, math.nan),
                      np.full(n, math.nan), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool),
                      np.full(n, int(Defect.UNDECODABLE), dtype=np.int8))
        by_length: dict[int, list[int]] = {}
        for i, raw in enumerate(raws):
            by_length.setdefault(len(raw), []).append(i)
        for length, idx in by_length.items():
            self._decode_group(raws, idx, length, out)
        return out

    def _decode_group(self, raws: list[bytes], idx: list[int], length: int,
                      out: Decoded) -> None:
        """Decode messages of one length: the first the parser takes sets the layout."""
        start = 0
        for i in idx:
            try:
                layout = self._little_endian_layout(raws[i])
                break
            except LayoutError:
                self._slow(i, raws[i], out)
                start += 1
        else:
            return
        idx, first = idx[start:], raws[idx[start]]
        rows = np.frombuffer(b''.join(raws[i] for i in idx), dtype=np.uint8).reshape(
            len(idx), length)
        same = self._same_structure(rows, first, layout)
        fast = np.asarray(idx)[same]
        if fast.size:
            self._fill(rows[same], fast, layout, out)
        for i in np.asarray(idx)[~same].tolist():
            self._alone(i, raws[i], out)

    def _alone(self, i: int, raw: bytes, out: Decoded) -> None:
        """Decode a message whose layout differs from its group's: parsed alone, else rosbags."""
        try:
            layout = self._little_endian_layout(raw)
        except LayoutError:
            self._slow(i, raw, out)
            return
        self._fill(np.frombuffer(raw, np.uint8).reshape(1, len(raw)), np.array([i]), layout,
                   out)

    def _little_endian_layout(self, raw: bytes) -> Any:
        if raw[:2] != CDR_LE:
            raise LayoutError('not little-endian CDR')
        return self._layout(raw)

    def _layout(self, raw: bytes) -> Any:
        if self.msgtype == FLOAT64:
            check_end(raw, 8, FLOAT64)
            return None
        if self.msgtype == JOINT_STATE:
            return joint_layout(raw, self.joint)
        end = header_end(raw)
        first_double = align(end, 8)
        check_end(raw, first_double + 16, self.msgtype)
        return end, first_double

    def _same_structure(self, rows: np.ndarray, first: bytes, layout: Any) -> np.ndarray:
        """Rows laid out like ``first``: same encapsulation, frame_id, names, array lengths."""
        ref = np.frombuffer(first, np.uint8)
        same: np.ndarray = np.all(rows[:, :4] == ref[:4], axis=1)
        if self.msgtype == FLOAT64:
            return same
        end = layout.names_end if self.msgtype == JOINT_STATE else layout[0]
        same &= np.all(rows[:, 12:4 + end] == ref[12:4 + end], axis=1)  # past the stamp
        if self.msgtype == JOINT_STATE:
            for at in layout.array_count_offsets:
                same &= np.all(rows[:, 4 + at:8 + at] == ref[4 + at:8 + at], axis=1)
        return same

    def _fill(self, rows: np.ndarray, fast: np.ndarray, layout: Any, out: Decoded) -> None:
        if self.msgtype == FLOAT64:
            out.values[fast] = _column(rows, 4, '<f8')
            out.has_value[fast] = True
            out.defects[fast] = Defect.NONE
            return
        sec = _column(rows, 4, '<i4').astype(np.int64)
        nanosec = _column(rows, 8, '<u4').astype(np.int64)
        header_ns = sec * 1_000_000_000 + nanosec
        out.stamps[fast] = np.where(header_ns != 0, header_ns, out.stamps[fast])
        if self.msgtype == JOINT_STATE:
            out.defects[fast] = layout.defect
            if layout.velocity is not None:
                out.values[fast] = _column(rows, 4 + layout.velocity, '<f8')
                out.has_value[fast] = True
            if layout.effort is not None:
                out.torques[fast] = _column(rows, 4 + layout.effort, '<f8')
                out.has_torque[fast] = True
            return
        out.values[fast] = _column(rows, 4 + layout[1], '<f8')
        out.has_value[fast] = True
        out.defects[fast] = Defect.NONE

    def _slow(self, i: int, raw: bytes, out: Decoded) -> None:
        """Decode one message with rosbags and the node's conversion function."""
        self.fallbacks += 1
        try:
            msg = self.typestore.deserialize_cdr(raw, self.msgtype)
        except Exception:
            return  # stays Defect.UNDECODABLE
        if self.spec.has_header:
            stamp = stamp_to_ns(msg.header.stamp)
            if stamp is not None:
                out.stamps[i] = stamp
        value, torque, defect = input_sample(self.spec, msg, self.joint)
        out.defects[i] = defect
        if value is not None:
            out.values[i] = value
            out.has_value[i] = True
        if torque is not None:
            out.torques[i] = torque
            out.has_torque[i] = True
