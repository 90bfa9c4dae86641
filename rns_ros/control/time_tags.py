"""Time-tagged commands: what a spacecraft does with a command sent through a delayed link.

The ground stamps each command with its issue time t_c [s] (the header stamp; ground and
spacecraft share a time scale, as both keep to GNSS or the ground's time service). On board the
command acts from its execution time

    t_x = t_c + D                                      (D: the execution delay [s])

whatever the link's jitter, so the ground's predictive display, which knows D, knows exactly
when each command acts (:mod:`rns_ros.ground.predictor`). A command received at t_r is refused

* as late when t_r > t_x + late_tolerance: the link took longer than the budget D, so the
  command's moment has passed (the spacecraft never runs a command at another time than the
  one the operator saw predicted);
* as from the future when t_c > t_r + future_tolerance: a clock error or a forged stamp.

D = 0 is a local operator: commands act on arrival, refused when older than late_tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rns_ros.core.errors import ConfigError

#: Largest execution delay accepted [s] (see rns_ros.ground.link.MAX_DELAY_S).
MAX_EXECUTION_DELAY_S = 1200.0


@dataclass(frozen=True)
class TimeTags:
    """When a stamped command acts, and which stamps are refused (module docstring).

    Attributes:
        execution_delay: D [s], in [0, :data:`MAX_EXECUTION_DELAY_S`].
        late_tolerance: a command received more than this after t_c + D is refused [s], > 0.
        future_tolerance: a stamp more than this ahead of the receiver's clock is refused
            [s], > 0.
    """

    execution_delay: float = 0.0
    late_tolerance: float = 0.5
    future_tolerance: float = 0.05

    def __post_init__(self) -> None:
        delay = self.execution_delay
        if not (math.isfinite(delay) and 0.0 <= delay <= MAX_EXECUTION_DELAY_S):
            raise ConfigError(
                f"execution_delay must be in [0, {MAX_EXECUTION_DELAY_S:g}] s, got {delay!r}"
            )
        for name in ("late_tolerance", "future_tolerance"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ConfigError(f"{name} must be finite and > 0 s, got {value!r}")

    def execution_time(self, stamp: float) -> float:
        """t_x = t_c + D [s] of a command stamped ``stamp`` [s]."""
        return stamp + self.execution_delay

    def refusal(self, stamp: float, received: float) -> str | None:
        """Why a command stamped ``stamp`` [s] and received at ``received`` [s] is refused, or
        None when it is taken."""
        if not math.isfinite(stamp):
            return f"stamp {stamp!r} is not a finite time"
        ahead = stamp - received
        if ahead > self.future_tolerance:
            return (
                f"stamped {ahead:.3f} s in the future (more than future_tolerance "
                f"{self.future_tolerance:g} s): a clock error or a forged stamp"
            )
        late = received - self.execution_time(stamp)
        if late > self.late_tolerance:
            return (
                f"received {late:.3f} s after its execution time (stamp + execution_delay "
                f"{self.execution_delay:g} s; late_tolerance {self.late_tolerance:g} s): the link "
                "took longer than the delay budget"
            )
        return None
