"""Reading the node's input topics from rosbag2 bags (sqlite3, mcap) with rosbags.

`BagInputs` opens a bag, checks its topics and types against what the node subscribes
(after remapping), and yields its messages in bag order, decoded to SI floats in chunks.

Decoding is batched: the input messages have a fixed layout in practice (same frame_id,
same joint names, same array lengths), so within a chunk the raw CDR payloads of a topic are
grouped by length, the field offsets are derived once per group from its first message by
a small CDR layout parser, the layout-defining bytes (frame_id, names, array lengths) are
checked to be identical across the group, and the numbers are read with numpy. A message
that does not fit (another layout, big-endian CDR) is decoded by rosbags' own deserialiser
and the node's conversion functions instead; both paths give the same floats.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .config import EstimatorConfig
from .errors import PumpFrictionError
from .ros_messages import joint_sample, stamp_to_ns

__all__ = ['BagError', 'BagInputs', 'Chunk', 'input_topics', 'parse_remaps']

JOINT_STATE = 'sensor_msgs/msg/JointState'
FLUID_PRESSURE = 'sensor_msgs/msg/FluidPressure'
FLOAT64 = 'std_msgs/msg/Float64'
TEMPERATURE = 'sensor_msgs/msg/Temperature'

# kinds of input events, in the order the replay dispatches them
JOINT, SPEED, TORQUE, PRESSURE, PORT_A, PORT_B, OIL_TEMPERATURE = range(7)

_CHUNK_MESSAGES = 20000


class BagError(PumpFrictionError):
    """The bag is missing, not a bag, unreadable, corrupt, empty or lacks the input topics."""


def _one_line(exc: BaseException, limit: int = 300) -> str:
    """Return an exception's text on one line (YAML and SQL errors span several)."""
    text = ' '.join(str(exc).split())
    return text if len(text) <= limit else text[:limit - 3] + '...'


def parse_remaps(items: list[str] | None) -> dict[str, str]:
    """Parse ``old:=new`` topic remappings (old: the node's topic name, new: the bag's).

    Parameters
    ----------
    items : list of str
        Remapping rules.

    Returns
    -------
    dict
        Absolute old name to absolute new name.

    Raises
    ------
    BagError
        A rule without ``:=`` or with an empty side.
    """
    remaps = {}
    for item in items or []:
        old, sep, new = item.partition(':=')
        if not sep or not old.strip() or not new.strip():
            raise BagError(f'bad --topic-remap {item!r}: expected old:=new')
        remaps[_absolute(old.strip())] = _absolute(new.strip())
    return remaps


def _absolute(name: str) -> str:
    return name if name.startswith('/') else '/' + name


def input_topics(config: EstimatorConfig, remaps: dict[str, str] | None = None
                 ) -> dict[str, tuple[str, int]]:
    """Topics the node subscribes with this config: bag topic -> (message type, kind).

    Parameters
    ----------
    config : EstimatorConfig
        Node parameters (sources of speed, torque, pressure, viscosity).
    remaps : dict, optional
        Remappings from `parse_remaps`.

    Returns
    -------
    dict
        Topic name in the bag to (message type, event kind).
    """
    remaps = remaps or {}
    wanted: dict[str, tuple[str, int]] = {}
    if 'joint_state' in (config.speed_source, config.torque_source):
        wanted['/joint_states'] = (JOINT_STATE, JOINT)
    if config.speed_source == 'float64':
        wanted['/shaft_speed'] = (FLOAT64, SPEED)
    if config.torque_source == 'float64':
        wanted['/motor_torque'] = (FLOAT64, TORQUE)
    if config.pressure_source == 'difference':
        wanted['/load_pressure'] = (FLUID_PRESSURE, PRESSURE)
    else:
        wanted['/pressure_a'] = (FLUID_PRESSURE, PORT_A)
        wanted['/pressure_b'] = (FLUID_PRESSURE, PORT_B)
    if config.viscosity_source == 'temperature':
        wanted['/oil_temperature'] = (TEMPERATURE, OIL_TEMPERATURE)
    return {remaps.get(topic, topic): spec for topic, spec in wanted.items()}


