"""A run's recorded topics as an MCAP file that ``ros2 bag``, Foxglove and PlotJuggler open,
written while the run goes on.

The file is what ``ros2 bag record -s mcap`` writes: profile ``ros2``, every channel's messages
in the ROS 2 wire encoding (``cdr``, the bytes rclpy serializes), and per message type one schema
in the ``ros2msg`` encoding: the type's ``.msg`` text followed by the ``.msg`` text of every type
it uses, each after a line of 80 ``=`` and a ``MSG: pkg/Type`` line (rosbag2's
"complete message definition"). The ``.msg`` files come from the installed interface packages'
``share/<pkg>/msg/`` (:func:`rns_ros.resources.share_folders`: the ament index, else the Python
environment's prefix, where the PyPI wheels install them).

:class:`McapRecording` writes each message as it arrives: a chunk reaches the disk at least every
:data:`FLUSH_PERIOD` of wall time, so a process killed outright leaves a file whose complete
chunks hold every message up to the last second or so (the PyPI ``mcap`` reader's
``StreamReader`` reads them, as ``mcap recover`` does). Closing it (also on Ctrl-C or SIGTERM)
writes the summary and footer. A write that fails (a full disk, a file-size limit) stops the
recording: the file is removed, since a reader cannot trust it, and :attr:`McapRecording.problem`
says why.

Each message's log and publish time is when this process received it, on the wall clock [ns],
as ``ros2 bag record`` stamps them; the messages' own header stamps are the simulation's.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from rns_ros.cli import signals_held
from rns_ros.core import RnsError
from rns_ros.harness import TopicLog
from rns_ros.resources import share_folders
from rns_ros.runs.logger import output_folder

#: Longest wall time a received message waits in memory before its chunk is written [s].
FLUSH_PERIOD = 1.0
#: Largest uncompressed chunk [bytes] (ros2 bag's MCAP default is 768 KiB; smaller chunks reach
#: the disk sooner at a little compression).
CHUNK_SIZE = 256 * 1024
#: The line that separates the definitions of a ros2msg schema.
SEPARATOR = "=" * 80
#: .msg field types that are not messages.
PRIMITIVE_TYPES = frozenset(
    {"bool", "byte", "char", "float32", "float64", "string", "wstring"}
    | {f"{sign}int{bits}" for sign in ("", "u") for bits in (8, 16, 32, 64)}
)


def msg_file(type_name: str) -> Path:
    """The installed ``.msg`` file of ``'pkg/Type'`` or ``'pkg/msg/Type'``.

    Raises:
        RnsError: no package share folder holds it.
    """
    package, *_, name = type_name.split("/")
    shares = share_folders(package)
    for share in shares:
        path = share / "msg" / f"{name}.msg"
        if path.is_file():
            return path
    where = ", ".join(str(share) for share in shares) or f"no share/{package} folder found"
    raise RnsError(f"no .msg definition of {type_name} installed ({where})")


def msg_dependencies(text: str, package: str) -> list[str]:
    """The message types (``'pkg/Type'``) the fields of the ``.msg`` ``text`` use, sorted;
    a type without a package is ``package``'s."""
    found = set()
    for line in text.splitlines():
        words = line.split("#", 1)[0].split()
        if len(words) < 2 or "=" in words[0]:
            continue
        kind = words[0].split("[", 1)[0].split("<=", 1)[0]
        if kind in PRIMITIVE_TYPES:
            continue
        found.add(kind if "/" in kind else f"{package}/{kind}")
    return sorted(found)


def message_definition(type_name: str) -> str:
    """rosbag2's complete ``ros2msg`` definition of ``'pkg/msg/Type'``: its ``.msg`` text, then
    each type it uses, depth first, once, after the separator and a ``MSG: pkg/Type`` line."""
    seen: set[str] = set()

    def text_of(name: str) -> str:
        text = msg_file(name).read_text()
        for dependency in msg_dependencies(text, name.split("/")[0]):
            if dependency not in seen:
                seen.add(dependency)
                text += f"\n{SEPARATOR}\nMSG: {dependency}\n{text_of(dependency)}"
        return text

    return text_of(type_name)


def ros_type_name(msg_type: type) -> str:
    """``'pkg/msg/Type'`` of a generated message class."""
    return f"{msg_type.__module__.split('.')[0]}/msg/{msg_type.__name__}"


