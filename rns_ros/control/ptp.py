"""Point-to-point motion planning of the free-floating arm (thesis sections 4.4-4.5).

Every method returns a :class:`PtpPlan` that is sampled in time (:meth:`PtpPlan.sample`); a
controller plays ``theta_dot`` (optionally with :meth:`PtpPlan.command`'s position feedback).

Methods (:class:`PtpMethod`, thesis names in brackets, thesis_rest section 2):

* ``three_phase`` (3-phase, section 4.4.1): Phase I follows the reactionless elbow path from the
  start towards the fold theta_4 = ``fold_angle`` (FA-1); Phase III is the reactionless path from
  the goal towards the fold (FA-2), played backwards; Phase II is a quintic joint-space line
  FA-1 -> FA-2, the only phase that is not reactionless.
* ``joint_space`` (JS-C): quintic straight line start -> goal over ``settings.duration``.
* ``inverse_jacobian`` (IJ-C): theta_dot_P = J*_P^+ (p_dot_des + K_p (p_des - p_e)), with J*_P the
  linear rows of the Generalized Jacobian of the camera for the positioning joints (A-2.8) and
  p_des a quintic straight line from the start camera position to ``camera_target``.
* ``transposed_jacobian`` (TJ-C): theta_dot_P = K J*_P^T (p_des - p_e), same p_des (A-2.9); K is
  the first of ``transposed_gains`` whose final error is below ``target_tolerance``.
* ``deploy`` (section 4.5.1): full reactionless deployment from the start configuration.

For IJ-C and TJ-C only the positioning subchain is driven by the law (section 4.4.2); the wrist
joints move start -> goal on the JS-C quintic (held when start and goal wrists agree, as in the
thesis scenario). Both are closed-loop laws: they are integrated offline on the kinematic
free-floating model (zero momentum, RK4, ``integration_step``) and the resulting trajectory is
stored, so :meth:`PtpPlan.sample` gives the same kind of output as for the other methods.

Reactionless elbow path (eqs. 4.3, 4.17-4.18 by arc length, A-2.2): the positioning joints move
along theta_dot_P = beta n(theta), n the unit vector spanning ker M~_P_omega_m (3 x 4 block of
M~_omega_m for the positioning joints; wrist held), kept sign-continuous. Unlike eq. (4.17)'s
theta_dot_4 / n_4 this has no singularity where n_4 = 0: the path passes turning points of
theta_4 smoothly. A fold ends where theta_4 reaches ``fold_angle`` or at the first turning point
where theta_4 turns back away from it (the most-folded configuration the path reaches), whichever
comes first. Each reactionless phase is timed with a rest-to-rest quintic in arc length,
sigma(t) = L s(t / T); T is stretched (never a per-joint clip) so that
sigma_dot_max |n_i| = 1.875 L |n_i| / T <= velocity_limit_i on the whole path.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ConfigError, InputError, ModelError
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.momentum import generalized_jacobian
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.timing import QUINTIC_PEAK_RATE, quintic
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


# reactionless elbow path ------------------------------------------------------------------------
class _NullVector:
    """n(theta): unit vector of ker M~_P_omega_m (eq. 4.3) on a private ``pin.Data``."""

    def __init__(self, robot: FreeFloatingModel) -> None:
        if robot.subchains is None:
            raise ModelError(f"{robot.name}: reactionless paths need positioning/wrist subchains")
        self.robot = robot
        self.data = robot.model.createData()
        self.positioning = robot.subchains.positioning

    def __call__(self, theta: np.ndarray, reference: np.ndarray | None = None) -> np.ndarray:
        """Unit n, shape (p,), signed so that n . reference >= 0 (sign continuity)."""
        q = self.robot.configuration(theta)
        centroidal = pin.computeCentroidalMap(self.robot.model, self.data, q)
        block = centroidal[3:, 6:][:, self.positioning]
        n = np.linalg.svd(block)[2][-1]
        if reference is not None and n @ reference < 0.0:
            n = -n
        return n


@dataclass(frozen=True)
class ReactionlessPath:
    """A reactionless elbow path by arc length (eqs. 4.3, 4.17-4.18; A-2.2).

    Attributes:
        arc: arc length of the nodes [rad], shape (m,), from 0 (the start).
        theta: configurations at the nodes [rad], shape (m, n) (wrist constant).
        tangent: unit d theta / d sigma at the nodes (zero on the wrist), shape (m, n).
        reached: theta_4 reached the target.
        turning_points: theta_4 where n_4 changed sign along the followed path [rad].
        min_n4: smallest |n_4| on the path [-].
        turn_kinks: |change of the unit tangent| over the step of each turning point [-]: ~step
            at a smooth turning point; O(1) where the path grazes a rank drop of M~_P_omega_m
            (sigma_3 -> 0) and n(theta) swings within one step.
    """

    arc: np.ndarray
    theta: np.ndarray
    tangent: np.ndarray
    reached: bool
    turning_points: tuple[float, ...]
    min_n4: float
    turn_kinks: tuple[float, ...] = ()

    @property
    def length(self) -> float:
        """Total arc length L [rad]."""
        return float(self.arc[-1])

    @property
    def end(self) -> np.ndarray:
        """Last configuration [rad], shape (n,)."""
        return self.theta[-1]

    def at(self, sigma: float) -> tuple[np.ndarray, np.ndarray]:
        """theta(sigma) by cubic Hermite interpolation of the nodes, and the interpolated tangent.

        Returns:
            (theta [rad] (n,), unit-ish tangent d theta / d sigma (n,)).
        """
        sigma = min(max(sigma, 0.0), self.length)
        k = int(np.clip(np.searchsorted(self.arc, sigma, side="right") - 1, 0, self.arc.size - 2))
        h = self.arc[k + 1] - self.arc[k]
        if h <= 0.0:
            return self.theta[k].copy(), self.tangent[k].copy()
        u = (sigma - self.arc[k]) / h
        p0, p1, m0, m1 = self.theta[k], self.theta[k + 1], self.tangent[k], self.tangent[k + 1]
        h00, h10 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u
        h01, h11 = -2 * u**3 + 3 * u**2, u**3 - u**2
        theta = h00 * p0 + h10 * h * m0 + h01 * p1 + h11 * h * m1
        d00, d10 = (6 * u**2 - 6 * u) / h, 3 * u**2 - 4 * u + 1
        d01, d11 = (-6 * u**2 + 6 * u) / h, 3 * u**2 - 2 * u
        tangent = d00 * p0 + d10 * m0 + d01 * p1 + d11 * m1
        return theta, tangent


def reactionless_path(
    robot: FreeFloatingModel,
    theta0,
    theta4_target: float,
    *,
    step: float = 0.01,
    max_arc: float = 12.0,
    stop_at_turning_point: bool = True,
) -> ReactionlessPath:
    """Follow the reactionless elbow family from ``theta0`` towards theta_4 = ``theta4_target``.

    d theta_P / d sigma = n(theta) (unit, sign-continuous), integrated with RK4 in arc length
    sigma [rad] (``step``); the wrist is held. The direction starts with n_4 towards the target.
    Stops where theta_4 crosses the target (the last node is interpolated onto it), after
    ``max_arc`` [rad], or, with ``stop_at_turning_point``, at the first point where n_4 changes
    sign (theta_4 turns back away from the target; the node is interpolated to n_4 = 0).

    Raises:
        InputError: ``theta0`` is not a finite vector of the model's size.
    """
    theta = as_vector(theta0, robot.n, "theta0").copy()
    step = positive(step, "path step", "[rad]")
    null = _NullVector(robot)
    p = null.positioning
    elbow = int(np.flatnonzero(p == p[-1])[0])  # index of the elbow (last positioning joint)
    sense = 1.0 if theta4_target >= theta[p[-1]] else -1.0
    n = null(theta)
    if n[elbow] * sense < 0.0:
        n = -n

    def tangent(vector: np.ndarray) -> np.ndarray:
        full = np.zeros(robot.n)
        full[p] = vector
        return full

    arcs, thetas, tangents = [0.0], [theta.copy()], [tangent(n)]
    turning, kinks, min_n4, reached, arc = [], [], abs(float(n[elbow])), False, 0.0
    while arc < max_arc - 1e-12:
        h = min(step, max_arc - arc)
        new, n_new = _rk4_step(null, theta, n, h, p)
        min_n4 = min(min_n4, abs(float(n_new[elbow])))
        elbow_before, elbow_after = theta[p[-1]], new[p[-1]]
        if (elbow_after - theta4_target) * sense >= 0.0:
            fraction = (theta4_target - elbow_before) / (elbow_after - elbow_before)
            new, n_new, h, reached = _refine(null, theta, n, h, fraction, p)
            arcs.append(arc + h)
            thetas.append(new)
            tangents.append(tangent(n_new))
            break
        if n_new[elbow] * n[elbow] < 0.0:
            fraction = n[elbow] / (n[elbow] - n_new[elbow])
            turn, n_turn, h_turn, _ = _refine(null, theta, n, h, fraction, p)
            turning.append(float(turn[p[-1]]))
            kinks.append(float(np.linalg.norm(n_new - n)))
            if stop_at_turning_point and n[elbow] * sense > 0.0:
                arcs.append(arc + h_turn)
                thetas.append(turn)
                tangents.append(tangent(n_turn))
                break
        arc += h
        theta, n = new, n_new
        arcs.append(arc)
        thetas.append(theta.copy())
        tangents.append(tangent(n))
    return ReactionlessPath(
        arc=np.array(arcs),
        theta=np.array(thetas),
        tangent=np.array(tangents),
        reached=reached,
        turning_points=tuple(turning),
        min_n4=min_n4,
        turn_kinks=tuple(kinks),
    )


def _rk4_step(null: _NullVector, theta, n, h, p) -> tuple[np.ndarray, np.ndarray]:
    """One RK4 step of arc length ``h`` [rad] along d theta_P / d sigma = n(theta) from
    (theta, n): (theta [rad] (n_joints,), unit n at it, sign-continuous)."""
    k1 = n
    x = theta.copy()
    x[p] += 0.5 * h * k1
    k2 = null(x, k1)
    x = theta.copy()
    x[p] += 0.5 * h * k2
    k3 = null(x, k2)
    x = theta.copy()
    x[p] += h * k3
    k4 = null(x, k3)
    new = theta.copy()
    new[p] += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return new, null(new, k4)


def _refine(null: _NullVector, theta, n, h, fraction, p):
    """One RK4 step of length ``fraction * h`` from (theta, n): (theta, n, length, True)."""
    h = float(np.clip(fraction, 0.0, 1.0)) * h
    new, n_new = _rk4_step(null, theta, n, h, p)
    return new, n_new, h, True


# segments ------------------------------------------------------------------------------------
class _Line:
    """Quintic straight line a -> b over ``duration`` [s] (JS-C, Phase II)."""

    reactionless = False

    def __init__(self, start: np.ndarray, end: np.ndarray, duration: float) -> None:
        self.start, self.delta, self.duration = start, end - start, duration

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        s, s_dot = quintic(t, self.duration)
        return self.start + s * self.delta, s_dot * self.delta


class _PathSegment:
    """A reactionless path played with sigma(t) = L s(t / T) (or reversed: L (1 - s)).

    theta_dot is sigma_dot n(theta(t)) with n evaluated at the sampled configuration, so
    M~_omega_m theta_dot vanishes to machine precision there.
    """

    reactionless = True

    def __init__(self, path: ReactionlessPath, duration: float, null: _NullVector, reverse: bool):
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


class _Stored:
    """A trajectory stored at equally spaced times (IJ-C / TJ-C), linearly interpolated."""

    reactionless = False

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
        local = t - phase.start
        theta_ref, theta_dot_ref = segment(local)
        if t >= self.duration:
            return np.zeros_like(theta)
        if isinstance(segment, _PathSegment):
            n = segment.direction(theta, local)
            speed = segment.speed(local)
            if speed < 0.0:
                n = -n
            beta = abs(speed) + self.elbow_gain * float(n @ (theta_ref - theta))
            return beta * n
        return theta_dot_ref + self.elbow_gain * (theta_ref - theta)

    def is_reactionless(self, t: float) -> bool:
        """Whether the phase at time ``t`` [s] is reactionless."""
        return self._locate(t)[1].reactionless


# planning -----------------------------------------------------------------------------------
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


def _limits(robot: FreeFloatingModel) -> np.ndarray:
    return np.where(robot.velocity_limits > 0.0, robot.velocity_limits, np.inf)


def _line_duration(robot: FreeFloatingModel, delta: np.ndarray, nominal: float) -> float:
    """Shortest quintic duration >= nominal [s] keeping 1.875 |delta_i| / T <= limit_i."""
    return max(nominal, float(np.max(QUINTIC_PEAK_RATE * np.abs(delta) / _limits(robot))))


def _path_duration(robot: FreeFloatingModel, path: ReactionlessPath, nominal: float) -> float:
    """Shortest duration >= nominal [s] with 1.875 L |n_i| / T <= limit_i on every node."""
    worst = float(np.max(np.abs(path.tangent) / _limits(robot))) if path.length > 0 else 0.0
    return max(nominal, QUINTIC_PEAK_RATE * path.length * worst)


def _stretch_note(name: str, nominal: float, duration: float) -> list[str]:
    if duration > nominal + 1e-9:
        return [
            f"phase {name} stretched from {nominal:g} to {duration:.2f} s: joint velocity limits"
        ]
    return []


def _fold_note(name: str, path: ReactionlessPath, target: float) -> str:
    reached = math.degrees(float(path.end[3]))
    turns = ", ".join(f"{math.degrees(v):.1f}" for v in path.turning_points)
    if path.reached:
        text = f"fold {name}: theta_4 reaches {math.degrees(target):.1f} deg"
    elif path.turning_points:
        kind = (
            "smooth turning point"
            if path.turn_kinks[-1] < 0.1
            else f"turning point at a near rank drop of M~_P (tangent swings by "
            f"{path.turn_kinks[-1]:.2f} in one step)"
        )
        text = (
            f"fold {name}: {kind} at theta_4 = {reached:.1f} deg before "
            f"{math.degrees(target):.1f} deg; the fold ends there (most-folded configuration)"
        )
    else:
        text = f"fold {name}: arc limit reached at theta_4 = {reached:.1f} deg"
    extra = f"; turning points passed: {turns} deg" if path.turning_points and path.reached else ""
    return text + f" (arc {path.length:.3f} rad, min |n4| {path.min_n4:.3f})" + extra


def _fold(robot, theta, settings, name, nominal, reverse):
    path = reactionless_path(
        robot,
        theta,
        settings.fold_angle,
        step=settings.path_step,
        max_arc=settings.max_arc,
    )
    duration = _path_duration(robot, path, positive(nominal, f"phase {name} duration", "[s]"))
    segment = _PathSegment(path, duration, _NullVector(robot), reverse)
    notes = [_fold_note(name, path, settings.fold_angle), *_stretch_note(name, nominal, duration)]
    return path, segment, duration, notes


def _three_phase(robot, start, goal, settings) -> PtpPlan:
    d1, d2, d3 = settings.phase_durations
    path1, seg1, t1, notes1 = _fold(robot, start, settings, "I", d1, reverse=False)
    path3, seg3, t3, notes3 = _fold(robot, goal, settings, "III", d3, reverse=True)
    fa1, fa2 = path1.end, path3.end
    nominal2 = positive(d2, "phase II duration", "[s]")
    t2 = _line_duration(robot, fa2 - fa1, nominal2)
    phases = [
        PhaseInfo("I", 0.0, t1, True, float(fa1[3])),
        PhaseInfo("II", t1, t1 + t2, False, None),
        PhaseInfo("III", t1 + t2, t1 + t2 + t3, True, float(fa2[3])),
    ]
    notes = [*notes1, *notes3, *_stretch_note("II", nominal2, t2)]
    segments = [seg1, _Line(fa1, fa2, t2), seg3]
    return PtpPlan(PtpMethod.THREE_PHASE, phases, segments, notes, goal, start, settings.elbow_gain)


def plan_partial_deployment(
    robot: FreeFloatingModel, theta_stowed, theta_goal, settings: PtpSettings | None = None
) -> PtpPlan:
    """Partial reactionless deployment (section 4.5.2): Phase II joint-space line from the stowed
    configuration to the fold FA-2 of the goal, then Phase III, the reversed reactionless path from
    FA-2 to the goal (A-2.11/A-2.12/A-2.13: Phase II interpolates all joints, wrist included).

    Raises:
        InputError: bad stowed or goal configuration (names the joint).
    """
    settings = settings or PtpSettings()
    start = _check_configuration(robot, theta_stowed, "theta_stowed")
    goal = _check_configuration(robot, theta_goal, "theta_goal")
    _, d2, d3 = settings.phase_durations
    path3, seg3, t3, notes3 = _fold(robot, goal, settings, "III", d3, reverse=True)
    nominal2 = positive(d2, "phase II duration", "[s]")
    t2 = _line_duration(robot, path3.end - start, nominal2)
    phases = [
        PhaseInfo("II", 0.0, t2, False, None),
        PhaseInfo("III", t2, t2 + t3, True, float(path3.end[3])),
    ]
    notes = [*notes3, *_stretch_note("II", nominal2, t2)]
    segments = [_Line(start, path3.end, t2), seg3]
    return PtpPlan(PtpMethod.THREE_PHASE, phases, segments, notes, goal, start, settings.elbow_gain)


def plan_deployment(
    robot: FreeFloatingModel, theta_stowed, settings: PtpSettings | None = None
) -> PtpPlan:
    """Full reactionless deployment from ``theta_stowed`` (section 4.5.1).

    The elbow path runs towards theta_4 = theta_4(0) + deploy_rate * deploy_duration (2.349 rad
    from the stowed -pi with the thesis' 0.183 rad/s x 30 s), or to its first turning point.
    Timing: a quintic in arc length over ``deploy_duration`` (stretched to the velocity limits)
    instead of the thesis' constant theta_dot_4 (eq. 4.17 divides by n_4; the quintic starts and
    ends at rest); the mean theta_dot_4 is noted.

    Raises:
        InputError: bad stowed configuration (names the joint).
    """
    settings = settings or PtpSettings()
    start = _check_configuration(robot, theta_stowed, "theta_stowed")
    nominal = positive(settings.deploy_duration, "deploy_duration", "[s]")
    target = float(start[3] + settings.deploy_rate * nominal)
    path = reactionless_path(
        robot, start, target, step=settings.path_step, max_arc=max(settings.max_arc, 25.0)
    )
    duration = _path_duration(robot, path, nominal)
    segment = _PathSegment(path, duration, _NullVector(robot), reverse=False)
    swept = float(path.end[3] - start[3])
    notes = [
        _fold_note("deploy", path, target),
        f"timing: quintic in arc length over {duration:.2f} s, mean theta_dot_4 "
        f"{swept / duration:.3f} rad/s (thesis: constant {settings.deploy_rate:g} rad/s)",
        *_stretch_note("deploy", nominal, duration),
    ]
    phase = PhaseInfo("deploy", 0.0, duration, True, float(path.end[3]))
    return PtpPlan(
        PtpMethod.DEPLOY, [phase], [segment], notes, path.end, start, settings.elbow_gain
    )


# offline integration of IJ-C / TJ-C --------------------------------------------------------------
def integrate_kinematic(
    robot: FreeFloatingModel,
    q0: np.ndarray,
    law: Callable[[float, FreeFloatingState], np.ndarray],
    duration: float,
    step: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Kinematic free-floating RK4 (zero momentum) of theta_dot = law(t, state).

    The base twist keeps the centroidal momentum zero (eq. 2.33): A_b v_b = -A_m theta_dot with
    Pinocchio's centroidal map A_G = [A_b, A_m]; stage velocities are pulled back with
    Jlog6(exp6) as in :mod:`rns_ros.sim.free_floating`.

    Returns:
        (times [s] (k,), q (k, 7 + n), theta_dot at the nodes [rad/s] (k, n)).
    """
    model = robot.model
    data = model.createData()
    count = max(1, math.ceil(duration / step - 1e-9))
    dt = duration / count

    def rate(t: float, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        state = FreeFloatingState.compute(robot, q)
        theta_dot = np.asarray(law(t, state), dtype=float)
        centroidal = pin.computeCentroidalMap(model, data, q)
        base = np.linalg.solve(centroidal[:, :6], -centroidal[:, 6:] @ theta_dot)
        return np.concatenate((base, theta_dot)), theta_dot

    q = np.array(q0, dtype=float)
    times, qs, rates = [0.0], [q.copy()], []
    for i in range(count):
        t = i * dt

        def stage(fraction: float, velocity: np.ndarray, t=t, q=q) -> np.ndarray:
            increment = fraction * dt * velocity
            v, _ = rate(t + fraction * dt, pin.integrate(model, q, increment))
            v[:6] = pin.Jlog6(pin.exp6(increment[:6])) @ v[:6]
            return v

        k1, theta_dot = rate(t, q)
        rates.append(theta_dot)
        k2 = stage(0.5, k1)
        k3 = stage(0.5, k2)
        k4 = stage(1.0, k3)
        q = pin.integrate(model, q, dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4))
        times.append(t + dt)
        qs.append(q.copy())
    rates.append(np.zeros(robot.n))
    return np.array(times), np.array(qs), np.array(rates)


