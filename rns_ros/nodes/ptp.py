"""rns_ptp: reactionless point-to-point motion of the arm (thesis chapter 4).

The planner is :func:`rns_ros.control.ptp.plan_ptp` (and :func:`plan_deployment`); this node
converts messages, plans a goal in a worker thread (:mod:`rns_ros.nodes.ptp_planning`) and plays
the plan back once per period from an executor timer (:mod:`rns_ros.control.ptp_playback`), with
exactly rns_controller's output contract (either drives the same simulator). Status:
:mod:`rns_ros.nodes.ptp_status`; parameters: :mod:`rns_ros.nodes.ptp_parameters`; states and
gaps in detail: docs/nodes/rns_ptp.md.

Subscribes:
    ptp_goal      sensor_msgs/JointState: target positions matched by joint name (the others
                  keep their measured value), or the name list ``["deploy"]``: the full
                  reactionless deployment. A new goal replaces the current plan.
    joint_states  sensor_msgs/JointState (matched by joint name); older than ``state_timeout``
                  holds the plan (HOLDING: zero velocity, plan clock frozen); fresh input resumes
                  it on its path (or replans to the same goal off it); none for
                  ``state_loss_timeout`` abandons it (STALE_STATE). Ages are simulated time under
                  ``use_sim_time`` (:class:`InputClock`), where a /clock that stands still for
                  ``clock_timeout`` of wall time also holds the plan, and one that goes back,
                  jumps beyond ``max_clock_jump`` or has two publishers holds it as CLOCK_FAULT
                  until it runs forward from one publisher again (abandoned after
                  ``state_loss_timeout`` of wall time). Ticks more than a few periods apart hold
                  the plan too: its clock never leaps with the node's.
    base_odom     nav_msgs/Odometry (base pose, for the coupling momentum; watched like
                  joint_states once it has arrived)
Publishes (while a plan plays, plus one zero-velocity message at each stop; every joint command
within the URDF limits and ``max_reference_error`` of the measured angles,
:mod:`rns_ros.control.command_bounds`):
    joint_references  trajectory_msgs/JointTrajectory (``output_interface: trajectory``): with
                      ``plan_output: tick`` one per period (rns_controller's shape); with
                      ``whole`` the plan once (refused, INVALID_GOAL, with a sample outside the
                      URDF limits or its first beyond max_reference_error), per-period messages
                      only to cancel or hold, the rest of the plan at a resume; or
    joint_velocities  std_msgs/Float64MultiArray in the order of ``joints`` (``velocity``), or
    joint_positions   the plan at the end of the period, in that order (``position``)
    ~/status          diagnostic_msgs/DiagnosticArray every period (:mod:`ptp_status`)
    /diagnostics      the newest status at 1 Hz (wall clock)
Service:
    ~/cancel      std_srvs/Trigger: the playback rate ramps from 1 to 0 at ``cancel_deceleration``
                  (the path is kept: reactionless phases stay reactionless), then IDLE
"""

from __future__ import annotations

import time

import numpy as np
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from rns_ros.control.command_bounds import BoundedCommand, CommandBounds, bound_joint_command
from rns_ros.control.ptp import PtpMethod, PtpSettings
from rns_ros.control.ptp_playback import PlanPlayback, PlaybackMode
from rns_ros.core.commands import ExtraJointsReport, match_joint_state
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.nodes import ptp_parameters
from rns_ros.nodes.cdr import odometry_fields
from rns_ros.nodes.input_clock import InputClock
from rns_ros.nodes.parameters import (
    declare_parameters,
    from_parameters,
    load_node_model,
    sim_time_change_refused,
)
from rns_ros.nodes.ptp_planning import DEPLOY_GOAL, GoalIntake, PtpPlanning
from rns_ros.nodes.ptp_status import (
    ACTIVE,
    DIAGNOSTICS_PERIOD,
    FAULTS,
    PLAYING,
    PtpState,
    PtpStatus,
    coupling_momentum,
    plan_values,
)
from rns_ros.nodes.robot_io import JointCommand, base_pose, measured_state_problem
from rns_ros.nodes.runner import publish_last, run_node

