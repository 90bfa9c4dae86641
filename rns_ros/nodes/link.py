"""rns_link: a simulated space link between the ground and the spacecraft.

Each topic of ``uplink_topics`` is taken from the ground's side, ``/<ground_namespace>/<topic>``,
and handed on to the spacecraft's, ``<topic>`` in the node's namespace, after the uplink's delay
(:class:`rns_ros.ground.link.LinkChannel`: delay, jitter, loss, bandwidth cap, the scheduled
``outages``, order kept); ``downlink_topics`` go the other way. Messages are carried as their
serialized bytes, so every field (the header stamp: a command's issue time, a measurement's
time) arrives as sent.

With ``ground_domain_id`` (>= 0, not the node's own domain) the ground's side is on that ROS
domain, as a ground station's network is apart from the spacecraft's: the node opens a second
Context there (a node ``rns_link_ground``, spun in its own thread) and the ground's topics,
still ``/<ground_namespace>/<topic>``, are that domain's.

Times are the node clock's: simulated time under ``use_sim_time`` (a lockstep run delays by
simulated seconds), else the wall clock. Due messages are handed on every ``release_period``.
A message larger than ``max_message_size``, or one more than ``max_in_flight`` waiting in its
direction (a flood), is refused and counted, never queued.

Subscribes:
    /<ground_namespace>/<topic>   each uplink topic (best effort, 1000 deep: matches any sender)
    <topic>                       each downlink topic
Publishes:
    <topic>                       each uplink topic, reliable (matches any receiver)
    /<ground_namespace>/<topic>   each downlink topic, reliable
    ~/status                      diagnostic_msgs/DiagnosticArray every ``status_period``: per
                                  direction sent, delivered, lost (of them in an outage),
                                  refused, in flight, last and largest delay [s]; WARN while an
                                  outage lasts
"""

from __future__ import annotations

import contextlib
import importlib
import threading

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy._rclpy_pybind11 import RCLError
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions

from rns_ros.core.errors import ConfigError
from rns_ros.ground.link import LinkChannel, LinkSettings, parse_outages, parse_topic
from rns_ros.nodes import link_parameters
from rns_ros.nodes.parameters import declare_parameters
from rns_ros.nodes.runner import run_node

#: Taken from any sender: best effort matches reliable and best-effort publishers.
RECEIVE_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT)
#: Handed on reliably: matches reliable and best-effort subscribers.
SEND_QOS = QoSProfile(depth=1000)


def message_class(type_name: str) -> type:
    """The message class of ``'package/msg/Type'``.

    Raises:
        ConfigError: the package or the type is not installed.
    """
    package, _, name = type_name.split("/")
    try:
        return getattr(importlib.import_module(f"{package}.msg"), name)
    except (ImportError, AttributeError):
        raise ConfigError(f"message type {type_name} is not installed in this Python") from None


class _Direction:
    """One direction of the link on ``node``: its channel, subscriptions and publishers."""

    def __init__(
        self,
        node: Node,
        name: str,
        params: dict,
        outages: tuple[tuple[float, float], ...],
        ground: str,
        ground_node: Node,
    ) -> None:
        self.name = name
        self._node = node
        # the ground node's callbacks may run in its own thread (another domain)
        self._lock = threading.Lock()
        self.channel = LinkChannel(
            LinkSettings(
                delay=params[f"{name}_delay"],
                jitter=params[f"{name}_jitter"],
                loss=params[f"{name}_loss"],
                bandwidth=params[f"{name}_bandwidth"],
                outages=outages,
                seed=params["seed"] + (0 if name == "uplink" else 1),
            )
        )
        self._max_in_flight = params["max_in_flight"]
        self._max_size = params["max_message_size"]
        self.refused = 0
        self._publishers = []
        topics = params[f"{name}_topics"]
        if len(topics) > link_parameters.MAX_TOPICS:
            raise ConfigError(
                f"{name}_topics: at most {link_parameters.MAX_TOPICS} topics, got {len(topics)}"
            )
        self.routes = []
        self.giver = node if name == "uplink" else ground_node
        for index, spec in enumerate(topics):
            topic, type_name = parse_topic(spec)
            cls = message_class(type_name)
            on_ground = f"/{ground}/{topic.lstrip('/')}"
            source, sink = (on_ground, topic) if name == "uplink" else (topic, on_ground)
            taker, giver = (ground_node, node) if name == "uplink" else (node, ground_node)
            taker.create_subscription(
                cls, source, lambda data, i=index: self._take(i, data), RECEIVE_QOS, raw=True
            )
            self._publishers.append(giver.create_publisher(cls, sink, SEND_QOS))
            self.routes.append(f"{_where(taker, source, node)} -> {_where(giver, sink, node)}")

    def _take(self, index: int, data: bytes) -> None:
        with self._lock:
            self._take_locked(index, data)

    def _take_locked(self, index: int, data: bytes) -> None:
        if len(data) > self._max_size or self.channel.in_flight >= self._max_in_flight:
            self.refused += 1
            self._node.get_logger().warn(
                f"{self.name}: a message of {len(data)} B refused (max_message_size "
                f"{self._max_size} B, {self.channel.in_flight} in flight of max_in_flight "
                f"{self._max_in_flight})",
                throttle_duration_sec=1.0,
            )
            return
        self.channel.send(self._node.now_s(), (index, data), len(data))

    def release(self, now: float) -> None:
        with self._lock:
            due = self.channel.deliver(now)
        for item in due:
            index, data = item.message
            self._publishers[index].publish(data)

    def status(self) -> list[KeyValue]:
        with self._lock:
            return self._status()

    def _status(self) -> list[KeyValue]:
        counts = self.channel.counts
        values = {
            "sent": counts.sent,
            "delivered": counts.delivered,
            "lost": counts.lost,
            "lost in outage": counts.lost_in_outage,
            "refused": self.refused,
            "in flight": self.channel.in_flight,
            "last delay [s]": f"{counts.last_delay:.4f}",
            "max delay [s]": f"{counts.max_delay:.4f}",
        }
        return [
            KeyValue(key=f"{self.name} {key}", value=str(value)) for key, value in values.items()
        ]


