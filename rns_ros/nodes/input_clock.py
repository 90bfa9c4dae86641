"""The clock a node's input watchdogs judge ages by, and the wall-clock watch over ``/clock``.

Under ``use_sim_time`` ages are simulated time, as ROS 2 timers count it: a simulation that a
busy machine delays, or that pauses in lockstep for a late controller, does not age the node's
inputs. A ``/clock`` that stops (a dead simulator) stops simulated time for every watchdog too,
so :class:`InputClock` also checks on the wall clock that it moves
(:class:`rns_ros.control.watchdog.ClockWatch`) and calls the node's ``on_clock_stopped`` with how
long it has stood still. On the wall clock, ages are monotonic wall time.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

from rclpy.clock import Clock, ClockType
from rclpy.node import Node

from rns_ros.control.ticks import COMMANDS, AwaitedTicks
from rns_ros.control.watchdog import ClockWatch

#: Checks of /clock per clock_timeout [-].
CHECKS_PER_TIMEOUT = 4


class InputClock:
    """Receipt times and ages for a node's input watchdogs.

    Args:
        node: the node (its ``use_sim_time`` parameter decides the clock).
        clock_timeout: under ``use_sim_time``, wall time [s] /clock may stand still (once it
            has moved) before ``on_clock_stopped`` is called, again every check while it
            stands still.
        on_clock_stopped: called with the wall time [s] /clock has stood still.
    """

    def __init__(
        self,
        node: Node,
        clock_timeout: float,
        on_clock_stopped: Callable[[float], None],
    ) -> None:
        self._node = node
        self.sim_time = bool(node.get_parameter("use_sim_time").value)
        self._on_stopped = on_clock_stopped
        self.timeout = clock_timeout
        self._watch: ClockWatch | None = None
        self._timer = None
        if self.sim_time:
            self._watch = ClockWatch(clock_timeout)
            self._timer = node.create_timer(
                clock_timeout / CHECKS_PER_TIMEOUT,
                self._check,
                clock=Clock(clock_type=ClockType.STEADY_TIME),
            )

    def now(self) -> float:
        """[s]: the node clock (simulated time) under use_sim_time, else monotonic wall time."""
        if self.sim_time:
            return self._node.get_clock().now().nanoseconds * 1e-9
        return time.monotonic()

    def receipt_time(self, stamp: float | None = None) -> float:
        """[s] to note as a message's receipt time: :meth:`now`; under use_sim_time before the
        first /clock (the clock reads 0), the message's header ``stamp`` [s] when given (a
        simulator publishes a state before its /clock; a node joining a running simulation
        would otherwise judge its first state as old as the simulated time)."""
        now = self.now()
        if self.sim_time and now == 0.0 and stamp is not None:
            return stamp
        return now

    def set_clock_timeout(self, clock_timeout: float) -> None:
        """A new clock_timeout [s] (a parameter change); the checks follow its period."""
        self.timeout = clock_timeout
        if self._watch is not None:
            self._watch.timeout = clock_timeout
            self._timer.timer_period_ns = round(clock_timeout / CHECKS_PER_TIMEOUT * 1e9)
            self._timer.reset()  # the next check one new period from now, not at the old one

    def _check(self) -> None:
        still = self._watch.check(self._node.get_clock().now().nanoseconds)
        if still is not None:
            self._on_stopped(still)


def awaited_commands(
    node: Node,
    command_timeout: float,
    on_timeout: Callable[[], None],
    streams: Sequence[str] = (COMMANDS,),
) -> AwaitedTicks:
    """``await_commands``: ticks that wait for the commands in force on ``streams``, given up
    after ``command_timeout`` [s] of wall time without a sample (``on_timeout``): a stalled or
    dead operator is caught however the simulation runs. The watchdog is a steady-clock timer,
    created stopped; :class:`AwaitedTicks` starts it while a tick waits."""
    watchdog = node.create_timer(
        command_timeout, on_timeout, clock=Clock(clock_type=ClockType.STEADY_TIME)
    )
    watchdog.cancel()
    return AwaitedTicks(watchdog, streams=streams)
