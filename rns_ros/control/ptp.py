"""A planned point-to-point motion (thesis sections 4.4-4.5): settings, segments, playback.

A :class:`PtpPlan` is a sequence of phases, each played by one segment: a quintic joint-space
line (:class:`QuinticLine`), a reactionless elbow path timed by a quintic in arc length
(:class:`PathSegment`), or a stored closed-loop trajectory (:class:`StoredTrajectory`).
:meth:`PtpPlan.sample` gives the reference, :meth:`PtpPlan.command` adds position feedback.
The planners are in :mod:`rns_ros.control.ptp_planner`.

Each reactionless phase is timed with a rest-to-rest quintic in arc length, sigma(t) = L s(t / T);
T is stretched (never a per-joint clip) so that sigma_dot_max |n_i| = 1.875 L |n_i| / T <=
velocity_limit_i on the whole path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from rns_ros.control.reactionless_path import NullVector, ReactionlessPath
from rns_ros.core.errors import InputError
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.timing import QUINTIC_PEAK_RATE, quintic
from rns_ros.core.validation import Choice, as_vector


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
        phase_durations: nominal durations of 3-phase phases I, II, III [s] (section 4.4.1);
            stretched when the joint velocity limits require it.
        duration: nominal duration of JS-C / IJ-C / TJ-C [s] (section 4.4.2).
        elbow_gain: k of eq. (4.18) [1/s] (A-2.1), used by :meth:`PtpPlan.command` on the
            position error projected on the path tangent.
        fold_angle: theta_4 target of the folds [rad] (section 4.4.1).
        deploy_rate: theta_4 rate of the full deployment [rad/s] (section 4.5.1); with
            ``deploy_duration`` it sets the deployment's theta_4 target
            theta_4(0) + rate * duration.
        deploy_duration: nominal duration of the full deployment [s].
        path_step: arc-length step of the RK4 path integration [rad].
        max_arc: longest joint-space arc followed per fold [rad].
        position_gain: K_p of IJ-C [1/s] (A-2.8).
        transposed_gains: candidate K of TJ-C [1/(m s) ~ rad/(m^2 s) scaled]: the first whose final
            camera error is below ``target_tolerance`` is used (A-2.9).
        target_tolerance: final camera error that TJ-C must reach [m].
        integration_step: step of the offline IJ-C/TJ-C integration [s] (RK4).
        camera_target: IJ-C/TJ-C camera target in world [m], shape (3,); None: the final camera
            position of the 3-phase plan from the same start to the same goal, integrated on
            the kinematic free-floating model (A-2.5).
    """

    phase_durations: tuple[float, float, float] = (5.0, 20.0, 5.0)
    duration: float = 30.0
    elbow_gain: float = 5.0
    fold_angle: float = -math.pi
    deploy_rate: float = 0.183
    deploy_duration: float = 30.0
    path_step: float = 0.01
    max_arc: float = 12.0
    position_gain: float = 1.0
    transposed_gains: tuple[float, ...] = (1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0)
    target_tolerance: float = 0.01
    integration_step: float = 0.02
    camera_target: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class PhaseInfo:
    """One phase of a plan.

    Attributes:
        name: "I", "II", "III", "JS-C", "IJ-C", "TJ-C", "deploy".
        start, end: [s] on the plan's clock.
        reactionless: the phase moves in the reaction null space.
        fold_reached: theta_4 reached at the folded end of a reactionless fold [rad], else None.
    """

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


# segments ------------------------------------------------------------------------------------
class JointSpaceSegment:
    """A segment that is not reactionless: its position feedback acts on every joint. A
    subclass is callable, t [s] -> (theta_ref [rad], theta_dot_ref [rad/s]), each (n,)."""

    reactionless = False

    def angles(self, t: float) -> np.ndarray:
        """theta_ref(t) [rad] (n,)."""
        return self(t)[0]

    def track(self, t, theta, error, rate, gain) -> np.ndarray:
        """r theta_dot_ref(t) + k e [rad/s] (n,): the reference rate scaled by ``rate`` r [-]
        plus ``gain`` k [1/s] times the position ``error`` e [rad] (n,) (``theta`` unused)."""
        return rate * self(t)[1] + gain * error


class QuinticLine(JointSpaceSegment):
    """Quintic straight line a -> b over ``duration`` [s] (JS-C, Phase II)."""

    def __init__(self, start: np.ndarray, end: np.ndarray, duration: float) -> None:
        self.start, self.delta, self.duration = start, end - start, duration

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        s, s_dot = quintic(t, self.duration)
        return self.start + s * self.delta, s_dot * self.delta


