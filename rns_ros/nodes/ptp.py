"""rns_ptp: reactionless point-to-point motion of the arm (thesis chapter 4).

The planner is :func:`rns_ros.control.ptp.plan_ptp` (and :func:`plan_deployment`); this node only
converts messages, plans a goal in a worker thread and plays the plan back once per period from an
executor timer, with exactly rns_controller's output contract (either drives the same simulator).

Subscribes:
    ptp_goal      sensor_msgs/JointState: target positions matched by joint name; joints the goal
                  does not name keep their measured value. A goal whose name list is exactly
                  ``["deploy"]`` (positions ignored) runs the full reactionless deployment
                  (plan_deployment) from the measured configuration. A new goal replaces the
                  current plan: the arm stops and the goal is planned from the measured state.
    joint_states  sensor_msgs/JointState (matched by joint name); watched: older than
                  ``state_timeout`` (receipt time) stops the arm and holds the plan (HOLDING);
                  fresh input resumes it on its path (:mod:`rns_ros.control.ptp_playback`) or,
                  with the arm moved off the path, replans to the same goal; no fresh input for
                  ``state_loss_timeout`` abandons it (STALE_STATE). Ages are simulated time
                  under ``use_sim_time`` (:class:`InputClock`), where a /clock that stands still
                  for ``clock_timeout`` of wall time with no joint state meanwhile (a dead
                  simulator) holds the arm the same way, and abandons the plan after
                  ``state_loss_timeout`` of wall time without a joint state; else monotonic
                  wall time.
    base_odom     nav_msgs/Odometry (base pose, for the predicted coupling momentum; watched like
                  joint_states once it has arrived)
Publishes (only while a plan plays, plus one zero-velocity message at each stop):
    joint_references  trajectory_msgs/JointTrajectory (``output_interface: trajectory``), with
                      ``plan_output: tick`` one per period, stamped at the tick: point 0 = plan at
                      the tick and its rate at mid-period, point 1 two periods on, at rest
                      (rns_controller's shape); with ``plan_output: whole`` the whole plan once
                      when it starts (samples every ``plan_sample_period`` at most, phase ends
                      included, the last at rest), then per-period messages only to cancel
                      or to hold, and the rest of the plan as one message at a resume; or
    joint_velocities  std_msgs/Float64MultiArray in the order of ``joints``
                      (``output_interface: velocity``), or
    joint_positions   std_msgs/Float64MultiArray, the plan at the end of the period, in that order
                      (``output_interface: position``)
    ~/status          diagnostic_msgs/DiagnosticArray every period: state, method, phase,
                      progress, predicted coupling momentum, folds reached, plan notes
    /diagnostics      the newest status at 1 Hz (wall clock)
Service:
    ~/cancel      std_srvs/Trigger: the playback rate ramps from 1 to 0 at ``cancel_deceleration``
                  (theta_dot scaled by the rate keeps the path: reactionless phases stay
                  reactionless), then IDLE
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from rns_ros.control.ptp import PtpMethod, PtpSettings
from rns_ros.control.ptp_phases import plan_deployment
from rns_ros.control.ptp_planner import plan_ptp
from rns_ros.control.ptp_playback import PlanPlayback, PlaybackMode
from rns_ros.control.ptp_sampling import PlanSamples, sample_plan
from rns_ros.core import FreeFloatingState
from rns_ros.core.commands import ExtraJointsReport, match_joint_state, partial_joint_goal
from rns_ros.core.errors import ConfigError, InputError, RnsError
from rns_ros.core.validation import Choice
from rns_ros.nodes import ptp_parameters
from rns_ros.nodes.cdr import odometry_fields
from rns_ros.nodes.input_clock import InputClock
from rns_ros.nodes.parameters import declare_parameters, from_parameters, load_node_model
from rns_ros.nodes.robot_io import (
    JointCommand,
    base_pose,
    measured_state_problem,
    plan_trajectory,
)
from rns_ros.nodes.runner import publish_last, run_node
from rns_ros.nodes.status import CommanderWatch, level_rank, node_names, status_text

#: A goal whose JointState name list is exactly this runs the full reactionless deployment.
DEPLOY_GOAL = ["deploy"]
#: A plan resumes after a hold on a joint state received this many periods after the stop: the
#: arm at rest, not still slowing down from the last command.
RESUME_PERIODS = 2.0
#: Period of the /diagnostics publication [s] (wall clock).
DIAGNOSTICS_PERIOD = 1.0


class PtpState(Choice):
    WAITING_FOR_STATE = "WAITING_FOR_STATE"
    IDLE = "IDLE"
    PLANNING = "PLANNING"
    MOVING = "MOVING"
    CANCELLING = "CANCELLING"
    HOLDING = "HOLDING"
    SETTLING = "SETTLING"
    DONE = "DONE"
    GOAL_MISSED = "GOAL_MISSED"
    INVALID_GOAL = "INVALID_GOAL"
    STALE_STATE = "STALE_STATE"
    CONFLICTING_STATE = "CONFLICTING_STATE"


STATE_LEVELS = {
    PtpState.WAITING_FOR_STATE: DiagnosticStatus.WARN,
    PtpState.HOLDING: DiagnosticStatus.WARN,
    PtpState.INVALID_GOAL: DiagnosticStatus.ERROR,
    PtpState.GOAL_MISSED: DiagnosticStatus.ERROR,
    PtpState.STALE_STATE: DiagnosticStatus.ERROR,
    PtpState.CONFLICTING_STATE: DiagnosticStatus.ERROR,
}

#: States in which each tick commands the joints from the plan.
PLAYING = (PtpState.MOVING, PtpState.CANCELLING)


class PtpNode(Node):
    """ROS 2 wrapper of the point-to-point planner (see the module docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(ptp_parameters.NODE_NAME, **node_kwargs)
        self._params = params = declare_parameters(self, ptp_parameters.PARAMETERS)
        self.robot = load_node_model(self, params["model_config"])
        self.method = PtpMethod.parse(params["method"])
        self.settings = from_parameters(PtpSettings, params)
        self._period = 1.0 / params["rate"]
        if params["state_loss_timeout"] < params["state_timeout"]:
            raise ConfigError(
                f"state_loss_timeout {params['state_loss_timeout']} s must be >= state_timeout "
                f"{params['state_timeout']} s (the input is stale before it is lost)"
            )
        self._theta: np.ndarray | None = None
        self._base_position = np.zeros(3)
        self._base_orientation = np.array([0.0, 0.0, 0.0, 1.0])
        # receipt times [s] on the input clock (simulated time under use_sim_time); the
        # monotonic receipt time of the newest joint state [s] (the /clock watch)
        self._state_received = -np.inf
        self._state_received_wall = -np.inf
        self._odom_received: float | None = None
        # plan playback: the plan, its playback (clock s, rate r), node-clock time of the last
        # tick [s]
        self.plan = None
        self._playback: PlanPlayback | None = None
        self._last_clock: float | None = None
        # HOLDING: the state, detail and input-clock time [s] of the hold (what fresh input
        # returns to)
        self._held: tuple[PtpState, str, float] | None = None
        self._hold_note = ""
        self._mode = PtpState.WAITING_FOR_STATE
        self._detail = ""
        self._rejected = ""  # why the newest goal was rejected (shown while not moving)
        # planning in one worker thread at a time: goals are numbered, only the newest result
        # is taken; a goal that comes while it plans waits as the newest request (flooded
        # goals replace each other there instead of starting threads)
        self._lock = threading.Lock()
        self._generation = 0
        self._request: tuple[int, np.ndarray, np.ndarray | None] | None = None
        self._planner_busy = False
        # (goal, plan, input-clock time it was ready [s]): compared with state receipt times
        self._planned: tuple[int, object, float] | None = None
        self._last_status: DiagnosticStatus | None = None
        # the graph, read once a second: joint_states sources (other joint commanders: the
        # commander watch made with the output below)
        self._state_publishers: list[str] = []
        self._velocities = np.zeros(self.robot.n)  # last published theta_dot [rad/s]
        # (goal, input-clock time of the stop [s]): compared with state receipt times
        self._deferred: tuple[JointState, float] | None = None
        # SETTLING: the plan's last sample [rad] (n,) and when it was played [s, input clock]
        self._settle_from: tuple[np.ndarray, float] | None = None
        self._input_clock = InputClock(self, params["clock_timeout"], self._on_clock_stopped)

        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.create_subscription(JointState, "ptp_goal", self._on_goal, QoSProfile(depth=10))
        self._extra_joints = ExtraJointsReport()  # joint_states names beyond the model's
        self.create_subscription(JointState, "joint_states", self._on_joint_state, qos)
        self.create_subscription(Odometry, "base_odom", self._on_odom, qos)
        self._state_topic = self.resolve_topic_name("joint_states")
        self._command = JointCommand(
            params["output_interface"], self.robot.joint_names, params["joints"], self._period
        )
        self._whole = params["plan_output"] == "whole"
        if self._whole and params["output_interface"] != "trajectory":
            raise ConfigError(
                "plan_output 'whole' sends one JointTrajectory: it needs output_interface "
                f"'trajectory', not {params['output_interface']!r}"
            )
        self._output = self.create_publisher(
            self._command.message_type, self._command.topic, QoSProfile(depth=1)
        )
        self._output_topic = self._output.topic_name
        self._commander_watch = CommanderWatch(
            self,
            self._output_topic,
            "only one of rns_controller / rns_ptp may command the joints at a time",
            publishes=True,
        )
        self._status = self.create_publisher(DiagnosticArray, "~/status", QoSProfile(depth=10))
        self._diagnostics = self.create_publisher(
            DiagnosticArray, "/diagnostics", QoSProfile(depth=10)
        )
        self.create_service(Trigger, "~/cancel", self._on_cancel)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self.create_timer(self._period, self._on_tick)
        self.create_timer(
            DIAGNOSTICS_PERIOD,
            self._on_diagnostics,
            clock=Clock(clock_type=ClockType.STEADY_TIME),
        )
        self.get_logger().info(
            f"{self.method.value} point-to-point motion of {self.robot.name} at "
            f"{params['rate']} Hz; goals on {self.resolve_topic_name('ptp_goal')}"
        )

    # --- inputs ---------------------------------------------------------------------------------
    def _on_joint_state(self, msg: JointState) -> None:
        try:
            command, extras = match_joint_state(
                msg.name, self.robot.joint_names, positions=msg.position
            )
        except InputError as exc:
            self.get_logger().error(f"ignored joint_states: {exc}", throttle_duration_sec=1.0)
            return
        note = self._extra_joints.note(extras)
        if note is not None:
            self.get_logger().info(note)
        if command.positions is None:
            return
        self._theta = command.positions
        stamp = msg.header.stamp
        self._state_received = self._input_clock.receipt_time(stamp.sec + 1e-9 * stamp.nanosec)
        self._state_received_wall = time.monotonic()

    def _on_odom(self, msg: Odometry) -> None:
        fields = odometry_fields(msg)
        pose = base_pose(fields.pose)
        if pose is not None:
            self._base_position, self._base_orientation = pose
            sec, nanosec = fields.stamp
            self._odom_received = self._input_clock.receipt_time(sec + 1e-9 * nanosec)

    def _on_goal(self, msg: JointState) -> None:
        fault = self._fault(self._input_clock.now())
        if self._theta is None or fault is not None:
            self._reject(fault[1] if fault is not None else "no joint_states yet")
            return
        theta = self._theta.copy()
        try:
            goal = None if list(msg.name) == DEPLOY_GOAL else self.goal_positions(msg, theta)
        except InputError as exc:
            self._reject(str(exc))
            return
        self._rejected = ""
        with self._lock:
            self._generation += 1  # a plan still being computed for an older goal is dropped
            self._planned = None
        if self._deferred is not None:  # still stopping for an earlier goal: this one replaces it
            self._deferred = (msg, self._deferred[1])
            return
        if self.plan is not None and self._mode in PLAYING:
            # the arm moves: stop it and plan from where it comes to rest, sampled by a joint
            # state received after the stop (joint_states lag by up to a publish period)
            self.get_logger().info("new goal: the current motion stops and is replaced")
            self._stop_output()
            self.plan = None
            self._deferred = (msg, self._input_clock.now())
            self._mode, self._detail = PtpState.PLANNING, "stopping for the new goal"
            return
        self._start_planning(theta, goal)

    def _start_planning(self, theta: np.ndarray, goal: np.ndarray | None) -> None:
        self.plan, self._playback, self._held = None, None, None
        self._mode, self._detail = PtpState.PLANNING, "deploy" if goal is None else "goal"
        with self._lock:
            self._generation += 1
            self._request = (self._generation, theta, goal)
            if self._planner_busy:
                self.get_logger().info(
                    "a plan for an earlier goal is still being computed: the newest goal is "
                    "planned next (goals in between are dropped)",
                    throttle_duration_sec=1.0,
                )
                return
            self._planner_busy = True
        threading.Thread(target=self._planner, daemon=True, name="rns_ptp_plan").start()

    def _planner(self) -> None:
        """The planning thread: plans the newest request until none is left."""
        while True:
            with self._lock:
                request, self._request = self._request, None
                if request is None:
                    self._planner_busy = False
                    return
            self._plan(*request)

    def goal_positions(self, msg: JointState, theta: np.ndarray) -> np.ndarray:
        """The goal configuration: the named joints at their positions, the others at ``theta``
        (:func:`rns_ros.core.commands.partial_joint_goal`; raises its InputError)."""
        robot = self.robot
        return partial_joint_goal(
            msg.name, msg.position, robot.joint_names, theta, robot.lower_limits, robot.upper_limits
        )

    def _plan(self, generation: int, theta: np.ndarray, goal: np.ndarray | None) -> None:
        try:
            if goal is None:
                result = plan_deployment(self.robot, theta, self.settings)
            else:
                result = plan_ptp(self.robot, theta, goal, self.method, self.settings)
        except RnsError as exc:
            result = exc
        except Exception as exc:  # a planner bug must not kill the node silently
            result = InputError(f"planning failed: {type(exc).__name__}: {exc}")
        with self._lock:
            if generation == self._generation:
                self._planned = (generation, result, self._input_clock.now())

    def _reject(self, reason: str) -> None:
        self.get_logger().error(f"rejected ptp_goal: {reason}")
        self._rejected = reason
        if self._mode not in (*PLAYING, PtpState.PLANNING, PtpState.HOLDING):
            self._mode, self._detail = PtpState.INVALID_GOAL, reason

    def _on_cancel(self, _request, response):
        if self._mode is PtpState.MOVING:
            self._playback.cancel()
            self._mode, self._detail = PtpState.CANCELLING, "decelerating on the path"
            response.success, response.message = True, "decelerating to rest on the path"
        elif self._mode is PtpState.HOLDING and self._held[0] is PtpState.MOVING:
            self._playback.cancel()  # held at rest on the path: the plan ends there
            self._held = (PtpState.CANCELLING, *self._held[1:])
            response.success = True
            response.message = "held at rest on the path (stale input): the plan ends there"
        elif self._mode is PtpState.PLANNING:
            with self._lock:
                self._generation += 1
                self._planned = None
                self._request = None  # a goal waiting for the planner too
            self._deferred = None
            self._mode, self._detail = PtpState.IDLE, "planning cancelled"
            response.success, response.message = True, "planning cancelled; the arm is at rest"
        else:
            response.success = False
            response.message = f"nothing to cancel ({self._mode.value})"
        return response

    # --- playback period ------------------------------------------------------------------------
    def _on_tick(self) -> None:
        clock_now = self.get_clock().now().nanoseconds * 1e-9
        elapsed = 0.0 if self._last_clock is None else max(clock_now - self._last_clock, 0.0)
        self._last_clock = clock_now
        if self._theta is None:
            self._publish_status(PtpState.WAITING_FOR_STATE, f"waiting for {self._state_topic}")
            return
        now = self._input_clock.now()
        fault = self._fault(now)
        loss = self._params["state_loss_timeout"]
        planning = self._mode is PtpState.PLANNING
        if fault is not None and planning:
            # planning holds the GIL and may starve the executor; the arm is at rest
            with self._lock:
                ready = self._planned[2] if self._planned is not None else None
            if self._deferred is not None:
                ready = self._deferred[1]
            if ready is None or now - ready < loss:
                self._publish_status(self._mode, f"{self._detail} (waiting: {fault[1]})")
                return
        if fault is not None:
            state, text = fault
            if state is PtpState.STALE_STATE and not planning and self._input_age(now) <= loss:
                self._hold(text, elapsed)
                self._publish_status(self._mode, self._detail)
                return
            if state is PtpState.STALE_STATE:
                text = f"{text}; no fresh input for state_loss_timeout {loss} s: input lost"
            if self._mode is not state:
                abandoned = "; the plan is abandoned" if self.plan is not None else ""
                self.get_logger().error(
                    f"{state.value}: {text}; joints commanded to rest{abandoned}"
                )
                self._abandon()
            self._mode, self._detail = state, text
            self._publish_status(self._mode, text)
            return
        if self._mode is PtpState.HOLDING:
            if not self._end_hold(now):
                self._publish_status(self._mode, self._detail)
                return
            elapsed = 0.0  # the arm stood still since the hold: the playback goes on from here
        if self._mode in FAULTS or self._mode is PtpState.WAITING_FOR_STATE:
            self._mode, self._detail = PtpState.IDLE, ""
        if self._mode is PtpState.PLANNING and self._deferred is not None:
            self._start_deferred(now)
        if self._mode is PtpState.PLANNING:
            self._take_plan()
            if self._mode is PtpState.MOVING:
                elapsed = 0.0  # the plan starts at this tick
        if self._mode in PLAYING:
            self._play(elapsed)
        elif self._mode is PtpState.SETTLING:
            self._settle(now)
        self._publish_status(self._mode, self._detail)

    def _input_age(self, now: float) -> float:
        """Age [s] at ``now`` (input clock) of the older of joint_states and base_odom (once
        seen)."""
        age = now - self._state_received
        if self._odom_received is not None:
            age = max(age, now - self._odom_received)
        return age

    def _hold(self, text: str, elapsed: float) -> None:
        """A stale input (``text`` says which): a moving arm stops at the plan's sample where
        the last command, ``elapsed`` [s] ago, brought it (zero velocity; the playback rate
        r = 0, s frozen: the path is kept); HOLDING until fresh input or state_loss_timeout."""
        loss = self._params["state_loss_timeout"]
        if self._mode is PtpState.HOLDING:
            self._detail = f"{text}; {self._hold_note}"
            return
        self._held = (self._mode, self._detail, self._input_clock.now())
        if self._mode in PLAYING:
            step = self._playback.hold(elapsed)
            self._publish_output(step.theta, step.theta_dot)
            what = (
                f"holding the plan at s = {step.s:.3g} s of {self.plan.duration:.3g} s (zero "
                "velocity); it resumes when fresh"
            )
        elif self._mode is PtpState.SETTLING:
            what = "the plan has played; the goal check waits for fresh input"
        else:
            what = "the arm is at rest; back to " + self._mode.value + " when fresh"
        self.get_logger().warn(f"{text}: {what} (abandoned after state_loss_timeout {loss} s)")
        self._hold_note = what
        self._mode, self._detail = PtpState.HOLDING, f"{text}; {what}"

    def _end_hold(self, now: float) -> bool:
        """Fresh input after a hold: True when the node goes on at this tick (a plan resumed
        on its path, or the state before the hold); False while it waits for a joint state of
        the arm at rest, or when the plan ended (cancelled) or is replanned."""
        held, detail, since = self._held
        if self._state_received < since + RESUME_PERIODS * self._period:
            return False
        self._held = None
        playback, plan = self._playback, self.plan
        if held not in PLAYING or playback is None:
            if held is PtpState.SETTLING:  # the goal check restarts with fresh input
                self._settle_from = (self._settle_from[0], now)
            self._mode, self._detail = held, detail
            return True
        if playback.mode is not PlaybackMode.HOLDING:  # cancelled: at rest where it stands
            self._mode, self._detail = PtpState.IDLE, "cancelled: at rest on the path"
            self.get_logger().info(self._detail)
            return False
        error = playback.path_error(self._theta)
        where = f"s = {playback.s:.3g} s of {plan.duration:.3g} s"
        tolerance = self._params["resume_tolerance"]
        if error > tolerance:
            self.get_logger().warn(
                f"fresh input: the arm is {error:.3g} rad from the held plan at {where} "
                f"(resume_tolerance {tolerance} rad): replanned from the measured angles to "
                "the same goal"
            )
            self._start_planning(self._theta.copy(), plan.goal)
            self._detail = "replanning to the same goal from where the arm stands"
            return False
        playback.resume()
        self._mode = PtpState.MOVING
        self._detail = f"{plan.method} plan of {plan.duration:.3g} s, resumed at {where}"
        self.get_logger().info(
            f"fresh input: the plan resumes at {where} ({error:.2g} rad from it); the "
            f"playback rate rises to 1 at resume_acceleration "
            f"{self._params['resume_acceleration']} /s"
        )
        if self._whole:
            self._publish_plan(playback.resumed_samples(self._params["plan_sample_period"]))
        return True

    def _settle(self, now: float) -> None:
        """After the plan's last sample: DONE once every measured joint is within
        goal_tolerance [rad] of it; GOAL_MISSED when one is not settle_timeout [s] (input clock,
        ``now``) after the end (a simulator that refused the motion, an arm that stalled):
        success is never reported for a motion that was not made."""
        goal, ended = self._settle_from
        error = np.abs(self._theta - goal)
        joint = int(np.argmax(error))
        if error[joint] <= self._params["goal_tolerance"]:
            self._mode, self._detail = (
                PtpState.DONE,
                f"goal reached (within {error[joint]:.2g} rad)",
            )
            self.get_logger().info(self._detail)
        elif now - ended > self._params["settle_timeout"]:
            self._mode = PtpState.GOAL_MISSED
            self._detail = (
                f"{self.robot.joint_names[joint]} is {error[joint]:.3g} rad from the goal "
                f"{self._params['settle_timeout']} s after the plan ended (goal_tolerance "
                f"{self._params['goal_tolerance']} rad): the arm did not follow the plan"
            )
            self.get_logger().error(self._detail)

    def _abandon(self) -> None:
        """Zero velocity; the plan, a deferred goal and a plan being computed are dropped."""
        self._stop_output()
        self.plan, self._playback, self._held = None, None, None
        self._deferred = None
        with self._lock:
            self._generation += 1
            self._planned = None
            self._request = None  # a goal waiting for the planner too

    def _on_clock_stopped(self, still: float) -> None:
        """use_sim_time: /clock has stood still for ``still`` [s] of wall time. When no joint
        state came for as long either (a dead simulator), a motion is held here as on a stale
        state, and abandoned once no joint state came for state_loss_timeout of wall time; the
        status is published from here: the sim-time playback timer that would do it has
        stopped too. An arm at rest is left as it is."""
        quiet = time.monotonic() - self._state_received_wall
        if quiet < self._input_clock.timeout:
            return
        text = (
            f"/clock stood still for {still:.3f} s (clock_timeout "
            f"{self._params['clock_timeout']} s wall time)"
        )
        loss = self._params["state_loss_timeout"]
        active = (PtpState.MOVING, PtpState.CANCELLING, PtpState.PLANNING, PtpState.HOLDING)
        if self._mode in active and quiet > loss:
            text = f"{text}; no joint_states for {quiet:.3f} s (state_loss_timeout {loss} s)"
            abandoned = "; the plan is abandoned" if self.plan is not None else ""
            self.get_logger().error(
                f"{PtpState.STALE_STATE.value}: {text}; joints commanded to rest{abandoned}"
            )
            self._abandon()
            self._mode, self._detail = PtpState.STALE_STATE, text
        elif self._mode in active and self._mode is not PtpState.PLANNING:
            clock_now = self.get_clock().now().nanoseconds * 1e-9
            last, self._last_clock = self._last_clock, clock_now
            self._hold(text, 0.0 if last is None else max(clock_now - last, 0.0))
        elif self._mode is PtpState.PLANNING:  # the arm is at rest: planning goes on
            self._publish_status(self._mode, f"{self._detail} (waiting: {text})")
            return
        elif self._mode is not PtpState.STALE_STATE or not self._detail.startswith("/clock"):
            return  # nothing commanded: the arm is at rest, nothing to stop
        else:
            self.get_logger().error(
                f"{PtpState.STALE_STATE.value}: {self._detail}", throttle_duration_sec=5.0
            )
        self._publish_status(self._mode, self._detail)

    def _apply_parameters(self, parameters) -> None:
        """After a set: the run-time parameters (clock_timeout) take their new values."""
        for parameter in parameters:
            if parameter.name == "clock_timeout":
                self._params["clock_timeout"] = parameter.value
                self._input_clock.set_clock_timeout(parameter.value)

    def _start_deferred(self, now: float) -> None:
        """Plan the goal that arrived during a motion once a joint state received at least two
        periods after the stop shows where the arm came to rest."""
        msg, stopped = self._deferred
        if self._state_received < stopped + 2.0 * self._period:
            return
        self._deferred = None
        theta = self._theta.copy()
        try:  # joints the goal does not name keep the angles where the arm stopped
            goal = None if list(msg.name) == DEPLOY_GOAL else self.goal_positions(msg, theta)
        except InputError as exc:
            self._mode = PtpState.IDLE
            self._reject(str(exc))
            return
        self._start_planning(theta, goal)

    def _take_plan(self) -> None:
        with self._lock:
            planned = self._planned
            # a plan starts only on a joint state received after it was ready: the planning
            # thread holds the GIL, and the last state before it may be close to stale already
            if planned is None or self._state_received < planned[2]:
                return
            self._planned = None
        result = planned[1]
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
        )
        self._mode = PtpState.MOVING
        self._detail = f"{result.method} plan of {result.duration:.3g} s"
        for note in result.notes:
            self.get_logger().info(f"plan: {note}")
        self.get_logger().info(f"moving: {self._detail}")
        if self._whole:
            self._publish_plan(sample_plan(result, self._params["plan_sample_period"]))

    def _play(self, elapsed: float) -> None:
        """One tick of the playback, ``elapsed`` [s] after the last (node clock): the plan at s
        and r_mid theta_dot_plan(s_mid), held over the period (reactionless over the hold)."""
        step = self._playback.tick(elapsed)
        if step.at_rest:
            if not self._whole or self._mode is PtpState.CANCELLING:
                # a whole plan ends at rest on its own; a cancelled one on this message
                self._publish_output(step.theta, step.theta_dot)
            if step.mode is PlaybackMode.CANCELLED:
                self._mode, self._detail = PtpState.IDLE, "cancelled: at rest on the path"
                self.get_logger().info(self._detail)
            else:
                # DONE only once the measured angles are there (:meth:`_settle`)
                self._mode, self._detail = PtpState.SETTLING, "plan played: checking the angles"
                self._settle_from = (step.theta, self._input_clock.now())
            return
        if not (np.all(np.isfinite(step.theta_dot)) and np.all(np.isfinite(step.theta))):
            self._stop_output()
            self.plan, self._playback = None, None
            self._mode, self._detail = PtpState.INVALID_GOAL, "the plan gave a non-finite sample"
            self.get_logger().error(self._detail)
            return
        if self._whole and self._mode is PtpState.MOVING:
            self._velocities = step.theta_dot  # the controller plays the trajectory sent
            return
        # per period (and with a whole plan, to cancel: the first replaces the plan)
        self._publish_output(step.theta, step.theta_dot)

    def _fault(self, now: float) -> tuple[PtpState, str] | None:
        """(state, reason) when the measured state cannot be trusted: two sources or stale."""
        problem = measured_state_problem(
            now,
            self._state_publishers,
            self._state_topic,
            self._state_received,
            self._odom_received,
            self._params["state_timeout"],
        )
        return None if problem is None else (PtpState(problem[0]), problem[1])

    def _stop_output(self) -> None:
        if self._theta is not None:
            self._publish_output(self._theta, np.zeros(self.robot.n))

    def _publish_output(self, positions: np.ndarray, velocities: np.ndarray) -> None:
        self._velocities = velocities
        stamp = self.get_clock().now().to_msg()
        self._output.publish(self._command.message(stamp, positions, velocities))

    def _publish_plan(self, samples: PlanSamples) -> None:
        """plan_output whole: ``samples`` (of a plan from its start, :func:`sample_plan`, or of
        its rest after a hold, :meth:`PlanPlayback.resumed_samples`) as one JointTrajectory
        stamped now (the playback clock goes on from this tick)."""
        if not (np.isfinite(samples.theta).all() and np.isfinite(samples.theta_dot).all()):
            self._abandon()
            self._mode, self._detail = PtpState.INVALID_GOAL, "the plan gave a non-finite sample"
            self.get_logger().error(self._detail)
            return
        self._velocities = samples.theta_dot[0]
        stamp = self.get_clock().now().to_msg()
        self._output.publish(
            plan_trajectory(
                stamp, self.robot.joint_names, samples.t, samples.theta, samples.theta_dot
            )
        )
        self.get_logger().info(f"plan sent whole: {samples.t.size} points")

    # --- status ---------------------------------------------------------------------------------
    def _values(self, state: PtpState) -> dict:
        values = {"method": self.method.value}
        plan, playback = self.plan, self._playback
        moving = state in PLAYING
        if plan is not None:
            s = playback.s if playback is not None else 0.0
            reference = plan.sample(s)
            on_path = moving or (state is PtpState.HOLDING and reference.phase != "done")
            values["plan_method"] = str(plan.method)
            values["phase"] = reference.phase if on_path else "done"
            values["progress"] = float(reference.progress)
            values["duration"] = float(plan.duration)
            values["playback_rate"] = playback.rate if moving else 0.0
            folds = [
                f"{p.name}: {math.degrees(p.fold_reached):.4g} deg"
                for p in plan.phases
                if p.fold_reached is not None
            ]
            values["fold_reached"] = ", ".join(folds) if folds else "none"
            values["notes"] = "; ".join(plan.notes) if plan.notes else "none"
        momentum = 0.0
        if moving and self._theta is not None:
            state_ff = FreeFloatingState.compute(
                self.robot,
                self.robot.configuration(self._theta, self._base_position, self._base_orientation),
            )
            momentum = float(
                np.linalg.norm(state_ff.coupling_angular_momentum_matrix @ self._velocities)
            )
        values["coupling_momentum"] = momentum
        if self._rejected:
            values["rejected_goal"] = self._rejected
        return values

    def _publish_status(self, state: PtpState, detail: str) -> None:
        level = STATE_LEVELS.get(state, DiagnosticStatus.OK)
        message = f"{state.value}: {detail}" if detail else state.value
        if self._rejected and state is not PtpState.INVALID_GOAL:
            message += f"; last goal rejected: {self._rejected}"
        commanders = self._commander_watch.others
        if commanders:
            level = max(level, DiagnosticStatus.WARN, key=level_rank)
            message += (
                f"; {', '.join(commanders)} also publish(es) on {self._output_topic}: "
                "run only one of rns_controller / rns_ptp"
            )
        status = DiagnosticStatus(
            level=level,
            name=f"{self.get_name()}: point-to-point motion",
            message=message,
            hardware_id=self.robot.name,
            values=[
                KeyValue(key=key, value=status_text(value))
                for key, value in {"state": state.value, **self._values(state)}.items()
            ],
        )
        self._last_status = status
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self.get_clock().now().to_msg()
        self._status.publish(msg)

    def _on_diagnostics(self) -> None:
        self._check_graph()
        if self._last_status is None:
            return
        msg = DiagnosticArray(status=[self._last_status])
        msg.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics.publish(msg)

    def _check_graph(self) -> None:
        """Who publishes joint_states (more than one source is a fault: the plan would start
        from one robot's angles and the watchdog be fed by another) and who else commands the
        joints on our output topic (reported: two commanders make the arm jerk between them)."""
        self._state_publishers = node_names(
            info
            for info in self.get_publishers_info_by_topic(self._state_topic)
            if info.topic_type == "sensor_msgs/msg/JointState"
        )
        self._commander_watch.check()

    def destroy_node(self) -> None:
        """Stop the arm: one zero-velocity output, then tear down."""
        if self._theta is not None:
            publish_last(self, self._stop_output, "zero velocity", acked_by=self._output)
        super().destroy_node()


#: States in which the measured state cannot be trusted (zero output, the plan abandoned).
FAULTS = (PtpState.STALE_STATE, PtpState.CONFLICTING_STATE)


def main(args=None) -> int:
    return run_node(PtpNode, ptp_parameters, args)


if __name__ == "__main__":
    raise SystemExit(main())