@dataclass
class Chunk:
    """Decoded input events, in bag order (parallel lists)."""

    kinds: list[int] = field(default_factory=list)
    stamps: list[int] = field(default_factory=list)  # ns; header stamp or log time
    log_times: list[int] = field(default_factory=list)  # ns
    values: list[float] = field(default_factory=list)  # speed / pressure / torque / degC
    torques: list[float] = field(default_factory=list)  # JointState effort (NaN: none)
    has_speed: list[bool] = field(default_factory=list)  # JointState velocity present


# -- CDR layout of the input messages ----------------------------------------------------


def _align(pos: int, size: int) -> int:
    return pos + (-pos % size)


def _header_end(raw: bytes) -> int:
    """Payload offset after std_msgs/Header (stamp + frame_id), raising on a bad length."""
    length = int.from_bytes(raw[12:16], 'little')
    end = 12 + length  # payload offsets: 0 sec, 4 nanosec, 8 frame_id length, 12 chars
    if length == 0 or 4 + end > len(raw):
        raise ValueError('bad frame_id length')
    return end


def _joint_layout(raw: bytes, joint: str) -> tuple[int, int, int | None, int | None]:
    """Offsets in a JointState payload (+4 for the raw buffer).

    Returns (end of the names, joint index or -1, velocity offset, effort offset); the
    offset of a double is None when its array is too short to hold the joint.
    """
    pos = _align(_header_end(raw), 4)
    count = int.from_bytes(raw[4 + pos:8 + pos], 'little')
    pos += 4
    names = []
    for _ in range(count):
        length = int.from_bytes(raw[4 + pos:8 + pos], 'little')
        names.append(raw[8 + pos:8 + pos + length - 1].decode())
        pos = _align(pos + 4 + length, 4)
    structure_end = pos
    index = names.index(joint) if joint in names else -1
    offsets = []
    for _ in range(3):  # position, velocity, effort
        pos = _align(pos, 4)
        n = int.from_bytes(raw[4 + pos:8 + pos], 'little')
        pos += 4
        if n:
            pos = _align(pos, 8)
        offsets.append((pos + 8 * index) if 0 <= index < n else None)
        pos += 8 * n
    if 4 + pos != len(raw):
        raise ValueError('JointState length mismatch')
    return structure_end, index, offsets[1], offsets[2]


def _column(rows: np.ndarray, offset: int, dtype: str) -> np.ndarray:
    size = np.dtype(dtype).itemsize
    return np.ascontiguousarray(rows[:, offset:offset + size]).view(dtype).ravel()


