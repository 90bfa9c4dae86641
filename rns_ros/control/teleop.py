"""Operator command handling for teleoperation: validation, timeout, ramps, state.

Pure logic (no ROS), used by the ``rns_controller`` node once per control period:

* :func:`validate_twist` checks one operator twist at the edge: non-finite values and unknown
  frames raise :class:`InputError` naming the bad value; a finite angular velocity above the
  speed limit is scaled down to the limit as a whole vector (its direction, hence the camera's
  rotation axis, is kept), as MoveIt Servo does, and the command says so.
* :class:`CommandGate` keeps the newest valid command. A command older than the timeout (judged
  on receipt time, so clocks cannot defeat it) or a rejected one makes the commanded angular
  velocity ramp down to zero at a fixed angular deceleration. Starting from rest (the first
  command, after a stop, after a zero command, or after :meth:`CommandGate.stop`) the speed
  ramps up at a fixed angular acceleration. The output never jumps up from rest.
* :class:`CommandSchedule` holds twists stamped ahead of simulated time until their stamps, and
  says when a control tick knows which twist is in force (lockstep runs on /clock).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from enum import StrEnum
from typing import Generic, TypeVar

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
    STALE_STATE = "STALE_STATE"  # [ERROR] joint_states / base_odom too old: zero velocity
    CONFLICTING_STATE = "CONFLICTING_STATE"  # [ERROR] several joint_states sources: zero


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
        if self._rejection is None and age <= self.timeout:
            return self._follow(command, wanted, period)
        if wanted > 0.0:
            self._speed = max(0.0, min(self._speed, wanted) - self.deceleration * period)
        else:
            self._speed = 0.0
        stopped = self._speed == 0.0
        if stopped:
            self._ramping = True
        if self._rejection is not None:
            state, detail = ControllerState.INVALID_COMMAND, self._rejection
        elif stopped:
            state, detail = ControllerState.IDLE, f"last command {age:.2f} s old"
        else:
            state, detail = ControllerState.DECELERATING, f"last command {age:.2f} s old"
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


Item = TypeVar("Item")


class CommandSchedule(Generic[Item]):
    """Stamped commands released at their stamps, for a controller ticking on simulated time.

    In lockstep the simulation waits for the controller but not for the operator, so a twist
    that acts on receipt acts whenever the operator's process got a core: a few milliseconds of
    wall time are a period or more of simulated time at ten times real time (the camera ended
    1-16 deg short in about one run in thirty on a busy 2-core machine). A scripted operator
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
        items = []
        while self._waiting and self._waiting[0][0] <= tick:
            items.append(self._waiting.popleft()[1])
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
