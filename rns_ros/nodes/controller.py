"""rns_controller: operator twist in, reactionless joint references out (thesis section 4.2-4.3).

The law is :class:`rns_ros.control.controller.ReactionlessController`; command safety is
:class:`rns_ros.control.teleop.CommandGate`. This node only converts messages and runs them once per
control period from an executor timer; with ``output_lead`` (use_sim_time, lockstep side by side)
from each period instant /clock passes (:class:`rns_ros.nodes.clock_ticks.ClockTicks`), its output
stamped that lead later; there ``await_commands`` also puts the operator in the lockstep: twists
wait for their stamps and each tick for the twist in force
(:class:`rns_ros.control.teleop.CommandSchedule`).

Subscribes:
    cmd_twist     geometry_msgs/TwistStamped (``twist_stamped: true``) or geometry_msgs/Twist;
                  best effort, depth 1 (50 with ``await_commands``). ``header.frame_id`` is
                  ``world_frame``, the base link or the camera frame (empty or unstamped:
                  ``default_twist_frame``). Only the angular part is achievable; the linear
                  part is reported as unachieved.
    joint_states  sensor_msgs/JointState (matched by joint name); watched: older than
                  ``state_timeout`` (receipt time) or from more than one publisher stops the arm
    base_odom     nav_msgs/Odometry (base pose in world; identity until the first message, then
                  watched like joint_states)
Publishes (joint commands only once a joint state has arrived):
    joint_references  trajectory_msgs/JointTrajectory, one point: positions = integrated
                      reference at the start of the period, velocities = held theta_dot
                      (``output_interface: trajectory``), or
    joint_velocities  std_msgs/Float64MultiArray, theta_dot [rad/s] in the order of the ``joints``
                      parameter (``output_interface: velocity``; the ros2_control
                      forward_command_controller convention: remap to <controller>/commands)
    ~/status          diagnostic_msgs/DiagnosticArray every period from start-up while it has a
                      subscriber: state, sigma_min, the three determinants, lambda^2, speed
                      scale, unachieved twist, predicted coupling momentum (telemetry)
    /diagnostics      diagnostic_msgs/DiagnosticArray at 1 Hz (wall clock): the newest status,
                      hardware_id = robot name (what diagnostic_updater users aggregate)
"""

from __future__ import annotations

import sys
import time
from collections import deque
from collections.abc import Callable

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time import Time
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from rns_ros.control.controller import (
    ControllerSettings,
    ControllerStep,
    ReactionlessController,
    TwistFrame,
    angular_velocity_in_world,
)
from rns_ros.control.inspection import ControlGains
from rns_ros.control.prediction import OutputTiming, PublishedOutput, predict_joint_angles
from rns_ros.control.teleop import (
    CommandGate,
    CommandSchedule,
    ControllerState,
    GateOutput,
    TwistCommand,
    resolve_twist_frame,
    twist_frame_ids,
    validate_twist,
)
from rns_ros.core import FreeFloatingState, load_model
from rns_ros.core.commands import match_named_command
from rns_ros.core.errors import InputError, RnsError
from rns_ros.nodes.cdr import (
    JointStateReader,
    SerializedTemplate,
    TemplateError,
    TwistFields,
    joint_trajectory_template,
    read_odometry,
    read_twist_stamped,
    split_stamp,
)
from rns_ros.nodes.clock_ticks import ClockTicks
from rns_ros.nodes.parameters import (
    JOINTS,
    MODEL_CONFIG,
    WORLD_FRAME,
    ParameterSpec,
    declare_parameters,
    specs_by_name,
    velocity_joint_order,
)
from rns_ros.nodes.robot_io import base_pose, joint_command, measured_state_problem
from rns_ros.nodes.runner import publish_last, run_node
from rns_ros.nodes.status import level_rank, node_names, status_text, type_name
from rns_ros.resources import default_model_config

NODE_NAME = "rns_controller"
SUMMARY = "Reactionless camera-pointing controller: twist in, joint references out (DLS / SC)."
#: Measured and integrated angles further apart than this [rad] restart the reference.
RESYNC_TOLERANCE = 0.2
#: joint_states older than this [s] are used as they are, not extrapolated.
MAX_PREDICTION_AGE = 0.1
#: cmd_twist under await_commands: best effort (matches the operators' best-effort publishers),
#: deep enough for the samples an operator publishes ahead (each is one instant of its
#: profile: none may be overwritten before it is read).
SCHEDULED_COMMAND_QOS = QoSProfile(depth=50, reliability=ReliabilityPolicy.BEST_EFFORT)
#: output_lead: a state stamped up to this far [s] past a tick is caught up to (the simulation
#: ran ahead of the ticks); farther is another clock, not a lag.
MAX_LEAD_CATCH_UP = 1.0
#: Defaults of the output timing [s]: a plant that acts on a JointTrajectory from its stamp
#: (rns_simulator, a joint trajectory controller) has neither latency nor update grid for it.
#: Measured for a plant acting on receipt (rns_simulator with the velocity interface):
#: output_latency 0.4-0.7 ms (loopback DDS), plant_period 1 ms (its step).
DEFAULT_OUTPUT_LATENCY = 0.0
DEFAULT_PLANT_PERIOD = 0.0
#: Shortest interval between two ticks when commands are served at once [s]: a command flood
#: cannot make the controller compute faster than this; a change within it waits for the tick.
MIN_TICK_INTERVAL = 1e-3
#: Period of the /diagnostics publication and of the check of who publishes our inputs [s].
DIAGNOSTICS_PERIOD = 1.0
#: Status level of each state (diagnostic_msgs/DiagnosticStatus).
STATE_LEVELS = {
    ControllerState.OK: DiagnosticStatus.OK,
    ControllerState.IDLE: DiagnosticStatus.OK,
    ControllerState.RAMPING: DiagnosticStatus.OK,
    ControllerState.INVALID_COMMAND: DiagnosticStatus.ERROR,
    ControllerState.STALE_STATE: DiagnosticStatus.ERROR,
    ControllerState.CONFLICTING_STATE: DiagnosticStatus.ERROR,
}

