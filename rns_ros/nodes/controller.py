"""rns_controller: operator twist in, reactionless joint references out (thesis section 4.2-4.3).

The law is :class:`rns_ros.control.controller.ReactionlessController`; command safety is
:class:`rns_ros.control.teleop.CommandGate`; which instant a tick serves and with which twist is
:mod:`rns_ros.control.ticks`. This node converts messages and runs them once per control period
from an executor timer; with ``output_lead`` (use_sim_time, lockstep side by side) from each
period instant /clock passes (:class:`rns_ros.nodes.clock_ticks.ClockTicks`), its output stamped
that lead later; there ``await_commands`` also puts the operator in the lockstep: twists wait for
their stamps and each tick for the twist in force (:class:`rns_ros.control.ticks.AwaitedTicks`).
Parameters: :mod:`rns_ros.nodes.controller_parameters`; status:
:mod:`rns_ros.nodes.controller_status`; the operator's twists and the attitude they add up to:
:mod:`rns_ros.nodes.controller_commands`; the measured state and its watchdogs:
:mod:`rns_ros.nodes.controller_inputs`.

Subscribes:
    cmd_twist     geometry_msgs/TwistStamped (``twist_stamped: true``) or geometry_msgs/Twist;
                  best effort, depth 1 (50 with ``await_commands`` or ``execution_delay``).
                  With ``execution_delay`` D > 0 (a delayed link) a twist stamped t acts from
                  t + D, and one received after t + D + ``late_tolerance`` or stamped more
                  than ``future_tolerance`` ahead is refused. ``header.frame_id`` is
                  ``world_frame``, the base link or the camera frame (empty or unstamped:
                  ``default_twist_frame``). Only the angular part is achievable; the linear
                  part is reported as unachieved.
    joint_states  sensor_msgs/JointState (matched by joint name); watched: older than
                  ``state_timeout`` (receipt time; simulated time under use_sim_time) or from
                  more than one publisher stops the arm; under use_sim_time a /clock standing
                  still for ``clock_timeout`` of wall time stops it too, and so does a /clock
                  that goes back, jumps forward beyond ``max_clock_jump`` or has more than one
                  publisher (CLOCK_FAULT)
    base_odom     nav_msgs/Odometry (base pose in world; identity until the first message, then
                  watched like joint_states)
Publishes (joint commands only once a joint state has arrived; every one within the URDF limits
and ``max_reference_error`` of the measured angles, :mod:`rns_ros.control.command_bounds`):
    joint_references  trajectory_msgs/JointTrajectory (``output_interface: trajectory``), stamped
                      when it applies: point 0 = integrated reference at the start of the period
                      and the held theta_dot, point 1 two periods on, at rest (what a stock
                      joint_trajectory_controller executes: docs/ros2_control.md), or
    joint_velocities  std_msgs/Float64MultiArray, theta_dot [rad/s] in the order of the ``joints``
                      parameter (``output_interface: velocity``; the ros2_control
                      forward_command_controller convention: remap to <controller>/commands), or
    joint_positions   std_msgs/Float64MultiArray, the reference at the end of the period [rad] in
                      that order (``output_interface: position``, JointGroupPositionController)
    ~/status          diagnostic_msgs/DiagnosticArray every period from start-up while it has a
                      subscriber: state, sigma_min, the three determinants, lambda^2, speed
                      scale, unachieved twist, predicted coupling momentum (telemetry)
    /diagnostics      diagnostic_msgs/DiagnosticArray at 1 Hz (wall clock): the newest status,
                      hardware_id = robot name (what diagnostic_updater users aggregate)
``~/pause`` (std_srvs/SetBool) and the camera orientation goal (``~/camera_goal``, reached goals
on ``~/camera_goal_reached``): :mod:`rns_ros.nodes.controller_requests`.
"""

from __future__ import annotations

import time

import numpy as np
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.time import Time
from sensor_msgs.msg import JointState