class _Decoder:
    """Batch decoding of one input topic; falls back to rosbags for irregular messages."""

    def __init__(self, msgtype: str, kind: int, joint_name: str, typestore) -> None:
        self.msgtype = msgtype
        self.kind = kind
        self.joint = joint_name
        self.typestore = typestore
        self.fallbacks = 0
        self.undecodable = 0
        self.missing_joint = 0

    def decode(self, raws: list[bytes], log_times: list[int]):
        """Return (stamps, values, torques, has_speed, ok) arrays for the messages."""
        n = len(raws)
        stamps = np.array(log_times, dtype=np.int64)
        values = np.full(n, math.nan)
        torques = np.full(n, math.nan)
        has_speed = np.zeros(n, dtype=bool)
        ok = np.zeros(n, dtype=bool)
        by_length: dict[int, list[int]] = {}
        for i, raw in enumerate(raws):
            by_length.setdefault(len(raw), []).append(i)
        for length, idx in by_length.items():
            self._decode_group(raws, idx, length, stamps, values, torques, has_speed, ok)
        return stamps, values, torques, has_speed, ok

    def _decode_group(self, raws, idx, length, stamps, values, torques, has_speed, ok):
        first = raws[idx[0]]
        try:
            if first[:2] != b'\x00\x01':
                raise ValueError('not little-endian CDR')
            layout = self._layout(first)
        except (ValueError, IndexError, UnicodeDecodeError):
            for i in idx:
                self._slow(i, raws[i], stamps, values, torques, has_speed, ok)
            return
        rows = np.frombuffer(b''.join(raws[i] for i in idx), dtype=np.uint8).reshape(
            len(idx), length)
        same = self._same_structure(rows, first, layout)
        fast = np.asarray(idx)[same]
        rows = rows[same]
        if fast.size:
            self._fill(rows, fast, layout, stamps, values, torques, has_speed, ok)
        for i in np.asarray(idx)[~same].tolist():
            self._slow(i, raws[i], stamps, values, torques, has_speed, ok)

    def _layout(self, raw: bytes):
        if self.msgtype == FLOAT64:
            if len(raw) != 12:
                raise ValueError('Float64 length')
            return 0
        end = _header_end(raw)
        if self.msgtype == JOINT_STATE:
            return (end, *_joint_layout(raw, self.joint))
        first_double = _align(end, 8)
        if 4 + first_double + 16 != len(raw):
            raise ValueError(f'{self.msgtype} length mismatch')
        return end, first_double

    def _same_structure(self, rows: np.ndarray, first: bytes, layout) -> np.ndarray:
        """Rows laid out like ``first``: same encapsulation, frame_id, names, array lengths."""
        ref = np.frombuffer(first, np.uint8)
        same = np.all(rows[:, :4] == ref[:4], axis=1)
        if self.msgtype == FLOAT64:
            return same
        end = layout[1] if self.msgtype == JOINT_STATE else layout[0]
        same &= np.all(rows[:, 12:4 + end] == ref[12:4 + end], axis=1)  # past the stamp
        if self.msgtype == JOINT_STATE:
            same &= self._joint_lengths_match(rows, first)
        return same

    def _joint_lengths_match(self, rows: np.ndarray, first: bytes) -> np.ndarray:
        """Rows whose position / velocity / effort lengths equal the first message's."""
        pos = _align(_header_end(first), 4)
        count = int.from_bytes(first[4 + pos:8 + pos], 'little')
        pos += 4
        for _ in range(count):
            length = int.from_bytes(first[4 + pos:8 + pos], 'little')
            pos = _align(pos + 4 + length, 4)
        match = np.ones(rows.shape[0], dtype=bool)
        for _ in range(3):
            pos = _align(pos, 4)
            n = int.from_bytes(first[4 + pos:8 + pos], 'little')
            match &= np.all(rows[:, 4 + pos:8 + pos] == np.frombuffer(
                first[4 + pos:8 + pos], np.uint8), axis=1)
            pos += 4
            if n:
                pos = _align(pos, 8)
            pos += 8 * n
        return match

    def _fill(self, rows, fast, layout, stamps, values, torques, has_speed, ok):
        if self.msgtype == FLOAT64:
            values[fast] = _column(rows, 4, '<f8')
            ok[fast] = True
            return
        sec = _column(rows, 4, '<i4').astype(np.int64)
        nanosec = _column(rows, 8, '<u4').astype(np.int64)
        header_ns = sec * 1_000_000_000 + nanosec
        stamps[fast] = np.where(header_ns != 0, header_ns, stamps[fast])
        if self.msgtype == JOINT_STATE:
            _, _, index, vel, eff = layout
            if index < 0:
                self.missing_joint += fast.size
                return
            if vel is not None:
                values[fast] = _column(rows, 4 + vel, '<f8')
                has_speed[fast] = True
            if eff is not None:
                torques[fast] = _column(rows, 4 + eff, '<f8')
            ok[fast] = True
            return
        values[fast] = _column(rows, 4 + layout[1], '<f8')
        ok[fast] = True

    def _slow(self, i, raw, stamps, values, torques, has_speed, ok):
        """Decode one message with rosbags and the node's conversion functions."""
        self.fallbacks += 1
        try:
            msg = self.typestore.deserialize_cdr(raw, self.msgtype)
        except Exception:  # rosbags.serde.SerdeError and friends: a damaged message
            self.undecodable += 1
            return
        if self.msgtype == FLOAT64:
            values[i] = msg.data
            ok[i] = True
            return
        stamp = stamp_to_ns(msg.header.stamp)
        if stamp is not None:
            stamps[i] = stamp
        if self.msgtype == JOINT_STATE:
            sample = joint_sample(msg, self.joint)
            if sample is None:
                self.missing_joint += 1
                return
            speed, torque = sample
            if speed is not None:
                values[i] = speed
                has_speed[i] = True
            if torque is not None:
                torques[i] = torque
        elif self.msgtype == FLUID_PRESSURE:
            values[i] = msg.fluid_pressure
        else:
            values[i] = msg.temperature
        ok[i] = True