def _where(node: Node, topic: str, home: Node) -> str:
    """``topic`` as ``node`` resolves it, with ``node``'s domain when it is not ``home``."""
    name = node.resolve_topic_name(topic)
    return name if node is home else f"{name} (domain {node.context.get_domain_id()})"


class _GroundSide:
    """The ground's side on its own ROS domain: a node in a Context of that domain, spun by
    its own executor in a thread (a Context's nodes take its executor only)."""

    def __init__(self, domain: int) -> None:
        self.context = rclpy.Context()
        # rclpy's signal handlers stay out: the node's runner owns Ctrl-C and SIGTERM
        rclpy.init(
            context=self.context, domain_id=domain, signal_handler_options=SignalHandlerOptions.NO
        )
        try:
            self.node = Node(f"{link_parameters.NODE_NAME}_ground", context=self.context)
            self.executor = SingleThreadedExecutor(context=self.context)
            self.executor.add_node(self.node)
        except BaseException:
            self.context.try_shutdown()
            raise
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, name="rns_link ground", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        with contextlib.suppress(ExternalShutdownException, RCLError):
            while not self._stop.is_set() and self.context.ok():
                self.executor.spin_once(timeout_sec=0.05)

    def close(self) -> None:
        """Stop the thread, then the node, then the Context."""
        self._stop.set()
        self._thread.join(timeout=5.0)
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        self.context.try_shutdown()


class LinkNode(Node):
    """ROS 2 wrapper of two :class:`LinkChannel` (module docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(link_parameters.NODE_NAME, **node_kwargs)
        params = declare_parameters(self, link_parameters.PARAMETERS)
        ground = params["ground_namespace"].strip("/")
        if not ground:
            raise ConfigError("ground_namespace must not be empty (the two sides would be one)")
        self._outages = parse_outages(params["outages"])
        domain = params["ground_domain_id"]
        self._ground = None
        if domain >= 0 and domain != self.context.get_domain_id():
            self._ground = _GroundSide(domain)
        ground_node = self if self._ground is None else self._ground.node
        try:
            self._directions = [
                _Direction(self, name, params, self._outages, ground, ground_node)
                for name in ("uplink", "downlink")
            ]
        except BaseException:
            self._close_ground()
            raise
        self._down = False
        self._status_pub = self.create_publisher(DiagnosticArray, "~/status", QoSProfile(depth=10))
        self.create_timer(params["release_period"], self._on_release)
        if self._ground is not None:  # the ground's publishers are used from its thread only
            self._ground.node.create_timer(
                params["release_period"], lambda: self._release(self._ground.node, self.now_s())
            )
        self.create_timer(params["status_period"], self._on_status)
        for direction in self._directions:
            settings = direction.channel.settings
            self.get_logger().info(
                f"{direction.name} {settings.delay:g} s (+ up to {settings.jitter:g} s jitter, "
                f"loss {settings.loss:g}): {', '.join(direction.routes) or 'no topics'}"
            )

    def _close_ground(self) -> None:
        if self._ground is not None:
            self._ground.close()
            self._ground = None

    def destroy_node(self) -> None:
        self._close_ground()
        super().destroy_node()

    def now_s(self) -> float:
        """The node clock [s]."""
        return self.get_clock().now().nanoseconds * 1e-9

    def _release(self, giver: Node, now: float) -> None:
        """Hand on the messages due at ``now`` [s] of the directions ``giver`` publishes."""
        for direction in self._directions:
            if direction.giver is giver:
                direction.release(now)

    def _on_release(self) -> None:
        now = self.now_s()
        self._release(self, now)
        down = self._directions[0].channel.settings.down(now)
        if down != self._down:
            self._down = down
            if down:
                self.get_logger().warn(f"outage: no contact from {now:.3f} s")
            else:
                self.get_logger().info(f"contact again at {now:.3f} s after an outage")

    def _on_status(self) -> None:
        status = DiagnosticStatus(
            name=self.get_fully_qualified_name(),
            level=DiagnosticStatus.WARN if self._down else DiagnosticStatus.OK,
            message="OUTAGE" if self._down else "OK",
            values=[value for direction in self._directions for value in direction.status()],
        )
        message = DiagnosticArray(status=[status])
        message.header.stamp = self.get_clock().now().to_msg()
        self._status_pub.publish(message)


def main(args=None) -> int:
    return run_node(LinkNode, link_parameters, args)


if __name__ == "__main__":
    raise SystemExit(main())
