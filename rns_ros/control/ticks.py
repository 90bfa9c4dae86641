"""Control ticks on the node clock: the instant each tick serves and the command in force there.

Pure logic (no ROS), used by the ``rns_controller`` and ``rns_force_controller`` nodes:

* :class:`TickInstants` keeps the last tick served (the hold it ended) and, with ``output_lead``
  (lockstep side by side on simulated time), moves a late tick to the state's instant.
* :class:`CommandSchedule` holds one stream of commands stamped ahead of simulated time until
  their stamps, and says when a tick knows which command is in force; :class:`AwaitedTicks` keeps
  the ticks that wait for it (``await_commands``) on one stream or several (a twist and a force
  setpoint: a tick is served once the command in force is known on every stream), under a
  wall-clock watchdog.
* :func:`next_tick_in` checks a timer's time to its next call; :class:`TickLateness` adds the
  timer's mean lateness to it: the hold a wall-clock tick's output is told.

Instants are integer nanoseconds of the node clock (the stamps the node publishes, exactly);
durations are seconds. Clocks and timers are injected.
"""

from __future__ import annotations

import heapq
import math
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import Generic, NamedTuple, Protocol, TypeVar

from rns_ros.core.errors import ConfigError

#: output_lead: a state stamped up to this far [s] past a tick is caught up to (the simulation
#: ran ahead of the ticks); farther is another clock, not a lag.
MAX_LEAD_CATCH_UP = 1.0
#: A timer's next call farther than this many periods away is not on its grid [-].
MAX_TIMER_DELAY = 1.5
#: The stream of a single-stream :class:`AwaitedTicks` (rns_controller's cmd_twist).
COMMANDS = "commands"
#: Weight of the newest call in :class:`TickLateness`'s running mean [-]: about the last
#: 1 / LATENESS_SMOOTHING calls (0.2 s at 100 Hz) count, so the mean follows a machine that
#: gets busier within a fraction of a second and one late call moves it little.
LATENESS_SMOOTHING = 0.05

Item = TypeVar("Item")


def next_tick_in(until_next_call: int | None, period: float) -> float | None:
    """Time until a periodic timer's next call [s] from its ``until_next_call`` [ns] (None: the
    timer is cancelled), or None when it is not in (0, MAX_TIMER_DELAY * ``period``] (a
    cancelled or badly late timer: the caller assumes the period)."""
    if until_next_call is None:
        return None
    seconds = until_next_call * 1e-9
    return seconds if 0.0 < seconds <= MAX_TIMER_DELAY * period else None


class TickLateness:
    """The hold of a periodic timer's output: until the next call, which comes late on average.

    A timer is called at its grid instants g_k, each call late by delta_k >= 0 (a busy executor
    is late, never early), and the output of a call acts until the next one. The midpoint hold
    (:meth:`ReactionlessController.step`) is reactionless to second order for the hold it is
    told; told g_(k+1) - t_k, every hold runs delta_(k+1) longer, and the residue
    M'(theta_dot, theta_dot) h delta / 2 of each has one sign along the motion, so the base turns
    in proportion to the mean lateness. The hold told is g_(k+1) - t_k plus the running mean of
    the calls' lateness, which cancels the mean part (the figures: docs/controller.md, "Late
    ticks on a busy machine"; :func:`rns_ros.analysis.delayed_loop.run_delayed_loop`).

    Args:
        period: the timer's period T [s], > 0.
        smoothing: weight of the newest call in the mean, in (0, 1].
    """

    def __init__(self, period: float, smoothing: float = LATENESS_SMOOTHING) -> None:
        if not period > 0.0:
            raise ConfigError(f"tick period must be > 0 s, got {period!r}")
        if not 0.0 < smoothing <= 1.0:
            raise ConfigError(f"lateness smoothing must be in (0, 1], got {smoothing!r}")
        self.period, self.smoothing = period, smoothing
        self.mean = 0.0  # running mean of the calls' lateness [s], each counted up to T

    def hold(self, until_next_call: int | None) -> float | None:
        """The expected hold [s] of the output of the call being served, from the timer's
        ``until_next_call`` [ns]: the time to its next call (:func:`next_tick_in`) plus the
        mean lateness, this call's (T minus that time, 0 to T) counted in first; None when the
        timer is not on its grid (the caller assumes the period)."""
        seconds = next_tick_in(until_next_call, self.period)
        if seconds is None:
            return None
        late = min(max(self.period - seconds, 0.0), self.period)
        self.mean += self.smoothing * (late - self.mean)
        return seconds + self.mean