class BagInputs:
    """A rosbag2 bag opened for the node's input topics.

    Parameters
    ----------
    path : str or Path
        Bag directory (sqlite3 or mcap storage).
    config : EstimatorConfig
        Node parameters (which topics, which joint).
    remaps : dict, optional
        Topic remappings (node name -> bag name).

    Raises
    ------
    BagError
        Missing path, not a bag, unreadable or corrupt storage, empty bag, no input topics,
        or an input topic of the wrong type.
    """

    def __init__(self, path: str | Path, config: EstimatorConfig,
                 remaps: dict[str, str] | None = None) -> None:
        from rosbags.highlevel import AnyReaderError
        from rosbags.rosbag2 import Reader, ReaderError
        from rosbags.typesys import Stores, get_typestore

        self.path = Path(path)
        if not self.path.exists():
            raise BagError(f'bag not found: {self.path}')
        if self.path.is_dir() and not (self.path / 'metadata.yaml').exists():
            raise BagError(f'not a rosbag2 bag (no metadata.yaml): {self.path}')
        if self.path.is_file() and not self.path.name.endswith(('.db3', '.mcap')):
            raise BagError(f'not a rosbag2 bag (neither a bag folder nor .db3 / .mcap): '
                           f'{self.path}')
        self.typestore = get_typestore(Stores.ROS2_JAZZY)
        try:
            self.reader = Reader(self.path)
            self.reader.open()
        except (ReaderError, AnyReaderError, FileNotFoundError, OSError, ValueError,
                KeyError) as exc:
            raise BagError(f'cannot read bag {self.path}: {_one_line(exc)}') from None
        except Exception as exc:  # a corrupt storage file: apsw, mcap or yaml errors
            raise BagError(f'cannot read bag {self.path}: corrupt or truncated storage '
                           f'({type(exc).__name__}: {_one_line(exc)})') from None
        try:
            self.storage = self._storage_name()
            self.wanted = input_topics(config, remaps)
            self._check_topics()
        except BagError:
            self.reader.close()
            raise
        self._decoders = {}
        self.connections = []
        for conn in self.reader.connections:
            if conn.topic in self.wanted:
                msgtype, kind = self.wanted[conn.topic]
                self._decoders[conn.id] = _Decoder(msgtype, kind, config.joint_name,
                                                   self.typestore)
                self.connections.append(conn)
        self.messages_read = dict.fromkeys(self.wanted, 0)

    def _storage_name(self) -> str:
        """Storage of the bag, 'mcap' or 'sqlite3', from its file names."""
        files = [self.path] if self.path.is_file() else list(self.path.iterdir())
        return 'mcap' if any('.mcap' in p.name for p in files) else 'sqlite3'

    def _check_topics(self) -> None:
        if self.reader.message_count == 0:
            raise BagError(f'bag {self.path} holds no messages')
        present = {c.topic: c.msgtype for c in self.reader.connections}
        for topic, (msgtype, _) in self.wanted.items():
            if topic in present and present[topic] != msgtype:
                raise BagError(f'bag {self.path}: topic {topic} has type {present[topic]}, '
                               f'the node expects {msgtype}')
        missing = [t for t in self.wanted if t not in present]
        if len(missing) == len(self.wanted):
            expected = ', '.join(f'{t} ({m})' for t, (m, _) in self.wanted.items())
            found = ', '.join(f'{t} ({m})' for t, m in sorted(present.items())) or 'none'
            raise BagError(f'bag {self.path}: none of the input topics {expected}; '
                           f'it has {found} (use --topic-remap old:=new)')
        if missing:
            raise BagError(f'bag {self.path}: input topic(s) missing: {", ".join(missing)} '
                           '(use --topic-remap old:=new)')

    @property
    def start_ns(self) -> int:
        """Log time of the first message [ns]."""
        return int(self.reader.start_time)

    @property
    def end_ns(self) -> int:
        """Log time of the last message [ns]."""
        return int(self.reader.end_time) - 1

    @property
    def input_message_count(self) -> int:
        """Number of messages on the input topics."""
        return sum(c.msgcount for c in self.connections)

    @property
    def fallbacks(self) -> int:
        """Messages decoded one by one by rosbags (irregular layout)."""
        return sum(d.fallbacks for d in self._decoders.values())

    @property
    def undecodable(self) -> int:
        """Messages that could not be decoded at all (skipped)."""
        return sum(d.undecodable for d in self._decoders.values())

    @property
    def missing_joint(self) -> int:
        """JointState messages without the configured joint (skipped)."""
        return sum(d.missing_joint for d in self._decoders.values())

    def meta(self) -> dict:
        """Return what the replay needs first: storage, time span, input message count."""
        return {'storage': self.storage, 'start_ns': self.start_ns, 'end_ns': self.end_ns,
                'input_message_count': self.input_message_count}

    def stats(self) -> dict:
        """Return what reading found: messages per topic, fallbacks, undecodable, no joint."""
        return {'messages_read': dict(self.messages_read), 'fallbacks': self.fallbacks,
                'undecodable': self.undecodable, 'missing_joint': self.missing_joint}

    def chunks(self) -> Iterator[Chunk]:
        """Yield the decoded input events in bag order, a chunk at a time.

        Raises
        ------
        BagError
            When the storage turns out to be corrupt while reading.
        """
        ids, times, raws = [], [], []
        try:
            for conn, log_time, raw in self.reader.messages(connections=self.connections):
                ids.append(conn.id)
                times.append(log_time)
                raws.append(raw)
                if len(raws) >= _CHUNK_MESSAGES:
                    yield self._decode(ids, times, raws)
                    ids, times, raws = [], [], []
        except BagError:
            raise
        except Exception as exc:  # apsw.CorruptError, ReaderError, OverflowError, ...
            raise BagError(f'bag {self.path}: corrupt or truncated storage while reading '
                           f'({type(exc).__name__}: {_one_line(exc)})') from None
        if raws:
            yield self._decode(ids, times, raws)

    def _decode(self, ids: list[int], times: list[int], raws: list[bytes]) -> Chunk:
        n = len(raws)
        kinds = np.empty(n, dtype=np.int64)
        stamps = np.empty(n, dtype=np.int64)
        values = np.empty(n)
        torques = np.empty(n)
        has_speed = np.zeros(n, dtype=bool)
        ok = np.zeros(n, dtype=bool)
        ids_arr = np.asarray(ids)
        for conn_id, decoder in self._decoders.items():
            sel = np.flatnonzero(ids_arr == conn_id)
            if not sel.size:
                continue
            topic = next(c.topic for c in self.connections if c.id == conn_id)
            self.messages_read[topic] += int(sel.size)
            s, v, t, h, k = decoder.decode([raws[i] for i in sel.tolist()],
                                           [times[i] for i in sel.tolist()])
            kinds[sel] = decoder.kind
            stamps[sel], values[sel], torques[sel], has_speed[sel], ok[sel] = s, v, t, h, k
        keep = np.flatnonzero(ok)
        return Chunk(kinds=kinds[keep].tolist(), stamps=stamps[keep].tolist(),
                     log_times=np.asarray(times, dtype=np.int64)[keep].tolist(),
                     values=values[keep].tolist(), torques=torques[keep].tolist(),
                     has_speed=has_speed[keep].tolist())

    def close(self) -> None:
        """Close the bag."""
        self.reader.close()

    def __enter__(self) -> BagInputs:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
