"""Goal intake and planning of rns_ptp (:mod:`rns_ros.nodes.ptp`): a goal message as a joint
configuration, the worker thread that plans one goal at a time, the node's goal and cancel
callbacks (:class:`GoalIntake`), and the check of a plan sent as one trajectory.

Goals are numbered: only the result for the newest is taken. A goal that comes while a plan is
being computed waits as the newest request (a flood of goals replaces itself there instead of
starting threads). A goal that comes while the arm moves waits, deferred, until the arm is at
rest; the node then plans it from where the arm stopped.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np
from sensor_msgs.msg import JointState

from rns_ros.control.command_bounds import CommandBounds
from rns_ros.control.ptp import PtpMethod, PtpPlan, PtpSettings
from rns_ros.control.ptp_phases import plan_deployment
from rns_ros.control.ptp_planner import plan_ptp
from rns_ros.control.ptp_playback import PlanPlayback
from rns_ros.control.ptp_sampling import PlanSamples, sample_plan
from rns_ros.core import FreeFloatingModel
from rns_ros.core.commands import partial_joint_goal
from rns_ros.core.errors import InputError, RnsError
from rns_ros.nodes.ptp_status import ACTIVE, HELD, PLAYING, PtpState
from rns_ros.nodes.robot_io import plan_trajectory

#: A goal whose JointState name list is exactly this runs the full reactionless deployment.
DEPLOY_GOAL = ["deploy"]
#: A deferred goal is planned from a joint state received this many periods after the stop:
#: joint_states lag by up to a publish period.
DEFERRED_PERIODS = 2.0
#: Relative margin on the URDF velocity limits for the samples of a whole plan [-]: a planner
#: stretches a phase to reach a limit exactly, up to rounding.
PLAN_VELOCITY_MARGIN = 1e-9


def goal_positions(robot: FreeFloatingModel, msg: JointState, theta: np.ndarray) -> np.ndarray:
    """The goal configuration [rad] (n,): the joints ``msg`` names at its positions, the others
    at ``theta`` [rad] (n,) (:func:`rns_ros.core.commands.partial_joint_goal`).

    Raises:
        InputError: a non-finite, unknown, duplicated or out-of-limits goal (names the reason).
    """
    return partial_joint_goal(
        msg.name, msg.position, robot.joint_names, theta, robot.lower_limits, robot.upper_limits
    )


def goal_of(robot: FreeFloatingModel, msg: JointState, theta: np.ndarray) -> np.ndarray | None:
    """The goal of ``msg`` from the measured angles ``theta`` [rad] (n,): None for the
    deployment (:data:`DEPLOY_GOAL`), else :func:`goal_positions` (raises its InputError)."""
    return None if list(msg.name) == DEPLOY_GOAL else goal_positions(robot, msg, theta)


class PtpPlanning:
    """Plans goals in one worker thread at a time (see the module docstring).

    Args:
        robot: the model the plans are for.
        method: the planner of joint goals.
        settings: the planners' settings.
        now: the node's input clock [s] (simulated time under use_sim_time): when a plan was
            ready, compared with the receipt time of joint states.
        info: logs one line at info level.

    Attributes:
        deferred: (goal message, input-clock time of the stop [s]) of a goal that waits for the
            arm to come to rest; None when none waits.
    """

    def __init__(
        self,
        robot: FreeFloatingModel,
        method: PtpMethod,
        settings: PtpSettings,
        now: Callable[[], float],
        info: Callable[[str], None],
    ) -> None:
        self.robot, self.method, self.settings = robot, method, settings
        self._now, self._info = now, info
        self._lock = threading.Lock()
        self._generation = 0
        self._request: tuple[int, np.ndarray, np.ndarray | None, PtpSettings] | None = None
        self._busy = False
        # (goal number, plan or the error that refused it, input-clock time it was ready [s])
        self._planned: tuple[int, PtpPlan | RnsError, float] | None = None
        self.deferred: tuple[JointState, float] | None = None

    def supersede(self) -> None:
        """A newer goal came: a plan still being computed, or ready, for an older one is
        dropped."""
        with self._lock:
            self._generation += 1
            self._planned = None

    def drop(self) -> None:
        """Nothing is to be planned: the plan being computed, a plan ready, a goal waiting for
        the planner and a deferred goal are dropped."""
        with self._lock:
            self._generation += 1
            self._planned = None
            self._request = None
        self.deferred = None

    def settings_for(self, replanned: PtpPlan | None) -> PtpSettings:
        """The settings to plan with: :attr:`settings`, and when ``replanned`` (a plan planned
        again from where the arm stands) has an IJ-C/TJ-C camera target, that target: the
        camera still goes where the first plan took it (A-2.5 computes it from the start)."""
        target = None if replanned is None else replanned.details.get("camera_target")
        if target is None:
            return self.settings
        return replace(self.settings, camera_target=tuple(float(x) for x in target))

    def submit(
        self, theta: np.ndarray, goal: np.ndarray | None, settings: PtpSettings | None = None
    ) -> None:
        """Plan from ``theta`` [rad] (n,) to ``goal`` [rad] (n,) (None: the deployment) in the
        worker thread, or as the next request when it is busy; with ``settings`` (None:
        :attr:`settings`)."""
        with self._lock:
            self._generation += 1
            self._request = (self._generation, theta, goal, settings or self.settings)
            if self._busy:
                self._info(
                    "a plan for an earlier goal is still being computed: the newest goal is "
                    "planned next (goals in between are dropped)"
                )
                return
            self._busy = True
        threading.Thread(target=self._run, daemon=True, name="rns_ptp_plan").start()

    def ready_time(self) -> float | None:
        """Input-clock time [s] the newest plan was ready, None while none is."""
        with self._lock:
            return None if self._planned is None else self._planned[2]

    def take(self, state_received: float) -> PtpPlan | RnsError | None:
        """The newest plan (or the error that refused its goal) once a joint state received at
        ``state_received`` [s] (input clock) came after it was ready; else None. The planning
        thread holds the GIL, and the last state before it may be close to stale already."""
        with self._lock:
            planned = self._planned
            if planned is None or state_received < planned[2]:
                return None
            self._planned = None
        return planned[1]

    def clip_times(self, now: float) -> None:
        """Times later than ``now`` [s] (noted on a clock that then went back) become ``now``."""
        with self._lock:
            if self._planned is not None and self._planned[2] > now:
                self._planned = (*self._planned[:2], now)
        if self.deferred is not None and self.deferred[1] > now:
            self.deferred = (self.deferred[0], now)

    def compute(
        self,
        generation: int,
        theta: np.ndarray,
        goal: np.ndarray | None,
        settings: PtpSettings | None = None,
    ) -> None:
        """Plan request ``generation`` with ``settings`` (None: :attr:`settings`; run in the
        worker thread); the result is kept only while no newer goal came."""
        settings = settings or self.settings
        try:
            if goal is None:
                result = plan_deployment(self.robot, theta, settings)
            else:
                result = plan_ptp(self.robot, theta, goal, self.method, settings)
        except RnsError as exc:
            result = exc
        except Exception as exc:  # a planner bug must not kill the node silently
            result = InputError(f"planning failed: {type(exc).__name__}: {exc}")
        with self._lock:
            if generation == self._generation:
                self._planned = (generation, result, self._now())

    def _run(self) -> None:
        """The worker thread: plans the newest request until none is left."""
        while True:
            with self._lock:
                request, self._request = self._request, None
                if request is None:
                    self._busy = False
                    return
            self.compute(*request)


class GoalIntake:
    """The goal side of :class:`rns_ros.nodes.ptp.PtpNode`, a mixin: the ``ptp_goal`` and
    ``~/cancel`` callbacks, the planning they start (:attr:`planning`), the plan taken when it
    is ready (sent as one trajectory with ``plan_output: whole``), and whether the goal was
    reached. It reads and sets the node's state (``_mode``, ``_detail``, ``plan``,
    ``_playback``, ``_held``) and uses its input watchdogs (``_input_clock``, ``_fault``) and
    its output (``_output``, ``_stop_output``, ``_abandon``)."""

    planning: PtpPlanning

    def _on_goal(self, msg: JointState) -> None:
        """A goal: refused while the clock cannot be trusted, with two state sources, or when
        it is not one (INVALID_GOAL, or noted while a motion goes on); else planned from the
        measured angles, after stopping the arm when it moves. While the input is late (a
        loaded machine) it waits, like a goal that stops a motion, for a fresh joint state
        (at most ``state_loss_timeout``)."""
        now = self._input_clock.now()
        fault = self._input_clock.clock_fault()
        problem = None if fault is not None else self._fault(now)
        late = problem is not None and problem[0] is PtpState.STALE_STATE
        if fault is None and problem is not None and not late:
            fault = problem[1]
        if self._theta is None or fault is not None:
            self._reject(fault if fault is not None else "no joint_states yet")
            return
        theta = self._theta.copy()
        try:
            goal = goal_of(self.robot, msg, theta)
        except InputError as exc:
            self._reject(str(exc))
            return
        self._status.rejected = ""
        self.planning.supersede()
        if late and self.planning.deferred is None:
            self.get_logger().info(f"new goal while {problem[1]}: planned once the state is fresh")
            if self.plan is not None and self._mode in PLAYING:
                self._stop_output()
            self.plan, self._playback, self._held = None, None, None
            self.planning.deferred = (msg, now)
            self._mode, self._detail = PtpState.PLANNING, "waiting for a fresh state"
            return
        if self.planning.deferred is not None:
            # still stopping for an earlier goal: this one replaces it
            self.planning.deferred = (msg, self.planning.deferred[1])
            return
        if self.plan is not None and self._mode in PLAYING:
            # the arm moves: stop it and plan from where it comes to rest, sampled by a joint
            # state received after the stop (joint_states lag by up to a publish period)
            self.get_logger().info("new goal: the current motion stops and is replaced")
            self._stop_output()
            self.plan = None
            self.planning.deferred = (msg, self._input_clock.now())
            self._mode, self._detail = PtpState.PLANNING, "stopping for the new goal"
            return
        self._start_planning(theta, goal)

    def _start_planning(
        self, theta: np.ndarray, goal: np.ndarray | None, replanned: PtpPlan | None = None
    ) -> None:
        """PLANNING from ``theta`` [rad] (n,) to ``goal`` (None: the deployment); ``replanned``:
        the plan this one replaces on its way to the same goal (its camera target is kept)."""
        self.plan, self._playback, self._held = None, None, None
        self._mode, self._detail = PtpState.PLANNING, "deploy" if goal is None else "goal"
        self.planning.submit(theta, goal, self.planning.settings_for(replanned))

    def _reject(self, reason: str) -> None:
        self.get_logger().error(f"rejected ptp_goal: {reason}")
        self._status.rejected = reason
        if self._mode not in (*ACTIVE, *HELD):
            self._mode, self._detail = PtpState.INVALID_GOAL, reason

    def _on_cancel(self, _request, response):
        """~/cancel: a motion slows to rest on its path; a held one ends where it stands; a
        planning is dropped."""
        held = self._held[0] if self._mode in HELD and self._held is not None else None
        if self._mode is PtpState.MOVING:
            self._playback.cancel()
            self._mode, self._detail = PtpState.CANCELLING, "decelerating on the path"
            response.success, response.message = True, "decelerating to rest on the path"
        elif held is PtpState.MOVING:
            self._playback.cancel()  # held at rest on the path: the plan ends there
            self._held = (PtpState.CANCELLING, *self._held[1:])
            response.success = True
            response.message = f"held at rest on the path ({self._mode.value}): the plan ends there"
        elif PtpState.PLANNING in (self._mode, held):
            self.planning.drop()
            if held is None:
                self._mode, self._detail = PtpState.IDLE, "planning cancelled"
            else:
                self._held = (PtpState.IDLE, "planning cancelled", self._held[2])
            response.success, response.message = True, "planning cancelled; the arm is at rest"
        else:
            response.success = False
            response.message = f"nothing to cancel ({self._mode.value})"
        return response

    def _start_deferred(self) -> None:
        """Plan the goal that arrived during a motion once a joint state received at least two
        periods after the stop shows where the arm came to rest."""
        msg, stopped = self.planning.deferred
        if self._state_received < stopped + DEFERRED_PERIODS * self._period:
            return
        self.planning.deferred = None
        theta = self._theta.copy()
        try:  # joints the goal does not name keep the angles where the arm stopped
            goal = goal_of(self.robot, msg, theta)
        except InputError as exc:
            self._mode = PtpState.IDLE
            self._reject(str(exc))
            return
        self._start_planning(theta, goal)

    def _take_plan(self) -> None:
        """PLANNING: the plan ready (after a fresh joint state) starts playing, MOVING; a goal
        the planner refused is reported (INVALID_GOAL, nothing moves)."""
        result = self.planning.take(self._state_received)
        if result is None:
            return
        if isinstance(result, RnsError):
            self._mode = PtpState.IDLE  # nothing moves; _reject reports INVALID_GOAL
            self._reject(str(result))
            return
        self.plan = result
        self._playback = PlanPlayback(
            result,
            self._period,
            self._params["resume_acceleration"],
            self._params["cancel_deceleration"],
            self._bounds.velocity,
        )
        self._mode = PtpState.MOVING
        self._detail = f"{result.method} plan of {result.duration:.3g} s"
        for note in result.notes:
            self.get_logger().info(f"plan: {note}")
        self.get_logger().info(f"moving: {self._detail}")
        if self._whole:
            self._publish_plan(sample_plan(result, self._params["plan_sample_period"]))

    def _settle(self, now: float) -> None:
        """After the plan's last sample: DONE once every measured joint is within
        goal_tolerance [rad] of it; GOAL_MISSED when one is not settle_timeout [s] (input clock,
        ``now``) after the end (a simulator that refused the motion, an arm that stalled):
        success is never reported for a motion that was not made. Meanwhile a streamed plan's
        position feedback brings the joints there (:meth:`_settle_output`)."""
        goal, ended = self._settle_from
        error = np.abs(self._theta - goal)
        joint = int(np.argmax(error))
        if error[joint] <= self._params["goal_tolerance"]:
            self._settle_output(reached=True)
            self._mode, self._detail = (
                PtpState.DONE,
                f"goal reached (within {error[joint]:.2g} rad)",
            )
            self.get_logger().info(self._detail)
        elif now - ended <= self._params["settle_timeout"]:
            self._settle_output(reached=None)
        else:
            self._settle_output(reached=False)
            self._mode = PtpState.GOAL_MISSED
            self._detail = (
                f"{self.robot.joint_names[joint]} is {error[joint]:.3g} rad from the goal "
                f"{self._params['settle_timeout']} s after the plan ended (goal_tolerance "
                f"{self._params['goal_tolerance']} rad): the arm did not follow the plan"
            )
            self.get_logger().error(self._detail)

    def _publish_plan(self, samples: PlanSamples) -> bool:
        """plan_output whole: ``samples`` (of a plan from its start, :func:`sample_plan`, or of
        its rest after a hold, :meth:`PlanPlayback.resumed_samples`) as one JointTrajectory
        stamped now (the playback clock goes on from this tick). A plan
        :func:`whole_plan_problem` finds fault with is refused (INVALID_GOAL, the arm at rest;
        False)."""
        measured = self._theta if self._theta is not None else np.full(self.robot.n, np.nan)
        problem = whole_plan_problem(samples, self._bounds, measured, self.robot.joint_names)
        if problem is not None:
            self._abandon()
            self._mode = PtpState.INVALID_GOAL
            self._detail = f"plan refused: {problem}"
            self.get_logger().error(self._detail)
            return False
        self._velocities = samples.theta_dot[0]
        stamp = self.get_clock().now().to_msg()
        self._output.publish(
            plan_trajectory(
                stamp, self.robot.joint_names, samples.t, samples.theta, samples.theta_dot
            )
        )
        self.get_logger().info(f"plan sent whole: {samples.t.size} points")
        return True


def whole_plan_problem(
    samples: PlanSamples,
    bounds: CommandBounds,
    measured: np.ndarray,
    joint_names: Sequence[str],
) -> str | None:
    """Why ``samples`` cannot be sent as one JointTrajectory, or None when they can.

    Every sample must be finite, within the URDF position limits and the velocity limits (up
    to PLAN_VELOCITY_MARGIN) of ``bounds``; the first, where the trajectory starts, also within
    max_reference_error of the measured angles ``measured`` [rad] (n,). A trajectory is not
    clipped point by point (that would bend the path between its samples): it goes out whole or
    not at all.
    """
    theta = np.asarray(samples.theta, dtype=float)
    theta_dot = np.asarray(samples.theta_dot, dtype=float)
    if not (np.isfinite(theta).all() and np.isfinite(theta_dot).all()):
        return "the plan gave a non-finite sample"
    outside = (theta < bounds.lower) | (theta > bounds.upper)
    if outside.any():
        k, joint = (int(i) for i in np.argwhere(outside)[0])
        return (
            f"its sample at {samples.t[k]:.4g} s puts {joint_names[joint]} at "
            f"{theta[k, joint]:.6g} rad, outside its URDF limits [{bounds.lower[joint]:.6g}, "
            f"{bounds.upper[joint]:.6g}] rad"
        )
    fast = np.abs(theta_dot) > bounds.velocity * (1.0 + PLAN_VELOCITY_MARGIN)
    if fast.any():
        k, joint = (int(i) for i in np.argwhere(fast)[0])
        return (
            f"its sample at {samples.t[k]:.4g} s moves {joint_names[joint]} at "
            f"{theta_dot[k, joint]:.6g} rad/s, beyond its URDF velocity limit "
            f"{bounds.velocity[joint]:.6g} rad/s"
        )
    low, high = bounds.box(np.asarray(measured, dtype=float))
    off = (theta[0] < low) | (theta[0] > high)
    if off.any():
        joint = int(np.argmax(off))
        return (
            f"its first point puts {joint_names[joint]} at {theta[0, joint]:.6g} rad, "
            f"{abs(theta[0, joint] - measured[joint]):.3g} rad from the measured angle "
            f"(max_reference_error {bounds.max_reference_error} rad)"
        )
    return None
