"""``ros2 bag record`` for rclpy alone: a node that subscribes to topics as their publishers
appear, with the QoS rosbag2 would ask for, and writes what arrives to a :class:`BagWriter`.

Each topic's type is learnt from the graph; its publishers' QoS, at the moment it is subscribed,
is recorded as the topic's ``offered_qos_profiles``. The subscription is reliable when every
publisher is, transient local when every publisher is (so ``/tf_static`` and
``/robot_description``, published once before the recorder started, are recorded too), and
keeps at least :data:`MIN_DEPTH` messages (a Python recorder falls behind a C++ one sooner).
Messages are stored as received (serialized), stamped with their receipt time and their
publisher's source time.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor

from rns_ros.bag.definitions import DefinitionError
from rns_ros.bag.metadata import BagError
from rns_ros.bag.qos import request_profile
from rns_ros.bag.ros import message_class, offered_profiles, qos_of
from rns_ros.bag.writer import BagWriter

#: Least history kept by each recording subscription [messages].
MIN_DEPTH = 1000
#: How often the graph is searched for new topics [s] (rosbag2's topic polling interval).
DISCOVERY_PERIOD = 0.1
NODE_NAME = "rns_bag_recorder"


def hidden(topic: str) -> bool:
    """A hidden topic: a name token starting with ``_`` (service events, action internals)."""
    return any(token.startswith("_") for token in topic.split("/") if token)


class Recorder:
    """Records ``topics`` (None: every topic, ``-a``) of the graph into ``writer``.

    Args:
        writer: the bag.
        topics: topic names (relative ones resolved as a node in ``/`` would), or None for all.
        include_hidden: with ``topics=None``, hidden topics too.
        context: the rclpy Context (initialized by the caller).
        say: called with each line to tell the user (a topic subscribed, one skipped).

    Raises:
        BagError (from :meth:`spin`): a named topic's type is not installed, or has no
            definition.
    """

    def __init__(
        self,
        writer: BagWriter,
        topics: Iterable[str] | None,
        *,
        include_hidden: bool = False,
        context: Context | None = None,
        say: Callable[[str], None] = print,
    ) -> None:
        self.writer = writer
        self.node = rclpy.create_node(NODE_NAME, context=context)
        self.wanted = None if topics is None else {self.node.resolve_topic_name(t) for t in topics}
        self.include_hidden = include_hidden
        self.say = say
        self.subscribed: dict[str, str] = {}  # topic -> type
        self._skipped: set[str] = set()
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.node.create_timer(DISCOVERY_PERIOD, self.discover)

    def discover(self) -> None:
        """Subscribe to each wanted topic that has publishers and is not recorded yet."""
        for topic, types in self.node.get_topic_names_and_types():
            if topic in self.subscribed or topic in self._skipped or not types:
                continue
            if self.wanted is None:
                if hidden(topic) and not self.include_hidden:
                    continue
            elif topic not in self.wanted:
                continue
            offers = offered_profiles(self.node, topic)
            if not offers:
                continue  # only subscribers so far: their publishers' QoS is not known yet
            if len(types) > 1:
                self.say(f"rns_bag: {topic} has {len(types)} types {types}; recording {types[0]}")
            try:
                self._subscribe(topic, types[0], offers)
            except (BagError, DefinitionError) as exc:
                if self.wanted is not None:
                    raise BagError(f"{topic}: {exc}") from None
                self._skipped.add(topic)
                self.say(f"rns_bag: {topic} not recorded: {exc}")

    def _subscribe(self, topic: str, type_name: str, offers: list) -> None:
        msg_type = message_class(type_name)
        entry = self.writer.add_topic(topic, type_name, offers)

        def received(data: bytes, info) -> None:
            info = info if isinstance(info, dict) else {}
            log_time = int(info.get("received_timestamp") or 0) or time.time_ns()
            self.writer.write(entry, data, log_time, int(info.get("source_timestamp") or 0))

        qos = qos_of(request_profile(offers, MIN_DEPTH))
        self.node.create_subscription(msg_type, topic, received, qos, raw=True)
        self.subscribed[topic] = type_name
        self.say(f"rns_bag: subscribed to {topic} ({type_name})")

    def spin(self, duration: float | None = None) -> None:
        """Record until Ctrl-C (KeyboardInterrupt), or for ``duration`` [s] of wall time."""
        if duration is None:
            self.executor.spin()
            return
        deadline = time.monotonic() + duration
        while (left := deadline - time.monotonic()) > 0.0:
            self.executor.spin_once(timeout_sec=min(left, 0.1))

    def close(self) -> None:
        """Destroy the node (the writer is the caller's to close)."""
        self.executor.remove_node(self.node)
        self.node.destroy_node()
        self.executor.shutdown()
