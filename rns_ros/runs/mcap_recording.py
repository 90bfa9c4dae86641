"""A run's recorded topics as a ROS 2 bag that ``ros2 bag``, ``rns_bag``, rosbags, Foxglove and
PlotJuggler open, written while the run goes on.

:func:`open_mcap` writes ``<output>/<name>/``: a rosbag2 folder as ``ros2 bag record -s mcap``
lays it out (``metadata.yaml`` and ``<name>_0.mcap``), with the writer ``rns_bag record`` uses
(:class:`rns_ros.bag.BagWriter`: rosbag2's MCAP layout, each message's CDR content, a chunk on
disk at least every :data:`FLUSH_PERIOD`, closed whole on Ctrl-C and SIGTERM, removed with one
line when it cannot be written whole). :class:`McapRecording` alone writes one MCAP file.

Each message's log and publish time is when this process received it, on the wall clock [ns],
as ``ros2 bag record`` stamps them; the messages' own header stamps are the simulation's. A
topic enters the bag with its first message, with the QoS its publishers offer then.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

from rns_ros.bag.definitions import message_definition
from rns_ros.bag.ros import offered_profiles
from rns_ros.bag.writer import FLUSH_PERIOD, BagWriter
from rns_ros.core import RnsError
from rns_ros.harness import Harness, TopicLog
from rns_ros.runs.logger import output_folder

#: How /tf_static and /robot_description are published (robot_state_publisher's latched QoS):
#: subscribed so, the recording gets them whenever it starts.
LATCHED_QOS = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)


def ros_type_name(msg_type: type) -> str:
    """``'pkg/msg/Type'`` of a generated message class."""
    return f"{msg_type.__module__.split('.')[0]}/msg/{msg_type.__name__}"


class McapRecording:
    """Recorded topics written while a run goes on: one MCAP file at ``path``, or with
    ``bag=True`` a rosbag2 folder at ``path`` (a bag in it from an earlier run replaced).

    Add the run's :class:`~rns_ros.harness.TopicLog` s with :meth:`add`: each becomes a topic
    of the bag at its first message, and its messages are written as they arrive, stamped with
    their receipt time on the wall clock [ns]. :meth:`close` finishes the bag.

    Args:
        path: the file (replaced when it exists) or the bag folder.
        resolve: a log's topic -> the bag's topic name (the absolute name, remaps applied).
        offers: a topic -> the QoS its publishers offer (rosbag2's form; default: none known).
        bag: a rosbag2 folder instead of one file.
        flush_period: wall time [s] after which a chunk in progress is written.
        clock: monotonic clock [s] of the flush period (the logs' receipt times share it).

    A write that raises OSError (disk full, file-size limit) ends the recording: later
    messages are dropped, :meth:`close` removes what was written and :attr:`problem` says why.
    """

    def __init__(
        self,
        path: Path,
        resolve: Callable[[str], str] = lambda name: name,
        *,
        offers: Callable[[str], list[dict[str, Any]]] | None = None,
        bag: bool = False,
        flush_period: float = FLUSH_PERIOD,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.path = Path(path)
        self._resolve = resolve
        self._offers = offers or (lambda _topic: [])
        self._topics: set[str] = set()
        # receipt times are monotonic: one offset puts them on the wall clock
        self._offset = time.time_ns() - time.monotonic_ns()
        self._writer = BagWriter(
            self.path, file=not bag, replace=True, flush_period=flush_period, clock=clock
        )

    @property
    def counts(self) -> dict[str, int]:
        """Messages written per topic (topics with at least one)."""
        return self._writer.counts

    @property
    def problem(self) -> str | None:
        """Why the recording could not be written whole, or None."""
        return self._writer.problem

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
        definition = message_definition(type_name)
        name = self._resolve(log.topic)
        if name in self._topics:
            return
        self._topics.add(name)
        topic = None

        def write(data: bytes, received: float) -> None:
            nonlocal topic
            if topic is None:  # its publishers are known once a message came
                try:
                    offers = self._offers(name)
                except Exception:  # a graph query that fails costs the QoS, not the message
                    offers = []
                topic = self._writer.add_topic(name, type_name, offers, definition=definition)
            self._writer.write(topic, data, round(received * 1e9) + self._offset)

        log.tap(write)

    def close(self) -> str | None:
        """Finish the file or bag (idempotent). Returns its path, or None when it could not be
        written (:attr:`problem`; what was written is removed)."""
        return self._writer.close()


class NoRecording:
    """What :func:`open_mcap` gives with ``--no-record``: records nothing, closes to None."""

    problem: str | None = None

    def add(self, log: TopicLog) -> None:
        """Nothing is recorded."""

    def close(self) -> None:
        """No file."""


def record_robot_model(stack: Harness, recording: McapRecording | NoRecording) -> None:
    """Have ``stack`` record what a viewer draws the robot from into ``recording``:
    ``/robot_description`` (URDF) and ``/tf_static`` (latched: subscribed transient local) and
    ``/tf``, as the simulator publishes them (``/tf`` only where tf2_msgs is installed)."""
    if isinstance(recording, NoRecording):
        return
    stack.record(String, "/robot_description", LATCHED_QOS, raw=True)
    try:
        from tf2_msgs.msg import TFMessage
    except ImportError:  # the simulator publishes no TF then either
        return
    stack.record(TFMessage, "/tf_static", LATCHED_QOS, raw=True)
    stack.record(TFMessage, "/tf", raw=True)


@contextlib.contextmanager
def open_mcap(args, name: str, stack: Harness) -> Iterator[McapRecording | NoRecording]:
    """The bag ``<output>/<name>/`` (``metadata.yaml``, ``<name>_0.mcap``) of the topics
    ``stack`` records, as a :class:`McapRecording` for the block, closed at its end whatever
    ends it (:class:`NoRecording` with ``--no-record``)."""
    if args.no_record:
        yield NoRecording()
        return
    probe = stack.probe()
    with McapRecording(
        (output_folder(args) / name).resolve(),
        probe.resolve_topic_name,
        offers=lambda topic: offered_profiles(probe, topic),
        bag=True,
    ) as recording:
        yield recording