#: A plan resumes after a hold on a joint state received this many periods after the stop: the
#: arm at rest, not still slowing down from the last command.
RESUME_PERIODS = 2.0
#: Ticks at most max(MAX_TICK_GAP_PERIODS T, MAX_TICK_GAP_FLOOR) [-], [s] apart advance the plan
#: clock by their interval: a busy executor fires a tick up to ~3 T late. A longer interval is a
#: clock that jumped (less than max_clock_jump) or a node that stalled: the arm did not follow a
#: plan clock that leapt, so the plan advances by the bound at most and is held there.
MAX_TICK_GAP_PERIODS = 5.0
MAX_TICK_GAP_FLOOR = 0.05
__all__ = ["DEPLOY_GOAL", "PtpNode", "PtpState", "main"]


class PtpNode(GoalIntake, Node):
    """ROS 2 wrapper of the point-to-point planner (see the module docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(ptp_parameters.NODE_NAME, **node_kwargs)
        self._params = params = declare_parameters(self, ptp_parameters.PARAMETERS)
        self.robot = load_node_model(self, params["model_config"])
        self.method = PtpMethod.parse(params["method"])
        self.settings = from_parameters(PtpSettings, params)
        self._period = 1.0 / params["rate"]
        self._max_gap = max(MAX_TICK_GAP_PERIODS * self._period, MAX_TICK_GAP_FLOOR)
        if params["state_loss_timeout"] < params["state_timeout"]:
            raise ConfigError(
                f"state_loss_timeout {params['state_loss_timeout']} s must be >= state_timeout "
                f"{params['state_timeout']} s (the input is stale before it is lost)"
            )
        self._bounds = CommandBounds.of(self.robot, params["max_reference_error"])
        self._theta: np.ndarray | None = None
        self._base_position = np.zeros(3)
        self._base_orientation = np.array([0.0, 0.0, 0.0, 1.0])
        # created before the tick timer: its jump callback runs before the timer's
        self._input_clock = InputClock(
            self,
            params["clock_timeout"],
            self._on_clock_stopped,
            on_clock_fault=self._on_clock_fault,
            max_clock_jump=params["max_clock_jump"],
        )
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
        # HOLDING / CLOCK_FAULT: the state, detail and input-clock time [s] of the hold (what
        # the node returns to); what the hold did; the monotonic time a clock fault began [s]
        self._held: tuple[PtpState, str, float] | None = None
        self._hold_note = ""
        self._clock_fault_began = 0.0
        self._mode = PtpState.WAITING_FOR_STATE
        self._detail = ""
        self.planning = PtpPlanning(
            self.robot,
            self.method,
            self.settings,
            self._input_clock.now,
            lambda text: self.get_logger().info(text, throttle_duration_sec=1.0),
        )
        # the graph, read once a second: joint_states sources (other joint commanders: the
        # commander watch made with the output below)
        self._state_publishers: list[str] = []
        self._velocities = np.zeros(self.robot.n)  # last published theta_dot [rad/s]
        # SETTLING: the plan's last sample [rad] (n,) and when it was played [s, input clock]
        self._settle_from: tuple[np.ndarray, float] | None = None

        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.create_subscription(JointState, "ptp_goal", self._on_goal, QoSProfile(depth=10))
        self._extra_joints = ExtraJointsReport()  # joint_states names beyond the model's
        self.create_subscription(JointState, "joint_states", self._on_joint_state, qos)
        self.create_subscription(Odometry, "base_odom", self._on_odom, qos)
        self._state_topic = self.resolve_topic_name("joint_states")
        self._command = JointCommand(
            params["output_interface"], self.robot.joint_names, params["joints"], self._period
        )
        trajectory = params["output_interface"] == "trajectory"
        self._whole = params["plan_output"] == "whole"
        # what the plant plays between two ticks at most [s]: one streamed command until it
        # ends at rest; a whole plan plays on by itself
        self._played = (
            self._max_gap if self._whole else min(self._command.acting_horizon, self._max_gap)
        )
        if self._whole and not trajectory:
            raise ConfigError(
                "plan_output 'whole' sends one JointTrajectory: it needs output_interface "
                f"'trajectory', not {params['output_interface']!r}"
            )
        self._output = self.create_publisher(
            self._command.message_type, self._command.topic, QoSProfile(depth=1)
        )
        self._status = PtpStatus(self, self.robot.name, self._output.topic_name)
        self.create_service(Trigger, "~/cancel", self._on_cancel)
        self.add_on_set_parameters_callback(self._validate_parameters)
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

    # --- playback period ------------------------------------------------------------------------
    def _on_tick(self) -> None:
        clock_now = self.get_clock().now().nanoseconds * 1e-9
        gap = None if self._last_clock is None else clock_now - self._last_clock
        self._last_clock = clock_now
        if self._theta is None:
            self._publish_status(PtpState.WAITING_FOR_STATE, f"waiting for {self._state_topic}")
            return
        clock_fault = self._input_clock.clock_fault()
        if clock_fault is not None:
            self._hold_clock_fault(clock_fault)
            self._publish_status(self._mode, self._detail)
            return
        now = self._input_clock.now()
        self._drop_future_times(now)
        if self._mode is PtpState.CLOCK_FAULT:
            self._clock_trusted(now)
        # the plan clock advances by what the plant played since the last tick: a late tick
        # on a loaded machine finds the arm at rest where the last command ended
        elapsed = 0.0 if gap is None else min(max(gap, 0.0), self._played)
        fault = self._fault(now)
        loss = self._params["state_loss_timeout"]
        planning = self._mode is PtpState.PLANNING
        if fault is not None and planning:
            # planning holds the GIL and may starve the executor; the arm is at rest
            ready = self.planning.ready_time()
            if self.planning.deferred is not None:
                ready = self.planning.deferred[1]
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
        if gap is not None and self._mode in PLAYING and self._clock_jumped(gap):
            self._hold(
                f"{gap:.4g} s between two ticks, outside [0, {self._max_gap:.3g}] s (the clock "
                "jumped or the node stalled)",
                elapsed,
            )
            self._publish_status(self._mode, self._detail)
            return
        if self._mode is PtpState.HOLDING:
            if not self._end_hold(now):
                self._publish_status(self._mode, self._detail)
                return
            elapsed = 0.0  # the arm stood still since the hold: the playback goes on from here
        if self._mode in FAULTS or self._mode is PtpState.WAITING_FOR_STATE:
            self._mode, self._detail = PtpState.IDLE, ""
        if self._mode is PtpState.PLANNING and self.planning.deferred is not None:
            self._start_deferred()
        if self._mode is PtpState.PLANNING:
            self._take_plan()
            if self._mode is PtpState.MOVING:
                elapsed = 0.0  # the plan starts at this tick
        if self._mode in PLAYING:
            self._play(elapsed)
        elif self._mode is PtpState.SETTLING:
            self._settle(now)
        self._publish_status(self._mode, self._detail)

    def _clock_jumped(self, gap: float) -> bool:
        """True when two ticks ``gap`` [s] apart (node clock) cannot be a late tick: the clock
        went back, or under use_sim_time moved on by more than the bound (a lockstep
        simulation waits for its nodes, so only another clock makes such a gap). On the wall
        clock a late tick is a loaded machine: the plan clock takes what the plant played."""
        return gap < 0.0 or (self._input_clock.sim_time and gap > self._max_gap)

    def _input_age(self, now: float) -> float:
        """Age [s] at ``now`` (input clock) of the older of joint_states and base_odom (once
        seen)."""
        age = now - self._state_received
        if self._odom_received is not None:
            age = max(age, now - self._odom_received)
        return age

    def _drop_future_times(self, now: float) -> None:
        """Input-clock times later than ``now`` [s] (noted on a clock that then went back)
        become ``now``: the watchdogs age them from here instead of never, and what waits for
        a joint state after them waits for the next one."""
        self._state_received = min(self._state_received, now)
        if self._odom_received is not None:
            self._odom_received = min(self._odom_received, now)
        if self._settle_from is not None:
            self._settle_from = (self._settle_from[0], min(self._settle_from[1], now))
        if self._held is not None:
            self._held = (*self._held[:2], min(self._held[2], now))
        self.planning.clip_times(now)

    def _stop_on_path(self, elapsed: float) -> str:
        """Stop the arm where the plan stands: a moving arm at the plan's sample where the last
        command, ``elapsed`` [s] ago, brought it (zero velocity; the playback rate r = 0, s
        frozen: the path is kept). The state before it is kept to return to. Returns what was
        done (one line)."""
        self._held = (self._mode, self._detail, self._input_clock.now())
        if self._mode in PLAYING:
            step = self._playback.hold(elapsed)
            self._publish_output(step.theta, step.theta_dot)
            what = (
                f"holding the plan at s = {step.s:.3g} s of {self.plan.duration:.3g} s (zero "
                "velocity); it resumes when fresh"
            )
        elif self._mode is PtpState.SETTLING:
            if not self._whole:
                self._stop_output()
            what = "the plan has played; the goal check waits for fresh input"
        else:
            what = "the arm is at rest; back to " + self._mode.value + " when fresh"
        self._hold_note = what
        return what

    def _hold(self, text: str, elapsed: float) -> None:
        """A stale input or a leap of the clock (``text`` says which): the arm stops on the
        path (:meth:`_stop_on_path`); HOLDING until fresh input or state_loss_timeout."""
        if self._mode is PtpState.HOLDING:
            self._detail = f"{text}; {self._hold_note}"
            return
        what = self._stop_on_path(elapsed)
        loss = self._params["state_loss_timeout"]
        self.get_logger().warn(f"{text}: {what} (abandoned after state_loss_timeout {loss} s)")
        self._mode, self._detail = PtpState.HOLDING, f"{text}; {what}"

    def _hold_clock_fault(self, text: str) -> None:
        """use_sim_time: simulated time cannot be trusted (``text``: why, and who publishes
        /clock). The arm stops on the path as on a stale input, at the sample one period past
        the last command (how long it acted, no clock difference can tell), with one error
        line; CLOCK_FAULT until the clock can be trusted again. After state_loss_timeout of
        wall time in the fault a motion or planning is abandoned."""
        if self._mode is not PtpState.CLOCK_FAULT:
            self._clock_fault_began = time.monotonic()
            if self._mode is PtpState.HOLDING:
                what = self._hold_note  # held already: the state before it is kept
            else:
                what = self._stop_on_path(self._period)
            self.get_logger().error(f"{PtpState.CLOCK_FAULT.value}: {text}; {what}")
            self._mode = PtpState.CLOCK_FAULT
        lasted = time.monotonic() - self._clock_fault_began
        loss = self._params["state_loss_timeout"]
        if lasted > loss and self._held is not None and self._held[0] in ACTIVE:
            self._hold_note = (
                f"the plan was abandoned after {lasted:.3g} s of an untrusted clock "
                f"(state_loss_timeout {loss} s wall time)"
            )
            self.get_logger().error(f"{text}: {self._hold_note}")
            self._abandon()
        self._detail = f"{text}; {self._hold_note}"

    def _clock_trusted(self, now: float) -> None:
        """The clock runs forward from one publisher again (``now`` [s]): the node holds as on
        a stale input that turned fresh (HOLDING, from ``now``), and goes back to its state, or
        resumes the plan, on a joint state received after that; IDLE when the plan was
        abandoned meanwhile."""
        if self._held is None:
            self._mode, self._detail = PtpState.IDLE, "the clock is trusted again; at rest"
        else:
            self._held = (*self._held[:2], now)
            self._mode = PtpState.HOLDING
            self._detail = f"the clock is trusted again; {self._hold_note}"
        self.get_logger().info(f"/clock runs forward from one publisher again: {self._detail}")

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
        error = playback.locate(self._theta)  # s where the arm stands on the path
        where = f"s = {playback.s:.3g} s of {plan.duration:.3g} s"
        tolerance = self._params["resume_tolerance"]
        if error > tolerance:
            self.get_logger().warn(
                f"fresh input: the arm is {error:.3g} rad from the held plan at {where} "
                f"(resume_tolerance {tolerance} rad): replanned from the measured angles to "
                "the same goal"
            )
            self._start_planning(self._theta.copy(), plan.goal, replanned=plan)
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

    def _abandon(self) -> None:
        """Zero velocity; the plan, a deferred goal and a plan being computed are dropped."""
        self._stop_output()
        self.plan, self._playback, self._held = None, None, None
        self.planning.drop()

    def _on_clock_stopped(self, still: float) -> None:
        """use_sim_time: /clock has stood still for ``still`` [s] of wall time. When no joint
        state came for as long either (a dead simulator), a motion is held here as on a stale
        state, and abandoned once no joint state came for state_loss_timeout of wall time; the
        status is published from here: the sim-time playback timer that would do it has
        stopped too. An arm at rest is left as it is; a clock fault goes on, abandoned after
        state_loss_timeout of wall time."""
        if self._mode is PtpState.CLOCK_FAULT:
            fault = self._input_clock.clock_fault()
            if fault is not None:  # else the next tick finds the clock trusted
                self._hold_clock_fault(fault)
                self._publish_status(self._mode, self._detail)
            return
        quiet = time.monotonic() - self._state_received_wall
        if quiet < self._input_clock.timeout:
            return
        text = (
            f"/clock stood still for {still:.3f} s (clock_timeout "
            f"{self._params['clock_timeout']} s wall time)"
        )
        loss = self._params["state_loss_timeout"]
        active = (*ACTIVE, PtpState.HOLDING)
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
            gap = 0.0 if last is None else clock_now - last
            self._hold(text, min(max(gap, 0.0), self._max_gap))
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

    def _on_clock_fault(self, text: str) -> None:
        """use_sim_time: a clock fault begins (``text``: why, and who publishes /clock),
        reported by the jump callback or the wall-clock graph check: the arm is held now, also
        when no tick comes (a /clock that stands still after it)."""
        if self._theta is None:
            return  # nothing commanded yet
        self._hold_clock_fault(text)
        self._publish_status(self._mode, self._detail)

    # --- parameters -----------------------------------------------------------------------------
    def _validate_parameters(self, parameters) -> SetParametersResult:
        """On set: refuse a change of use_sim_time (the node keeps the clock it started with)
        and run-time values their spec refuses; the reason names what is wrong."""
        refused = sim_time_change_refused(self, parameters) or ptp_parameters.refused(parameters)
        return SetParametersResult(successful=refused is None, reason=refused or "")

    def _apply_parameters(self, parameters) -> None:
        """After a set: the run-time parameters (clock_timeout) take their new values."""
        for parameter in parameters:
            if parameter.name == "clock_timeout":
                self._params["clock_timeout"] = parameter.value
                self._input_clock.set_clock_timeout(parameter.value)

    # --- playback ------------------------------------------------------------------------------
    def _play(self, elapsed: float) -> None:
        """One tick of the playback, ``elapsed`` [s] after the last (node clock): the plan at s
        and r_mid theta_dot_plan(s_mid), held over the period (reactionless over the hold);
        streamed, with the position feedback on the newest joint state and its age
        (:class:`PlanPlayback`)."""
        if self._whole:
            step = self._playback.tick(elapsed)
        else:
            age = max(self._input_clock.now() - self._state_received, 0.0)
            step = self._playback.tick(elapsed, self._theta, age)
        if step.at_rest:
            if self._whole and self._mode is PtpState.CANCELLING:
                # a whole plan ends at rest on its own; a cancelled one on this message
                self._publish_output(step.theta, step.theta_dot)
            if step.mode is PlaybackMode.CANCELLED:
                if not self._whole:
                    self._publish_output(step.theta, step.theta_dot)
                self._mode, self._detail = PtpState.IDLE, "cancelled: at rest on the path"
                self.get_logger().info(self._detail)
            else:
                # DONE only once the measured angles are there (:meth:`_settle`)
                self._mode, self._detail = PtpState.SETTLING, "plan played: checking the angles"
                self._settle_from = (step.theta, self._input_clock.now())
                self._settle_output(reached=None)
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

    # --- output ---------------------------------------------------------------------------------
    def _settle_output(self, reached: bool | None) -> None:
        """SETTLING, streamed output: the position feedback towards the plan's last sample
        (``reached`` None: still settling), or at rest there (True, DONE) or where the arm
        stands (False, GOAL_MISSED). A whole plan's controller settles it on its own."""
        if self._whole or self._playback is None or self._theta is None:
            return
        if reached is None:
            step = self._playback.settle(self._theta)
            self._publish_output(step.theta, step.theta_dot)
        elif reached:
            self._publish_output(self._playback.settle(self._theta).theta, np.zeros(self.robot.n))
        else:
            self._stop_output()

    def _stop_output(self) -> None:
        if self._theta is not None:
            self._publish_output(self._theta, np.zeros(self.robot.n))

    def _publish_output(self, positions: np.ndarray, velocities: np.ndarray) -> BoundedCommand:
        """One joint command, ``positions`` [rad] and ``velocities`` [rad/s] (n,) held from
        now, within the URDF limits and max_reference_error of the measured angles (a NaN/Inf
        in it as a stop; :func:`bound_joint_command`). Returns what was published."""
        measured = self._theta if self._theta is not None else np.full(self.robot.n, np.nan)
        sent = bound_joint_command(
            positions, velocities, measured, self._bounds, self._command.bound_horizon
        )
        if sent.clipped_joint is not None:
            joint = sent.clipped_joint
            low, high = self._bounds.box(measured)
            self.get_logger().warn(
                f"joint command clipped: {self.robot.joint_names[joint]} "
                f"{positions[joint]:.6g} rad is outside [{low[joint]:.6g}, {high[joint]:.6g}] "
                "rad (URDF limits, max_reference_error "
                f"{self._params['max_reference_error']} rad of the measured angle)",
                throttle_duration_sec=1.0,
            )
        self._velocities = sent.velocities
        stamp = self.get_clock().now().to_msg()
        self._output.publish(self._command.message(stamp, sent.positions, sent.velocities))
        return sent

    # --- status ---------------------------------------------------------------------------------
    def _publish_status(self, state: PtpState, detail: str) -> None:
        momentum = 0.0
        if state in PLAYING and self._theta is not None:
            momentum = coupling_momentum(
                self.robot,
                self._theta,
                self._base_position,
                self._base_orientation,
                self._velocities,
            )
        values = plan_values(
            state, self.method, self.plan, self._playback, momentum, self._status.rejected
        )
        self._status.publish(state, detail, values)

    def _on_diagnostics(self) -> None:
        """Once a second (wall clock): the graph (joint_states sources: more than one is a
        fault; other commanders: reported), then the newest status on /diagnostics."""
        self._state_publishers = self._status.check_graph(self._state_topic)
        self._status.publish_diagnostics()

    def realtime_scheduling(self) -> tuple[int, bool]:
        """(thread_priority, whether it applies: on the wall clock), for
        :func:`rns_ros.nodes.runner.run_node` (the process, never a host's in-process node)."""
        return self._params["thread_priority"], not self.get_parameter("use_sim_time").value

    def destroy_node(self) -> None:
        """Stop the arm: one zero-velocity output, then tear down."""
        if self._theta is not None:
            publish_last(self, self._stop_output, "zero velocity", acked_by=self._output)
        super().destroy_node()


def main(args=None) -> int:
    return run_node(PtpNode, ptp_parameters, args)


if __name__ == "__main__":
    raise SystemExit(main())
