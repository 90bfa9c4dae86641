"""Operator command handling for teleoperation: validation, timeout, ramps, state.

Pure logic (no ROS), used by the ``rns_controller`` node once per control period:

* :func:`validate_twist` checks one operator twist at the edge: non-finite values and unknown
  frames raise :class:`InputError` naming the bad value; a finite angular velocity above the
  speed limit is scaled down to the limit as a whole vector (its direction, hence the camera's
  rotation axis, is kept), as MoveIt Servo does, and the command says so.
* :class:`CommandGate` keeps the newest valid command. A command older than the timeout (judged
  on receipt time, so clocks cannot defeat it; one received after the time of the update, on a
  clock that went back since, counts as stale) or a rejected one makes the commanded angular
  velocity ramp down to zero at a fixed angular deceleration. Starting from rest (the first
  command, after a stop, after a zero command, or after :meth:`CommandGate.stop`) the speed
  ramps up at a fixed angular acceleration. The output never jumps up from rest.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from rns_ros.control.controller import TwistFrame
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.validation import positive

#: Frame-id alias of the base axes, accepted besides the URDF's base link name.
BASE_ALIAS = "base"


class ControllerState(StrEnum):
    """What the controller is doing, as reported on its status topic (level in brackets)."""

    WAITING_FOR_STATE = "WAITING_FOR_STATE"  # [WARN] no joint_states yet: nothing published
    IDLE = "IDLE"  # [OK] no command, or the last one ended: exactly zero velocity
    OK = "OK"  # [OK] following a fresh command
    RAMPING = "RAMPING"  # [OK] starting from rest: speed rising at start_acceleration
    SPEED_LIMITED = "SPEED_LIMITED"  # [WARN] command above max_angular_speed, scaled to it
    DECELERATING = "DECELERATING"  # [WARN] command stale or rejected: ramping to zero
    SINGULAR_REGION = "SINGULAR_REGION"  # [WARN] sigma_min(J-bar) < epsilon
    JOINT_LIMIT = "JOINT_LIMIT"  # [WARN] a joint position limit slows or stops the motion
    INVALID_COMMAND = "INVALID_COMMAND"  # [ERROR] the newest command was rejected
    STATE_GAP = "STATE_GAP"  # [WARN] joint_states / base_odom late: held still until fresh
    STALE_STATE = "STALE_STATE"  # [ERROR] joint_states / base_odom too old: zero velocity
    CONFLICTING_STATE = "CONFLICTING_STATE"  # [ERROR] several joint_states sources: zero
    CLOCK_FAULT = "CLOCK_FAULT"  # [ERROR] /clock went back, jumped or has two sources: zero
    PAUSED = "PAUSED"  # [OK] held by ~/pause: exactly zero velocity, commands ignored
    GOAL_ACTIVE = "GOAL_ACTIVE"  # [OK] turning the camera to an orientation goal
    GOAL_REACHED = "GOAL_REACHED"  # [OK] the orientation goal was reached: zero command


@dataclass(frozen=True)
class TwistCommand:
    """One validated operator command.

    Attributes:
        angular: commanded camera angular velocity in ``frame`` axes [rad/s], shape (3,); at most
            the speed limit (see ``requested_speed``).
        linear: commanded linear velocity [m/s], shape (3,): not achievable reactionlessly by a
            camera-pointing controller, so it is only reported back as unachieved.
        frame: axes of both vectors.
        received: receipt time on a monotonic clock [s].
        requested_speed: |angular| as sent [rad/s] when it was above the limit and scaled down;
            None when the command was within the limit.
    """

    angular: np.ndarray
    linear: np.ndarray
    frame: TwistFrame
    received: float
    requested_speed: float | None = None


def twist_frame_ids(
    robot: FreeFloatingModel, world_frame: str, default: TwistFrame | str
) -> dict[str, TwistFrame]:
    """frame_id -> axes of the accepted command frames.

    Accepted: the world frame, the base link's URDF name and the alias ``base``, the camera
    frame's name, and "" (an empty frame_id) for ``default``. ``default`` itself may be any of
    these names or a :class:`TwistFrame` value (``world``, ``base``, ``camera``).

    Raises:
        ConfigError: ``default`` names none of them (the message lists the valid names).
    """
    frames = {
        BASE_ALIAS: TwistFrame.BASE,
        TwistFrame.CAMERA.value: TwistFrame.CAMERA,
        robot.base_link: TwistFrame.BASE,
        robot.model.frames[robot.camera_frame_id].name: TwistFrame.CAMERA,
        world_frame: TwistFrame.WORLD,
    }
    frames[""] = resolve_twist_frame(default, frames, "default_twist_frame")
    return frames


def resolve_twist_frame(name: TwistFrame | str, frames: dict[str, TwistFrame], what: str):
    """The axes named by ``name`` (a frame id in ``frames`` or a :class:`TwistFrame` value).

    Raises:
        ConfigError: unknown name; the message names ``what`` and lists the valid names.
    """
    if isinstance(name, TwistFrame):
        return name
    if name in frames and name:
        return frames[name]
    if name in {frame.value for frame in TwistFrame}:
        return TwistFrame(name)
    valid = sorted({*(key for key in frames if key), *(frame.value for frame in TwistFrame)})
    raise ConfigError(f"parameter '{what}' must be one of {valid}, got {name!r}")


def validate_twist(
    angular,
    linear,
    frame_id: str,
    frames: dict[str, TwistFrame],
    max_angular_speed: float,
    received: float,
) -> TwistCommand:
    """Check an operator twist and return it as a :class:`TwistCommand`.

    An angular velocity faster than ``max_angular_speed`` is scaled as a whole vector,
    omega <- omega * max_angular_speed / |omega|: the camera still turns about the commanded
    axis, at the limit (``requested_speed`` keeps what was asked).

    Args:
        angular, linear: the message's vectors [rad/s], [m/s], shape (3,).
        frame_id: the message's frame; looked up in ``frames`` (frame id -> axes).
        max_angular_speed: largest |angular| passed on [rad/s], > 0.
        received: monotonic receipt time [s].

    Raises:
        InputError: non-finite values or an unknown frame.
    """
    angular = _finite3(angular, "angular velocity")
    linear = _finite3(linear, "linear velocity")
    if frame_id not in frames:
        named = sorted(name for name in frames if name)
        raise InputError(f"frame_id {frame_id!r} is not one of {named}")
    speed = float(np.linalg.norm(angular))
    requested = None
    if speed > max_angular_speed:
        angular, requested = angular * (max_angular_speed / speed), speed
    return TwistCommand(angular, linear, frames[frame_id], received, requested)


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
        state: OK (fresh command, full speed), RAMPING, SPEED_LIMITED, DECELERATING, IDLE
            (stopped, no fresh command) or INVALID_COMMAND (the newest message was rejected).
        stopped: True when the output must be exactly zero joint velocity.
        detail: human-readable reason.
    """

    angular: np.ndarray
    linear: np.ndarray
    frame: TwistFrame
    state: ControllerState
    stopped: bool
    detail: str