class TickInstants:
    """The instants of the control ticks served, and the catch-up of late ticks.

    With ``output_lead`` (lockstep side by side) the simulator runs at most the lead past a tick
    before that tick's output arrives. A state stamped later than that (by half a period more)
    means the simulation got ahead of the ticks (a command reaching it while it ran in real time
    after a reset or a dropped command, a patience step): the tick's output would start late,
    and every later one too, each letting the simulation run one more period (the lockstep
    period counts from the newest command), so the lag would last the whole run and the base
    would turn by the motion made up after the controller had predicted it. Such a tick is
    served at the state's instant (its output acts a lead later, as usual), and the ticks up to
    that instant are skipped. A clock that went back (a reset) starts over, and a state received
    before it, or more than ``max_catch_up`` ahead, is not caught up to.

    Args:
        period: control period T [s], > 0.
        lead: output_lead [s], >= 0 (0: ticks are served at their instants).
        monotonic: the wall clock of receipt times [s].
        max_catch_up: farthest catch-up [s].
    """

    def __init__(
        self,
        period: float,
        lead: float = 0.0,
        monotonic: Callable[[], float] = time.monotonic,
        max_catch_up: float = MAX_LEAD_CATCH_UP,
    ) -> None:
        if not period > 0.0:
            raise ConfigError(f"tick period must be > 0 s, got {period!r}")
        self.period, self.lead = period, lead
        self._monotonic = monotonic
        self._max_catch_up = max_catch_up
        self.last: float | None = None  # node-clock instant of the last tick served [s]
        self.last_wall = -math.inf  # monotonic time the last tick was served [s]
        self._clock_tick: float | None = None  # the newest tick as the clock gave it [s]
        self._clock_back_at = -math.inf  # monotonic time [s] the clock last went back

    def serve(self, instant: int) -> tuple[float, float | None]:
        """Record the tick of ``instant`` [ns] as served now.

        Returns:
            (monotonic time now [s], how long the previous tick's output was held on the node
            clock [s], None for the first tick).
        """
        now, seconds = self._monotonic(), instant * 1e-9
        held = None if self.last is None else seconds - self.last
        self.last_wall, self.last = now, seconds
        return now, held

    def lead_instant(self, tick: int, state_stamp: int | None, state_received: float) -> int | None:
        """With ``output_lead``: the instant [ns] to serve for the clock's tick ``tick`` [ns],
        or None to skip it (served already by a catch-up).

        Args:
            state_stamp: stamp of the newest joint state [ns], None before the first.
            state_received: its monotonic receipt time [s].
        """
        seconds = tick * 1e-9
        previous, self._clock_tick = self._clock_tick, seconds
        if previous is not None and seconds < previous - 0.5 * self.period:
            # the clock went back: states received before are from before the reset
            self._clock_back_at = self._monotonic()
        elif self.last is not None and seconds <= self.last + 1e-9:
            return None  # this instant was served already (caught up past it)
        if state_stamp is not None and state_received > self._clock_back_at:
            ahead = state_stamp * 1e-9 - seconds
            if self.lead + 0.5 * self.period <= ahead <= self._max_catch_up:
                return state_stamp
        return tick


