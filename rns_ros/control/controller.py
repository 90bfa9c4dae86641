"""Sampled reactionless camera controller: the law of :mod:`rns_ros.control.camera_law`, held.

A digital controller evaluates eq. (4.5)/(4.15) at the sampled configuration theta_k and holds the
resulting theta_dot for one period T while the arm moves. The constraint M~_omega_m(theta) theta_dot
= 0 (eq. 3.3) holds only where it was evaluated, so over the hold the base turns by

    delta_phi ~= -M~_omega^-1 integral_0^T M~_omega_m(theta_k + tau theta_dot) theta_dot dtau,

first order in T when the law is evaluated at theta_k (``naive``). Evaluating the whole law at the
predicted mid-interval configuration theta_k + T/2 theta_dot (``midpoint``) makes the integral
vanish to second order and also centres the camera's angular velocity on the interval. The
prediction extrapolates the last two held outputs and is checked against the output (repeated
from the output when they disagree by more than HOLD_CONSISTENCY); the law at the midpoint runs on a
partial state in closed form (:meth:`FreeFloatingState.arm_kinematics`,
:func:`~rns_ros.control.camera_law.arm_law_rates`). The base deviations of both corrections
are compared in docs/controller.md.

The controller also integrates the joint position reference theta_ref += T theta_dot that a
position servo tracks, and keeps the wrist reference p_w^init of eq. (4.6).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rns_ros.control.camera_law import (
    ControlGains,
    ControlOutput,
    LawRates,
    Method,
    arm_law_rates,
    control_output,
    law_rates,
    wrist_offset,
)
from rns_ros.core.errors import ConfigError
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import Choice, as_vector, positive

#: Default control rate [Hz] of the ROS controller.
DEFAULT_RATE = 100.0
#: Largest number of midpoint iterations accepted (one suffices at 100 Hz, docs/controller.md).
MAX_HOLD_ITERATIONS = 5
#: A midpoint evaluation is consistent when its output theta_dot and the prediction it was
#: evaluated at differ by at most HOLD_CONSISTENCY * T * max(max|theta_dot|, HOLD_SPEED_FLOOR)
#: (inf-norm) [1/s]: the evaluation point is then within 1.5e-2 T^2 max|theta_dot| [rad] of the
#: held motion's midpoint, about what the law at the sample leaves as predictor. The check keeps
#: an extrapolation that misses (near the algorithmic singularity, where the speed limit binds)
#: from being trusted; a looser or tighter value changes the base deviation little and the
#: number of evaluations per period more (docs/controller.md).
HOLD_CONSISTENCY = 3e-2
#: A hold ends within max(MAX_HOLD_PERIODS T, MAX_HOLD_FLOOR) [-], [s]: a late tick of a busy
#: executor ends one after up to ~3 T (28 ms seen at 100 Hz); a longer interval between two ticks
#: means the clock jumped or the node stalled, and how far the held theta_dot took the arm is
#: not known (:meth:`ReactionlessController.end_hold`).
MAX_HOLD_PERIODS = 5.0
MAX_HOLD_FLOOR = 0.05
#: Speed floor of HOLD_CONSISTENCY [rad/s]: below it the tolerance stays at this speed's (slow
#: motion turns the base by little: the error of an evaluation point scales with max|theta_dot|).
HOLD_SPEED_FLOOR = 0.1


def max_hold(period: float) -> float:
    """max(MAX_HOLD_PERIODS T, MAX_HOLD_FLOOR) [s] for the control period T = ``period`` [s]:
    ticks further apart than this are no late tick but a stall (or a clock jump)."""
    return max(MAX_HOLD_PERIODS * period, MAX_HOLD_FLOOR)


class HoldCorrection(Choice):
    """Where the law is evaluated for an output held over one control period."""

    __label__ = "hold_correction"

    NAIVE = "naive"
    MIDPOINT = "midpoint"


class TwistFrame(Choice):
    """Axes a commanded angular velocity is expressed in."""

    __label__ = "twist frame"

    WORLD = "world"
    BASE = "base"
    CAMERA = "camera"


def angular_velocity_in_world(state: FreeFloatingState, omega, frame: TwistFrame) -> np.ndarray:
    """Rotate a commanded angular velocity into world axes [rad/s], shape (3,).

    ``base``: omega_world = R_base omega; ``camera``: omega_world = R_camera omega, both at the
    sampled state (a free vector, so only the rotation matters).
    """
    omega = as_vector(omega, 3, "angular velocity")
    if frame is TwistFrame.WORLD:
        return omega
    rotation = state.base_rotation if frame is TwistFrame.BASE else state.camera.rotation
    return rotation @ omega


@dataclass(frozen=True)
class ControllerSettings:
    """Settings of :class:`ReactionlessController`.

    Attributes:
        method: singularity handling (:class:`Method`).
        gains: thesis gains (:class:`ControlGains`).
        period: control period T the output is held for [s], > 0.
        hold_correction: ``midpoint`` (default) or ``naive``.
        hold_iterations: midpoint evaluations after the law at the sample when there is no
            history, and the most repeats of a checked extrapolation otherwise, 1..5.
    """

    method: Method = Method.DLS
    gains: ControlGains = field(default_factory=ControlGains)
    period: float = 1.0 / DEFAULT_RATE
    hold_correction: HoldCorrection = HoldCorrection.MIDPOINT
    hold_iterations: int = 1

    def __post_init__(self) -> None:
        object.__setattr__(
            self,
            "method",
            Method.parse(self.method),
        )
        object.__setattr__(
            self,
            "hold_correction",
            HoldCorrection.parse(self.hold_correction),
        )
        positive(self.period, "period", "s")
        if not 1 <= int(self.hold_iterations) <= MAX_HOLD_ITERATIONS:
            raise ConfigError(
                f"hold_iterations must be in [1, {MAX_HOLD_ITERATIONS}], "
                f"got {self.hold_iterations!r}"
            )


@dataclass(frozen=True)
class ControllerStep:
    """One control period.

    Attributes:
        output: the law evaluated where it was last evaluated (the predicted mid-interval
            configuration for ``midpoint``); its ``joint_velocity`` is the command.
        joint_velocity: theta_dot held over the period [rad/s], shape (n,).
        reference_positions: theta_ref at the start of the period [rad], shape (n,); during
            the period the reference moves on at ``joint_velocity`` (what a servo tracks).
        evaluated_theta: joint angles the law was evaluated at [rad], shape (n,).
    """

    output: ControlOutput
    joint_velocity: np.ndarray
    reference_positions: np.ndarray
    evaluated_theta: np.ndarray


class ReactionlessController:
    """Teleoperation controller: omega_ref in, held theta_dot and theta_ref out, once per period.

    Usage::

        controller = ReactionlessController(robot, ControllerSettings(method="dls"))
        controller.reset(state)                # wrist reference and theta_ref from the robot
        step = controller.step(state, omega)   # every period, state sampled now
    """

    def __init__(self, robot: FreeFloatingModel, settings: ControllerSettings | None = None):
        self.robot = robot
        self.settings = settings or ControllerSettings()
        self._wrist_reference: np.ndarray | None = None
        self._reference: np.ndarray | None = None
        # the hold in progress: theta_ref at its start and theta_dot held (for end_hold)
        self._open_hold: tuple[np.ndarray, np.ndarray] | None = None
        # theta_dot held over the last (up to) two periods, oldest first: the midpoint predictor
        self._recent_rates: tuple[np.ndarray, ...] = ()

    @property
    def wrist_reference(self) -> np.ndarray | None:
        """p_w^init of eq. (4.6): wrist offset from the base origin, world axes [m], (3,)."""
        return self._wrist_reference

    @property
    def reference_positions(self) -> np.ndarray | None:
        """Integrated joint position reference theta_ref [rad], shape (n,)."""
        return self._reference

    def reset(self, state: FreeFloatingState) -> None:
        """Take p_w^init and theta_ref from ``state`` (start, or after the operator idled)."""
        self._wrist_reference = wrist_offset(state) if state.wrist is not None else None
        self._reference = state.theta.copy()
        self._open_hold = None
        self._recent_rates = ()

    def resync(self, state: FreeFloatingState) -> None:
        """Restart theta_ref at the measured angles, keeping the wrist reference (taken from
        ``state`` when there is none yet: a controller that starts by resyncing must still hold
        the wrist, eq. 4.6)."""
        if self._wrist_reference is None and state.wrist is not None:
            self._wrist_reference = wrist_offset(state)
        self._reference = state.theta.copy()
        self._open_hold = None
        self._recent_rates = ()

    @property
    def max_hold(self) -> float:
        """The longest hold [s] :meth:`end_hold` takes: :func:`max_hold` of the period T."""
        return max_hold(self.settings.period)

    def end_hold(self, elapsed: float, limit: float | None = None) -> bool:
        """End the hold in progress after ``elapsed`` [s], which may differ from the period T.

        A plant holds theta_dot until the next output arrives, and outputs do not come exactly T
        apart: a new command is served at once (early), and a busy executor fires its timer late.
        theta_ref then stands where the held theta_dot actually brought the arm:
        theta_ref = theta_ref,start + elapsed * theta_dot, so a position-tracking servo follows
        the motion the arm actually made.

        ``elapsed`` outside [0, ``limit``] (default :attr:`max_hold`; or not finite) is a clock
        that went back or jumped, or a node that stalled: the hold is dropped, theta_ref stays
        where it started (never moved on by a clock difference), and False is returned: the
        caller restarts theta_ref at the measured angles (:meth:`resync`). A caller that has
        checked ``elapsed`` on a steady clock (a stall, not a jump) may pass a longer ``limit``
        [s]. Without a hold in progress this does nothing (True).
        """
        if self._open_hold is None:
            return True
        start, theta_dot = self._open_hold
        self._open_hold = None
        elapsed = float(elapsed)
        limit = self.max_hold if limit is None else limit
        if not 0.0 <= elapsed <= limit:
            self._reference = start
            return False
        self._reference = start + elapsed * theta_dot
        return True

    def abandon_hold(self) -> None:
        """Drop the hold in progress without ending it: theta_ref stays where it started (how
        long the output was held is not known, e.g. the clock cannot be trusted)."""
        if self._open_hold is not None:
            self._reference = self._open_hold[0]
            self._open_hold = None

    def configure(self, settings: ControllerSettings) -> None:
        """Swap settings between steps (run-time parameter changes)."""
        self.settings = settings
        self._recent_rates = ()

    def step(
        self, state: FreeFloatingState, omega_ref, hold: float | None = None
    ) -> ControllerStep:
        """Evaluate the law for the coming hold and advance theta_ref.

        Args:
            state: the robot sampled now (where the hold starts).
            omega_ref: commanded camera angular velocity, world axes [rad/s], shape (3,).
            hold: how long this output will be held [s], > 0; default the period T. A
                sampled controller that knows its next output comes early (a command served
                between ticks, a late tick followed by one on the timer's grid) puts the
                midpoint at theta_k + hold/2 theta_dot: the hold stays reactionless to second
                order whatever its length.
        """
        if self._reference is None:
            self.reset(state)
        settings = self.settings
        period = settings.period if hold is None else positive(hold, "hold", "s")
        omega_ref = as_vector(omega_ref, 3, "omega_ref")
        evaluated_theta = state.theta
        if settings.hold_correction is HoldCorrection.NAIVE:
            output = control_output(state, omega_ref, self._rates(state, omega_ref, period))
        else:
            evaluated_theta, output = self._midpoint(state, omega_ref, period)
        theta_dot = output.joint_velocity
        start = self._reference
        self._reference = start + period * theta_dot
        self._open_hold = (start, theta_dot)
        self._recent_rates = (*self._recent_rates[-1:], theta_dot)
        return ControllerStep(
            output=output,
            joint_velocity=theta_dot,
            reference_positions=start,
            evaluated_theta=evaluated_theta,
        )

    def _midpoint(
        self, state: FreeFloatingState, omega_ref: np.ndarray, period: float
    ) -> tuple[np.ndarray, ControlOutput]:
        """The law at the predicted mid-hold configuration theta_k + h/2 theta_dot_pred (h =
        ``period``, the hold [s]): (evaluated theta, output).

        Predictor: the held theta_dot extrapolated linearly from the last two periods (the
        previous one alone after one period). It is checked, not trusted: an evaluation whose
        output differs from its prediction by more than HOLD_CONSISTENCY T max|theta_dot| is
        repeated from its own output (fixed-point iteration of the midpoint rule), up to
        ``hold_iterations`` times. The extrapolation lies much closer to the output than the law
        at the sample and usually passes at once; repeats cluster where the speed limit binds or
        J-bar nears a singularity. The check matters: an unchecked warm start can make SC
        oscillate. Without history (after reset, resync or configure) the predictor is the law
        at the sample, followed by ``hold_iterations`` evaluations.
        """
        settings = self.settings
        half = 0.5 * period
        held = self._recent_rates
        if not held:
            predicted = self._rates(state, omega_ref, period).joint_velocity
            for _ in range(settings.hold_iterations):
                theta = state.theta + half * predicted
                rates, output = self._midpoint_rates(state, theta, omega_ref, half)
                predicted = rates.joint_velocity
            return theta, output
        predicted = 2.0 * held[1] - held[0] if len(held) == 2 else held[0]
        for _ in range(1 + settings.hold_iterations):
            theta = state.theta + half * predicted
            rates, output = self._midpoint_rates(state, theta, omega_ref, half)
            theta_dot = rates.joint_velocity
            miss = max(map(abs, (theta_dot - predicted).tolist()))
            speed = max(max(map(abs, theta_dot.tolist())), HOLD_SPEED_FLOOR)
            if miss <= HOLD_CONSISTENCY * settings.period * speed:
                break
            predicted = theta_dot
        return theta, output

    def _midpoint_rates(
        self, state: FreeFloatingState, theta: np.ndarray, omega_ref: np.ndarray, horizon: float
    ) -> tuple[LawRates, ControlOutput]:
        """The law at the predicted midpoint ``theta`` (base pose of ``state``); position limits
        judged over the ``horizon`` [s] (half the hold) left after it. Exact either way: the
        closed form on :class:`ArmKinematics` (no SVD, no P_RNS) where it applies, else the
        full state."""
        settings = self.settings
        arm = state.arm_kinematics(theta)
        closed = arm_law_rates(
            self.robot,
            arm,
            omega_ref,
            settings.method,
            settings.gains,
            self._wrist_reference,
            horizon,
            float(state.coupling_singular_values[0]),
        )
        if closed is not None:
            return closed
        evaluated = state.with_joint_angles(theta)
        rates = self._rates(evaluated, omega_ref, horizon)
        return rates, control_output(evaluated, omega_ref, rates)

    def _rates(self, state: FreeFloatingState, omega_ref: np.ndarray, horizon: float) -> LawRates:
        settings = self.settings
        return law_rates(
            self.robot,
            state,
            omega_ref,
            settings.method,
            settings.gains,
            self._wrist_reference,
            horizon,
        )
