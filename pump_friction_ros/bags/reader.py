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
Reading the node's input topics from rosbag2 bags (sqlite3, mcap) with rosbags.

`BagInputs` opens a bag, checks its topics and types against what the node subscribes with
the same configuration (``inputs.inputs_for``, after remapping), and yields its messages in
bag order, decoded to SI samples in chunks (``cdr``).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path, PurePath
import struct
from typing import Any

import numpy as np

from ..core.inputs import INPUTS, inputs_for, InputSpec
from ..core.node_parameters import EstimatorConfig
from ..errors import BagError, ConfigError
from ..messages.cdr import TopicDecoder
from ..yaml_files import read_yaml

__all__ = ['BagInputs', 'BagMeta', 'Chunk', 'ReadStats', 'input_topics', 'mcap_chunk_compression',
           'one_line', 'parse_remaps']

_CHUNK_MESSAGES = 20000


def one_line(exc: BaseException, limit: int = 300) -> str:
    """Return an exception's text on one line (YAML and SQL errors span several)."""
    text = ' '.join(str(exc).split())
    return text if len(text) <= limit else text[:limit - 3] + '...'


def parse_remaps(items: list[str] | None) -> dict[str, str]:
    """
    Parse ``old:=new`` topic remappings (old: the node's topic name, new: the bag's).

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
        A rule without ``:=``, with an empty side or a second ``:=``, naming no input of
        the node, or remapping one twice.

    """
    remaps = {}
    known = {'/' + spec.topic for spec in INPUTS}
    for item in items or []:
        old, sep, new = item.partition(':=')
        if not sep or not old.strip() or not new.strip() or ':=' in new:
            raise BagError(f'bad --topic-remap {item!r}: expected old:=new')
        old = _absolute(old.strip())
        if old not in known:  # a typo would leave the input it meant unremapped
            raise BagError(f'bad --topic-remap {item!r}: the node has no input {old} (its '
                           f'inputs: {", ".join(sorted(known))})')
        if old in remaps:
            raise BagError(f'bad --topic-remap {item!r}: {old} remapped twice')
        remaps[old] = _absolute(new.strip())
    return remaps


def _absolute(name: str) -> str:
    return name if name.startswith('/') else '/' + name


_MCAP_MAGIC = b'\x89MCAP0\r\n'
_MCAP_CHUNK, _MCAP_FOOTER, _MCAP_DATA_END = 0x06, 0x02, 0x0F


def mcap_chunk_compression(path: str | Path, max_records: int = 10000) -> str:
    """
    Return the compression of the first chunk of an MCAP file ('' when none or no chunk).

    rosbag2 records MCAP chunk compression (``--storage-preset-profile zstd_fast`` and the
    like) in the MCAP file only, not in metadata.yaml, and rosbags' Reader does not report
    it; this reads the records up to the first Chunk (MCAP spec: opcode, uint64 length,
    body; a Chunk body starts with three uint64, a uint32 CRC and the compression string).

    Parameters
    ----------
    path : str or Path
        The ``.mcap`` file.
    max_records : int
        Records read before giving up (schemas and channels precede the first chunk).

    Returns
    -------
    str
        'zstd', 'lz4', or '' (uncompressed chunks, no chunk, or not an MCAP file).

    """
    with open(path, 'rb') as handle:
        if handle.read(8) != _MCAP_MAGIC:
            return ''
        for _ in range(max_records):
            head = handle.read(9)
            if len(head) < 9:
                return ''
            opcode, length = head[0], int.from_bytes(head[1:], 'little')
            if opcode == _MCAP_CHUNK:
                body = handle.read(32)
                if len(body) < 32:
                    return ''
                (size,) = struct.unpack_from('<I', body, 28)
                name = handle.read(min(size, 16))
                return name.decode('ascii', 'replace') if len(name) == size else ''
            if opcode in (_MCAP_FOOTER, _MCAP_DATA_END):
                return ''
            handle.seek(length, 1)
    return ''