def final_camera_position(robot: FreeFloatingModel, plan: PtpPlan, step: float) -> np.ndarray:
    """Camera position in world [m] (3,) at the end of ``plan`` played on the kinematic
    free-floating model from the base at the origin with identity attitude (A-2.5)."""
    q0 = robot.configuration(plan.start)
    _, qs, _ = integrate_kinematic(
        robot, q0, lambda t, state: plan.sample(t).theta_dot, plan.duration, step
    )
    return np.array(FreeFloatingState.compute(robot, qs[-1]).camera.position)


def _jacobian_baseline(robot, start, goal, method, settings) -> PtpPlan:
    if robot.subchains is None:
        raise ModelError(f"{robot.name}: IJ-C/TJ-C drive the positioning subchain; none is set")
    positioning, wrist = robot.subchains.positioning, robot.subchains.wrist
    duration = positive(settings.duration, "duration", "[s]")
    step = positive(settings.integration_step, "integration_step", "[s]")
    notes = []
    if settings.camera_target is None:
        reference = _three_phase(robot, start, goal, settings)
        target = final_camera_position(robot, reference, step)
        notes.append("camera target: final camera position of the 3-phase plan (A-2.5)")
    else:
        target = as_vector(settings.camera_target, 3, "camera_target")
        notes.append("camera target: settings.camera_target")
    q0 = robot.configuration(start)
    p0 = np.array(FreeFloatingState.compute(robot, q0).camera.position)
    limits = _limits(robot)
    wrist_line = _Line(start[wrist], goal[wrist], duration)

    def run(gain: float):
        scaled = [0]

        def law(t: float, state: FreeFloatingState) -> np.ndarray:
            s, s_dot = quintic(t, duration)
            p_des, v_des = p0 + s * (target - p0), s_dot * (target - p0)
            jacobian = generalized_jacobian(state, state.camera)[:3]
            error = p_des - state.camera.position
            theta_dot = np.zeros(robot.n)
            theta_dot[wrist] = wrist_line(t)[1]
            j_p = jacobian[:, positioning]
            if method is PtpMethod.INVERSE_JACOBIAN:
                rhs = v_des + gain * error - jacobian[:, wrist] @ theta_dot[wrist]
                theta_dot[positioning] = np.linalg.lstsq(j_p, rhs, rcond=1e-10)[0]
            else:
                theta_dot[positioning] = gain * (j_p.T @ error)
            excess = float(np.max(np.abs(theta_dot) / limits))
            if excess > 1.0:
                scaled[0] += 1
                theta_dot /= excess
            return theta_dot

        times, qs, rates = integrate_kinematic(robot, q0, law, duration, step)
        error = float(
            np.linalg.norm(FreeFloatingState.compute(robot, qs[-1]).camera.position - target)
        )
        return times, qs, rates, error, scaled[0]

    if method is PtpMethod.INVERSE_JACOBIAN:
        gain = positive(settings.position_gain, "position_gain", "[1/s]")
        times, qs, rates, error, scaled = run(gain)
        name = "IJ-C"
        notes.append(
            f"IJ-C: Generalized Jacobian, K_p = {gain:g} 1/s; "
            f"final camera error {error * 1e3:.2f} mm"
        )
    else:
        name = "TJ-C"
        for gain in settings.transposed_gains:
            times, qs, rates, error, scaled = run(positive(gain, "transposed gain"))
            if error < settings.target_tolerance:
                break
        notes.append(
            f"TJ-C: Generalized Jacobian transpose, K = {gain:g}; final camera error "
            f"{error * 1e3:.2f} mm (tolerance {settings.target_tolerance * 1e3:g} mm)"
        )
    if scaled:
        notes.append(
            f"{name}: command scaled uniformly to the velocity limits at {scaled} evaluations"
        )
    thetas = qs[:, 7:]
    segment = _Stored(times, thetas, rates)
    phase = PhaseInfo(name, 0.0, duration, False, None)
    details = {"camera_target": target, "gain": gain, "final_error": error}
    return PtpPlan(
        method, [phase], [segment], notes, thetas[-1], start, settings.elbow_gain, details
    )