class CommandSchedule(Generic[Item]):
    """Stamped commands released at their stamps, for a controller ticking on simulated time.

    In lockstep the simulation waits for the controller but not for the operator, so a twist
    that acts on receipt acts whenever the operator's process got a core: a few milliseconds of
    wall time are a period or more of simulated time at ten times real time. A scripted operator
    can publish each sample ahead of its instant, stamped with the instant. The controller then
    serves the tick at t with the newest command stamped at or before t, which it knows to be
    the one in force once it holds a command stamped at or after t (:meth:`ready`).

    A command whose stamp goes back (a clock reset, an operator's final stop stamped now)
    replaces everything still waiting: it is the newest word of the operator.

    Stamps are integer nanoseconds of the node clock. At most ``max_waiting`` commands wait: a
    publisher stamping far ahead cannot grow the schedule without bound (the oldest waiting
    command is dropped, and :attr:`dropped` counts it).
    """

    def __init__(self, max_waiting: int = 1000) -> None:
        if max_waiting < 1:
            raise ConfigError(f"max_waiting must be >= 1, got {max_waiting!r}")
        self._waiting: deque[tuple[int, Item]] = deque()
        self._max_waiting = max_waiting
        self.dropped = 0  # commands dropped unreleased (more than max_waiting waited)
        self._newest: int | None = None  # stamp of the newest command received [ns]
        self._moving = False  # the newest command asks for motion
        self._moved = False  # some command asked for motion
        self._released = False  # waiting for a newer command was given up (release_all)

    @property
    def newest(self) -> int | None:
        """Stamp of the newest command received [ns], None before the first."""
        return self._newest

    def push(self, stamp: int, item: Item, moving: bool) -> None:
        """A command stamped ``stamp`` [ns]; ``moving``: it asks for motion (non-zero)."""
        if self._newest is not None and stamp < self._newest:
            self._waiting.clear()
        if len(self._waiting) >= self._max_waiting:
            self._waiting.popleft()
            self.dropped += 1
        self._waiting.append((stamp, item))
        self._newest, self._moving, self._released = stamp, moving, False
        self._moved = self._moved or moving

    def due(self, tick: int) -> list[Item]:
        """The commands stamped at or before ``tick`` [ns], oldest first, taken off the
        schedule (the last one is in force at ``tick``)."""
        return [item for _, item in self.due_stamped(tick)]

    def due_stamped(self, tick: int) -> list[tuple[int, Item]]:
        """:meth:`due` with each command's stamp [ns]: (stamp, command), oldest first."""
        items = []
        while self._waiting and self._waiting[0][0] <= tick:
            items.append(self._waiting.popleft())
        return items

    def ready(self, tick: int) -> bool:
        """True when the command in force at ``tick`` [ns] is known: no command yet (nothing
        to wait for), one stamped at or after ``tick`` received, or :meth:`release_all` since
        the newest; or the newest is a stop after motion (a stream may end on a stop, which
        is then waited on no longer: a scripted profile ends with zeros). Zeros before any
        motion are waited on: a profile starts at rest, and a stall there would skip its
        start."""
        if self._newest is None or self._newest >= tick or self._released:
            return True
        return not self._moving and self._moved

    def release_all(self) -> None:
        """Stop waiting for a newer command until one arrives (the stream stalled or ended)."""
        self._released = True


class Watchdog(Protocol):
    """A one-shot wall-clock alarm (an rclpy timer on the steady clock has this interface)."""

    def reset(self) -> None:
        """(Re)start the countdown."""

    def cancel(self) -> None:
        """Stop the countdown."""


class ServedTick(NamedTuple, Generic[Item]):
    """A tick whose command in force is known (on every stream).

    Attributes:
        instant: the tick [ns].
        commands: the commands stamped up to it (of every stream, merged by stamp), oldest
            first, to apply before serving it.
    """

    instant: int
    commands: list[Item]