class PathSegment:
    """A reactionless path played with sigma(t) = L s(t / T) (or reversed: L (1 - s)).

    theta_dot is sigma_dot n(theta(t)) with n evaluated at the sampled configuration, so
    M~_omega_m theta_dot vanishes to machine precision there.
    """

    reactionless = True

    def __init__(self, path: ReactionlessPath, duration: float, null: NullVector, reverse: bool):
        self.path, self.duration, self.null, self.reverse = path, duration, null, reverse

    def _sigma(self, t: float) -> tuple[float, float]:
        s, s_dot = quintic(t, self.duration)
        length = self.path.length
        if self.reverse:
            return length * (1.0 - s), -length * s_dot
        return length * s, length * s_dot

    def direction(self, theta: np.ndarray, t: float) -> np.ndarray:
        """Unit n(theta) (n,) at any ``theta``, signed like the path tangent at time ``t``."""
        sigma, _ = self._sigma(t)
        _, tangent = self.path.at(sigma)
        p = self.null.positioning
        full = np.zeros(theta.size)
        full[p] = self.null(theta, tangent[p])
        return full

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        sigma, sigma_dot = self._sigma(t)
        theta, _ = self.path.at(sigma)
        return theta, sigma_dot * self.direction(theta, t)

    def speed(self, t: float) -> float:
        """d sigma / dt [rad/s] at time ``t``."""
        return self._sigma(t)[1]

    def angles(self, t: float) -> np.ndarray:
        """theta_ref(t) [rad] (n,), the path at time ``t`` [s]."""
        return self.path.at(self._sigma(t)[0])[0]

    def track(self, t, theta, error, rate, gain) -> np.ndarray:
        """(r sigma_dot(t) + k n . e) n [rad/s] (n,), n = n(``theta``) the unit null vector at
        the arm's angles ``theta`` [rad] (n,): the arc-length form of eq. (4.18) with the
        rate scaled by ``rate`` r [-] and the position ``error`` e [rad] (n,) projected on the
        path tangent (gain k [1/s]); exactly reactionless at ``theta``."""
        n = self.direction(theta, t)
        return (rate * self.speed(t) + gain * float(n @ error)) * n


class StoredTrajectory(JointSpaceSegment):
    """A trajectory stored at equally spaced times (IJ-C / TJ-C), linearly interpolated."""

    def __init__(self, times: np.ndarray, thetas: np.ndarray, rates: np.ndarray) -> None:
        self.times, self.thetas, self.rates = times, thetas, rates
        self.duration = float(times[-1])

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        k = int(np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, self.times.size - 2))
        u = (t - self.times[k]) / (self.times[k + 1] - self.times[k])
        u = min(max(u, 0.0), 1.0)
        theta = (1.0 - u) * self.thetas[k] + u * self.thetas[k + 1]
        rate = (1.0 - u) * self.rates[k] + u * self.rates[k + 1]
        return theta, rate


