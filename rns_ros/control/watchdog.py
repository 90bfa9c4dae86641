"""Liveness and trust of a simulated clock (no ROS; the wall clock and the readings are injected).

Under ``use_sim_time`` a node's input watchdogs judge ages in simulated time: a simulation the
machine delays (or pauses in lockstep) does not age the node's inputs, so a busy machine does
not stop the arm. A simulator that dies stops ``/clock`` too, and then no simulated time passes
for any watchdog: :class:`ClockWatch` catches that on the wall clock. A clock that jumps (a
second ``/clock`` publisher, one far ahead, a reset) makes every age and every held interval
meaningless: :class:`ClockJumps` says when it cannot be trusted.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence

from rns_ros.core.errors import ConfigError


class ClockWatch:
    """How long a node clock has stood still, in wall time.

    Args:
        timeout: wall time [s], > 0, the clock may stand still before :meth:`check` reports it.
        wall: monotonic wall clock [s].
    """

    def __init__(self, timeout: float, wall: Callable[[], float] = time.monotonic) -> None:
        if not (math.isfinite(timeout) and timeout > 0.0):
            raise ConfigError(f"clock timeout must be a finite number > 0 s, got {timeout!r}")
        self.timeout = timeout
        self._wall = wall
        self._reading: int | None = None  # the node clock's last reading [ns]
        self._moved_at = -math.inf  # wall time [s] it last moved

    def check(self, reading: int) -> float | None:
        """Note the node clock's ``reading`` [ns]; the wall time [s] it has stood still once
        that exceeds :attr:`timeout`, else None. A clock that has not moved since this watch
        started (no ``/clock`` yet) is not judged: a node waits for its simulator."""
        now = self._wall()
        if self._reading is None:
            self._reading = reading
            return None
        if reading != self._reading:
            self._reading, self._moved_at = reading, now
            return None
        if self._moved_at == -math.inf:
            return None
        still = now - self._moved_at
        return still if still > self.timeout else None


#: Default of ``max_clock_jump`` [s]: a simulated clock that one reading moves farther forward
#: than this has jumped (a stranger's /clock, a restarted simulation far ahead); rns_simulator
#: moves it by one step or one lockstep period.
DEFAULT_MAX_CLOCK_JUMP = 1.0
#: A jump fault ends once the clock has run this long [s] past the last faulty reading: ten
#: control periods at 100 Hz of a clock that runs forward again (a stranger's readings in
#: between would have begun the fault anew).
CLOCK_SETTLE = 0.1


class ClockJumps:
    """Whether a simulated clock can be trusted: it runs forward, at most ``max_jump`` per
    reading, and one node publishes it.

    A reading that goes back (a second /clock publisher behind the first, a simulation reset)
    or forward farther than ``max_jump`` (a publisher far ahead) begins a fault; so does more
    than one publisher in the graph. A jump fault ends once the clock reads more than
    ``settle`` past the last faulty reading (it runs forward again); a publishers fault ends
    with the graph check that finds one publisher.

    Args:
        max_jump: the largest forward step of one reading [s], finite and > 0.
        topic: the clock topic, named in the fault texts.
        settle: how long [s] the clock runs on after a jump before it is trusted, >= 0.
    """

    def __init__(
        self,
        max_jump: float = DEFAULT_MAX_CLOCK_JUMP,
        topic: str = "/clock",
        settle: float = CLOCK_SETTLE,
    ) -> None:
        self.max_jump = max_jump
        if not (math.isfinite(settle) and settle >= 0.0):
            raise ConfigError(f"clock settle time must be a finite number >= 0 s, got {settle!r}")
        self._settle = round(settle * 1e9)  # [ns]
        self._topic = topic
        self._judged = False  # a reading was judged (the first /clock moves from 0 unjudged)
        self._jump: str | None = None  # the newest faulty reading, described
        self._jumped_to = 0  # and where it set the clock [ns]
        self._publishers: list[str] = []  # the nodes publishing the clock at the last check

    @property
    def max_jump(self) -> float:
        """The largest forward step of one reading [s]."""
        return self._max_jump

    @max_jump.setter
    def max_jump(self, value: float) -> None:
        if not (math.isfinite(value) and value > 0.0):
            raise ConfigError(f"max_clock_jump must be a finite number > 0 s, got {value!r}")
        self._max_jump = float(value)

    def jump(self, before: int, after: int) -> bool:
        """The clock was set from ``before`` to ``after`` [ns] (a jump handler's call). Returns
        True when that is a fault: back, or more than :attr:`max_jump` forward. The very first
        reading (from 0, the clock before any /clock) is not judged."""
        if before == 0 and not self._judged:
            self._judged = True
            return False
        self._judged = True
        step = (after - before) * 1e-9
        if 0.0 <= step <= self._max_jump:
            return False
        moved = f"back {-step:.4g} s" if step < 0.0 else f"{step:.4g} s forward"
        self._jump = (
            f"{self._topic} jumped {moved} (from {before * 1e-9:.3f} s to {after * 1e-9:.3f} s; "
            f"max_clock_jump {self._max_jump:g} s)"
        )
        self._jumped_to = after
        return True

    def publishers(self, names: Sequence[str]) -> None:
        """The nodes publishing the clock, read from the graph."""
        self._publishers = list(names)

    def fault(self, now: int) -> str | None:
        """Why the clock cannot be trusted when it reads ``now`` [ns], or None when it can."""
        parts = []
        if len(self._publishers) > 1:
            parts.append(
                f"{len(self._publishers)} publishers on {self._topic} "
                f"({', '.join(self._publishers)}): simulated time from more than one source"
            )
        if self._jump is not None and now <= self._jumped_to + self._settle:
            parts.append(self._jump)
            if len(self._publishers) == 1:
                parts.append(f"{self._topic} published by {self._publishers[0]}")
        else:
            self._jump = None
        return "; ".join(parts) if parts else None