from rns_ros.control.command_bounds import BoundedCommand, CommandBounds
from rns_ros.control.controller import (
    ControllerSettings,
    ControllerStep,
    ReactionlessController,
    TwistFrame,
    angular_velocity_in_world,
)
from rns_ros.control.prediction import OutputTiming
from rns_ros.control.teleop import (
    CommandGate,
    ControllerState,
    GateOutput,
    TwistCommand,
    twist_frame_ids,
)
from rns_ros.control.ticks import ServedTick, TickInstants, TickLateness
from rns_ros.core import FreeFloatingState
from rns_ros.core.commands import ExtraJointsReport, match_joint_state
from rns_ros.core.errors import InputError, RnsError
from rns_ros.nodes import controller_parameters
from rns_ros.nodes.cdr import JointStateReader, MalformedMessageError, TwistFields, read_odometry
from rns_ros.nodes.clock_ticks import ClockTicks
from rns_ros.nodes.controller_commands import INPUT_QOS, CommandTracking, OperatorTwists
from rns_ros.nodes.controller_inputs import MAX_PREDICTION_AGE, MeasuredState
from rns_ros.nodes.controller_output import JointOutput
from rns_ros.nodes.controller_parameters import (
    NODE_NAME,
    PARAMETERS,
    SPECS,
    command_gate,
    controller_settings,
    tracking_settings,
)
from rns_ros.nodes.controller_requests import OperatorRequests, goal_settings
from rns_ros.nodes.controller_status import (
    DIAGNOSTICS_PERIOD,
    InputPublishers,
    JointLimitStop,
    StatusReporter,
    joint_limit_text,
    step_values,
)
from rns_ros.nodes.input_clock import InputClock
from rns_ros.nodes.parameters import (
    declare_parameters,
    load_node_model,
    sim_time_change_refused,
)
from rns_ros.nodes.robot_io import base_pose
from rns_ros.nodes.runner import publish_last, run_node

#: How closely [-, relative] the node clock and the steady clock must agree on the time
#: between two ticks for a long one to count as a stall rather than a clock jump.
STEADY_AGREEMENT = 0.05
#: Measured and integrated angles further apart than this [rad] restart the reference.
RESYNC_TOLERANCE = 0.2
#: Shortest interval between two ticks when commands are served at once [s]: a command flood
#: cannot make the controller compute faster than this; a change within it waits for the tick.
MIN_TICK_INTERVAL = 1e-3


