"""The operator's motion reference: twist feed-forward, speed and acceleration limits."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rns_ros.control.force.commands import TwistCommand
from rns_ros.control.force.settings import MAX_STEP, CommandFrame, ForceControlSettings
from rns_ros.control.force.status import ForceControlState

#: The first-order hold of a twist extrapolates it with its acceleration feed-forward for up to
#: this many of its message periods past its stamp: a twist usually reaches the controller a
#: control step after its stamp, so one period would drop the feed-forward every other step; a
#: stream that stops is held, not extrapolated.
EXTRAPOLATION_PERIODS = 2.0
#: Removed or ignored command components smaller than this are not reported [m/s, rad/s, N].
REPORT_TOLERANCE = 1e-6


class TwistTrack(NamedTuple):
    """An accepted twist with its feed-forward: accelerations (3,) in the command's axes
    [m/s^2, rad/s^2] and the message period [s] (0: none)."""

    command: TwistCommand
    linear_acceleration: np.ndarray
    angular_acceleration: np.ndarray
    period: float

    @classmethod
    def following(cls, previous: TwistTrack | None, command: TwistCommand) -> TwistTrack:
        """``command`` with the difference to ``previous`` over their stamps as feed-forward
        (0 for equal/zero stamps or another frame)."""
        zero = np.zeros(3)
        lin_acc, ang_acc, period = zero, zero, 0.0
        if previous is not None and previous.command.frame is command.frame:
            step = (command.stamp - previous.command.stamp) * 1e-9
            if command.stamp and previous.command.stamp and step > 0.0:
                lin_acc = (command.linear - previous.command.linear) / step
                ang_acc = (command.angular - previous.command.angular) / step
                period = min(step, MAX_STEP)
        return cls(command, lin_acc, ang_acc, period)


def in_world(vector: np.ndarray, frame: CommandFrame, rotation: np.ndarray) -> np.ndarray:
    """``vector`` (3,) of ``frame`` axes in world axes (``rotation``: world <- EE, (3, 3))."""
    return rotation @ vector if frame is CommandFrame.EE else vector


def limit_norm(vector: np.ndarray, limit: float) -> tuple[np.ndarray, float | None]:
    """``vector`` scaled to norm ``limit`` if longer (and its original norm), else as is."""
    norm = float(np.linalg.norm(vector))
    if norm > limit:
        return vector * (limit / norm), norm
    return vector, None


def rate_limit(previous, target, feedforward, step: float, limit: float):
    """(v, a): ``target`` reached from ``previous`` with at most ``limit`` * step change; the
    acceleration is the feed-forward when unconstrained, else the limiting one."""
    change = target - previous
    norm = float(np.linalg.norm(change))
    allowed = limit * step
    if norm <= allowed * (1.0 + 1e-9) + 1e-12:
        return target, feedforward
    direction = change / norm
    return previous + allowed * direction, limit * direction


def held_twist(track: TwistTrack, settings: ForceControlSettings, rotation, stamp: int):
    """(v (6,), a (6,)) in world axes: the twist held first-order from its stamp to ``stamp``
    [ns] with its feed-forward clipped to the acceleration limits; a = 0 past the hold."""
    command = track.command
    hold, horizon = 0.0, EXTRAPOLATION_PERIODS * track.period
    if track.period > 0.0:
        hold = min(max((stamp - command.stamp) * 1e-9, 0.0), horizon)
    lin_acc = in_world(track.linear_acceleration, command.frame, rotation)
    ang_acc = in_world(track.angular_acceleration, command.frame, rotation)
    lin_acc = limit_norm(lin_acc, settings.max_linear_acceleration)[0]
    ang_acc = limit_norm(ang_acc, settings.max_angular_acceleration)[0]
    linear = in_world(command.linear, command.frame, rotation) + lin_acc * hold
    angular = in_world(command.angular, command.frame, rotation) + ang_acc * hold
    if track.period == 0.0 or hold >= horizon:
        lin_acc, ang_acc = np.zeros(3), np.zeros(3)
    return np.concatenate([linear, angular]), np.concatenate([lin_acc, ang_acc])


def remove_constrained(v: np.ndarray, a: np.ndarray, rows, n: np.ndarray) -> np.ndarray:
    """Zero the non-task rows and the components along the normal n (3,) of v and a (6,) in
    place (the normal is force-controlled: its motion is not commanded); returns the removed
    part of v (6,)."""
    removed = np.zeros(6)
    for i in range(6):
        if i not in rows:
            removed[i], v[i], a[i] = v[i], 0.0, 0.0
    along = float(n @ v[:3])
    removed[:3] += along * n
    v[:3] -= along * n
    a[:3] -= float(n @ a[:3]) * n
    return removed


def limit_speed(v: np.ndarray, settings: ForceControlSettings, notes: list[str], flags: set):
    """Scale the linear and angular parts of v (6,) in place to the speed limits (whole
    vectors), reported as SPEED_LIMITED."""
    v[:3], requested_linear = limit_norm(v[:3], settings.max_linear_speed)
    v[3:], requested_angular = limit_norm(v[3:], settings.max_angular_speed)
    if requested_linear is not None or requested_angular is not None:
        flags.add(ForceControlState.SPEED_LIMITED)
        asked = [
            f"{value:.4g} {unit} scaled to {limit:g}"
            for value, unit, limit in (
                (requested_linear, "m/s", settings.max_linear_speed),
                (requested_angular, "rad/s", settings.max_angular_speed),
            )
            if value is not None
        ]
        notes.append("cmd_twist " + ", ".join(asked))


__all__ = [
    "EXTRAPOLATION_PERIODS",
    "REPORT_TOLERANCE",
    "TwistTrack",
    "held_twist",
    "in_world",
    "limit_norm",
    "limit_speed",
    "rate_limit",
    "remove_constrained",
]