class PtpPlan:
    """A planned point-to-point motion (immutable after planning).

    Attributes:
        method: :class:`PtpMethod`.
        duration: total duration [s].
        phases: :class:`PhaseInfo` per phase, consecutive.
        notes: what was stretched, where folds ended, gains chosen.
        goal: configuration at the end [rad], shape (n,).
        start: configuration at t = 0 [rad], shape (n,).
        elbow_gain: k of eq. (4.18) used by :meth:`command` [1/s].
        details: method-specific read-only facts, e.g. IJ-C/TJ-C ``camera_target`` [m] (3,),
            ``gain`` and ``final_error`` [m].
    """

    def __init__(
        self, method, phases, segments, notes, goal, start, elbow_gain=5.0, details=None
    ) -> None:
        self.method = PtpMethod.parse(method)
        self.phases: tuple[PhaseInfo, ...] = tuple(phases)
        self._segments = tuple(segments)
        self.notes: tuple[str, ...] = tuple(notes)
        self.goal = np.array(goal, dtype=float)
        self.goal.setflags(write=False)
        self.start = np.array(start, dtype=float)
        self.start.setflags(write=False)
        self.duration = float(self.phases[-1].end)
        self.elbow_gain = float(elbow_gain)
        self.details = MappingProxyType(dict(details or {}))

    def _locate(self, t: float):
        t = min(max(float(t), 0.0), self.duration)
        for phase, segment in zip(self.phases, self._segments, strict=True):
            if t <= phase.end or phase is self.phases[-1]:
                return t, phase, segment
        raise AssertionError("unreachable")

    def sample(self, t: float) -> PtpReference:
        """Reference at time ``t`` [s] (clipped to [0, duration]); theta_dot = 0 after the end."""
        t, phase, segment = self._locate(t)
        theta, theta_dot = segment(t - phase.start)
        done = t >= self.duration
        return PtpReference(
            theta=np.array(theta),
            theta_dot=np.zeros(len(theta)) if done else np.array(theta_dot),
            phase="done" if done else phase.name,
            progress=t / self.duration,
        )

    def command(self, t: float, theta) -> np.ndarray:
        """Joint velocity command [rad/s] (n,) at time ``t`` [s] for the measured ``theta``.

        In a reactionless phase: theta_dot = (sigma_dot + k n . (theta_ref - theta)) n(theta), the
        arc-length form of eq. (4.18) (error projected on the path tangent), exactly reactionless
        at the measured configuration. Elsewhere: theta_dot_ref + k (theta_ref - theta).
        """
        theta = np.asarray(theta, dtype=float)
        t, phase, segment = self._locate(t)
        if t >= self.duration:
            return np.zeros_like(theta)
        local = t - phase.start
        return segment.track(local, theta, segment.angles(local) - theta, 1.0, self.elbow_gain)

    def track(self, t: float, theta, error, rate: float) -> np.ndarray:
        """Joint velocity [rad/s] (n,) at plan time ``t`` [s] (clipped to [0, duration]) for
        an arm at ``theta`` [rad] (n,) that is ``error`` e [rad] (n,) behind the plan, at the
        playback rate ``rate`` r [-]: r theta_dot_ref + k e, or in a reactionless phase
        (r sigma_dot + k n . e) n(theta), reactionless at ``theta`` (eq. 4.18, k =
        ``elbow_gain``). :meth:`command` is this at r = 1 with e = theta_ref(t) - theta."""
        t, phase, segment = self._locate(t)
        theta = np.asarray(theta, dtype=float)
        error = np.asarray(error, dtype=float)
        return segment.track(t - phase.start, theta, error, rate, self.elbow_gain)

    def angles(self, t: float) -> np.ndarray:
        """theta_ref(t) [rad] (n,) at ``t`` [s] (clipped to [0, duration])."""
        t, phase, segment = self._locate(t)
        return np.asarray(segment.angles(t - phase.start), dtype=float)

    def is_reactionless(self, t: float) -> bool:
        """Whether the phase at time ``t`` [s] is reactionless."""
        return self._locate(t)[1].reactionless


# timing --------------------------------------------------------------------------------------
def check_configuration(robot: FreeFloatingModel, theta, name: str) -> np.ndarray:
    """``theta`` as a finite vector (n,) [rad] within the position limits (1e-9 rad slack), else
    :class:`InputError` naming the joint."""
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


def joint_speed_limits(robot: FreeFloatingModel) -> np.ndarray:
    """Velocity limits [rad/s] (n,), a limit of 0 (none given) read as unlimited."""
    return np.where(robot.velocity_limits > 0.0, robot.velocity_limits, np.inf)


def line_duration(robot: FreeFloatingModel, delta: np.ndarray, nominal: float) -> float:
    """Shortest quintic duration >= nominal [s] keeping 1.875 |delta_i| / T <= limit_i."""
    return max(
        nominal, float(np.max(QUINTIC_PEAK_RATE * np.abs(delta) / joint_speed_limits(robot)))
    )


def path_duration(robot: FreeFloatingModel, path: ReactionlessPath, nominal: float) -> float:
    """Shortest duration >= nominal [s] with 1.875 L |n_i| / T <= limit_i on every node."""
    worst = (
        float(np.max(np.abs(path.tangent) / joint_speed_limits(robot))) if path.length > 0 else 0.0
    )
    return max(nominal, QUINTIC_PEAK_RATE * path.length * worst)


def stretch_note(name: str, nominal: float, duration: float) -> list[str]:
    """The note for phase ``name`` if it was stretched from ``nominal`` to ``duration`` [s]."""
    if duration > nominal + 1e-9:
        return [
            f"phase {name} stretched from {nominal:g} to {duration:.2f} s: joint velocity limits"
        ]
    return []