PARAMETERS = (
    MODEL_CONFIG,
    ParameterSpec(
        "method",
        "dls",
        "Singularity handling: dls (4.10-4.12), sc (4.13-4.15), pinv (4.9), or the "
        "conventional wrist-only baseline (4.7-4.8, disturbs the base)",
        choices=("dls", "sc", "pinv", "conventional"),
        read_only=False,
    ),
    ParameterSpec(
        "epsilon",
        0.2,
        "DLS singular region: damping starts below this sigma_min of J-bar",
        "[-]",
        1e-6,
        10.0,
        read_only=False,
    ),
    ParameterSpec(
        "lambda2_max",
        2.0,
        "DLS maximum damping lambda^2_max",
        "[-]",
        1e-6,
        100.0,
        read_only=False,
    ),
    ParameterSpec(
        "sc_gain",
        1.7,
        "Singularity-Consistent gain b of eq. (4.13)",
        "[-]",
        1e-3,
        100.0,
        read_only=False,
    ),
    ParameterSpec(
        "wrist_gain",
        100.0,
        "Wrist-position stabilization gain k_g of eq. (4.5); 0 disables",
        "[1/(m s)]",
        0.0,
        1e4,
        read_only=False,
    ),
    ParameterSpec("rate", 100.0, "Control rate (output period)", "[Hz]", 1.0, 1000.0),
    ParameterSpec(
        "hold_correction",
        "midpoint",
        "midpoint: evaluate the law at the predicted mid-period configuration (reactionless "
        "over the whole hold); naive: at the sample (base turns, first order in the period)",
        choices=("midpoint", "naive"),
        read_only=False,
    ),
    ParameterSpec(
        "hold_iterations", 1, "Midpoint predictions per period", "[-]", 1, 5, read_only=False
    ),
    ParameterSpec(
        "max_angular_speed",
        1.0,
        "Commands with a larger |angular| are scaled down to it as a whole vector (axis kept, "
        "status SPEED_LIMITED); NaN/Inf are rejected",
        "[rad/s]",
        1e-3,
        10.0,
        read_only=False,
    ),
    ParameterSpec(
        "command_timeout",
        0.5,
        "A command older than this (by receipt time) decelerates to zero",
        "[s]",
        0.01,
        60.0,
        read_only=False,
    ),
    ParameterSpec(
        "stop_deceleration",
        1.0,
        "Angular deceleration of the command when stale or rejected",
        "[rad/s^2]",
        1e-3,
        1000.0,
        read_only=False,
    ),
    ParameterSpec(
        "start_acceleration",
        1.0,
        "Angular acceleration of the command when starting from rest (first command, after a "
        "stop, a stale or jumping state, or a restart)",
        "[rad/s^2]",
        1e-3,
        1000.0,
        read_only=False,
    ),
    ParameterSpec(
        "state_timeout",
        0.1,
        "joint_states (and base_odom once it has arrived) older than this by receipt time stop "
        "the arm: zero velocity, STALE_STATE error; a fresh state resumes with a ramp",
        "[s]",
        0.005,
        10.0,
        read_only=False,
    ),
    ParameterSpec(
        "state_jump_tolerance",
        0.05,
        "A joint angle this far from its prediction (previous sample moved on at its rate) is a "
        "discontinuity (reset, new source): the reference restarts there, the command ramps up",
        "[rad]",
        1e-4,
        10.0,
        read_only=False,
    ),
    ParameterSpec(
        "immediate_reaction",
        True,
        "Serve a changed command at once and restart the period (the hold in progress is cut "
        "short) instead of at the next tick: latency ~2 ms instead of up to one period. Wall "
        "clock only: under use_sim_time ticks stay on the period grid (reproducible lockstep)",
    ),
    ParameterSpec(
        "predict_state",
        True,
        "Extrapolate the last joint_states to where the joints are when the new output takes "
        "effect (its arrival, output_latency after the tick, rounded up to the plant's next "
        "update): at their measured rates, then at this controller's own outputs from when "
        "they act (the sample lags by up to one publish period); and hold for the time until "
        "the next tick. false: the sample as it is, held for the period",
    ),
    ParameterSpec(
        "output_latency",
        DEFAULT_OUTPUT_LATENCY,
        "Publish-to-receipt time of an output at a plant that acts on receipt (the velocity "
        "interface: ~0.5 ms on loopback), for predict_state; 0 for a plant that acts from the "
        "output's stamp (JointTrajectory to rns_simulator or a trajectory controller). Wall "
        "clock only: under use_sim_time it counts as 0 (a lockstep simulator waits for outputs)",
        "[s]",
        0.0,
        0.05,
        read_only=False,
    ),
    ParameterSpec(
        "output_lead",
        0.0,
        "Under use_sim_time: stamp each output this long after the tick that computed it, and "
        "predict the joints to then. rns_simulator starts a JointTrajectory at its stamp and, in "
        "lockstep, simulates up to it meanwhile, so controller and simulator compute side by "
        "side (rns_demo off real time: one period); a tick whose state is already stamped past "
        "its output's instant is served at the state's instant. 0: the output acts from its "
        "tick. Wall clock: not used (a real plant's lead is its latency, output_latency)",
        "[s]",
        0.0,
        0.1,
    ),
    ParameterSpec(
        "plant_period",
        DEFAULT_PLANT_PERIOD,
        "Update period of a plant that acts on receipt (rns_simulator step_size with the "
        "velocity interface, the ros2_control update period), on a grid through the "
        "joint_states stamps: an output acts at the first update after it arrives; 0: at once",
        "[s]",
        0.0,
        0.1,
        read_only=False,
    ),
    ParameterSpec(
        "await_commands",
        False,
        "Under use_sim_time with output_lead (lockstep side by side): serve each tick with the "
        "newest cmd_twist stamped at or before it, waiting (up to command_timeout, wall clock) "
        "for one stamped at or after it unless the newest is a stop after motion; twists "
        "stamped ahead (rns_operator's lead) wait for their stamps. The simulation then waits "
        "for the operator too, so a run's figures do not depend on when its process got a "
        "core (rns_demo off real time). Needs twist_stamped. false: a twist acts on receipt",
    ),
    ParameterSpec("twist_stamped", True, "cmd_twist is TwistStamped (false: plain Twist)"),
    ParameterSpec(
        "default_twist_frame",
        "camera",
        "Axes of unstamped commands and of an empty header.frame_id: world (or the world_frame "
        "name), base (or the URDF base link name), camera (or the camera frame name)",
    ),
    ParameterSpec(
        "output_interface",
        "trajectory",
        "trajectory: JointTrajectory on joint_references; velocity: Float64MultiArray on "
        "joint_velocities (order: the joints parameter)",
        choices=("trajectory", "velocity"),
    ),
    JOINTS,
    WORLD_FRAME,
)
SPECS = specs_by_name(PARAMETERS)


