"""Camera orientation goal: turn the camera to a given attitude with the reactionless law.

Pure logic (no ROS), used by ``rns_controller`` once per control period. The operator gives a
goal attitude R_goal (world <- camera) instead of a rate; the goal becomes the rate command of
the existing camera law (eq. 4.5 with DLS / SC, so the turn stays reactionless) through an
orientation-error feedback, world axes:

    e = log(R_goal R_c^T)                         [rad], (3,)   (the rotation left to turn)
    omega_ref = k e * min(1, omega_max / (k |e|))  [rad/s], (3,)

k the goal gain [1/s], omega_max the goal speed [rad/s]: far from the goal the camera turns at
omega_max about the remaining axis, near it the error decays as exp(-k t). The command then
passes the controller's command gate (ramp from rest at start_acceleration, the speed limit)
and the law's joint-limit and joint-speed scaling, so the joint rates stay within the URDF
limits. The goal counts as reached once |e| <= tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import InputError
from rns_ros.core.validation import positive

#: A goal quaternion whose norm differs from 1 by more than this is rejected [-]: a quaternion
#: far from unit length is a sender's mistake (an unset orientation is (0, 0, 0, 0)), not a
#: rounding difference (a float32 round trip is ~1e-7).
UNIT_NORM_TOLERANCE = 1e-3


def goal_rotation(quaternion) -> np.ndarray:
    """The rotation matrix (3, 3) of a unit quaternion (x, y, z, w) (geometry_msgs order),
    renormalized.

    Raises:
        InputError: not 4 finite numbers, or a norm further than UNIT_NORM_TOLERANCE from 1.
    """
    q = np.asarray(quaternion, dtype=float)
    if q.shape != (4,) or not np.all(np.isfinite(q)):
        raise InputError(f"goal orientation must be 4 finite numbers, got {q.tolist()}")
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > UNIT_NORM_TOLERANCE:
        raise InputError(
            f"goal orientation is not a unit quaternion: |q| = {norm:.6g} (x, y, z, w) = "
            f"{q.tolist()}, allowed 1 +- {UNIT_NORM_TOLERANCE}"
        )
    x, y, z, w = q / norm
    return pin.Quaternion(w, x, y, z).toRotationMatrix()


@dataclass(frozen=True)
class GoalSettings:
    """Settings of :class:`CameraGoal`.

    Attributes:
        gain: k, error feedback gain [1/s], > 0.
        max_speed: omega_max, largest |omega_ref| the goal commands [rad/s], > 0.
        tolerance: |e| at which the goal counts as reached [rad], > 0.
    """

    gain: float = 2.0
    max_speed: float = 0.3
    tolerance: float = 1e-3

    def __post_init__(self) -> None:
        positive(self.gain, "goal_gain", "1/s")
        positive(self.max_speed, "goal_max_speed", "rad/s")
        positive(self.tolerance, "goal_tolerance", "rad")


@dataclass(frozen=True)
class GoalStep:
    """One period of a goal.

    Attributes:
        omega: commanded camera angular velocity, world axes [rad/s], (3,); zero once reached.
        error: |e|, angle left to turn [rad].
        reached: the goal was reached at this period (reported once).
    """

    omega: np.ndarray
    error: float
    reached: bool


class CameraGoal:
    """The active camera orientation goal, if any.

    Usage::

        goal = CameraGoal(GoalSettings())
        goal.set(goal_rotation(q))
        step = goal.step(state.camera.rotation)   # every period while goal.active
    """

    def __init__(self, settings: GoalSettings | None = None) -> None:
        self.settings = settings or GoalSettings()
        self._target: np.ndarray | None = None
        self.error: float | None = None  # |e| at the last step [rad]

    @property
    def active(self) -> bool:
        """A goal is being turned to."""
        return self._target is not None

    @property
    def target(self) -> np.ndarray | None:
        """R_goal (world <- camera), (3, 3), or None."""
        return self._target

    def set(self, rotation: np.ndarray) -> None:
        """A new goal R_goal (world <- camera), replacing any active one."""
        self._target = np.array(rotation, dtype=float).reshape(3, 3)
        self.error = None

    def cancel(self) -> None:
        """Drop the goal (an operator twist took over, the goal was rejected)."""
        self._target = None
        self.error = None

    def step(self, camera_rotation: np.ndarray) -> GoalStep:
        """The rate command for the camera at ``camera_rotation`` (world <- camera, (3, 3)).

        Raises:
            InputError: no goal is active.
        """
        if self._target is None:
            raise InputError("no camera goal is active")
        error = pin.log3(self._target @ np.asarray(camera_rotation).T)
        angle = float(np.linalg.norm(error))
        self.error = angle
        settings = self.settings
        if angle <= settings.tolerance:
            self._target = None
            return GoalStep(np.zeros(3), angle, True)
        omega = settings.gain * error
        speed = settings.gain * angle
        if speed > settings.max_speed:
            omega = omega * (settings.max_speed / speed)
        return GoalStep(omega, angle, False)
