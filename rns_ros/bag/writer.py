"""Bags written as messages arrive, laid out as ``ros2 bag record -s mcap`` lays them out.

:class:`BagWriter` writes a rosbag2 folder: ``DIR/metadata.yaml`` plus ``DIR/DIR_0.mcap``
(``DIR_1.mcap``, ... after a split by size or duration), or, as ``file=True``, one MCAP file
alone. Each MCAP file is what rosbag2's MCAP storage plugin writes (:class:`McapFile`): profile
``ros2``; per message type one schema in the ``ros2msg`` encoding holding the type's complete
definition (:func:`rns_ros.bag.definitions.message_definition`); per topic one channel in the
``cdr`` encoding whose metadata holds ``offered_qos_profiles`` (the publishers' QoS as a YAML
string) and ``topic_type_hash``; each message's log time is its receipt time and its publish
time the publisher's stamp, in nanoseconds since the epoch; at its close, one ``rosbag2``
metadata record whose ``serialized_metadata`` is the bag's metadata as of then (so
``ros2 bag info FILE.mcap`` reads it).

Messages are stored as their CDR content (:class:`rns_ros.bag.cdr.CdrLayout`): bytes after it,
which publishers that send ``rclpy.serialization`` buffers as they are put on the wire, are cut
off, so every reader decodes them; a message that cannot be walked as its type is stored as
received.

A chunk reaches the disk at least every ``flush_period`` of wall time, so a process killed
outright leaves files whose complete chunks hold every message up to the last second or so
(``mcap recover`` reads them). Closing the writer (also on Ctrl-C or SIGTERM: signals are held
while a record is half written) writes each file's summary and footer and ``metadata.yaml``. A
write that fails (a full disk, a file-size limit) stops the recording: what it wrote is removed,
since a reader cannot trust it, and :attr:`BagWriter.problem` says why.
"""

from __future__ import annotations

import contextlib
import re
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rns_ros.bag.cdr import CdrLayout
from rns_ros.bag.definitions import (
    DefinitionError,
    full_type_name,
    message_definition,
    parse_definition,
    type_description_hash,
)
from rns_ros.bag.metadata import METADATA_FILE, BagError, BagMetadata, FileInfo, TopicInfo
from rns_ros.bag.qos import profiles_yaml
from rns_ros.cli import signals_held

#: Longest wall time a received message waits in memory before its chunk is written [s].
FLUSH_PERIOD = 1.0
#: Largest uncompressed chunk [bytes] (ros2 bag's MCAP default is 768 KiB; smaller chunks reach
#: the disk sooner at a little compression).
CHUNK_SIZE = 256 * 1024
#: rosbag2's smallest split size of the MCAP storage [bytes].
MIN_SPLIT_SIZE = 1024
LIBRARY = "rns_ros"
#: Bytes of an MCAP message record besides the message (opcode, length, channel, sequence, times).
MESSAGE_RECORD = 31


class McapFile:
    """One MCAP file as rosbag2's MCAP storage plugin writes it (zstd chunks).

    Raises:
        OSError: the file cannot be created or written.
    """

    def __init__(self, path: Path) -> None:
        from mcap.well_known import Profile
        from mcap.writer import CompressionType, Writer

        self.path = Path(path)
        self._schemas: dict[str, int] = {}
        self._pending = 0  # message bytes not yet on disk (the chunk in progress)
        self._stream = open(self.path, "wb")  # noqa: SIM115 - closed by close()
        try:
            self._writer = Writer(
                self._stream, chunk_size=CHUNK_SIZE, compression=CompressionType.ZSTD
            )
            self._writer.start(profile=Profile.ROS2, library=LIBRARY)
            self._stream.flush()
        except BaseException:
            self._stream.close()
            raise

    @property
    def size(self) -> int:
        """Bytes written to the file so far (the chunk in progress not counted)."""
        return self._stream.tell()

    @property
    def pending(self) -> int:
        """Uncompressed bytes of the chunk in progress (its messages and their records)."""
        return self._pending

    def add_topic(self, topic: TopicInfo, definition: str) -> int:
        """A channel for ``topic`` (its schema registered once per type); its id."""
        from mcap.well_known import SchemaEncoding

        if topic.type not in self._schemas:
            self._schemas[topic.type] = self._writer.register_schema(
                name=topic.type, encoding=SchemaEncoding.ROS2, data=definition.encode()
            )
        return self._writer.register_channel(
            topic=topic.name,
            message_encoding=topic.serialization_format,
            schema_id=self._schemas[topic.type],
            metadata={
                "offered_qos_profiles": profiles_yaml(topic.offered_qos_profiles),
                "topic_type_hash": topic.type_description_hash,
            },
        )

    def write(self, channel: int, data: bytes, log_time: int, publish_time: int, sequence: int):
        before = self._stream.tell()
        self._writer.add_message(
            channel_id=channel,
            log_time=log_time,
            publish_time=publish_time,
            sequence=sequence,
            data=data,
        )
        # a full chunk went to the disk with this message: the next chunk starts empty
        self._pending = 0 if self._stream.tell() != before else self._pending
        self._pending += len(data) + MESSAGE_RECORD

    def flush(self) -> None:
        """The chunk so far, to the disk."""
        self._writer.flush()
        self._pending = 0

    def close(self, metadata: BagMetadata) -> None:
        """The ``rosbag2`` metadata record, summary and footer; the file closed."""
        try:
            self._writer.add_metadata("rosbag2", {"serialized_metadata": metadata.serialized()})
            self._writer.finish()
        finally:
            self._stream.close()

    def abandon(self) -> None:
        """Close the file without finishing it (after a failed write)."""
        with contextlib.suppress(OSError):
            self._stream.close()