class ControllerNode(Node):
    """ROS 2 wrapper of :class:`ReactionlessController` (see the module docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(NODE_NAME, **node_kwargs)
        self._params = params = declare_parameters(self, PARAMETERS)
        self.robot = load_node_model(self, params["model_config"])
        self._period = 1.0 / params["rate"]
        self.controller = ReactionlessController(self.robot, controller_settings(params))
        self._frames = twist_frame_ids(
            self.robot, params["world_frame"], params["default_twist_frame"]
        )
        self._gate = command_gate(params, self._frames)
        # the camera attitude the operator's rates add up to, and the last gap to it
        self._tracking = CommandTracking(self, tracking_settings(params))
        self._requests = OperatorRequests(
            self, params["world_frame"], goal_settings(params), self._gate.reject
        )
        # input watchdogs judge ages on the input clock (simulated time under use_sim_time)
        self._input_clock = InputClock(
            self,
            params["clock_timeout"],
            self._on_clock_stopped,
            on_clock_fault=self._on_clock_fault,
            max_clock_jump=params["max_clock_jump"],
        )
        # the newest joint state and base pose, their receipt times, a jump seen in joint_states
        self._measured = MeasuredState(self.robot.joint_names, self._input_clock)
        self._stopped = True  # the last output was zero velocity: the next one ramps up
        self._singular_time = 0.0  # [s] of outputs served in the singular region
        self._resync = False  # the reference restarts at the measured angles this tick
        self._steady_tick: float | None = None  # time.monotonic() of the last served tick [s]
        self._served: tuple[np.ndarray, TwistFrame] | None = None  # (angular, frame) last tick
        self._predict = params["predict_state"]
        self._sim_time = bool(self.get_parameter("use_sim_time").value)
        # [s] from a tick to its output's stamp (sim time only: lockstep side by side)
        self._lead = params["output_lead"] if self._sim_time else 0.0
        if params["output_lead"] and not self._sim_time:
            self.get_logger().warn("output_lead is for use_sim_time (lockstep) only: not used")
        # latency is a wall-clock matter: under simulated time a command served between ticks
        # would land while a lockstep simulator runs on, so ticks stay on the period grid
        # time-tagged twists act on the tick grid at their execution time
        self._immediate = (
            params["immediate_reaction"] and not self._sim_time and not params["execution_delay"]
        )
        self._instants = TickInstants(self._period, self._lead)
        self._lateness = TickLateness(self._period)  # wall clock: the timer's mean lateness
        self._reporter = StatusReporter(self, self.robot.name)  # the intakes report into it
        self._twists = OperatorTwists(
            self,
            params,
            self._lead,
            self._frames,
            self._input_clock,
            self._reporter,
            on_command=self._take_command,
            reject=self._gate.reject,
            serve_ready=self._serve_ready,
        )
        self._awaited = self._twists.awaited  # None without await_commands
        self._create_state_inputs()
        self._joint_output = JointOutput(
            self,
            params["output_interface"],
            self.robot.joint_names,
            params["joints"],
            self._period,
            keep=2 * MAX_PREDICTION_AGE,
            bounds=CommandBounds.of(self.robot, params["max_reference_error"]),
        )
        self._output = self._joint_output.publisher  # destroy_node waits for its acks
        self._limit_stop = JointLimitStop(self._period)
        self._sources = InputPublishers(
            self, self._topics, self._twists.message_type, self._output.topic_name
        )
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self._start_ticks()
        # wall clock: diagnostics and the graph check go on while sim time is paused
        self.create_timer(
            DIAGNOSTICS_PERIOD,
            self._on_diagnostics,
            clock=Clock(clock_type=ClockType.STEADY_TIME),
        )
        self.get_logger().info(
            f"{params['method']} reactionless control of {self.robot.name} at {params['rate']} Hz "
            f"({params['hold_correction']} hold); waiting for {self._topics['joint_states']}"
        )

    def _create_state_inputs(self) -> None:
        """joint_states and base_odom subscriptions, taken serialized: reading the few fields
        used from the bytes (rns_ros.nodes.cdr) is cheaper than rclpy building the message."""
        self._clock_type = self.get_clock().clock_type
        self._joint_state_reader = JointStateReader()
        self._extra_joints = ExtraJointsReport()  # joint_states names beyond the model's
        self.create_subscription(
            JointState, "joint_states", self._on_joint_state, INPUT_QOS, raw=True
        )
        self.create_subscription(Odometry, "base_odom", self._on_odom, INPUT_QOS, raw=True)
        self._topics = {
            "cmd_twist": self._twists.topic,
            "joint_states": self.resolve_topic_name("joint_states"),
        }

    def realtime_scheduling(self) -> tuple[int, bool]:
        """(thread_priority, whether it applies: on the wall clock), for
        :func:`rns_ros.nodes.runner.run_node` (the process, never a host's in-process node)."""
        return self._params["thread_priority"], not self._sim_time

    def _start_ticks(self) -> None:
        """The control timer, or with output_lead the ticks of /clock itself: the events
        executor can run a sim-time timer two or three times for one /clock message and then
        skip as many periods, and each output here acts the period after its tick, so a lockstep
        simulator needs every one (a missed tick stalls it; a repeated one sends a period
        twice)."""
        if self._lead:
            self._timer = None
            self._clock_ticks = ClockTicks(self, self._period, self._serve)
        else:
            self._timer = self.create_timer(self._period, self._on_tick)

    # the newest measured sample (None until the first joint state), read here and by tests
    @property
    def _theta(self) -> np.ndarray | None:
        return self._measured.theta

    @property
    def _theta_stamp(self) -> int | None:
        return None if self._measured.joints is None else self._measured.joints.stamp

    @property
    def _state_received(self) -> float:
        return self._measured.state_received

    # --- inputs ---------------------------------------------------------------------------------
    def _take_command(self, command: TwistCommand, stamp: float) -> None:
        """A valid operator twist stamped ``stamp`` [s] (the sender's clock, else its receipt):
        the gate, the camera goal and the commanded attitude take it; with immediate_reaction
        a change of the output is served at once."""
        self._gate.accept(command)
        self._requests.twist_taken(command)
        self._tracking.take(command, stamp, self._measured.base_orientation)
        if self._immediate and self._changes_output(command):
            now = time.monotonic()
            if now - self._instants.last_wall >= MIN_TICK_INTERVAL:
                self._timer.reset()  # the next tick is one full period from now
                self._on_tick()

    def _changes_output(self, command: TwistCommand) -> bool:
        """True when ``command`` differs from what the last tick served (and ticks run)."""
        if self._theta is None or self._served is None:
            return False
        angular, frame = self._served
        return frame is not command.frame or not np.array_equal(angular, command.angular)

    def _on_joint_state(self, data: bytes) -> None:
        try:
            fields = self._joint_state_reader(data)
        except MalformedMessageError as exc:
            self._reporter.reject(self._topics["joint_states"], exc)
            return
        try:
            command, extras = match_joint_state(
                fields.names,
                self.robot.joint_names,
                positions=fields.position,
                velocities=fields.velocity,
            )
        except InputError as exc:
            self.get_logger().error(f"ignored joint_states: {exc}", throttle_duration_sec=1.0)
            return
        note = self._extra_joints.note(extras)
        if note is not None:
            self.get_logger().info(note)
        if command.positions is None:
            return
        sec, nanosec = fields.stamp
        stamp = Time(seconds=sec, nanoseconds=nanosec, clock_type=self._clock_type).nanoseconds
        self._measured.take_joint_state(
            command.positions,
            command.velocities,
            stamp,
            self.controller.reference_positions,
            self._params["state_jump_tolerance"],
        )

    def _on_odom(self, data: bytes) -> None:
        try:
            fields = read_odometry(data)
        except MalformedMessageError as exc:
            self._reporter.reject(self.resolve_topic_name("base_odom"), exc)
            return
        pose = base_pose(fields.pose)
        if pose is not None:
            sec, nanosec = fields.stamp
            self._measured.take_base_pose(*pose, sec + 1e-9 * nanosec)

    # --- control period -------------------------------------------------------------------------
    def _on_tick(self) -> None:
        self._serve(self.get_clock().now())

    def _serve(self, tick: Time) -> None:
        """The control period of the instant ``tick``: the timer's call, or with
        ``output_lead`` each period instant /clock passes (:class:`ClockTicks`)."""
        if self._theta is None:
            self._reporter.report(
                ControllerState.WAITING_FOR_STATE,
                f"waiting for {self._topics['joint_states']}",
                {"method": self.controller.settings.method.value},
            )
            return
        instant = tick.nanoseconds
        if self._lead:
            instant = self._lead_instant(instant)
            if instant is None:
                return
        if self._awaited is None or self._input_clock.clock_fault() is not None:
            self._serve_tick(instant)  # a tick on an untrusted clock holds still: no wait
        else:
            self._serve_ready(self._awaited.tick(instant))

    def _lead_instant(self, tick: int) -> int | None:
        """With ``output_lead``: the instant [ns] to serve for the /clock tick ``tick`` [ns], or
        None to skip it (:meth:`TickInstants.lead_instant`)."""
        instant = self._instants.lead_instant(
            tick, self._theta_stamp, self._measured.state_received_wall
        )
        if instant is not None and instant != tick:
            # the simulation ran on without this controller (after a reset or a dropped
            # command it runs in real time until commands come back; a patience step)
            self.get_logger().info(
                f"late tick {tick * 1e-9:.3f} s: the simulation is at {instant * 1e-9:.3f} s; "
                "served there (the ticks in between are skipped)",
                throttle_duration_sec=1.0,
            )
        return instant

    def _serve_ready(self, ticks: list[ServedTick[TwistFields]]) -> None:
        """await_commands: the ticks whose twist in force is known, each after its twists."""
        for tick in ticks:
            for fields in tick.commands:
                self._twists.take(fields.angular, fields.linear, fields.frame_id, fields.stamp)
            self._serve_tick(tick.instant)

    def _serve_tick(self, tick: int) -> None:
        """The control period of ``tick`` [ns] once its inputs are there: state, law, output."""
        _, held = self._instants.serve(tick)
        self._twists.release_due(tick)  # time-tagged twists acting by this tick
        clock_fault = self._input_clock.clock_fault()
        if clock_fault is not None:
            self.controller.abandon_hold()  # held for a time no clock difference can tell
            self._hold_still(ControllerState.CLOCK_FAULT, clock_fault, at=tick)
            return
        # the previous output was held this long on the plant's clock (sim time: /clock)
        steady = time.monotonic()
        steady_held = None if self._steady_tick is None else steady - self._steady_tick
        self._steady_tick = steady
        limit = self._hold_limit(held, steady_held) if held is not None else None
        if held is not None and not self.controller.end_hold(held, limit):
            self._lost_hold(held, limit)
            if not self._sim_time:
                # the node itself stalled: the executor runs this timer before the samples that
                # came meanwhile, so the state would look stale and stop the arm; the next
                # period is judged on them (the plant ended the last output at rest)
                return
        now = self._input_clock.now()
        self._measured.drop_future_receipts(now)
        fault = self._measured.fault(
            now,
            self._sources.state_publishers,
            self._topics["joint_states"],
            self._params["state_timeout"],
        )
        if fault is not None:
            self._hold_still(*fault, at=tick)
            return
        if self._requests.paused:
            self._hold_still(ControllerState.PAUSED, "~/pause: resume with false", at=tick)
            return
        gap = self._measured.gap(now, self._params["state_hold_age"], self._params["state_timeout"])
        if gap is not None:
            self._hold_still(ControllerState.STATE_GAP, gap, at=tick)
            return
        theta, hold = self._plan(tick)
        state = self._sampled_state(theta)
        goal = self._requests.goal_command(state.camera.rotation, now)
        if goal is not None:
            self._gate.accept(goal)
        gate = self._gate.update(now, self._period)
        if self._stopped or gate.stopped or self._resync:
            self.controller.resync(state)  # restart the reference where the arm is
            self._resync = False
        elif np.abs(self.controller.reference_positions - state.theta).max() > RESYNC_TOLERANCE:
            self.get_logger().warn("joint reference far from the measured angles: resynced")
            self.controller.resync(state)
        self._served = (gate.angular, gate.frame)
        omega = angular_velocity_in_world(state, gate.angular, gate.frame)
        omega = omega + self._tracking.correction(
            state.camera.rotation, gate.state, goal is not None, now, self._lead
        )
        step = self.controller.step(state, omega, hold)
        self._stopped = gate.stopped
        velocities = np.zeros(self.robot.n) if gate.stopped else step.joint_velocity
        sent = self._publish_output(step.reference_positions, velocities, tick, self._lead)
        if sent.non_finite:  # published as a stop at the finite positions
            self._hold_still(
                ControllerState.INVALID_COMMAND,
                "the law produced a non-finite joint velocity",
                publish=False,
            )
            return
        reported, detail = self._requests.state(
            self._controller_state(step, gate, state, self._period if hold is None else hold),
            gate.detail,
        )
        self._reporter.report(
            reported,
            detail,
            lambda: {
                **step_values(self.controller.settings.method.value, step, gate),
                "tracking_error": self._tracking.error,
                "singular_time": self._singular_time,
                **self._requests.values(),
            },
        )

    def _sampled_state(self, theta: np.ndarray) -> FreeFloatingState:
        """The robot at joint angles ``theta`` [rad] (n,) and the measured base pose; after a
        jump in joint_states the reference and the wrist reference restart there."""
        state = FreeFloatingState.compute(
            self.robot,
            self.robot.configuration(
                theta, self._measured.base_position, self._measured.base_orientation
            ),
        )
        jump = self._measured.take_jump()
        if jump is not None:
            self.get_logger().warn(
                f"{jump}: reference and wrist reference restarted at the measured pose, "
                "command ramps up from rest"
            )
            self._gate.stop()
            self._tracking.stop(self._input_clock.now())
            self._stopped = True
            # a new pose (reset, re-homed arm): the wrist is held where it is now, eq. (4.6)
            self.controller.reset(state)
        return state

    def _on_clock_stopped(self, still: float) -> None:
        """use_sim_time: /clock has stood still for ``still`` [s] of wall time. While the arm
        moves, no joint state came for as long either (a dead simulator) and no tick waits for
        the operator's twist (that wait has its own watchdog), stop it here: the sim-time
        ticks that would stop it have stopped too."""
        waiting = self._awaited is not None and self._awaited.oldest_waiting is not None
        quiet = self._measured.wall_quiet()
        if self._theta is None or self._stopped or waiting or quiet < self._input_clock.timeout:
            return
        self._hold_still(
            ControllerState.STALE_STATE,
            f"/clock stood still for {still:.3f} s (clock_timeout "
            f"{self._params['clock_timeout']} s wall time)",
        )

    def _on_clock_fault(self, text: str) -> None:
        """use_sim_time: simulated time cannot be trusted (``text``: why, and who publishes
        /clock): the arm is stopped now, and every tick holds it until /clock runs forward from
        one publisher again (:meth:`InputClock.clock_fault`); it then resumes from the measured
        angles, ramping up, as after a stale state. Ticks waiting for the operator are served
        (held still) at once. With ``output_lead`` the ticks ride on /clock: the tick of the
        faulty reading (or of the next reading) holds the arm, stamped as every output."""
        if self._theta is None:
            return  # nothing commanded yet
        if self._awaited is not None:
            self._serve_ready(self._awaited.give_up())
        if not self._lead:
            self._hold_still(ControllerState.CLOCK_FAULT, text)

    def _hold_limit(self, held: float, steady: float | None) -> float:
        """The longest hold [s] the reference moves on over: ``max_hold``; on the wall clock, up
        to ``state_hold_age`` when the steady clock saw the same interval ``steady`` [s] (the
        node stalled, the clock did not jump): the plant held the output that long (velocity
        interface), or ended its trajectory early and its position loop catches up with the
        next one, so the motion commanded over the stall is not lost."""
        if (
            self._sim_time
            or steady is None
            or abs(held - steady) > STEADY_AGREEMENT * max(held, self._period)
        ):
            return self.controller.max_hold
        return max(self.controller.max_hold, self._params["state_hold_age"])

    def _lost_hold(self, held: float, limit: float) -> None:
        """The ticks came ``held`` [s] apart, outside what the controller integrates a held
        output over (the clock went back or jumped less than max_clock_jump, or the node
        stalled): where the held output took the arm is not known, so the reference restarts
        at the measured angles (on the wall clock at the next tick, after the samples that came
        during the stall). A stall shorter than state_timeout is ridden through
        like a gap in joint_states (the command goes on); a clock fault stops the arm."""
        self.get_logger().warn(
            f"{held:.4g} s between two ticks, outside [0, {limit:.3g}] s (the "
            "clock jumped or the node stalled): the reference restarts at the measured angles",
            throttle_duration_sec=5.0,
        )
        self._resync = True

    def _hold_still(
        self,
        state: ControllerState,
        detail: str,
        at: int | None = None,
        publish: bool = True,
    ) -> None:
        """Publish zero velocity where the reference stands (bounded around the measured
        angles), report ``state``; the next good tick restarts the reference at the measured
        angles and ramps the command up. ``at``: the tick's instant [ns] (its output is stamped
        ``output_lead`` later, as a tick's is); None: now. ``publish`` False: the stop was
        published already."""
        if state is ControllerState.STATE_GAP:
            self.get_logger().warn(f"{state.value}: {detail}", throttle_duration_sec=5.0)
        elif self._reporter.last_state is not state and state is not ControllerState.PAUSED:
            self.get_logger().error(f"{state.value}: {detail}; joints commanded to rest")
        self._limit_stop.end()
        self._gate.stop()
        if state not in (ControllerState.STATE_GAP, ControllerState.STALE_STATE):
            # a gap in the state stream holds the arm but not the operator: the commanded
            # attitude runs on and the arm catches up when the state is fresh again
            self._tracking.stop(self._input_clock.now())
        self._stopped = True
        self._served = None
        if publish:
            positions = self.controller.reference_positions
            lead = self._lead if at is not None else 0.0
            self._publish_output(
                self._theta if positions is None else positions, np.zeros(self.robot.n), at, lead
            )
        self._reporter.report(state, detail, {"method": self.controller.settings.method.value})

    def _plan(self, now: int) -> tuple[np.ndarray, float | None]:
        """Where the output of the tick at ``now`` [ns] starts on the plant and how long it is
        held there: (joint angles [rad] (n,), hold [s] or None for the period T).

        The angles are the measured ones moved on to when the output acts
        (:func:`predict_joint_angles`): joint_states lag by up to one publish period, the output
        reaches the plant a moment later and acts at its next update, and the midpoint hold is
        reactionless only for the configuration it starts from. The hold runs until the next
        output acts: the timer's next call (on its grid, so a late tick holds for less than T),
        late by the timer's mean lateness (:class:`TickLateness`), through the same latency and
        update grid. A state up to ``output_lead`` newer than the
        tick (a late tick in lockstep) is taken from its stamp."""
        if not self._predict:
            return self._theta, None  # the sample as it is, held for T
        # with output_lead the ticks lie on the period grid (ClockTicks)
        if self._lead:
            hold = self._period
        else:
            hold = self._lateness.hold(self._timer.time_until_next_call())
        if hold is not None and not 0.0 < hold <= self.controller.max_hold:
            hold = None  # not a time the next tick can be from: the period
        if self._stopped:
            return self._theta, hold
        timing = OutputTiming(
            latency=self._lead if self._sim_time else self._params["output_latency"],
            plant_period=self._params["plant_period"],
            horizon=self._joint_output.command.acting_horizon,
        )
        return self._measured.output_start(now, hold, self._lead, timing, self._joint_output.recent)

    def _controller_state(
        self, step: ControllerStep, gate: GateOutput, state: FreeFloatingState, hold: float
    ) -> ControllerState:
        """The state of a served tick whose output is held ``hold`` [s]."""
        if gate.state not in (ControllerState.OK, ControllerState.RAMPING):
            self._limit_stop.end()
            return gate.state
        stopped, began = self._limit_stop.update(step.output.position_limited, hold)
        if stopped:
            if began:
                self.get_logger().warn(joint_limit_text(self.robot, state.theta))
            return ControllerState.JOINT_LIMIT
        epsilon = self.controller.settings.gains.epsilon
        if step.output.sigma_min < epsilon:
            if self._reporter.last_state is not ControllerState.SINGULAR_REGION:  # entering
                self.get_logger().warn(
                    f"SINGULAR_REGION: sigma_min of J-bar {step.output.sigma_min:.3g} < epsilon "
                    f"{epsilon:g}: the commanded rate is damped (the camera lags; section 4.3)",
                    throttle_duration_sec=5.0,
                )
            self._singular_time += hold
            return ControllerState.SINGULAR_REGION
        return gate.state

    def _publish_output(
        self,
        positions: np.ndarray,
        velocities: np.ndarray,
        at: int | None = None,
        lead: float = 0.0,
    ) -> BoundedCommand:
        """One joint command planned at ``at`` [ns] (default now), stamped ``lead`` [s] later,
        within the URDF limits and max_reference_error of the measured angles (a non-finite one
        as a stop; :meth:`JointOutput.publish`). Returns what was published."""
        now = self.get_clock().now().nanoseconds if at is None else at
        sent = self._joint_output.publish(positions, velocities, self._theta, now, lead)
        if sent.clipped_joint is not None:
            joint = sent.clipped_joint
            low, high = self._joint_output.bounds.box(self._theta)
            self.get_logger().warn(
                f"joint command clipped: {self.robot.joint_names[joint]} "
                f"{positions[joint]:.6g} rad is outside [{low[joint]:.6g}, {high[joint]:.6g}] "
                "rad (URDF limits, max_reference_error "
                f"{self._params['max_reference_error']} rad of the measured angle)",
                throttle_duration_sec=1.0,
            )
        return sent

    # --- once a second: who publishes our inputs, /diagnostics --------------------------------
    def _on_diagnostics(self) -> None:
        self._reporter.advisories = self._sources.check()
        self._reporter.publish_diagnostics()

    # --- parameters, shutdown ---------------------------------------------------------------------
    def _validate_parameters(self, parameters) -> SetParametersResult:
        """On set: accept a change only when its values pass their specs and make valid law
        settings and command gate, and use_sim_time stays (the reason names what is wrong)."""
        refused = sim_time_change_refused(self, parameters)
        if refused is not None:
            return SetParametersResult(successful=False, reason=refused)
        try:
            self._configured(parameters)
        except RnsError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters) -> None:
        """After a set: the law and the command gate take the new values."""
        self._params, settings, gate = self._configured(parameters)
        self.controller.configure(settings)
        self._gate.timeout, self._gate.deceleration = gate.timeout, gate.deceleration
        self._gate.acceleration = gate.acceleration
        self._requests.goal.settings = goal_settings(self._params)
        self._tracking.settings = tracking_settings(self._params)
        self._input_clock.set_clock_timeout(self._params["clock_timeout"])
        self._twists.max_angular_speed = self._params["max_angular_speed"]
        self._twists.command_timeout = self._params["command_timeout"]

    def _configured(self, parameters) -> tuple[dict, ControllerSettings, CommandGate]:
        """(parameter values, law settings, command gate) with ``parameters`` set.

        Raises:
            RnsError: a value breaks its spec, the settings or the gate.
        """
        updated = dict(self._params)
        for parameter in parameters:
            if parameter.name in SPECS:
                updated[parameter.name] = parameter.value
        for parameter in parameters:
            if parameter.name in SPECS:
                SPECS[parameter.name].check(parameter.value)
        goal_settings(updated)  # raises on an invalid goal setting
        tracking_settings(updated)
        return updated, controller_settings(updated), command_gate(updated, self._frames)

    def destroy_node(self) -> None:
        """Stop the arm: one zero-velocity output, then tear down."""
        if self._theta is not None:
            publish_last(
                self,
                lambda: self._publish_output(self._theta, np.zeros(self.robot.n)),
                "zero velocity",
                acked_by=self._output,
            )
        super().destroy_node()


def main(args=None) -> int:
    return run_node(ControllerNode, controller_parameters, args)


if __name__ == "__main__":
    raise SystemExit(main())
