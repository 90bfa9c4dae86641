"""Liveness of a simulated clock, judged on the wall clock (no ROS; the wall clock is injected).

Under ``use_sim_time`` a node's input watchdogs judge ages in simulated time: a simulation the
machine delays (or pauses in lockstep) does not age the node's inputs, so a busy machine does
not stop the arm. A simulator that dies stops ``/clock`` too, and then no simulated time passes
for any watchdog: :class:`ClockWatch` catches that on the wall clock.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

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
