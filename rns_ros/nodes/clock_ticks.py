"""Periodic ticks on simulated time, driven by /clock itself instead of an rclpy timer.

Under ``use_sim_time`` the experimental events executor (the one :mod:`rns_ros.nodes.runner`
spins) can run a sim-time timer two or three times for one /clock message, advancing its
schedule as many periods, and then skip the periods it ran ahead: in a fast lockstep run the
operator's 50 Hz twists came 0, 30, 40 or 50 ms apart about 40 times in 20 s, and a controller
stamping its outputs a period ahead missed ticks (a stalled lockstep period) or repeated them.
:class:`ClockTicks` subscribes to /clock and calls back once for every period instant the clock
passes, on a grid that starts at the first /clock it receives.
"""

from __future__ import annotations

from collections.abc import Callable

from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time import Time
from rosgraph_msgs.msg import Clock

from rns_ros.core.errors import ConfigError

#: At most this many instants from one /clock message: two messages handed over at once are
#: caught up; farther behind (a paused or reset clock) the grid restarts at the new time.
MAX_TICKS = 2


def due_ticks(last: int | None, now: int, period: int, max_ticks: int = MAX_TICKS) -> list[int]:
    """Period instants [ns] due when the clock reads ``now`` [ns], the last one served being
    ``last`` [ns] (None: none yet) and the period ``period`` [ns] > 0.

    A clock within a quarter period of an instant counts as on it (stamps are nanosecond
    integers). Returns [] when no instant was passed (a repeated /clock, or one between two
    instants), the instants after ``last`` up to ``now`` in order (at most ``max_ticks``), or
    [now] to restart the grid (the first /clock, a clock that went back or jumped farther).
    """
    if last is None or now < last:
        return [now]
    passed = (now - last + period // 4) // period
    if passed <= 0:
        return []
    if passed > max_ticks:
        return [now]
    return [last + k * period for k in range(1, passed + 1)]


class ClockTicks:
    """Calls ``callback(instant)`` for each period instant /clock passes (see
    :func:`due_ticks`); ``instant`` is a :class:`rclpy.time.Time` of the node's clock type.

    The subscription is best effort with depth 10: it matches reliable and best-effort /clock
    publishers, and a burst of messages is taken in order.
    """

    def __init__(self, node: Node, period: float, callback: Callable[[Time], None]) -> None:
        if not period > 0.0:
            raise ConfigError(f"tick period must be > 0 s, got {period!r}")
        self._period = round(period * 1e9)
        self._callback = callback
        self._clock_type = node.get_clock().clock_type
        self.last: int | None = None  # newest instant served [ns]
        node.create_subscription(
            Clock,
            "/clock",
            self._on_clock,
            QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT),
        )

    def _on_clock(self, msg: Clock) -> None:
        now = msg.clock.sec * 1_000_000_000 + msg.clock.nanosec
        for instant in due_ticks(self.last, now, self._period):
            self.last = instant
            self._callback(Time(nanoseconds=instant, clock_type=self._clock_type))


__all__ = ["MAX_TICKS", "ClockTicks", "due_ticks"]
