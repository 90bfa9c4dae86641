"""The clock a node's input watchdogs judge ages by, and the wall-clock watch over ``/clock``.

Under ``use_sim_time`` ages are simulated time, as ROS 2 timers count it: a simulation that a
busy machine delays, or that pauses in lockstep for a late controller, does not age the node's
inputs. A ``/clock`` that stops (a dead simulator) stops simulated time for every watchdog too,
so :class:`InputClock` also checks on the wall clock that it moves
(:class:`rns_ros.control.watchdog.ClockWatch`) and calls the node's ``on_clock_stopped`` with how
long it has stood still. On the wall clock, ages are monotonic wall time.

A node that passes ``on_clock_fault`` is also told when simulated time cannot be trusted
(:class:`rns_ros.control.watchdog.ClockJumps`): a /clock reading that goes back or jumps forward
farther than ``max_clock_jump`` (a jump callback on the node's clock, called by rclpy only for
such readings), or more than one /clock publisher (the graph, read once a second of wall time
and at each faulty reading). The callback gets one line naming the publishers when a fault
begins; :meth:`InputClock.clock_fault` says whether it lasts.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

from rclpy.clock import Clock, ClockType, JumpThreshold, TimeJump
from rclpy.duration import Duration
from rclpy.node import Node
from rosgraph_msgs.msg import Clock as ClockMsg

from rns_ros.control.ticks import COMMANDS, AwaitedTicks
from rns_ros.control.watchdog import DEFAULT_MAX_CLOCK_JUMP, ClockJumps, ClockWatch
from rns_ros.nodes.status import node_names, type_name

#: Checks of /clock per clock_timeout [-].
CHECKS_PER_TIMEOUT = 4
#: The topic rclpy's TimeSource reads simulated time from.
CLOCK_TOPIC = "/clock"
#: Period of the graph check of who publishes /clock [s] (wall clock).
CLOCK_GRAPH_PERIOD = 1.0


class InputClock:
    """Receipt times and ages for a node's input watchdogs.

    Args:
        node: the node (its ``use_sim_time`` parameter decides the clock).
        clock_timeout: under ``use_sim_time``, wall time [s] /clock may stand still (once it
            has moved) before ``on_clock_stopped`` is called, again every check while it
            stands still.
        on_clock_stopped: called with the wall time [s] /clock has stood still.
        on_clock_fault: under ``use_sim_time``, called with one line (what is wrong, the
            publishers of /clock) when simulated time stops being trustworthy (see the module
            docstring); None: not watched.
        max_clock_jump: the largest forward step of one /clock reading [s], > 0.

    Raises:
        ConfigError: ``max_clock_jump`` is not a finite number > 0.
    """

    def __init__(
        self,
        node: Node,
        clock_timeout: float,
        on_clock_stopped: Callable[[float], None],
        *,
        on_clock_fault: Callable[[str], None] | None = None,
        max_clock_jump: float = DEFAULT_MAX_CLOCK_JUMP,
    ) -> None:
        self._node = node
        self.sim_time = bool(node.get_parameter("use_sim_time").value)
        self._on_stopped = on_clock_stopped
        self.timeout = clock_timeout
        self._watch: ClockWatch | None = None
        self._timer = None
        self._on_fault = on_clock_fault
        self._jumps: ClockJumps | None = None
        self._jump_handle = None
        self._faulted = False  # a fault was reported and has not ended since
        if self.sim_time:
            steady = Clock(clock_type=ClockType.STEADY_TIME)
            self._watch = ClockWatch(clock_timeout)
            self._timer = node.create_timer(
                clock_timeout / CHECKS_PER_TIMEOUT, self._check, clock=steady
            )
            if on_clock_fault is not None:
                self._jumps = ClockJumps(max_clock_jump, CLOCK_TOPIC)
                self._watch_jumps()
                node.create_timer(CLOCK_GRAPH_PERIOD, self._check_publishers, clock=steady)

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

    def clock_fault(self) -> str | None:
        """Why simulated time cannot be trusted now (one line), or None: it can, or faults are
        not watched. Once it reads None, the next fault is reported to ``on_clock_fault``."""
        if self._jumps is None:
            return None
        fault = self._jumps.fault(self._node.get_clock().now().nanoseconds)
        if fault is None:
            self._faulted = False
        return fault

    def _watch_jumps(self) -> None:
        """Register the jump callback: rclpy calls it for readings that go back at all or
        forward by at least max_clock_jump, before the jump callbacks registered later (the
        ticks of :class:`rns_ros.nodes.clock_ticks.ClockTicks`): create this object first."""
        self._jump_handle = self._node.get_clock().create_jump_callback(
            JumpThreshold(
                min_forward=Duration(nanoseconds=max(round(self._jumps.max_jump * 1e9), 1)),
                min_backward=Duration(nanoseconds=-1),
                on_clock_change=False,
            ),
            post_callback=self._on_jump,
        )

    def _on_jump(self, jump: TimeJump) -> None:
        after = self._node.get_clock().now().nanoseconds
        if self._jumps.jump(after - jump.delta.nanoseconds, after):
            self._check_publishers()

    def _check_publishers(self) -> None:
        """Read who publishes /clock; report a fault that begins."""
        infos = self._node.get_publishers_info_by_topic(CLOCK_TOPIC)
        clock_type = type_name(ClockMsg)
        self._jumps.publishers(node_names(i for i in infos if i.topic_type == clock_type))
        fault = self.clock_fault()
        if fault is not None and not self._faulted:
            self._faulted = True
            self._on_fault(fault)

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