def input_topics(config: EstimatorConfig, remaps: dict[str, str] | None = None
                 ) -> dict[str, InputSpec]:
    """
    Return the topics the node subscribes with this config, as named in the bag.

    Parameters
    ----------
    config : EstimatorConfig
        Node parameters (sources of speed, torque, pressure, viscosity).
    remaps : dict, optional
        Remappings from `parse_remaps`.

    Returns
    -------
    dict
        Topic name in the bag to its input.

    """
    remaps = remaps or {}
    topics: dict[str, InputSpec] = {}
    for spec in inputs_for(config):
        topic = remaps.get('/' + spec.topic, '/' + spec.topic)
        if topic in topics:  # one bag topic cannot be two inputs: one would go unread
            raise BagError(f'--topic-remap: /{topics[topic].topic} and /{spec.topic} would '
                           f'both read {topic}')
        topics[topic] = spec
    return topics


@dataclass(frozen=True)
class BagMeta:
    """What the replay needs to know of a bag before its messages."""

    storage: str  # 'sqlite3' or 'mcap'
    start_ns: int  # log time of the first message
    end_ns: int  # log time of the last message
    input_message_count: int  # messages on the input topics
    compression_format: str = ''  # '' or 'zstd' ('lz4': mcap chunks written by rosbag2)
    compression_mode: str = ''  # '', 'file' or 'message' (sqlite3), 'storage' (mcap chunks)


@dataclass
class ReadStats:
    """What reading found: messages per input topic, messages decoded one by one."""

    messages_read: dict[str, int] = field(default_factory=dict)
    fallbacks: int = 0
    # messages per input topic that the bag's metadata counts (more than read: the storage
    # ends early or is corrupt where rosbags stops without an error)
    claimed: dict[str, int] = field(default_factory=dict)
    # messages on an input topic of another type, not read: the node's subscription of its
    # type never receives them (``'/load_pressure (sensor_msgs/msg/Temperature)'``: count)
    other_type: dict[str, int] = field(default_factory=dict)

    def unread(self) -> dict[str, int]:
        """Return the messages the metadata counts but the storage did not give, per topic."""
        return {topic: n - self.messages_read.get(topic, 0) for topic, n in self.claimed.items()
                if n > self.messages_read.get(topic, 0)}


@dataclass
class Chunk:
    """
    Decoded input events, in bag order (parallel arrays, one entry per message).

    numpy arrays: they cross the pipe from the reader process as raw buffers, and the core
    takes them whole (``TorqueEstimator.on_chunk``).
    """

    kinds: np.ndarray  # int64 `InputKind`
    stamps: np.ndarray  # int64 ns; header stamp or log time
    log_times: np.ndarray  # ns; int64 (another dtype only for log times beyond int64)
    values: np.ndarray  # float64 speed / pressure / torque / degC, where has_value
    torques: np.ndarray  # float64 JointState effort, where has_torque
    has_value: np.ndarray  # bool
    has_torque: np.ndarray  # bool
    defects: np.ndarray  # int8 `Defect`; 0: a sample

    def __len__(self) -> int:
        return int(self.kinds.size)


