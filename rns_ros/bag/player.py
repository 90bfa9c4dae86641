"""``ros2 bag play`` for rclpy alone: a bag's messages published again with their timing.

Each topic gets a publisher with the QoS rosbag2's player restores from the recorded offers
(:func:`rns_ros.bag.qos.playback_profile`: the recorded profile when the publishers agreed,
history keep_last 10). Message ``k`` is published ``(t_k - t_0) / rate`` after playback
started, ``t`` being its receipt time in the bag; with a clock rate, ``/clock`` carries the
bag's time (``t_0`` plus the elapsed wall time times ``rate``) that often, as
``ros2 bag play --clock`` does, but never past the next message to publish: a player that runs
late (a busy machine) holds the clock at that message's time until it is out, so no message
arrives older than a clock already sent, and the last clock is at most the bag's end.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable

import rclpy
from builtin_interfaces.msg import Time as TimeMsg
from rclpy.context import Context
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

from rns_ros.bag.metadata import BagError
from rns_ros.bag.qos import playback_profile
from rns_ros.bag.reader import Bag
from rns_ros.bag.ros import message_class, qos_of

NODE_NAME = "rns_bag_player"
#: rclcpp::ClockQoS: the last clock only, best effort.
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)


def check_rate(rate: float, what: str = "--rate") -> float:
    """``rate`` if it is a finite number > 0.

    Raises:
        BagError: it is not.
    """
    if not (isinstance(rate, int | float) and math.isfinite(rate) and rate > 0.0):
        raise BagError(f"{what} must be a finite number > 0, got {rate}")
    return float(rate)


def message_classes(bag: Bag, topics: Iterable[str] | None = None) -> dict[str, type]:
    """The message class of each of ``topics`` (default: every topic of ``bag``).

    Raises:
        BagError: a topic not in the bag, or a message type that is not installed.
    """
    known = bag.topics
    classes = {}
    for name in known if topics is None else topics:
        if name not in known:
            raise BagError(f"{name} is not in {bag.path} (its topics: {', '.join(known)})")
        try:
            classes[name] = message_class(known[name].type)
        except BagError as exc:
            raise BagError(f"{name}: {exc}") from None
    return classes


class Player:
    """Publishes ``bag`` (its ``topics``, default all) once or in a loop.

    Args:
        rate: playback speed (2: twice as fast).
        clock_hz: publish ``/clock`` this often [Hz] (0: not).
        context: the rclpy Context (initialized by the caller).

    Raises:
        BagError: a bad rate, a topic not in the bag, or a message type that is not installed.
    """

    def __init__(
        self,
        bag: Bag,
        *,
        rate: float = 1.0,
        clock_hz: float = 0.0,
        topics: Iterable[str] | None = None,
        context: Context | None = None,
    ) -> None:
        self.bag = bag
        self.rate = check_rate(rate)
        self.clock_period = 1.0 / check_rate(clock_hz, "--clock") if clock_hz else None
        known = bag.topics
        classes = message_classes(bag, topics)
        self.topics = list(classes)
        self.node = rclpy.create_node(NODE_NAME, context=context)
        self.publishers = {
            name: self.node.create_publisher(
                classes[name], name, qos_of(playback_profile(known[name].offered_qos_profiles))
            )
            for name in self.topics
        }
        self.clock = self.node.create_publisher(Clock, "/clock", CLOCK_QOS) if clock_hz else None
        self.published = 0

    def play_once(self) -> int:
        """Publish every message once with its timing; returns how many."""
        start_wall = time.monotonic()
        start_bag = None
        next_clock = start_wall
        count = 0
        for message in self.bag.messages(self.topics):
            if start_bag is None:
                start_bag = message.log_time
            due = start_wall + (message.log_time - start_bag) / 1e9 / self.rate
            while True:
                now = time.monotonic()
                if self.clock is not None and now >= next_clock:
                    self._tick(start_bag, start_wall, now, message.log_time)
                    # a late tick is not made up for: no burst of clocks after a stall
                    next_clock += self.clock_period
                    if next_clock <= now:
                        next_clock = now + self.clock_period
                    continue
                if now >= due:
                    break
                wake = due if self.clock is None else min(due, next_clock)
                time.sleep(max(wake - now, 0.0))
            self.publishers[message.topic].publish(bytes(message.data))
            count += 1
            self.published += 1
        return count

    def _tick(self, start_bag: int, start_wall: float, now: float, upcoming: int) -> None:
        """Publish the bag's time [ns] at wall time ``now`` [s], held at ``upcoming`` (the
        next message's bag time [ns]) while that message is late."""
        stamp = min(start_bag + round((now - start_wall) * self.rate * 1e9), upcoming)
        self.clock.publish(
            Clock(clock=TimeMsg(sec=stamp // 1_000_000_000, nanosec=stamp % 1_000_000_000))
        )

    def close(self) -> None:
        self.node.destroy_node()
