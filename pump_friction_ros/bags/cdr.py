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
Strings are checked as rosbags checks them (NUL terminator, UTF-8): a message rosbags
refuses is never read by the batch path.

`MessageDecoder` does the same for one message at a time: the live node subscribes raw
(serialised) messages and decodes them here, which costs less than rclpy building a Python
message object per message. The node and the replay thus read the same bytes the same way.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
import math
import struct
from typing import Any

import numpy as np

from ..inputs import Defect, FLOAT64, InputSpec, JOINT_STATE
from ..ros_messages import input_sample, stamp_to_ns

__all__ = ['Decoded', 'MessageDecoder', 'TopicDecoder', 'joint_layout']


class LayoutError(ValueError):
    """A payload that does not parse as the expected message."""


def _align(pos: int, size: int) -> int:
    return pos + (-pos % size)


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


def _header_end(raw: bytes) -> int:
    """Payload offset after std_msgs/Header (stamp + frame_id), raising on a bad frame_id."""
    return _string(raw, 8, 'frame_id')[1]  # payload offsets: 0 sec, 4 nanosec, 8 frame_id


@dataclass(frozen=True)
class JointLayout:
    """Where the numbers of one JointState layout are (payload offsets)."""

    header_end: int
    names_end: int
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
        over.

    """
    end = _header_end(raw)
    pos = _align(end, 4)
    count = _u32(raw, pos)
    pos += 4
    if count > (len(raw) - 4 - pos) // 5:  # each name takes at least 5 bytes
        raise LayoutError('name count beyond the payload')
    names = []
    for _ in range(count):
        name, end = _string(raw, pos, 'name')
        names.append(name)
        pos = _align(end, 4)
    names_end = pos
    index = names.index(joint) if joint in names else -1
    counts, firsts, length_at = [], [], []
    for _ in range(3):  # position, velocity, effort
        pos = _align(pos, 4)
        length_at.append(pos)
        n = _u32(raw, pos)
        pos += 4
        if n:
            pos = _align(pos, 8)
        if 4 + pos + 8 * n > len(raw):
            raise LayoutError('array length beyond the payload')
        counts.append(n)
        firsts.append(pos)
        pos += 8 * n
    if 4 + pos != len(raw):
        raise LayoutError('JointState length mismatch')
    velocity = effort = None
    if index < 0:
        defect = Defect.MISSING_JOINT
    elif any(n not in (0, count) for n in counts) or not (counts[1] or counts[2]):
        defect = Defect.MALFORMED
    else:
        defect = Defect.NONE
        velocity = firsts[1] + 8 * index if counts[1] else None
        effort = firsts[2] + 8 * index if counts[2] else None
    return JointLayout(end, names_end, (length_at[0], length_at[1], length_at[2]), index,
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
        first = raws[idx[0]]
        try:
            if first[:2] != b'\x00\x01':
                raise LayoutError('not little-endian CDR')
            layout = self._layout(first)
        except LayoutError:
            for i in idx:
                self._slow(i, raws[i], out)
            return
        rows = np.frombuffer(b''.join(raws[i] for i in idx), dtype=np.uint8).reshape(
            len(idx), length)
        same = self._same_structure(rows, first, layout)
        fast = np.asarray(idx)[same]
        if fast.size:
            self._fill(rows[same], fast, layout, out)
        for i in np.asarray(idx)[~same].tolist():
            self._slow(i, raws[i], out)

    def _layout(self, raw: bytes) -> Any:
        if self.msgtype == FLOAT64:
            if len(raw) != 12:
                raise LayoutError('Float64 length')
            return None
        if self.msgtype == JOINT_STATE:
            return joint_layout(raw, self.joint)
        end = _header_end(raw)
        first_double = _align(end, 8)
        if 4 + first_double + 16 != len(raw):
            raise LayoutError(f'{self.msgtype} length mismatch')
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


_STAMP = struct.Struct('<iI')
_DOUBLE = struct.Struct('<d')
_CDR_LE = b'\x00\x01'


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
            if raw[:2] != _CDR_LE:
                raise LayoutError('not little-endian CDR')
            return self._decode(raw)
        except (LayoutError, UnicodeDecodeError, struct.error):
            return self._slow(raw)

    def _stamp(self, raw: bytes) -> int | None:
        sec, nanosec = _STAMP.unpack_from(raw, 4)
        return (sec * 1_000_000_000 + nanosec) or None

    def _float64(self, raw: bytes) -> tuple[None, float, None, Defect]:
        if len(raw) != 12:
            raise LayoutError('Float64 length')
        return None, _DOUBLE.unpack_from(raw, 4)[0], None, Defect.NONE

    def _header_and_double(self, raw: bytes) -> tuple[int | None, float, None, Defect]:
        first_double = _align(_header_end(raw), 8)
        if 4 + first_double + 16 != len(raw):
            raise LayoutError(f'{self.spec.msgtype} length mismatch')
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
        stamp = stamp_to_ns(msg.header.stamp) if self.spec.has_header else None
        return stamp, value, torque, defect