class BagInputs:
    """
    A rosbag2 bag opened for the node's input topics.

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
        Missing path, not a bag, unreadable or corrupt storage, a metadata.yaml listing a
        storage file twice, no input topics, or an input topic of the wrong type.

    """

    def __init__(self, path: str | Path, config: EstimatorConfig,
                 remaps: dict[str, str] | None = None) -> None:
        from rosbags.highlevel import AnyReaderError
        from rosbags.rosbag2 import Reader, ReaderError
        from rosbags.typesys import get_typestore, Stores

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
            raise BagError(f'cannot read bag {self.path}: {one_line(exc)}') from exc
        except Exception as exc:
            raise BagError(f'cannot read bag {self.path}: corrupt or truncated storage '
                           f'({type(exc).__name__}: {one_line(exc)})') from exc
        try:
            self._check_storage_files()
            self.wanted = input_topics(config, remaps)
            self._check_topics()
        except BagError:
            self.reader.close()
            raise
        self._decoders: dict[int, TopicDecoder] = {}
        self._topic_of: dict[int, str] = {}
        self.connections: list[Any] = []
        self._other_type: dict[str, int] = {}
        for conn in self.reader.connections:
            if conn.topic in self.wanted and conn.msgtype != self.wanted[conn.topic].msgtype:
                key = f'{conn.topic} ({conn.msgtype})'  # a second publisher's type
                self._other_type[key] = self._other_type.get(key, 0) + int(conn.msgcount or 0)
            elif conn.topic in self.wanted:
                self._decoders[conn.id] = TopicDecoder(self.wanted[conn.topic],
                                                       config.joint_name, self.typestore)
                self._topic_of[conn.id] = conn.topic
                self.connections.append(conn)
        self.messages_read = dict.fromkeys(self.wanted, 0)

    def _storage_name(self) -> str:
        """Storage of the bag, 'mcap' or 'sqlite3', from its file names."""
        files = [self.path] if self.path.is_file() else list(self.path.iterdir())
        return 'mcap' if any('.mcap' in p.name for p in files) else 'sqlite3'

    def _check_storage_files(self) -> None:
        """Refuse a metadata.yaml that lists a storage file twice (rosbags reads it twice)."""
        if not self.path.is_dir():
            return
        try:
            meta = read_yaml(self.path / 'metadata.yaml', 'bag metadata', ros_numbers=False,
                             unique_keys=False)
        except ConfigError as exc:
            raise BagError(f'cannot read bag {self.path}: {exc}') from exc
        names = [PurePath(str(x)).name
                 for x in meta['rosbag2_bagfile_information']['relative_file_paths']]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise BagError(f'bag {self.path}: metadata.yaml lists {", ".join(twice)} twice '
                           '(a corrupt or hand-edited metadata.yaml; `ros2 bag reindex` '
                           'rebuilds it)')

    def _check_topics(self) -> None:
        if self.reader.message_count == 0 and not self._has_any_message():
            raise BagError(f'bag {self.path} holds no messages')
        types: dict[str, set[str]] = {}
        for conn in self.reader.connections:
            types.setdefault(conn.topic, set()).add(conn.msgtype)
        for topic, spec in self.wanted.items():  # only another type: nothing the node reads
            if topic in types and spec.msgtype not in types[topic]:
                raise BagError(f'bag {self.path}: topic {topic} has type '
                               f'{", ".join(sorted(types[topic]))}, the node expects '
                               f'{spec.msgtype}')
        missing = [t for t in self.wanted if t not in types]
        if len(missing) == len(self.wanted):
            expected = ', '.join(f'{t} ({s.msgtype})' for t, s in self.wanted.items())
            found = ', '.join(f'{t} ({", ".join(sorted(m))})'
                              for t, m in sorted(types.items())) or 'none'
            raise BagError(f'bag {self.path}: none of the input topics {expected}; '
                           f'it has {found} (use --topic-remap old:=new)')
        if missing:
            raise BagError(f'bag {self.path}: input topic(s) missing: {", ".join(missing)} '
                           '(use --topic-remap old:=new)')

    def _has_any_message(self) -> bool:
        """Whether the storage holds a message (the metadata's count may be wrong)."""
        try:
            return next(iter(self.reader.messages()), None) is not None
        except Exception:
            return True

    def meta(self) -> BagMeta:
        """
        Return what the replay needs first: storage, time span, message count, compression.

        Returns
        -------
        BagMeta
            From the bag's metadata (the message count is the metadata's claim).

        """
        reader = self.reader
        mode = str(reader.compression_mode or '').lower()
        mode = '' if mode == 'none' else mode
        fmt = str(reader.compression_format or '') if mode else ''
        storage = self._storage_name()
        if storage == 'mcap' and not mode:
            fmt = self._mcap_chunk_compression()
            mode = 'storage' if fmt else ''
        start_ns, end_ns = self._storage_span()
        return BagMeta(storage=storage, start_ns=start_ns, end_ns=max(end_ns - 1, start_ns),
                       input_message_count=sum(c.msgcount for c in self.connections),
                       compression_format=fmt, compression_mode=mode)

    def _storage_span(self) -> tuple[int, int]:
        """
        Return the log times of the first message and just after the last [ns].

        From the storage files (sqlite3's MIN and MAX, MCAP's statistics or chunk indexes),
        as ``ros2 bag info`` reports them after ``ros2 bag reindex``: metadata.yaml's
        ``starting_time`` and ``duration`` are a copy, and an edited or stale copy would
        shift every ``time_s`` and put diagnostics in a gap that is not there.
        """
        reader = self.reader
        inner = getattr(reader, 'storage', None)  # a bag folder's reader, or a storage file's
        storages = getattr(inner, 'storages', None) or [inner]
        spans = [(int(m.start_time), int(m.end_time)) for m in
                 (getattr(x, 'metadata', None) for x in storages)
                 if m is not None and m.message_count]
        if not spans:  # (a rosbags without per-storage times): the metadata's
            return int(reader.start_time), int(reader.end_time)
        return min(a for a, _ in spans), max(b for _, b in spans)

    def _mcap_chunk_compression(self) -> str:
        """Chunk compression of the bag's first MCAP file ('' if none, or unreadable)."""
        files = [self.path] if self.path.is_file() else sorted(self.path.glob('*.mcap'))
        try:
            return mcap_chunk_compression(files[0]) if files else ''
        except OSError:
            return ''

    def stats(self) -> ReadStats:
        """
        Return what reading found so far.

        Returns
        -------
        ReadStats
            Messages per input topic and messages decoded one by one by rosbags.

        """
        claimed = dict.fromkeys(self.wanted, 0)
        for conn in self.connections:
            claimed[self._topic_of[conn.id]] += int(conn.msgcount or 0)
        return ReadStats(dict(self.messages_read),
                         sum(d.fallbacks for d in self._decoders.values()), claimed,
                         dict(self._other_type))

    def chunks(self) -> Iterator[Chunk]:
        """
        Yield the decoded input events in bag order, a chunk at a time.

        Yields
        ------
        Chunk
            Up to 20,000 events.

        Raises
        ------
        BagError
            When the storage turns out to be corrupt while reading, or when the input topics
            hold no message at all.

        """
        ids: list[int] = []
        times: list[int] = []
        raws: list[bytes] = []
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
        except Exception as exc:
            raise BagError(f'bag {self.path}: corrupt or truncated storage while reading '
                           f'({type(exc).__name__}: {one_line(exc)})') from exc
        if raws:
            yield self._decode(ids, times, raws)
        if not any(self.messages_read.values()):
            raise BagError(f'bag {self.path}: the input topics '
                           f'{", ".join(self.wanted)} hold no messages')

    def _decode(self, ids: list[int], times: list[int], raws: list[bytes]) -> Chunk:
        n = len(raws)
        kinds = np.empty(n, dtype=np.int64)
        stamps = np.empty(n, dtype=np.int64)
        values = np.empty(n)
        torques = np.empty(n)
        has_value = np.zeros(n, dtype=bool)
        has_torque = np.zeros(n, dtype=bool)
        defects = np.zeros(n, dtype=np.int8)
        ids_arr = np.asarray(ids)
        for conn_id, decoder in self._decoders.items():
            sel = np.flatnonzero(ids_arr == conn_id)
            if not sel.size:
                continue
            self.messages_read[self._topic_of[conn_id]] += int(sel.size)
            d = decoder.decode([raws[i] for i in sel.tolist()],
                               [times[i] for i in sel.tolist()])
            kinds[sel] = decoder.spec.kind
            stamps[sel], values[sel], torques[sel] = d.stamps, d.values, d.torques
            has_value[sel], has_torque[sel], defects[sel] = d.has_value, d.has_torque, d.defects
        return Chunk(kinds=kinds, stamps=stamps, log_times=np.asarray(times), values=values,
                     torques=torques, has_value=has_value, has_torque=has_torque,
                     defects=defects)

    def close(self) -> None:
        """Close the bag."""
        self.reader.close()

    def __enter__(self) -> BagInputs:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
