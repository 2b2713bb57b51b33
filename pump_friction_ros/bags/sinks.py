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
The output bag: the node's published topics and /diagnostics, written here or in a helper.

Both writers satisfy `Sink`; the helper process writes batches while the core runs and is
stopped like the reader (`sources.stop_process`). The bag is what ``ros2 bag play`` needs to
republish like the node: rosbag2 metadata version 9 with each topic's offered QoS (the
node's: reliable, keep last, volatile) and the compression chosen by `output_compression`.
"""

from __future__ import annotations

import sqlite3
from typing import Any, Protocol

from .reader import BagMeta
from .sources import child_signals, process_context, start_helper, stop_process
from ..core.node_parameters import NODE_NAME
from ..errors import BagError
from ..messages.conversions import (
    DIAGNOSTICS_QOS_DEPTH,
    float64_cdr,
    OUTPUT_QOS_DEPTH,
    OUTPUT_TOPICS,
)
from ..staging import cannot_write

__all__ = ['COMPRESSION_CHOICES', 'DIAGNOSTICS_INDEX', 'OUTPUT_INDEX', 'InlineSink',
           'ProcessSink', 'Sink', 'float64_cdr', 'open_sink', 'output_compression',
           'output_qos', 'output_topics']

_BATCH = 5000

COMPRESSION_CHOICES = ('auto', 'none', 'zstd')
"""``--compression`` of the replay: follow the input, none, or zstd."""


def output_topics() -> list[tuple[str, str, int]]:
    """
    Return the topics of the output bag: the node's Float64 outputs, then /diagnostics.

    Returns
    -------
    list of (str, str, int)
        Topic, message type, and the history depth [messages] the node publishes it with.

    """
    return [(f'/{NODE_NAME}/{name}', 'std_msgs/msg/Float64', OUTPUT_QOS_DEPTH)
            for name in OUTPUT_TOPICS] + \
        [('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray', DIAGNOSTICS_QOS_DEPTH)]


DIAGNOSTICS_INDEX = len(OUTPUT_TOPICS)
OUTPUT_INDEX = {name: i for i, name in enumerate(OUTPUT_TOPICS)}


def output_qos(depth: int) -> Any:
    """
    Return the node's publisher QoS as rosbags writes it into the bag.

    Reliable, keep last ``depth``, volatile (``node.reliable_qos``); deadline, lifespan and
    liveliness lease unspecified (0 s) and liveliness ``system_default``, as rclpy's
    ``QoSProfile`` leaves them. rosbags writes this, in metadata version 9, as Jazzy's
    rosbag2 does: a list of maps with lower-case policy names and ``{sec, nsec}``
    durations; ``ros2 bag play`` offers it when it republishes the topic.

    Parameters
    ----------
    depth : int
        History depth [messages].

    Returns
    -------
    rosbags.interfaces.Qos
        The profile.

    """
    from rosbags.interfaces import (
        Qos,
        QosDurability,
        QosHistory,
        QosLiveliness,
        QosReliability,
        QosTime,
    )

    unspecified = QosTime(sec=0, nsec=0)
    return Qos(history=QosHistory.KEEP_LAST, depth=depth,
               reliability=QosReliability.RELIABLE, durability=QosDurability.VOLATILE,
               deadline=unspecified, lifespan=unspecified,
               liveliness=QosLiveliness.SYSTEM_DEFAULT,
               liveliness_lease_duration=unspecified, avoid_ros_namespace_conventions=False)


def output_compression(requested: str, storage: str, source: BagMeta) -> str:
    """
    Return the compression mode of the output bag (its format is always zstd).

    Parameters
    ----------
    requested : {'auto', 'none', 'zstd'}
        ``auto`` follows the input: uncompressed stays uncompressed; a compressed input
        gives the same mode when the storage is the same (MCAP chunks stay chunks, sqlite3
        file or message compression stays so), else the usual zstd mode of the output's
        storage. ``zstd``: that usual mode, chunks for MCAP and file for sqlite3.
    storage : {'sqlite3', 'mcap'}
        Storage of the output bag.
    source : BagMeta
        The input bag (``compression_mode``: '', 'file', 'message', 'storage').

    Returns
    -------
    str
        '' (none), 'file', 'message' (sqlite3 only) or 'storage' (MCAP chunks).

    Raises
    ------
    ValueError
        An unknown ``requested``.

    """
    if requested not in COMPRESSION_CHOICES:
        raise ValueError(f'compression must be one of {", ".join(COMPRESSION_CHOICES)}, '
                         f'got {requested!r}')
    usual = 'storage' if storage == 'mcap' else 'file'
    if requested == 'none' or (requested == 'auto' and not source.compression_mode):
        return ''
    if requested == 'zstd':
        return usual
    mode, same_storage = source.compression_mode, source.storage == storage
    if same_storage and (mode == 'file' or (mode == 'message' and storage == 'sqlite3')):
        return mode
    return usual  # MCAP chunks stay chunks; rosbag2's MCAP plugin refuses message mode


class Sink(Protocol):
    """Where the replay's output messages go."""

    def write(self, index: int, log_ns: int, payload: bytes) -> None:
        """Write one serialised message on output topic ``index`` at ``log_ns``."""

    def close(self) -> None:
        """Finish the bag; raise BagError if it could not be written."""

    def abort(self) -> None:
        """Stop writing; the staged output is discarded by the caller."""


