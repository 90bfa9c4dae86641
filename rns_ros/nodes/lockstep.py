"""The stepping loop of the simulator nodes: paced to wall time at a real-time factor, and in
lockstep with a controller (paused ``lockstep_period`` of simulated time past its newest
command). No ROS here: the node is a :class:`SteppedSimulation`, the clock is injected."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Mapping
from typing import Any, NamedTuple, Protocol

#: A lockstep pause longer than this [s] (wall time) ends in the node's way
#: (:meth:`SteppedSimulation.patience_over`), so a controller whose sim-time timer waits for a
#: later /clock is never deadlocked.
LOCKSTEP_PATIENCE = 5.0
#: Lockstep before the first command: a wait this long [s] (wall time) moves the pause one
#: ``lockstep_period`` on, with a state and /clock there, so a controller that subscribed after
#: the last one gets a tick to answer.
START_PATIENCE = 0.25
#: Largest lag [s] of the loop behind its pace (and of a state's stamp behind its publication):
#: an overloaded simulator re-anchors its pace this far behind instead of sprinting.
MAX_STAMP_LAG = 0.5
#: Lockstep at real_time_factor 0: a command callback runs at most this many steps to the next
#: pause itself (a long lockstep_period goes on in the simulation thread, so the executor is
#: not blocked for long).
CALLBACK_STEPS = 200
#: Wait [s] of a lockstep pause for the command event (a command, a reset or a parameter change
#: sets it), so the patience is checked.
PAUSE_POLL = 0.005
#: Wait [s] of the simulation thread while a command callback steps (it sets the command event
#: when it hands on).
CALLBACK_POLL = 0.1


class Pace(NamedTuple):
    """A real-time pace: simulated time ``sim_anchor`` [s] is reached at monotonic wall time
    ``wall_anchor`` [s], and ``factor`` (> 0) simulated seconds pass per wall second."""

    wall_anchor: float
    sim_anchor: float
    factor: float


def pace_lead(pace: Pace, sim_time: float, now: float) -> float:
    """Wall time [s] from ``now`` [s] until ``pace`` reaches ``sim_time`` [s]; negative once it
    is past."""
    wall_anchor, sim_anchor, factor = pace
    return wall_anchor + (sim_time - sim_anchor) / factor - now


class SteppedSimulation(Protocol):
    """What :class:`LockstepPacer` drives: a node around a fixed-step simulator."""

    def faulted(self) -> bool:
        """A step diverged and no reset is requested: the held state is published instead."""

    def publish_held_state(self) -> None:
        """Publish the last finite state at rest (every ``publish_period`` while faulted)."""

    def advance(self) -> float | None:
        """One step and what it publishes; the simulated time after it [s], None when it
        diverged. Caller holds :attr:`LockstepPacer.stepping`."""

    def steps_in_callback(self) -> bool:
        """A command callback steps to the next pause itself. Caller holds the lock."""

    def patience_over(self) -> bool:
        """A pause outlasted :data:`LOCKSTEP_PATIENCE`: True to take one step and pause again,
        False once the node has dropped the command (then it runs on). Caller holds the lock."""


class LockstepPacer:
    """When the simulation thread steps and how long it waits.

    Real time: steps follow a :class:`Pace` (anchored anew after every pause, reset, change of
    the real-time factor, or lag beyond :data:`MAX_STAMP_LAG`). Lockstep (``lockstep_period`` >
    0): the simulation pauses once it is ``lockstep_period`` of simulated time past the newest
    command. Before the first command it stands one ``lockstep_period`` in (its first state and
    /clock out) until a controller answers, one period on every :data:`START_PATIENCE`, so
    simulated time, and a scripted operator's profile on it, cannot run ahead of a controller
    that joins late. A dropped command (the node's
    :meth:`SteppedSimulation.patience_over` returned False, a stale one, a reset) leaves it
    running in real time until commands come back.

    Args:
        simulator: the stepped simulator; read: ``time`` [s], ``dt`` [s].
        lockstep_period: [s]; 0: off.
        real_time_factor: simulated seconds per wall second; 0: as fast as possible.
        publish_period: wait [s] between held states while faulted.
        lock: the node's lock over the simulator and the command state (new if None).
        stop, wake: the loop's stop event and the command event (new if None).
        clock: monotonic wall time [s].
        idle_poll: wait [s] of a pause at real_time_factor 0.
    """

    def __init__(
        self,
        simulator,
        *,
        lockstep_period: float,
        real_time_factor: float,
        publish_period: float,
        lock: threading.Lock | None = None,
        stop: threading.Event | None = None,
        wake: threading.Event | None = None,
        clock: Callable[[], float] = time.monotonic,
        idle_poll: float = PAUSE_POLL,
    ) -> None:
        self.simulator = simulator
        self.period = lockstep_period
        self.real_time_factor = real_time_factor
        self.publish_period = publish_period
        self.lock = threading.Lock() if lock is None else lock
        # held by whoever steps (the simulation thread, or a command callback: run_to_pause)
        self.stepping = threading.Lock()
        self.stop = threading.Event() if stop is None else stop
        self.wake = threading.Event() if wake is None else wake
        self.clock = clock
        self.idle_poll = idle_poll
        self.last_command: float | None = None  # wall receipt time of the newest command [s]
        # lockstep: no command yet since the start, so the simulation stands a period in
        self.awaiting_first = True
        self.command_sim_time = 0.0  # simulated time its lockstep period counts from [s]
        self.paused_since: float | None = None  # wall start of a lockstep pause [s]
        self.reanchor = True
        # the stepping thread's pace, for the stamps; None off real time (a step run from a
        # command callback)
        self.pace: Pace | None = None
        self._anchor = (0.0, 0.0)

    # --- decisions (caller holds the lock where noted) ----------------------------------------
    @classmethod
    def from_parameters(cls, simulator, params: Mapping[str, Any], **options) -> LockstepPacer:
        """The pacer of a simulator node, from the node's ``lockstep_period``,
        ``real_time_factor`` and ``publish_rate`` [Hz] (the wait between held states while
        faulted); ``options`` as for the constructor. Its lock and events are new."""
        return cls(
            simulator,
            lockstep_period=params["lockstep_period"],
            real_time_factor=params["real_time_factor"],
            publish_period=1.0 / params["publish_rate"],
            **options,
        )

    def pauses_here(self) -> bool:
        """Lockstep: the simulation has reached ``lockstep_period`` past the newest command (or,
        awaiting the first one, past the start). Caller holds the lock."""
        if self.period <= 0.0:
            return False
        if self.last_command is None and not self.awaiting_first:
            return False
        sim = self.simulator
        return sim.time + 0.5 * sim.dt - self.command_sim_time >= self.period

    def paused(self) -> bool:
        with self.lock:
            return self.pauses_here()

    def note_pause(self) -> bool:
        """:meth:`pauses_here`, and a pause reached now starts the patience. Caller holds the
        lock."""
        pauses = self.pauses_here()
        if pauses:
            self.paused_since = self.clock()
        return pauses

    def factor(self) -> float:
        """The real-time factor of the next step: 1 in lockstep before the first command (a
        controller joins before much simulated time passes), else ``real_time_factor``."""
        if self.period > 0.0 and self.last_command is None:
            return 1.0
        return self.real_time_factor

    def command_received(self, sim_anchor: float) -> None:
        """A command arrived; its lockstep period counts from ``sim_anchor`` [s] (simulated
        time). Caller holds the lock."""
        if self.last_command is None and self.period > 0.0:
            self.reanchor = True  # lockstep starts: leave the real-time pace of the wait
        self.awaiting_first = False
        self.last_command = self.clock()
        self.command_sim_time = sim_anchor

    def command_age(self, received: float, sim_received: float) -> float:
        """Age [s] of a command received at wall time ``received`` [s], simulated time
        ``sim_received`` [s]: simulated time in lockstep (a paused simulation does not move, so
        a controller busy for a while only pauses it), else wall time."""
        if self.period > 0.0:
            return self.simulator.time - sim_received
        return self.clock() - received

    def reset(self) -> None:
        """The simulation was reset: no command (real time until the next one), a new pace.
        Caller holds the lock."""
        self.last_command = None
        self.command_sim_time = 0.0
        self.reanchor = True

    def set_real_time_factor(self, factor: float) -> None:
        self.real_time_factor = factor
        self.reanchor = True

    def stamp_lead(self, sim_time: float) -> float | None:
        """Wall time [s] from now until the pace reaches ``sim_time`` [s], within
        [-MAX_STAMP_LAG, one step]; None off real time."""
        pace = self.pace
        if pace is None:
            return None
        lead = pace_lead(pace, sim_time, self.clock())
        return min(max(lead, -MAX_STAMP_LAG), self.simulator.dt / pace.factor)

    def pause_wait(self, sim: SteppedSimulation) -> float | None:
        """Lockstep: None to step, 0 for one step forced by :meth:`SteppedSimulation.
        patience_over`, else the wait [s] for the command event. Caller holds the lock."""
        if not self.pauses_here():
            self.paused_since = None
            if not sim.steps_in_callback() or self.wake.is_set():
                return None
            # a command callback is stepping to the pause: only wait (racing it for the
            # stepping lock cost both threads a GIL hand-off per period); it sets the event
            # when it hands on
            self.wake.clear()
            return CALLBACK_POLL
        now = self.clock()
        if self.paused_since is None:
            self.paused_since = now
        elif self.awaiting_first and now - self.paused_since > START_PATIENCE:
            # no controller yet: the next period instant, for one that joined late
            self.command_sim_time += self.period
            self.paused_since = None
            return None
        elif now - self.paused_since > LOCKSTEP_PATIENCE:
            if sim.patience_over():
                self.paused_since = now
                return 0.0
            self.paused_since = None
            return None
        self.wake.clear()
        return PAUSE_POLL if self.real_time_factor > 0.0 else self.idle_poll

    # --- the loop -----------------------------------------------------------------------------
    def run(self, sim: SteppedSimulation) -> None:
        """Step ``sim`` until :attr:`stop` is set (the simulation thread's target)."""
        while not self.stop.is_set():
            if sim.faulted():
                sim.publish_held_state()
                self.stop.wait(self.publish_period)
                self.reanchor = True
                continue
            forced = self._await_command(sim)
            if forced is None:
                self.reanchor = True  # paused for the controller: do not sprint afterwards
                continue
            pace = self._next_pace()
            with self.stepping:
                # a command callback may have run to the pause since the check
                if not forced and self.paused():
                    continue
                sim_time = sim.advance()
            if sim_time is None:
                continue
            if pace is not None:
                self._keep_pace(pace, sim_time)

    def run_to_pause(self, sim: SteppedSimulation) -> None:
        """Executor thread, after a command: step until the next lockstep pause (at most
        :data:`CALLBACK_STEPS` steps; the simulation thread takes over beyond them)."""
        with self.stepping:
            self.pace = None  # off real time: stamped when published
            for _ in range(CALLBACK_STEPS):
                with self.lock:
                    if self.stop.is_set() or not sim.steps_in_callback() or self.pauses_here():
                        break
                if sim.advance() is None:
                    break
            paused = self.paused()
        if not paused:  # beyond CALLBACK_STEPS, a reset, a fault: the simulation thread goes on
            self.wake.set()

    def _await_command(self, sim: SteppedSimulation) -> bool | None:
        """Lockstep: None (after a wait) while paused, True for a step forced by the patience,
        else False."""
        if self.period <= 0.0:
            return False
        with self.lock:
            wait = self.pause_wait(sim)
        if wait is None:
            return False
        if wait == 0.0:
            return True
        self.wake.wait(wait)
        return None

    def _next_pace(self) -> Pace | None:
        """The pace of the next step (re-anchored at the current time when due), None off real
        time; kept in :attr:`pace` for the stamps."""
        if self.reanchor:
            self._anchor = (self.clock(), self.simulator.time)
            self.reanchor = False
        factor = self.factor()
        self.pace = Pace(*self._anchor, factor) if factor > 0.0 else None
        return self.pace

    def _keep_pace(self, pace: Pace, sim_time: float) -> None:
        """Wait until ``pace`` reaches ``sim_time`` [s]; far behind (an overloaded machine):
        re-anchor, do not sprint."""
        delay = pace_lead(pace, sim_time, self.clock())
        if delay > 0.0:
            self.stop.wait(delay)
        elif delay < -MAX_STAMP_LAG:
            self.reanchor = True
