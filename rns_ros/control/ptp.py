"""Point-to-point motion planning of the free-floating arm (thesis sections 4.4-4.5).

Methods (:class:`PtpMethod`), all producing a :class:`PtpPlan` that is sampled in time:

* ``joint_space`` (JS-C): quintic straight line in joint space, start -> goal, over
  ``settings.duration``.

The reactionless methods (3-phase, deployment) and the Jacobian baselines follow in this module.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rns_ros.core.errors import InputError
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.timing import quintic
from rns_ros.core.validation import Choice, as_vector, positive


class PtpMethod(Choice):
    """Point-to-point method (thesis section 4.4.2 names in brackets)."""

    __label__ = "ptp method"

    THREE_PHASE = "three_phase"
    JOINT_SPACE = "joint_space"
    INVERSE_JACOBIAN = "inverse_jacobian"
    TRANSPOSED_JACOBIAN = "transposed_jacobian"
    DEPLOY = "deploy"


@dataclass(frozen=True)
class PtpSettings:
    """Planner settings (thesis_rest section 2 recommended defaults).

    Attributes:
        phase_durations: nominal durations of 3-phase phases I, II, III [s] (section 4.4.1).
        duration: duration of JS-C / IJ-C / TJ-C [s] (section 4.4.2).
        elbow_gain: k of eq. (4.18) [1/s] (A-2.1).
        fold_angle: theta_4 target of the folds [rad] (section 4.4.1).
        deploy_rate: theta_4 rate of the full deployment [rad/s] (section 4.5.1).
        deploy_duration: duration of the full deployment [s].
    """

    phase_durations: tuple[float, float, float] = (5.0, 20.0, 5.0)
    duration: float = 30.0
    elbow_gain: float = 5.0
    fold_angle: float = -math.pi
    deploy_rate: float = 0.183
    deploy_duration: float = 30.0


@dataclass(frozen=True)
class PhaseInfo:
    """One phase of a plan: name, [start, end] on the plan clock [s], whether it is reactionless,
    and theta_4 reached at the end of a reactionless fold [rad] (None otherwise)."""

    name: str
    start: float
    end: float
    reactionless: bool
    fold_reached: float | None = None


@dataclass(frozen=True)
class PtpReference:
    """Reference at one time: theta (n,) [rad], theta_dot (n,) [rad/s], phase name ("done" after
    the end) and progress t / duration in [0, 1]."""

    theta: np.ndarray
    theta_dot: np.ndarray
    phase: str
    progress: float


class _Line:
    """Quintic straight line a -> b over ``duration`` [s]."""

    def __init__(self, start: np.ndarray, end: np.ndarray, duration: float) -> None:
        self.start, self.delta, self.duration = start, end - start, duration

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        s, s_dot = quintic(t, self.duration)
        return self.start + s * self.delta, s_dot * self.delta


class PtpPlan:
    """A planned point-to-point motion (immutable after planning)."""

    def __init__(self, method, phases, segments, notes, goal) -> None:
        self.method = method
        self.phases: tuple[PhaseInfo, ...] = tuple(phases)
        self._segments = tuple(segments)
        self.notes: tuple[str, ...] = tuple(notes)
        self.goal = np.array(goal, dtype=float)
        self.goal.setflags(write=False)
        self.duration = float(self.phases[-1].end)

    def sample(self, t: float) -> PtpReference:
        """Reference at time ``t`` [s] (clipped to [0, duration]); theta_dot = 0 after the end."""
        t = min(max(float(t), 0.0), self.duration)
        for phase, segment in zip(self.phases, self._segments, strict=True):
            if t <= phase.end or phase is self.phases[-1]:
                theta, theta_dot = segment(t - phase.start)
                done = t >= self.duration
                return PtpReference(
                    theta=np.array(theta),
                    theta_dot=np.zeros_like(theta) if done else np.array(theta_dot),
                    phase="done" if done else phase.name,
                    progress=t / self.duration,
                )
        raise AssertionError("unreachable")


def _check_configuration(robot: FreeFloatingModel, theta, name: str) -> np.ndarray:
    theta = as_vector(theta, robot.n, name)
    for i, (value, low, high) in enumerate(
        zip(theta, robot.lower_limits, robot.upper_limits, strict=True)
    ):
        if not low - 1e-9 <= value <= high + 1e-9:
            raise InputError(
                f"{name}: joint {i + 1} ({robot.joint_names[i]}) = {math.degrees(value):.2f} deg "
                f"is outside its position limits [{math.degrees(low):.1f}, "
                f"{math.degrees(high):.1f}] deg"
            )
    return theta


def _line_duration(robot: FreeFloatingModel, delta: np.ndarray, nominal: float) -> float:
    """Shortest quintic duration >= nominal [s] keeping 1.875 |delta_i| / T <= limit_i."""
    limits = np.where(robot.velocity_limits > 0.0, robot.velocity_limits, np.inf)
    return max(nominal, float(np.max(1.875 * np.abs(delta) / limits)))


def plan_ptp(
    robot: FreeFloatingModel,
    theta_start,
    theta_goal,
    method: PtpMethod | str,
    settings: PtpSettings | None = None,
) -> PtpPlan:
    """Plan a point-to-point motion start -> goal with ``method``.

    Raises:
        InputError: non-finite or out-of-limit start/goal (the message names the joint).
        ConfigError: unknown method.
    """
    settings = settings or PtpSettings()
    method = PtpMethod.parse(method)
    start = _check_configuration(robot, theta_start, "theta_start")
    goal = _check_configuration(robot, theta_goal, "theta_goal")
    if method is PtpMethod.JOINT_SPACE:
        nominal = positive(settings.duration, "duration", "[s]")
        duration = _line_duration(robot, goal - start, nominal)
        notes = []
        if duration > nominal:
            notes.append(
                f"JS-C stretched from {nominal:g} to {duration:.2f} s: joint velocity limits"
            )
        phase = PhaseInfo("JS-C", 0.0, duration, False, None)
        return PtpPlan(method, [phase], [_Line(start, goal, duration)], notes, goal)
    raise NotImplementedError(f"ptp method {method.value} is not implemented yet")


def plan_deployment(robot: FreeFloatingModel, theta_stowed, settings: PtpSettings | None = None):
    """Full reactionless deployment from ``theta_stowed`` (section 4.5.1)."""
    raise NotImplementedError("deployment is not implemented yet")