def _open_writer(path: str, storage: str, compression: str) -> tuple[Any, list[Any]]:
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores

    typestore = get_typestore(Stores.ROS2_JAZZY)
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    writer = Writer(path, version=9, storage_plugin=plugin)
    if compression:
        writer.set_compression(CompressionMode[compression.upper()], CompressionFormat.ZSTD)
    writer.open()
    connections = [writer.add_connection(topic, msgtype, typestore=typestore,
                                         offered_qos_profiles=[output_qos(depth)])
                   for topic, msgtype, depth in output_topics()]
    return writer, connections


def _write_errors() -> tuple[type[Exception], ...]:
    """Return what a bag writer raises when the disk will not take the bag."""
    from rosbags.rosbag2 import WriterError

    return OSError, sqlite3.Error, WriterError  # mcap's file, sqlite3's, rosbags' own


class InlineSink:
    """Writes the output bag in this process."""

    def __init__(self, path: str, storage: str, compression: str = '', name: str = '') -> None:
        self._name = name
        try:
            self._writer, self._connections = _open_writer(path, storage, compression)
        except Exception as exc:
            raise BagError(cannot_write(name or 'bag', exc)) from exc

    def write(self, index: int, log_ns: int, payload: bytes) -> None:
        """Write one message (a full disk: BagError naming the output)."""
        try:
            self._writer.write(self._connections[index], log_ns, payload)
        except _write_errors() as exc:  # a full disk, say
            raise BagError(cannot_write(self._name or 'bag', exc)) from exc

    def close(self) -> None:
        """Finish the bag (BagError naming the output if it could not be written)."""
        try:
            self._writer.close()
        except _write_errors() as exc:
            raise BagError(cannot_write(self._name or 'bag', exc)) from exc

    def abort(self) -> None:
        """Close what can be closed; the staged output is discarded anyway."""
        try:
            self._writer.close()
        except Exception:
            pass


def _writer_process(conn: Any, parent_end: Any, path: str, storage: str,
                    compression: str, name: str) -> None:
    """Write the batches received into the output bag (in a helper process)."""
    child_signals()
    parent_end.close()  # our inherited copy: the parent closing its end must reach us
    try:
        batch = conn.recv()  # the bag is made only once the parent sends: an aborted or
        writer, connections = _open_writer(path, storage, compression)  # interrupted start
        try:
            while True:
                if batch is None:
                    break
                for index, log_ns, payload in zip(*batch, strict=True):
                    writer.write(connections[index], log_ns, payload)
                batch = conn.recv()
        finally:
            writer.close()
        conn.send(('ok', ''))
    except (EOFError, BrokenPipeError):
        return  # the parent aborted
    except Exception as exc:
        try:
            conn.send(('error', cannot_write(name or 'bag', exc)))
        except (BrokenPipeError, OSError):
            pass
    finally:
        conn.close()


class ProcessSink:
    """Writes the output bag in a helper process, in batches, while the core runs."""

    def __init__(self, path: str, storage: str, compression: str = '', name: str = '') -> None:
        ctx = process_context()
        self._conn, child = ctx.Pipe(duplex=True)
        self._proc = ctx.Process(target=_writer_process,
                                 args=(child, self._conn, path, storage, compression, name),
                                 daemon=True)
        start_helper(self._proc, child, self.abort)
        self._batch: tuple[list[int], list[int], list[bytes]] = ([], [], [])

    def write(self, index: int, log_ns: int, payload: bytes) -> None:
        """Queue one message; a full batch is sent to the writer."""
        batch = self._batch
        batch[0].append(index)
        batch[1].append(log_ns)
        batch[2].append(payload)
        if len(batch[0]) >= _BATCH:
            self._flush()

    def _flush(self) -> None:
        if self._batch[0]:
            self._send(self._batch)
            self._batch = ([], [], [])

    def _send(self, item: Any) -> None:
        try:
            self._conn.send(item)
        except (BrokenPipeError, OSError):
            self._finish()  # the writer died: report its error

    def _finish(self) -> None:
        try:
            kind, message = self._conn.recv()
        except (EOFError, OSError):
            kind, message = 'error', 'the bag writer process died'
        self._conn.close()
        stop_process(self._proc)
        if kind != 'ok':
            raise BagError(message)

    def close(self) -> None:
        """Send the rest, tell the writer to finish, and wait for its answer."""
        self._flush()
        self._send(None)
        self._finish()

    def abort(self) -> None:
        """Stop the writer: close the pipe (it ends on its own), bounded wait, then kill."""
        self._conn.close()
        stop_process(self._proc)


def open_sink(path: str, storage: str, pipeline: bool, compression: str = '',
              name: str = '') -> Sink:
    """
    Open the output bag writer.

    Parameters
    ----------
    path : str
        Bag directory to create.
    storage : {'sqlite3', 'mcap'}
        Storage plugin.
    pipeline : bool
        Write in a helper process.
    compression : {'', 'file', 'message', 'storage'}
        zstd compression mode (`output_compression`); '' for none.
    name : str, optional
        The output as the messages name it (``--out out/replayed``; default ``bag``).

    Returns
    -------
    Sink
        The writer.

    """
    return (ProcessSink if pipeline else InlineSink)(path, storage, compression, name)
