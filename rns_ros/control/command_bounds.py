"""Bounds on every joint command a controller publishes (no ROS).

A joint command leaves a controller as positions theta [rad] and velocities theta_dot [rad/s],
held for a horizon h [s]: a streamed JointTrajectory (point 0, and point 1 at theta + h
theta_dot), the end of the held period on a position interface (theta + T theta_dot), or the
velocities alone. Whatever the law, the clock or a fault made of them, the command published is

* finite: a command with a NaN/Inf anywhere becomes a stop, zero velocity at its finite
  positions (the measured angle where a position is not finite);
* within the box B = [max(lower, theta_m - e), min(upper, theta_m + e)] per joint: the URDF
  position limits (+-inf for a continuous joint) and ``max_reference_error`` e of the newest
  measured angles theta_m (where a measured angle lies farther than e beyond a limit, B is the
  limit itself: the URDF wins). Positions are clipped to B;
* within the URDF velocity limits, and such that theta + h theta_dot stays in B: a joint at a
  limit is not pushed past it (its velocity into the limit is zero).

Clipping joint by joint changes the direction of theta_dot, so a clipped motion is no longer
reactionless (eq. 3.3). The law keeps its output within the limits by uniform scaling
(:mod:`rns_ros.control.joint_limits`), and its reference within a few periods of the measured
angles. The position bounds bind only when something else went wrong (a jumped clock, a reference
left behind), and :attr:`BoundedCommand.clipped_joint` says where; the velocity bound also slows a
joint in its last horizon before a limit when h is longer than the law's look-ahead (a streamed
trajectory's point 1 lies two periods ahead).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.model import FreeFloatingModel

#: Default of ``max_reference_error`` [rad]: rns_simulator rejects JointTrajectory positions
#: farther than its parameter of the same name (also 0.25 rad) from its current angles.
DEFAULT_MAX_REFERENCE_ERROR = 0.25
#: Velocities are bounded to (1 - ROOM_MARGIN) of the room left in B over the horizon [-]:
#: theta + h theta_dot then rounds to a value inside B, never one ulp past a limit.
ROOM_MARGIN = 1e-9


@dataclass(frozen=True)
class CommandBounds:
    """The bounds of one robot's joint commands (model order).

    Attributes:
        lower, upper: URDF position limits [rad], shape (n,); -inf / +inf for a continuous
            joint; lower <= upper.
        velocity: URDF velocity limits [rad/s], shape (n,), > 0; +inf where the URDF gives none.
        max_reference_error: e, the farthest a commanded position may lie from the measured
            angle [rad], finite and > 0.

    Raises:
        ConfigError: shapes differ, lower > upper, a velocity limit <= 0 or NaN, or e is not a
            finite number > 0.
    """

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    max_reference_error: float

    def __post_init__(self) -> None:
        arrays = {
            name: np.array(getattr(self, name), dtype=float)
            for name in ("lower", "upper", "velocity")
        }
        shapes = {array.shape for array in arrays.values()}
        if len(shapes) != 1 or arrays["lower"].ndim != 1:
            raise ConfigError(
                "command bounds need lower, upper and velocity limits of one shape (n,), got "
                f"{[array.shape for array in arrays.values()]}"
            )
        bad = np.flatnonzero(~(arrays["lower"] <= arrays["upper"]))
        if bad.size:
            joint = int(bad[0])
            raise ConfigError(
                f"joint {joint}: lower limit {arrays['lower'][joint]} rad is above its upper "
                f"limit {arrays['upper'][joint]} rad"
            )
        bad = np.flatnonzero(~(arrays["velocity"] > 0.0))
        if bad.size:
            joint = int(bad[0])
            raise ConfigError(
                f"joint {joint}: velocity limit must be > 0 rad/s (inf: none), got "
                f"{arrays['velocity'][joint]}"
            )
        error = float(self.max_reference_error)
        if not (math.isfinite(error) and error > 0.0):
            raise ConfigError(
                "max_reference_error must be a finite number > 0 rad, got "
                f"{self.max_reference_error!r}"
            )
        for name, array in arrays.items():
            array.flags.writeable = False
            object.__setattr__(self, name, array)
        object.__setattr__(self, "max_reference_error", error)

    @classmethod
    def of(cls, robot: FreeFloatingModel, max_reference_error: float) -> CommandBounds:
        """The bounds of ``robot``'s URDF limits and ``max_reference_error`` [rad]."""
        return cls(
            robot.lower_limits, robot.upper_limits, robot.velocity_limits, max_reference_error
        )

    def box(self, measured: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """B for the measured angles ``measured`` [rad] (n,): (low, high) [rad], each (n,).
        Where a measured angle is not finite, B is the URDF limits alone."""
        e = self.max_reference_error
        low = np.clip(measured - e, self.lower, self.upper)
        high = np.clip(measured + e, self.lower, self.upper)
        known = np.isfinite(measured)
        if not known.all():
            low, high = np.where(known, low, self.lower), np.where(known, high, self.upper)
        return low, high


class BoundedCommand(NamedTuple):
    """A joint command within its bounds.

    Attributes:
        positions: theta [rad], shape (n,), finite, within B.
        velocities: theta_dot [rad/s], shape (n,), finite, within the velocity limits, and
            theta + h theta_dot within B.
        non_finite: the command asked for had a NaN/Inf: this is a stop (zero velocities).
        clipped_joint: a finite position asked for was outside B: the index of the joint moved
            most [-]; None when none was (velocities bounded near a limit are not reported:
            that is a motion coming to rest there).
    """

    positions: np.ndarray
    velocities: np.ndarray
    non_finite: bool
    clipped_joint: int | None


def bound_joint_command(
    positions, velocities, measured, bounds: CommandBounds, horizon: float
) -> BoundedCommand:
    """The joint command ``positions`` [rad], ``velocities`` [rad/s] (n,), held for ``horizon``
    [s], within ``bounds`` around the newest measured angles ``measured`` [rad] (n,) (see the
    module docstring).

    Raises:
        InputError: an array is not of shape (n,) of ``bounds``.
        ConfigError: ``horizon`` is not a finite number > 0.
    """
    if not (math.isfinite(horizon) and horizon > 0.0):
        raise ConfigError(f"command horizon must be a finite number > 0 s, got {horizon!r}")
    n = bounds.lower.shape
    asked_p = np.asarray(positions, dtype=float)
    asked_v = np.asarray(velocities, dtype=float)
    measured = np.asarray(measured, dtype=float)
    for name, array in (("positions", asked_p), ("velocities", asked_v), ("measured", measured)):
        if array.shape != n:
            raise InputError(f"joint command {name} must have shape {n}, got {array.shape}")
    low, high = bounds.box(measured)
    non_finite = not (np.isfinite(asked_p).all() and np.isfinite(asked_v).all())
    p, v = asked_p, asked_v
    if non_finite:
        p = np.where(np.isfinite(p), p, measured)
        p = np.where(np.isfinite(p), p, np.clip(0.0, bounds.lower, bounds.upper))
        v = np.zeros(n)
    p = np.clip(p, low, high)
    # room in B over the horizon [rad/s]: <= 0 below, >= 0 above (p lies in B)
    keep = 1.0 - ROOM_MARGIN
    slowest = np.maximum(-bounds.velocity, keep * (low - p) / horizon)
    fastest = np.minimum(bounds.velocity, keep * (high - p) / horizon)
    v = np.clip(v, slowest, fastest)
    clipped = None
    if not non_finite:
        moved = np.abs(p - asked_p)
        if moved.any():
            clipped = int(np.argmax(moved))
    return BoundedCommand(p, v, non_finite, clipped)


__all__ = [
    "DEFAULT_MAX_REFERENCE_ERROR",
    "BoundedCommand",
    "CommandBounds",
    "bound_joint_command",
]