class ControllerNode(Node):
    """ROS 2 wrapper of :class:`ReactionlessController` (see the module docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(NODE_NAME, **node_kwargs)
        self._params = declare_parameters(self, PARAMETERS)
        params = self._params
        self.robot = load_model(params["model_config"] or default_model_config())
        self._period = 1.0 / params["rate"]
        self.controller = ReactionlessController(self.robot, self._settings(params))
        self._frames = twist_frame_ids(
            self.robot, params["world_frame"], params["default_twist_frame"]
        )
        self._gate = self._command_gate(params)
        self._theta: np.ndarray | None = None
        self._base_position = np.zeros(3)
        self._base_orientation = np.array([0.0, 0.0, 0.0, 1.0])
        self._stopped = True
        self._predict = params["predict_state"]
        self._sim_time = bool(self.get_parameter("use_sim_time").value)
        # [s] from a tick to its output's stamp (sim time only: lockstep side by side)
        self._lead = params["output_lead"] if self._sim_time else 0.0
        if params["output_lead"] and not self._sim_time:
            self.get_logger().warn("output_lead is for use_sim_time (lockstep) only: not used")
        # what this node published recently (node clock), for the prediction
        self._outputs: deque[PublishedOutput] = deque()
        # latency is a wall-clock matter; in simulated time, commands served between ticks
        # would land while a lockstep simulator runs on (base 4e-4 instead of 2e-6 deg)
        self._immediate = params["immediate_reaction"] and not self._sim_time
        # await_commands: twists wait for their stamps, ticks for the twist in force
        self._schedule: CommandSchedule[TwistFields] | None = None
        self._deferred: deque[Time] = deque()  # ticks waiting for it, oldest first
        self._await_timer = None
        if params["await_commands"]:
            if self._lead and params["twist_stamped"]:
                self._schedule = CommandSchedule()
                self._await_timer = self.create_timer(
                    params["command_timeout"],
                    self._on_await_timeout,
                    clock=Clock(clock_type=ClockType.STEADY_TIME),
                )
                self._await_timer.cancel()
            else:
                self.get_logger().warn(
                    "await_commands needs use_sim_time, output_lead > 0 and twist_stamped: not used"
                )
        self._last_tick = -np.inf  # monotonic time of the last tick [s]
        # output_lead (_lead_instant): a late tick is served at the state's instant, and the
        # ticks up to the last instant served (_last_tick_clock) are skipped
        self._clock_tick: float | None = None  # the newest tick's instant as /clock gave it [s]
        self._clock_back_at = -np.inf  # monotonic time [s] /clock last went back (a reset)
        self._last_tick_clock: float | None = None  # node-clock time of the last tick [s]
        self._served: tuple[np.ndarray, TwistFrame] | None = None  # (angular, frame) last tick
        self._theta_rate: np.ndarray | None = None
        self._theta_stamp = None
        # input watchdogs: monotonic receipt times [s], a discontinuity seen in joint_states,
        # and what the graph says about who publishes our inputs (checked every second)
        self._state_received = -np.inf
        self._odom_received: float | None = None
        self._jump: str | None = None
        self._state_publishers: list[str] = []
        self._advisories: list[str] = []
        self._warned_types: set[str] = set()
        self._last_state = ControllerState.WAITING_FOR_STATE
        # the newest status; the message (and its key values) is built only for a subscriber
        # of ~/status and for /diagnostics (a status per tick costs ~0.2 ms)
        self._last_status: tuple | None = None  # (level, message, state, values)

        command_qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        self._command_type = TwistStamped if params["twist_stamped"] else Twist
        if params["twist_stamped"]:
            # awaited twists are each one sample: none may be overwritten before it is read
            twist_qos = command_qos if self._schedule is None else SCHEDULED_COMMAND_QOS
            self.create_subscription(
                TwistStamped, "cmd_twist", self._on_stamped, twist_qos, raw=True
            )
        else:
            self.create_subscription(Twist, "cmd_twist", self._on_twist, command_qos)
        # Only the newest state matters; best effort also matches reliable publishers. Taken
        # serialized: the fields used are read from the bytes (rns_ros.nodes.cdr), which cost
        # less than rclpy building the message (20 us a JointState, 70 us an Odometry)
        self._clock_type = self.get_clock().clock_type
        self._joint_state_reader = JointStateReader()
        self.create_subscription(
            JointState, "joint_states", self._on_joint_state, command_qos, raw=True
        )
        self.create_subscription(Odometry, "base_odom", self._on_odom, command_qos, raw=True)
        self._topics = {
            name: self.resolve_topic_name(name) for name in ("cmd_twist", "joint_states")
        }

        trajectory = params["output_interface"] == "trajectory"
        output_qos = QoSProfile(depth=1)
        self._velocity_order = None  # JointTrajectory output
        self._output_template: SerializedTemplate | None = None
        if trajectory:
            self._output = self.create_publisher(JointTrajectory, "joint_references", output_qos)
            try:
                # pre-serialized: the message's conversion cost more than the publish itself
                self._output_template = joint_trajectory_template(self.robot.joint_names)
            except TemplateError as exc:
                self.get_logger().warn(f"{exc}: publishing JointTrajectory messages")
        else:
            # ros2_control convention: data[p[i]] is model joint i (see velocity_joint_order)
            self._velocity_order = velocity_joint_order(params["joints"], self.robot.joint_names)
            self._output = self.create_publisher(Float64MultiArray, "joint_velocities", output_qos)
        self._status = self.create_publisher(DiagnosticArray, "~/status", QoSProfile(depth=10))
        self._diagnostics = self.create_publisher(
            DiagnosticArray, "/diagnostics", QoSProfile(depth=10)
        )
        self.add_on_set_parameters_callback(self._on_set_parameters)
        if self._lead:
            # ticks from /clock itself: the events executor can run a sim-time timer two or
            # three times for one /clock message and then skip as many periods, and each
            # output here acts the period after its tick, so a lockstep simulator needs every
            # one (a missed tick stalls it; a repeated one sends a period twice)
            self._timer = None
            self._ticks = ClockTicks(self, self._period, self._serve)
        else:
            self._timer = self.create_timer(self._period, self._on_tick)
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

    # --- inputs ---------------------------------------------------------------------------------
    def _on_stamped(self, data: bytes) -> None:
        fields = read_twist_stamped(data)
        if self._schedule is None:
            self._take_twist(fields.angular, fields.linear, fields.frame_id)
            return
        sec, nanosec = fields.stamp
        moving = any(value != 0.0 for value in (*fields.angular, *fields.linear))
        dropped = self._schedule.dropped
        self._schedule.push(sec * 1_000_000_000 + nanosec, fields, moving)
        if self._schedule.dropped > dropped:
            self.get_logger().warn(
                "too many cmd_twist stamped ahead are waiting for their stamps: the oldest was "
                "dropped (stamps far ahead of the clock?)",
                throttle_duration_sec=1.0,
            )
        self._serve_deferred()

    def _release_twists(self, tick: Time) -> None:
        """await_commands: the twists stamped up to ``tick`` reach the gate, in order."""
        for fields in self._schedule.due(tick.nanoseconds):
            self._take_twist(fields.angular, fields.linear, fields.frame_id)

    def _serve_deferred(self) -> None:
        """await_commands: serve the waiting ticks whose twist in force is known now."""
        while self._deferred and self._schedule.ready(self._deferred[0].nanoseconds):
            tick = self._deferred.popleft()
            self._release_twists(tick)
            self._serve_tick(tick)
        if self._deferred:
            self._await_timer.reset()  # the operator is alive: command_timeout from now
        else:
            self._await_timer.cancel()

    def _on_await_timeout(self) -> None:
        """await_commands: no twist came for command_timeout (wall clock) while ticks waited:
        the operator stalled or its stream ended on a motion; serve with the newest (the gate
        then stops a stale command as usual)."""
        self._await_timer.cancel()
        if not self._deferred:
            return
        self.get_logger().warn(
            f"no cmd_twist stamped at or after {self._deferred[0].nanoseconds * 1e-9:.3f} s "
            f"within command_timeout ({self._params['command_timeout']} s wall clock): served "
            "with the newest one",
            throttle_duration_sec=1.0,
        )
        self._schedule.release_all()
        self._serve_deferred()

    def _on_twist(self, msg: Twist) -> None:
        a, v = msg.angular, msg.linear
        self._take_twist([a.x, a.y, a.z], [v.x, v.y, v.z], "")

    def _take_twist(self, angular, linear, frame_id: str) -> None:
        """An operator twist: ``angular`` [rad/s] and ``linear`` [m/s] (3,) in ``frame_id``."""
        try:
            command = validate_twist(
                angular,
                linear,
                frame_id,
                self._frames,
                self._params["max_angular_speed"],
                time.monotonic(),
            )
        except InputError as exc:
            self._gate.reject(str(exc))
            self.get_logger().error(f"rejected cmd_twist: {exc}", throttle_duration_sec=1.0)
            return
        if command.requested_speed is not None:
            self.get_logger().warn(
                f"cmd_twist |angular| {command.requested_speed:.4g} rad/s is over "
                f"max_angular_speed {self._params['max_angular_speed']:.4g} rad/s: scaled to it "
                "(axis kept)",
                throttle_duration_sec=1.0,
            )
        self._gate.accept(command)
        if self._immediate and self._changes_output(command):
            now = time.monotonic()
            if now - self._last_tick >= MIN_TICK_INTERVAL:
                self._timer.reset()  # the next tick is one full period from now
                self._on_tick()

    def _changes_output(self, command: TwistCommand) -> bool:
        """True when ``command`` differs from what the last tick served (and ticks run)."""
        if self._theta is None or self._served is None:
            return False
        angular, frame = self._served
        return frame is not command.frame or not np.array_equal(angular, command.angular)

    def _on_joint_state(self, data: bytes) -> None:
        fields = self._joint_state_reader(data)
        try:
            command = match_named_command(
                fields.names,
                self.robot.joint_names,
                positions=fields.position,
                velocities=fields.velocity,
            )
        except InputError as exc:
            self.get_logger().error(f"ignored joint_states: {exc}", throttle_duration_sec=1.0)
            return
        if command.positions is None:
            return
        sec, nanosec = fields.stamp
        stamp = Time(seconds=sec, nanoseconds=nanosec, clock_type=self._clock_type)
        if self._theta is not None and self._jump is None:
            self._jump = self._discontinuity(command.positions, stamp)
        self._theta = command.positions
        self._theta_rate = command.velocities
        self._theta_stamp = stamp
        self._state_received = time.monotonic()

    def _discontinuity(self, theta: np.ndarray, stamp: Time) -> str | None:
        """Why ``theta`` cannot follow from the previous sample, or None.

        The previous sample moved on by the stamp difference (clipped to [0, MAX_PREDICTION_AGE])
        at its rates predicts this one within far less than ``state_jump_tolerance`` while the arm
        moves smoothly; a reset, a re-homed robot or a second source does not.
        """
        dt = (stamp - self._theta_stamp).nanoseconds * 1e-9
        predicted = self._theta
        if self._theta_rate is not None:
            predicted = predicted + min(max(dt, 0.0), MAX_PREDICTION_AGE) * self._theta_rate
        error = np.abs(theta - predicted)
        joint = int(np.argmax(error))
        if error[joint] <= self._params["state_jump_tolerance"]:
            return None
        return (
            f"joint_states jumped: {self.robot.joint_names[joint]} {theta[joint]:.4g} rad where "
            f"{predicted[joint]:.4g} rad was predicted (state_jump_tolerance "
            f"{self._params['state_jump_tolerance']} rad)"
        )

    def _on_odom(self, data: bytes) -> None:
        fields = read_odometry(data)
        pose = base_pose(fields.pose)
        if pose is not None:
            self._base_position, self._base_orientation = pose
            self._odom_received = time.monotonic()

    # --- control period -------------------------------------------------------------------------
    def _on_tick(self) -> None:
        self._serve(self.get_clock().now())

    def _serve(self, tick: Time) -> None:
        """The control period of the instant ``tick``: the timer's call, or with
        ``output_lead`` each period instant /clock passes (:class:`ClockTicks`)."""
        if self._theta is None:
            self._publish_status(
                ControllerState.WAITING_FOR_STATE,
                f"waiting for {self._topics['joint_states']}",
                {"method": self.controller.settings.method.value},
            )
            return
        if self._lead:
            tick = self._lead_instant(tick)
            if tick is None:
                return
        if self._schedule is not None:
            if self._deferred or not self._schedule.ready(tick.nanoseconds):
                if not self._deferred:
                    self._await_timer.reset()
                self._deferred.append(tick)  # served when its twist in force arrives
                return
            self._release_twists(tick)
        self._serve_tick(tick)

    def _serve_tick(self, tick: Time) -> None:
        """The control period of ``tick`` once its inputs are there: state, law, output."""
        now = time.monotonic()
        # the previous output was held this long on the plant's clock (sim time under /clock)
        clock_now = tick.nanoseconds * 1e-9
        if self._last_tick_clock is not None:
            self.controller.end_hold(clock_now - self._last_tick_clock)
        self._last_tick, self._last_tick_clock = now, clock_now
        fault = self._input_fault(now)
        if fault is not None:
            self._hold_still(*fault, at=tick)
            return
        planned, theta, hold = self._plan(tick)
        state = FreeFloatingState.compute(
            self.robot,
            self.robot.configuration(theta, self._base_position, self._base_orientation),
        )
        if self._jump is not None:
            self.get_logger().warn(
                f"{self._jump}: reference and wrist reference restarted at the measured pose, "
                "command ramps up from rest"
            )
            self._jump = None
            self._gate.stop()
            self._stopped = True
            # a new pose (reset, re-homed arm): the wrist is held where it is now, eq. (4.6)
            self.controller.reset(state)
        gate = self._gate.update(now, self._period)
        if self._stopped or gate.stopped:
            self.controller.resync(state)  # restart the reference where the arm is
        elif np.abs(self.controller.reference_positions - state.theta).max() > RESYNC_TOLERANCE:
            self.get_logger().warn("joint reference far from the measured angles: resynced")
            self.controller.resync(state)
        self._served = (gate.angular, gate.frame)
        omega = angular_velocity_in_world(state, gate.angular, gate.frame)
        step = self.controller.step(state, omega, hold)
        self._stopped = gate.stopped
        velocities = np.zeros(self.robot.n) if gate.stopped else step.joint_velocity
        if not (np.isfinite(velocities).all() and np.isfinite(step.reference_positions).all()):
            self._hold_still(
                ControllerState.INVALID_COMMAND,
                "the law produced a non-finite joint velocity",
                at=tick,
            )
            return
        self._publish_output(step.reference_positions, velocities, planned, self._lead)
        state_now = self._state(step, gate, state)
        self._publish_status(state_now, gate.detail, lambda: self._step_values(step, gate))

    def _lead_instant(self, tick: Time) -> Time | None:
        """With ``output_lead``: the instant to serve for the /clock tick ``tick``, or None to
        skip it.

        In lockstep side by side the simulator runs at most ``output_lead`` past a tick before
        that tick's output arrives. A state stamped later than that (by half a period more)
        means the simulation got ahead of the ticks (a first command reaching it while it ran
        in real time, a patience step): the tick's output would start late, and every later
        one too, each letting the simulation run one more period (the lockstep period counts
        from the newest command), so the lag would last the whole run, with the missed motion
        made up after the controller had predicted it (measured: the base turned 1.7e-3 deg,
        or the camera fell short when the lag passed 50 ms). Such a tick is served at the
        state's instant instead (its output acts a lead later, as usual), and the ticks up to
        that instant, still coming from /clock, are skipped. A clock that went back (a reset)
        starts over, and a state received before it, or more than ``MAX_LEAD_CATCH_UP`` ahead,
        is not caught up to."""
        seconds = tick.nanoseconds * 1e-9
        previous, self._clock_tick = self._clock_tick, seconds
        if previous is not None and seconds < previous - 0.5 * self._period:
            # the clock went back: states received before are from before the reset
            self._clock_back_at = time.monotonic()
        elif self._last_tick_clock is not None and seconds <= self._last_tick_clock + 1e-9:
            return None  # this instant was served already (caught up past it)
        if self._theta_stamp is not None and self._state_received > self._clock_back_at:
            stamp = self._theta_stamp.nanoseconds * 1e-9
            if self._lead + 0.5 * self._period <= stamp - seconds <= MAX_LEAD_CATCH_UP:
                # expected once at the start: the first command reaches a simulation that
                # still runs in real time
                self.get_logger().info(
                    f"late tick {seconds:.3f} s: the simulation is at {stamp:.3f} s; served "
                    "there (the ticks in between are skipped)",
                    throttle_duration_sec=1.0,
                )
                tick = self._theta_stamp
        return tick

    def _input_fault(self, now: float) -> tuple[ControllerState, str] | None:
        """(state, detail) when the measured state cannot be trusted: stale or two sources."""
        problem = measured_state_problem(
            now,
            self._state_publishers,
            self._topics["joint_states"],
            self._state_received,
            self._odom_received,
            self._params["state_timeout"],
        )
        return None if problem is None else (ControllerState(problem[0]), problem[1])

    def _hold_still(self, state: ControllerState, detail: str, at: Time | None = None) -> None:
        """Publish zero velocity where the reference stands, report ``state``; the next good
        tick restarts the reference at the measured angles and ramps the command up. ``at``:
        the tick's instant (its output is stamped ``output_lead`` later, as a tick's is);
        None: now."""
        if self._last_state is not state:
            self.get_logger().error(f"{state.value}: {detail}; joints commanded to rest")
        self._gate.stop()
        self._stopped = True
        self._served = None
        positions = self.controller.reference_positions
        if positions is None or not np.all(np.isfinite(positions)):
            positions = self._theta
        lead = self._lead if at is not None else 0.0
        self._publish_output(positions, np.zeros(self.robot.n), at, lead)
        self._publish_status(state, detail, {"method": self.controller.settings.method.value})

    def _plan(self, now: Time) -> tuple[Time, np.ndarray, float | None]:
        """When this tick's output is planned for (now), where it starts on the plant and how
        long it will be held there: (instant, joint angles [rad] (n,), hold [s] or None for the
        period T).

        The angles are the measured ones moved on to when the output acts
        (:func:`predict_joint_angles`): joint_states lag by up to one publish period, the output
        reaches the plant a moment later and acts at its next update, and the midpoint hold is
        reactionless only for the configuration it starts from. The hold runs until the next
        output acts: the timer's next call (on its grid, so a late tick holds for less than T)
        through the same latency and update grid. ``now``: the tick's instant
        (:meth:`_serve`); a state up to ``output_lead`` newer than it (a late tick in
        lockstep) is taken from its stamp."""
        if not self._predict:
            return now, self._theta, None  # the sample as it is, held for T
        # with output_lead the ticks lie on the period grid (ClockTicks)
        theta, hold = self._theta, self._period if self._lead else self._next_tick_in()
        if self._theta_rate is None or self._stopped:
            return now, theta, hold
        seconds, stamp = now.nanoseconds * 1e-9, self._theta_stamp.nanoseconds * 1e-9
        if not -self._lead <= seconds - stamp < MAX_PREDICTION_AGE:
            return now, theta, hold  # clocks disagree or the state is stale: do not extrapolate
        timing = OutputTiming(
            latency=self._lead if self._sim_time else self._params["output_latency"],
            plant_period=self._params["plant_period"],
        )
        start = predict_joint_angles(theta, self._theta_rate, stamp, seconds, self._outputs, timing)
        if hold is not None:
            ends = timing.acting_time(seconds + hold, stamp)
            hold = ends - start.acting_time if ends > start.acting_time else None
        return now, start.theta, hold

    def _next_tick_in(self) -> float | None:
        """Time until the control timer's next call [s], or None when it is not in (0, 1.5 T]
        (a cancelled or badly late timer: assume the period). Timer ticks only: their instant
        is now."""
        until = self._timer.time_until_next_call()
        if until is None:
            return None
        seconds = until * 1e-9
        return seconds if 0.0 < seconds <= 1.5 * self._period else None

    def _state(
        self, step: ControllerStep, gate: GateOutput, state: FreeFloatingState
    ) -> ControllerState:
        if gate.state not in (ControllerState.OK, ControllerState.RAMPING):
            return gate.state
        if step.output.position_limited:
            if self._last_state is not ControllerState.JOINT_LIMIT:
                self.get_logger().warn(self._limit_text(state))  # once per episode
            return ControllerState.JOINT_LIMIT
        if step.output.sigma_min < self.controller.settings.gains.epsilon:
            return ControllerState.SINGULAR_REGION
        return gate.state

    def _limit_text(self, state: FreeFloatingState) -> str:
        lower, upper = self.robot.lower_limits, self.robot.upper_limits
        margin = np.minimum(state.theta - lower, upper - state.theta)
        joint = int(np.argmin(margin))
        return (
            f"JOINT_LIMIT: {self.robot.joint_names[joint]} at {state.theta[joint]:.4g} rad is "
            f"{margin[joint]:.3g} rad from its limit [{lower[joint]:.4g}, {upper[joint]:.4g}]; "
            "the motion is slowed or stopped (choose another direction)"
        )

    def _publish_output(
        self,
        positions: np.ndarray,
        velocities: np.ndarray,
        at: Time | None = None,
        lead: float = 0.0,
    ) -> None:
        """One joint command planned at ``at`` (default now), stamped ``lead`` [s] later: a tick
        stamps the instant its output was planned to act from, which a plant acting from the
        stamp starts it at. The record for the prediction keeps ``at`` (the timing adds the
        lead)."""
        now = self.get_clock().now() if at is None else at
        stamp_ns = now.nanoseconds + round(lead * 1e9)
        seconds = now.nanoseconds * 1e-9
        self._outputs.append(PublishedOutput(seconds, velocities))
        while self._outputs and self._outputs[0].time < seconds - 2 * MAX_PREDICTION_AGE:
            self._outputs.popleft()
        if self._output_template is not None:
            values = {"positions": positions, "velocities": velocities}
            self._output.publish(self._output_template.serialize(values, split_stamp(stamp_ns)))
            return
        sec, nanosec = split_stamp(stamp_ns)
        self._output.publish(
            joint_command(
                TimeMsg(sec=sec, nanosec=nanosec),
                self.robot.joint_names,
                positions,
                velocities,
                self._velocity_order,
            )
        )

    def _step_values(self, step: ControllerStep, gate: GateOutput) -> dict:
        out = step.output
        unachieved = out.angular_residual if not gate.stopped else np.zeros(3)
        return {
            "method": self.controller.settings.method.value,
            "frame": gate.frame.value,
            "sigma_min": out.sigma_min,
            "det_kinematic": out.determinants.kinematic,
            "det_coupling": out.determinants.coupling,
            "det_algorithmic": out.determinants.algorithmic,
            "damping": out.damping,
            "speed_scale": out.speed_scale,
            "unachieved_angular": unachieved,
            "unachieved_linear": gate.linear,
            "coupling_momentum": out.coupling_momentum if not gate.stopped else np.zeros(3),
        }

    def _publish_status(
        self, state: ControllerState, detail: str, values: dict | Callable[[], dict]
    ) -> None:
        """Keep the newest status (``values``: its key values, or what makes them, called only
        when a message is built) and publish it to a ~/status subscriber."""
        level = STATE_LEVELS.get(state, DiagnosticStatus.WARN)
        message = f"{state.value}: {detail}" if detail else state.value
        if self._advisories:
            level = max(level, DiagnosticStatus.WARN, key=level_rank)
            message = "; ".join([message, *self._advisories])
        self._last_state = state
        self._last_status = (level, message, state, values)
        if self._status.get_subscription_count():
            self._status.publish(self._status_message())

    def _status_message(self) -> DiagnosticArray:
        """The newest status as a DiagnosticArray stamped now."""
        level, message, state, values = self._last_status
        values = {"state": state.value, **(values() if callable(values) else values)}
        status = DiagnosticStatus(
            level=level,
            name=f"{self.get_name()}: reactionless control",
            message=message,
            hardware_id=self.robot.name,
            values=[KeyValue(key=key, value=status_text(value)) for key, value in values.items()],
        )
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self.get_clock().now().to_msg()
        return msg

    # --- once a second: who publishes our inputs, /diagnostics --------------------------------
    def _on_diagnostics(self) -> None:
        self._check_publishers()
        if self._last_status is None:
            return
        self._diagnostics.publish(self._status_message())

    def _check_publishers(self) -> None:
        """Read the graph: more than one joint_states source is a fault (two robots' states
        interleaved make the law reverse at every message); more than one command source, or a
        command publisher of the other message type (its messages never arrive), is reported."""
        expected = type_name(self._command_type)
        commands, others = [], []
        for info in self.get_publishers_info_by_topic(self._topics["cmd_twist"]):
            (commands if info.topic_type == expected else others).append(info)
        advisories = []
        if len(commands) > 1:
            advisories.append(
                f"{len(commands)} publishers on {self._topics['cmd_twist']} "
                f"({', '.join(node_names(commands))}): their commands interleave"
            )
        for info in others:
            if info.topic_type not in self._warned_types:
                self._warned_types.add(info.topic_type)
                other = "false" if self._command_type is TwistStamped else "true"
                self.get_logger().warn(
                    f"{node_names([info])[0]} publishes {info.topic_type} on "
                    f"{self._topics['cmd_twist']}, but this controller takes {expected}: those "
                    f"commands are dropped; restart with -p twist_stamped:={other} (or make the "
                    "teleop publish the other type)"
                )
            advisories.append(
                f"{node_names([info])[0]} publishes {info.topic_type}, ignored: set "
                f"twist_stamped:={'false' if self._command_type is TwistStamped else 'true'}"
            )
        self._advisories = advisories
        self._state_publishers = node_names(
            info
            for info in self.get_publishers_info_by_topic(self._topics["joint_states"])
            if info.topic_type == type_name(JointState)
        )

    # --- parameters, shutdown ---------------------------------------------------------------------
    def _on_set_parameters(self, parameters) -> SetParametersResult:
        updated = dict(self._params)
        for parameter in parameters:
            if parameter.name in SPECS:
                updated[parameter.name] = parameter.value
        try:
            for parameter in parameters:
                if parameter.name in SPECS:
                    SPECS[parameter.name].check(parameter.value)
            settings = self._settings(updated)
            gate = self._command_gate(updated)
        except RnsError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        self._params = updated
        self.controller.configure(settings)
        self._gate.timeout, self._gate.deceleration = gate.timeout, gate.deceleration
        self._gate.acceleration = gate.acceleration
        return SetParametersResult(successful=True)

    def _command_gate(self, params: dict) -> CommandGate:
        return CommandGate(
            params["command_timeout"],
            params["stop_deceleration"],
            resolve_twist_frame(params["default_twist_frame"], self._frames, "default_twist_frame"),
            acceleration=params["start_acceleration"],
        )

    def _settings(self, params: dict) -> ControllerSettings:
        return ControllerSettings(
            method=params["method"],
            gains=ControlGains(
                epsilon=params["epsilon"],
                lambda2_max=params["lambda2_max"],
                sc_gain=params["sc_gain"],
                wrist_gain=params["wrist_gain"],
            ),
            period=1.0 / params["rate"],
            hold_correction=params["hold_correction"],
            hold_iterations=params["hold_iterations"],
        )

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
    return run_node(ControllerNode, sys.modules[__name__], args)


if __name__ == "__main__":
    raise SystemExit(main())
