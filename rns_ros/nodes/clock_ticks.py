"""Periodic ticks on simulated time, driven by /clock itself instead of an rclpy timer.

Under ``use_sim_time`` the experimental events executor (the one :mod:`rns_ros.nodes.runner`
spins) can run a sim-time timer two or three times for one /clock message, advancing its
schedule as many periods, and then skip the periods it ran ahead: in a fast lockstep run the
operator's 50 Hz twists came 0, 30, 40 or 50 ms apart about 40 times in 20 s, and a controller
stamping its outputs a period ahead missed ticks (a stalled lockstep period) or repeated them.
:class:`ClockTicks` calls back once for every period instant the node's clock passes as /clock
sets it, on a grid that starts at the first reading.
"""

from __future__ import annotations

from collections.abc import Callable

from rclpy.clock import JumpThreshold, TimeJump
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.time import Time

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
    """Calls ``callback(instant)`` for each period instant the node's sim-time clock passes (see
    :func:`due_ticks`, at most ``max_ticks`` per reading); ``instant`` is a
    :class:`rclpy.time.Time` of the node's clock type. For nodes with ``use_sim_time``.

    The ticks ride on the /clock subscription rclpy's TimeSource already has: a jump callback on
    the node's clock runs after each /clock reading sets the time (any jump, forward or back).
    A second /clock subscription of its own cost each node a delivery and a callback per period
    and the simulator one more reader to publish to, which in a lockstep run as fast as possible
    was several percent of its CPU. TimeSource keeps only the newest /clock (depth 1), so a node
    that fell k periods behind reads one time k periods on: ``max_ticks`` says how many missed
    instants it still serves in order (beyond that the grid restarts at the reading).

    Keep the object: the jump callback lives as long as it does (:meth:`destroy` ends it).
    """

    def __init__(
        self,
        node: Node,
        period: float,
        callback: Callable[[Time], None],
        max_ticks: int = MAX_TICKS,
    ) -> None:
        if not period > 0.0:
            raise ConfigError(f"tick period must be > 0 s, got {period!r}")
        if max_ticks < 1:
            raise ConfigError(f"max_ticks must be >= 1, got {max_ticks!r}")
        self._period = round(period * 1e9)
        self._max_ticks = max_ticks
        self._callback = callback
        self._clock = node.get_clock()
        self._clock_type = self._clock.clock_type
        self.last: int | None = None  # newest instant served [ns]
        self._handle = self._clock.create_jump_callback(
            JumpThreshold(
                min_forward=Duration(nanoseconds=1),
                min_backward=Duration(nanoseconds=-1),
                on_clock_change=False,
            ),
            post_callback=self._on_time_set,
        )

    def _on_time_set(self, _jump: TimeJump) -> None:
        now = self._clock.now().nanoseconds
        for instant in due_ticks(self.last, now, self._period, self._max_ticks):
            self.last = instant
            self._callback(Time(nanoseconds=instant, clock_type=self._clock_type))

    def destroy(self) -> None:
        """Stop ticking (unregisters the jump callback)."""
        if self._handle is not None:
            self._handle.unregister()
            self._handle = None


__all__ = ["MAX_TICKS", "ClockTicks", "due_ticks"]
