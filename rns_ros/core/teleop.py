"""Operator command handling for teleoperation: validation, timeout, deceleration, state.

Pure logic (no ROS), used by the ``rns_controller`` node once per control period:

* :func:`validate_twist` checks one operator twist at the edge (finite, within the angular-speed
  limit, a known frame) and raises :class:`InputError` naming the bad value.
* :class:`CommandGate` keeps the newest valid command. A command older than the timeout (judged
  on receipt time, so clocks cannot defeat it) or a rejected one makes the commanded angular
  velocity ramp down to zero at a fixed angular deceleration; the output never jumps.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from rns_ros.core.controller import TwistFrame
from rns_ros.core.errors import InputError
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.validation import positive


class ControllerState(StrEnum):
    """What the controller is doing, as reported on its status topic."""

    OK = "OK"
    DECELERATING = "DECELERATING"
    SINGULAR_REGION = "SINGULAR_REGION"
    JOINT_LIMIT = "JOINT_LIMIT"
    STALE_COMMAND = "STALE_COMMAND"
    INVALID_COMMAND = "INVALID_COMMAND"


@dataclass(frozen=True)
class TwistCommand:
    """One validated operator command.

    Attributes:
        angular: commanded camera angular velocity in ``frame`` axes [rad/s], shape (3,).
        linear: commanded linear velocity [m/s], shape (3,): not achievable reactionlessly by a
            camera-pointing controller, so it is only reported back as unachieved.
        frame: axes of both vectors.
        received: receipt time on a monotonic clock [s].
    """

    angular: np.ndarray
    linear: np.ndarray
    frame: TwistFrame
    received: float


def twist_frame_ids(
    robot: FreeFloatingModel, world_frame: str, default: TwistFrame | str
) -> dict[str, TwistFrame]:
    """frame_id -> axes of the accepted command frames: the world frame, the base link, the
    camera frame, and "" (an empty frame_id) for ``default``."""
    return {
        world_frame: TwistFrame.WORLD,
        robot.base_link: TwistFrame.BASE,
        robot.model.frames[robot.camera_frame_id].name: TwistFrame.CAMERA,
        "": TwistFrame.parse(default),
    }


def validate_twist(
    angular,
    linear,
    frame_id: str,
    frames: dict[str, TwistFrame],
    max_angular_speed: float,
    received: float,
) -> TwistCommand:
    """Check an operator twist and return it as a :class:`TwistCommand`.

    Args:
        angular, linear: the message's vectors [rad/s], [m/s], shape (3,).
        frame_id: the message's frame; looked up in ``frames`` (frame id -> axes).
        max_angular_speed: largest accepted |angular| [rad/s].
        received: monotonic receipt time [s].

    Raises:
        InputError: non-finite values, |angular| over the limit, or an unknown frame.
    """
    angular = _finite3(angular, "angular velocity")
    linear = _finite3(linear, "linear velocity")
    speed = float(np.linalg.norm(angular))
    if speed > max_angular_speed:
        raise InputError(
            f"angular speed {speed:.4g} rad/s is over max_angular_speed "
            f"{max_angular_speed:.4g} rad/s"
        )
    if frame_id not in frames:
        named = sorted(name for name in frames if name)
        raise InputError(f"frame_id {frame_id!r} is not one of {named}")
    return TwistCommand(angular, linear, frames[frame_id], received)


def _finite3(vector, name: str) -> np.ndarray:
    array = np.asarray(vector, dtype=float)
    if array.shape != (3,) or not np.all(np.isfinite(array)):
        raise InputError(f"{name} must be 3 finite numbers, got {array.tolist()}")
    return array


@dataclass(frozen=True)
class GateOutput:
    """The command to apply this period.

    Attributes:
        angular: angular velocity to command, ``frame`` axes [rad/s], shape (3,).
        linear: the operator's linear velocity (unachieved) [m/s], shape (3,).
        frame: axes of ``angular``.
        state: OK (fresh command), DECELERATING, STALE_COMMAND (stopped, no fresh command) or
            INVALID_COMMAND (the newest message was rejected).
        stopped: True when the output must be exactly zero joint velocity.
        detail: human-readable reason.
    """

    angular: np.ndarray
    linear: np.ndarray
    frame: TwistFrame
    state: ControllerState
    stopped: bool
    detail: str


class CommandGate:
    """Newest valid command, with receipt-time timeout and a bounded ramp to zero.

    Args:
        timeout: a command older than this is stale [s], > 0.
        deceleration: angular deceleration of the command when stale or rejected [rad/s^2], > 0.
        default_frame: frame reported before any command arrives.
    """

    def __init__(
        self,
        timeout: float,
        deceleration: float,
        default_frame: TwistFrame = TwistFrame.CAMERA,
    ) -> None:
        self.timeout = positive(timeout, "command_timeout", "s")
        self.deceleration = positive(deceleration, "stop_deceleration", "rad/s^2")
        self._command: TwistCommand | None = None
        self._factor = 0.0  # fraction of the last command still applied
        self._rejection: str | None = None
        self._default_frame = default_frame

    def accept(self, command: TwistCommand) -> None:
        """A valid command: applied at once, in full."""
        self._command, self._factor, self._rejection = command, 1.0, None

    def reject(self, reason: str) -> None:
        """An invalid message: it never reaches the output; the current command ramps down."""
        self._rejection = reason

    def update(self, now: float, period: float) -> GateOutput:
        """Advance by one control period ending at monotonic time ``now`` [s]."""
        command = self._command
        if command is None:
            zero = np.zeros(3)
            state = (
                ControllerState.INVALID_COMMAND
                if self._rejection
                else ControllerState.STALE_COMMAND
            )
            return GateOutput(
                zero, zero, self._default_frame, state, True, self._rejection or "no command yet"
            )
        age = now - command.received
        if self._rejection is None and age <= self.timeout:
            return GateOutput(
                command.angular, command.linear, command.frame, ControllerState.OK, False, ""
            )
        speed = float(np.linalg.norm(command.angular))
        if speed > 0.0 and self._factor > 0.0:
            self._factor = max(0.0, self._factor - self.deceleration * period / speed)
        else:
            self._factor = 0.0
        stopped = self._factor == 0.0
        if self._rejection is not None:
            state, detail = ControllerState.INVALID_COMMAND, self._rejection
        elif stopped:
            state, detail = ControllerState.STALE_COMMAND, f"last command {age:.2f} s old"
        else:
            state, detail = ControllerState.DECELERATING, f"last command {age:.2f} s old"
        return GateOutput(
            self._factor * command.angular,
            np.zeros(3),
            command.frame,
            state,
            stopped,
            detail,
        )