#: A command received at most this long [s] after the gate's ``now`` is fresh, not from a clock
#: that went back: times summed in floats (periods, key-repeat grids) differ by ~1e-15 s.
RECEIPT_SLACK = 1e-6


class CommandGate:
    """Newest valid command, with receipt-time timeout and bounded ramps.

    The applied speed s = |omega| follows the command with two limits per period T:

    * down to rest when the command is stale or rejected: s <- max(0, s - a_stop T), direction
      of the last command kept;
    * up from rest: after the output was at rest (or :meth:`stop`), s <- min(|omega_cmd|,
      s + a_start T) until it reaches the command; then changes pass at once (an operator who
      slows down or reverses is followed without delay).

    Args:
        timeout: a command older than this is stale [s], > 0.
        deceleration: a_stop, angular deceleration when stale or rejected [rad/s^2], > 0.
        default_frame: frame reported before any command arrives.
        acceleration: a_start, angular acceleration when starting from rest [rad/s^2], > 0;
            default: ``deceleration``.
    """

    def __init__(
        self,
        timeout: float,
        deceleration: float,
        default_frame: TwistFrame = TwistFrame.CAMERA,
        acceleration: float | None = None,
    ) -> None:
        self.timeout = positive(timeout, "command_timeout", "s")
        self.deceleration = positive(deceleration, "stop_deceleration", "rad/s^2")
        self.acceleration = positive(
            deceleration if acceleration is None else acceleration, "start_acceleration", "rad/s^2"
        )
        self._command: TwistCommand | None = None
        self._speed = 0.0  # |omega| applied last period [rad/s]
        self._ramping = True  # the output starts from rest
        self._rejection: str | None = None
        self._default_frame = default_frame

    def accept(self, command: TwistCommand) -> None:
        """A valid command: applied from the next update (ramped up when starting from rest)."""
        self._command, self._rejection = command, None

    def reject(self, reason: str) -> None:
        """An invalid message: it never reaches the output; the current command ramps down."""
        self._rejection = reason

    def stop(self) -> None:
        """Force the output to rest now (lost state, resynchronization): the next fresh command
        ramps up from zero."""
        self._speed, self._ramping = 0.0, True

    def update(self, now: float, period: float) -> GateOutput:
        """Advance by one control period ending at monotonic time ``now`` [s]."""
        command = self._command
        if command is None:
            self.stop()
            zero = np.zeros(3)
            if self._rejection:
                state, detail = ControllerState.INVALID_COMMAND, self._rejection
            else:
                state, detail = ControllerState.IDLE, "no command yet"
            return GateOutput(zero, zero, self._default_frame, state, True, detail)
        age = now - command.received
        wanted = float(np.linalg.norm(command.angular))
        # received after now: the clock went back since, and its age is unknown (stale); a
        # receipt within RECEIPT_SLACK after now is the rounding of times summed in floats
        if self._rejection is None and -RECEIPT_SLACK <= age <= self.timeout:
            return self._follow(command, wanted, period)
        if wanted > 0.0:
            self._speed = max(0.0, min(self._speed, wanted) - self.deceleration * period)
        else:
            self._speed = 0.0
        stopped = self._speed == 0.0
        if stopped:
            self._ramping = True
        detail = (
            f"last command {age:.2f} s old"
            if age >= 0.0
            else f"last command received {-age:.3g} s later on a clock that went back"
        )
        if self._rejection is not None:
            state, detail = ControllerState.INVALID_COMMAND, self._rejection
        else:
            state = ControllerState.IDLE if stopped else ControllerState.DECELERATING
        angular = command.angular * (self._speed / wanted) if wanted > 0.0 else np.zeros(3)
        return GateOutput(angular, np.zeros(3), command.frame, state, stopped, detail)

    def _follow(self, command: TwistCommand, wanted: float, period: float) -> GateOutput:
        if wanted == 0.0:
            # followed as it is (the law may still act, e.g. the wrist term), but from rest:
            # the next non-zero command ramps up
            self.stop()
            return GateOutput(
                command.angular, command.linear, command.frame, ControllerState.OK, False, ""
            )
        speed = wanted
        if self._ramping:
            speed = self._speed + self.acceleration * period
            if speed >= wanted * (1.0 - 1e-9):  # reached (up to rounding of the sum)
                speed = wanted
            self._ramping = speed < wanted
        self._speed = speed
        angular = command.angular * (speed / wanted)
        if command.requested_speed is not None:
            state = ControllerState.SPEED_LIMITED
            detail = f"|omega| {command.requested_speed:.4g} rad/s scaled to the limit {wanted:.4g}"
        elif speed < wanted:
            state, detail = ControllerState.RAMPING, f"{speed:.3g} of {wanted:.3g} rad/s"
        else:
            state, detail = ControllerState.OK, ""
        return GateOutput(angular, command.linear, command.frame, state, False, detail)