def plan_ptp(
    robot: FreeFloatingModel,
    theta_start,
    theta_goal,
    method: PtpMethod | str,
    settings: PtpSettings | None = None,
) -> PtpPlan:
    """Plan a point-to-point motion start -> goal with ``method`` (see the module docstring).

    ``deploy`` ignores the goal (it deploys from the start, :func:`plan_deployment`); IJ-C/TJ-C
    end where their closed loop brings the arm (``plan.goal``), not exactly at ``theta_goal``.

    Raises:
        InputError: non-finite or out-of-limit start/goal (the message names the joint).
        ConfigError: unknown method or a non-positive duration.
    """
    settings = settings or PtpSettings()
    method = PtpMethod.parse(method)
    start = _check_configuration(robot, theta_start, "theta_start")
    if method is PtpMethod.DEPLOY:
        return plan_deployment(robot, start, settings)
    goal = _check_configuration(robot, theta_goal, "theta_goal")
    if method is PtpMethod.JOINT_SPACE:
        nominal = positive(settings.duration, "duration", "[s]")
        duration = _line_duration(robot, goal - start, nominal)
        notes = _stretch_note("JS-C", nominal, duration)
        phase = PhaseInfo("JS-C", 0.0, duration, False, None)
        return PtpPlan(
            method, [phase], [_Line(start, goal, duration)], notes, goal, start, settings.elbow_gain
        )
    if method is PtpMethod.THREE_PHASE:
        return _three_phase(robot, start, goal, settings)
    if method in (PtpMethod.INVERSE_JACOBIAN, PtpMethod.TRANSPOSED_JACOBIAN):
        return _jacobian_baseline(robot, start, goal, method, settings)
    raise ConfigError(f"ptp method {method.value} is not handled")  # pragma: no cover