@dataclass
class Topic:
    """A topic of a :class:`BagWriter`: what metadata.yaml says of it, how to write it."""

    info: TopicInfo
    definition: str
    layout: CdrLayout | None
    channel: int = -1
    sequence: int = 0


class BagWriter:
    """A bag that grows while messages arrive (see the module docstring); thread-safe.

    Args:
        path: the bag folder (made with its parents), or with ``file=True`` the MCAP file.
        file: write one MCAP file at ``path``, no folder and no metadata.yaml.
        max_bag_size: split when a file reaches this many bytes (0: never; else at least
            :data:`MIN_SPLIT_SIZE`), as ``ros2 bag record --max-bag-size``.
        max_bag_duration: split when a file spans more than this [s] (0: never), as
            ``--max-bag-duration``.
        replace: a folder that holds a bag of the same name is emptied of it first (its
            metadata.yaml and ``NAME_<n>.mcap``); without it such a folder is refused.
        flush_period: wall time [s] after which a chunk in progress is written.
        clock: monotonic clock [s] of the flush period.

    Raises:
        BagError: the folder holds files already (without ``replace``), or a bad split size.

    A file that cannot be created or written is not an exception: the recording stops,
    :meth:`close` removes what it wrote and :attr:`problem` says why.
    """

    def __init__(
        self,
        path: Path,
        *,
        file: bool = False,
        max_bag_size: int = 0,
        max_bag_duration: float = 0.0,
        replace: bool = False,
        flush_period: float = FLUSH_PERIOD,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.path = Path(path)
        self.single_file = file
        if max_bag_size < 0 or 0 < max_bag_size < MIN_SPLIT_SIZE:
            raise BagError(
                f"--max-bag-size must be 0 (no split) or at least {MIN_SPLIT_SIZE} bytes, "
                f"got {max_bag_size}"
            )
        if not max_bag_duration >= 0.0:
            raise BagError(f"--max-bag-duration must be >= 0 s, got {max_bag_duration}")
        self.max_bag_size = max_bag_size
        self.max_duration_ns = round(max_bag_duration * 1e9)
        self.metadata = BagMetadata()
        #: messages written per topic (topics with at least one)
        self.counts: dict[str, int] = {}
        self.problem: str | None = None
        self._topics: dict[str, Topic] = {}
        self._flush_period = flush_period
        self._clock = clock
        self._lock = threading.Lock()
        self._made: list[Path] = []  # what this writer created, removed if it fails
        self._made_folder = False
        self._file: McapFile | None = None
        self._closed = False
        if not file:
            self._clear_folder(replace)
        with signals_held():
            try:
                if not file and not self.path.is_dir():
                    self.path.mkdir(parents=True)
                    self._made_folder = True
                self._open_file()
            except OSError as exc:
                self._fail(exc)
        self._flushed = clock()

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(self, *_exc) -> None:
        self.close()

    # --- files ------------------------------------------------------------------------------
    def _file_path(self, index: int) -> Path:
        if self.single_file:
            return self.path
        return self.path / f"{self.path.name}_{index}.mcap"

    def _clear_folder(self, replace: bool) -> None:
        if not self.path.is_dir():
            return
        ours = re.compile(rf"{re.escape(self.path.name)}_\d+\.mcap")
        names = [item.name for item in self.path.iterdir()]
        mine = [name for name in names if name == METADATA_FILE or ours.fullmatch(name)]
        if not replace and names:
            raise BagError(f"{self.path}: the folder exists and is not empty")
        for name in mine:
            with contextlib.suppress(OSError):
                (self.path / name).unlink()

    def _open_file(self) -> None:
        path = self._file_path(len(self.metadata.files))
        self._made.append(path)
        self._file = McapFile(path)
        self.metadata.files.append(FileInfo(path.name))
        for topic in self._topics.values():  # every topic again in the new file
            topic.channel = self._file.add_topic(topic.info, topic.definition)

    def _split(self) -> None:
        self._file.close(self._finished_metadata())
        self._file = None
        self._open_file()

    def _should_split(self, stamp_ns: int) -> bool:
        current = self.metadata.files[-1]
        if self.max_bag_size and self._file.size + self._file.pending >= self.max_bag_size:
            self._file.flush()  # compressed, the chunk may still fit
            if self._file.size >= self.max_bag_size:
                return True
        return bool(
            self.max_duration_ns
            and current.message_count
            and stamp_ns - current.starting_time_ns > self.max_duration_ns
        )

    def _finished_metadata(self) -> BagMetadata:
        metadata = self.metadata.copy()
        metadata.summarize_files()
        metadata.bag_size = sum(path.stat().st_size for path in self._made if path.is_file())
        return metadata

    # --- topics and messages ------------------------------------------------------------------
    def add_topic(
        self,
        name: str,
        type_name: str,
        offered_qos_profiles: Iterable[dict[str, Any]] = (),
        *,
        definition: str | None = None,
        type_hash: str | None = None,
    ) -> Topic:
        """A topic to write (the same one again if ``name`` is known). ``definition``: the
        complete ros2msg text (default: the installed one); ``type_hash``: default the
        installed type description's.

        Raises:
            DefinitionError: no definition given or installed.
        """
        type_name = full_type_name(type_name)
        if definition is None:
            definition = message_definition(type_name)
        try:
            layout = CdrLayout(type_name, parse_definition(type_name, definition))
        except DefinitionError:
            layout = None  # stored as received
        info = TopicInfo(
            name=name,
            type=type_name,
            offered_qos_profiles=[dict(item) for item in offered_qos_profiles],
            type_description_hash=(
                type_description_hash(type_name) if type_hash is None else type_hash
            ),
        )
        with self._lock, signals_held():
            if name in self._topics:
                return self._topics[name]
            topic = Topic(info, definition, layout)
            self._topics[name] = topic
            self.metadata.topics.append(info)
            if self._file is not None:
                try:
                    topic.channel = self._file.add_topic(info, definition)
                except OSError as exc:
                    self._fail(exc)
            return topic

    def write(self, topic: Topic, data: bytes, log_time_ns: int, publish_time_ns: int = 0):
        """Write one serialized message received at ``log_time_ns`` [ns since the epoch]
        (``publish_time_ns``: its source stamp; 0: the receipt time)."""
        if topic.layout is not None:
            data = topic.layout.content(data)
        with self._lock, signals_held():
            if self._file is None:
                return
            try:
                if self._should_split(log_time_ns):
                    self._split()
                self._file.write(
                    topic.channel, data, log_time_ns, publish_time_ns or log_time_ns, topic.sequence
                )
                topic.sequence += 1
                topic.info.message_count += 1
                self.counts[topic.info.name] = topic.info.message_count
                self.metadata.files[-1].add(log_time_ns)
                if self._clock() - self._flushed >= self._flush_period:
                    self._file.flush()
                    self._flushed = self._clock()
            except OSError as exc:
                self._fail(exc)

    def _fail(self, error: OSError) -> None:
        """Stop recording after a failed write: what was written stays until :meth:`close`."""
        reason = error.strerror or str(error)
        what = "the file is removed" if self.single_file else "the bag is removed"
        self.problem = f"cannot write {self.path}: {reason}; {what}"
        if self._file is not None:
            self._file.abandon()
        self._file = None

    def close(self) -> str | None:
        """Finish the file(s) and write metadata.yaml (idempotent). Returns the bag's path, or
        None when it could not be written (:attr:`problem`; what it wrote is removed)."""
        with self._lock, signals_held():
            if not self._closed:
                self._closed = True
                try:
                    if self._file is not None:
                        self._file.close(self._finished_metadata())
                        self._file = None
                        if not self.single_file:
                            final = self._finished_metadata()
                            self._made.append(self.path / METADATA_FILE)
                            (self.path / METADATA_FILE).write_text(final.file_text())
                            self.metadata = final
                except OSError as exc:
                    self._fail(exc)
                if self.problem is not None:
                    self._remove()
        return None if self.problem is not None else str(self.path)

    def _remove(self) -> None:
        for path in self._made:
            with contextlib.suppress(OSError):  # a folder given as a file stays
                path.unlink()
        if self._made_folder:
            with contextlib.suppress(OSError):
                self.path.rmdir()