class McapRecording:
    """An MCAP file (profile ``ros2``, zstd chunks) that grows while a run goes on.

    Add the run's :class:`~rns_ros.harness.TopicLog` s with :meth:`add`: each becomes a channel
    (the first message's type sets the schema) and its messages are written as they arrive,
    stamped with their receipt time on the wall clock [ns]. :meth:`close` finishes the file.

    Args:
        path: the file (replaced when it exists).
        resolve: a log's topic -> the channel's name (the absolute name, remaps applied).
        flush_period: wall time [s] after which a chunk in progress is written.
        clock: monotonic clock [s] of the flush period (the logs' receipt times share it).

    A write that raises OSError (disk full, file-size limit) ends the recording: later
    messages are dropped, :meth:`close` removes the file and :attr:`problem` says why.
    """

    def __init__(
        self,
        path: Path,
        resolve: Callable[[str], str] = lambda name: name,
        *,
        flush_period: float = FLUSH_PERIOD,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        from mcap.well_known import Profile
        from mcap.writer import CompressionType, Writer

        self.path = Path(path)
        self.counts: dict[str, int] = {}
        self.problem: str | None = None
        self._resolve = resolve
        self._flush_period = flush_period
        self._clock = clock
        self._lock = threading.Lock()
        self._schemas: dict[str, int] = {}
        self._topics: set[str] = set()
        self._closed = False
        # receipt times are monotonic: one offset puts them on the wall clock
        self._offset = time.time_ns() - time.monotonic_ns()
        self._stream = None
        self._writer = None
        try:
            with signals_held():
                self._stream = open(self.path, "wb")  # noqa: SIM115 - closed by close()
                self._writer = Writer(
                    self._stream, chunk_size=CHUNK_SIZE, compression=CompressionType.ZSTD
                )
                self._writer.start(profile=Profile.ROS2, library="rns_ros")
                self._stream.flush()
        except OSError as exc:
            self._fail(exc)
        self._flushed = clock()

    def __enter__(self) -> McapRecording:
        return self

    def __exit__(self, *_exc) -> None:
        self.close()

    def add(self, log: TopicLog) -> None:
        """Record ``log`` from now on, its messages so far first (:meth:`TopicLog.tap`); a
        second log of a topic already recorded is left out.

        Raises:
            RnsError: the log's message type is unknown (no ``msg_type``, no message yet) or
                has no installed ``.msg`` definition.
        """
        msg_type = log.msg_type or (type(log.messages[0]) if len(log) else None)
        if msg_type is None:
            raise RnsError(f"{log.topic}: the message type of an empty log is unknown")
        type_name = ros_type_name(msg_type)
        definition = message_definition(type_name).encode()
        topic = self._resolve(log.topic)
        with self._lock, signals_held():
            if self._writer is None or topic in self._topics:
                return
            self._topics.add(topic)
            try:
                channel = self._channel(topic, type_name, definition)
            except OSError as exc:
                self._fail(exc)
                return
        sequence = 0

        def write(data: bytes, received: float) -> None:
            nonlocal sequence
            with self._lock, signals_held():
                if self._writer is None:
                    return
                stamp = round(received * 1e9) + self._offset
                try:
                    self._writer.add_message(
                        channel_id=channel,
                        log_time=stamp,
                        publish_time=stamp,
                        sequence=sequence,
                        data=data,
                    )
                    sequence += 1
                    self.counts[topic] = sequence
                    if self._clock() - self._flushed >= self._flush_period:
                        self._writer.flush()  # the chunk so far, to the disk
                        self._flushed = self._clock()
                except OSError as exc:
                    self._fail(exc)

        log.tap(write)

    def _channel(self, topic: str, type_name: str, definition: bytes) -> int:
        """A new channel of ``type_name`` messages (its schema registered once)."""
        from mcap.well_known import MessageEncoding, SchemaEncoding

        if type_name not in self._schemas:
            self._schemas[type_name] = self._writer.register_schema(
                name=type_name, encoding=SchemaEncoding.ROS2, data=definition
            )
        return self._writer.register_channel(
            topic=topic, message_encoding=MessageEncoding.CDR, schema_id=self._schemas[type_name]
        )

    def _fail(self, error: OSError) -> None:
        """Stop recording after a failed write: the file stays until :meth:`close` removes it."""
        reason = error.strerror or str(error)
        self.problem = f"cannot write {self.path}: {reason}; the file is removed"
        self._writer = None

    def close(self) -> str | None:
        """Write the summary and footer and close the file (idempotent). Returns the file's
        path, or None when it could not be written (:attr:`problem`; the file is removed)."""
        with self._lock, signals_held():
            if not self._closed:
                self._closed = True
                try:
                    if self._writer is not None:
                        self._writer.finish()
                    if self._stream is not None:
                        self._stream.close()
                except OSError as exc:
                    self._fail(exc)
                if self.problem is not None:
                    with contextlib.suppress(OSError, AttributeError):  # None: never opened
                        self._stream.close()
                    with contextlib.suppress(OSError):
                        self.path.unlink()
                self._writer = None
        return None if self.problem is not None else str(self.path)


class NoRecording:
    """What :func:`open_mcap` gives with ``--no-record``: records nothing, closes to None."""

    problem: str | None = None

    def add(self, log: TopicLog) -> None:
        """Nothing is recorded."""

    def close(self) -> None:
        """No file."""


@contextlib.contextmanager
def open_mcap(
    args, name: str, resolve: Callable[[str], str]
) -> Iterator[McapRecording | NoRecording]:
    """``<output>/<name>.mcap`` as a :class:`McapRecording` for the block, closed at its end
    whatever ends it (:class:`NoRecording` with ``--no-record``)."""
    if args.no_record:
        yield NoRecording()
        return
    with McapRecording((output_folder(args) / f"{name}.mcap").resolve(), resolve) as recording:
        yield recording