class AwaitedTicks(Generic[Item]):
    """Ticks that wait for the commands in force (``await_commands``), oldest first.

    Each of ``streams`` (e.g. ``("cmd_twist", "force_setpoint")``) is a
    :class:`CommandSchedule` of its own; a tick is served once the command in force is known on
    every stream (:meth:`CommandSchedule.ready`), in order: a tick waits while an older one does.
    It is served with the commands stamped up to it from all streams, merged by stamp (equal
    stamps in the order of ``streams``).

    The ``watchdog`` runs while ticks wait. It restarts when the oldest waiting tick changes and
    when a command comes on a stream that tick waits for (the operator is alive); commands on
    the other streams do not restart it, so one stream stalled while another goes on is still
    given up on. Its alarm (:meth:`give_up`) stops waiting for the streams the oldest tick
    waits for and serves the waiting ticks with the newest commands there are.

    Args:
        watchdog: the wall-clock alarm (:class:`Watchdog`), started and stopped here.
        max_waiting: commands each stream holds at most (:class:`CommandSchedule`).
        streams: the names of the command streams, at least one, distinct; the default is the
            single stream :data:`COMMANDS`.

    Raises:
        ConfigError: no stream, or a name twice.
    """

    def __init__(
        self,
        watchdog: Watchdog,
        max_waiting: int = 1000,
        streams: Sequence[str] = (COMMANDS,),
    ) -> None:
        streams = tuple(streams)
        if not streams or len(set(streams)) != len(streams):
            raise ConfigError(f"streams must be at least one distinct name, got {list(streams)}")
        self.schedules: dict[str, CommandSchedule[Item]] = {
            name: CommandSchedule(max_waiting) for name in streams
        }
        self._waiting: deque[int] = deque()
        self._watchdog = watchdog

    @property
    def schedule(self) -> CommandSchedule[Item]:
        """The schedule of the first stream (of a single-stream user, its only one)."""
        return next(iter(self.schedules.values()))

    @property
    def oldest_waiting(self) -> int | None:
        """The oldest tick waiting [ns], None when none waits."""
        return self._waiting[0] if self._waiting else None

    def ready(self, instant: int) -> bool:
        """True when the command in force at ``instant`` [ns] is known on every stream."""
        return all(schedule.ready(instant) for schedule in self.schedules.values())

    def awaited_streams(self) -> list[str]:
        """The streams the oldest waiting tick waits for (none when no tick waits)."""
        if not self._waiting:
            return []
        oldest = self._waiting[0]
        return [name for name, schedule in self.schedules.items() if not schedule.ready(oldest)]

    def tick(self, instant: int) -> list[ServedTick[Item]]:
        """The tick of ``instant`` [ns]: served now (one entry) or waiting ([])."""
        if self._waiting or not self.ready(instant):
            if not self._waiting:
                self._watchdog.reset()
            self._waiting.append(instant)
            return []
        return [ServedTick(instant, self._due(instant))]

    def push(
        self, stamp: int, item: Item, moving: bool, stream: str = COMMANDS
    ) -> list[ServedTick[Item]]:
        """A command stamped ``stamp`` [ns] on ``stream`` (see :meth:`CommandSchedule.push`);
        returns the waiting ticks it makes ready, in order.

        Raises:
            KeyError: ``stream`` is not one of the streams.
        """
        schedule = self.schedules[stream]
        awaited = bool(self._waiting) and not schedule.ready(self._waiting[0])
        schedule.push(stamp, item, moving)
        return self._ready(restart=awaited)

    def give_up(self) -> list[ServedTick[Item]]:
        """The watchdog's alarm: no command came for its time on a stream the oldest waiting
        tick waits for; those streams are waited on no longer (until their next command) and
        the ticks they held are served with the newest commands."""
        self._watchdog.cancel()
        if not self._waiting:
            return []
        for name in self.awaited_streams():
            self.schedules[name].release_all()
        return self._ready(restart=True)

    def _due(self, instant: int) -> list[Item]:
        """The commands of every stream stamped at or before ``instant`` [ns], by stamp."""
        due = [schedule.due_stamped(instant) for schedule in self.schedules.values()]
        if len(due) == 1:
            return [item for _, item in due[0]]
        # heapq.merge is stable: equal stamps come in the order of the streams
        return [item for _, item in heapq.merge(*due, key=lambda entry: entry[0])]

    def _ready(self, restart: bool) -> list[ServedTick[Item]]:
        """Serve the waiting ticks that are ready; the watchdog restarts when ``restart`` or
        when the oldest waiting tick changed, and stops when none waits."""
        served = []
        while self._waiting and self.ready(self._waiting[0]):
            instant = self._waiting.popleft()
            served.append(ServedTick(instant, self._due(instant)))
        if not self._waiting:
            self._watchdog.cancel()
        elif restart or served:
            self._watchdog.reset()
        return served


__all__ = [
    "COMMANDS",
    "MAX_LEAD_CATCH_UP",
    "AwaitedTicks",
    "CommandSchedule",
    "ServedTick",
    "TickInstants",
    "TickLateness",
    "Watchdog",
    "next_tick_in",
]
