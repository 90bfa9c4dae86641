"""rns_controller: operator twist in, reactionless joint references out (thesis section 4.2-4.3).

The law is :class:`rns_ros.core.controller.ReactionlessController`; command safety is
:class:`rns_ros.core.teleop.CommandGate`. This node only converts messages and runs them once per
control period from an executor timer.

Subscribes:
    cmd_twist     geometry_msgs/TwistStamped (``twist_stamped: true``) or geometry_msgs/Twist;
                  best effort, depth 1. ``header.frame_id`` is ``world_frame``, the base link or
                  the camera frame (empty or unstamped: ``default_twist_frame``). Only the
                  angular part is achievable; the linear part is reported as unachieved.
    joint_states  sensor_msgs/JointState (matched by joint name)
    base_odom     nav_msgs/Odometry (base pose in world; identity until the first message)
Publishes (nothing until the first joint state):
    joint_references  trajectory_msgs/JointTrajectory, one point: positions = integrated
                      reference at the start of the period, velocities = held theta_dot
                      (``output_interface: trajectory``), or
    joint_velocities  std_msgs/Float64MultiArray, theta_dot [rad/s] in the order of the ``joints``
                      parameter (``output_interface: velocity``; the ros2_control
                      forward_command_controller convention: remap to <controller>/commands)
    ~/status          diagnostic_msgs/DiagnosticArray every period: state, sigma_min, the three
                      determinants, lambda^2, speed scale, unachieved twist, predicted coupling
                      momentum
"""

from __future__ import annotations

import time

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import SetParametersResult
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time import Time
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from rns_ros.core import FreeFloatingState, load_model
from rns_ros.core.commands import match_named_command
from rns_ros.core.control import ControlGains
from rns_ros.core.controller import (
    ControllerSettings,
    ControllerStep,
    ReactionlessController,
    TwistFrame,
    angular_velocity_in_world,
)
from rns_ros.core.errors import InputError, RnsError
from rns_ros.core.teleop import (
    CommandGate,
    ControllerState,
    GateOutput,
    TwistCommand,
    twist_frame_ids,
    validate_twist,
)
from rns_ros.nodes.parameters import (
    JOINTS,
    MODEL_CONFIG,
    WORLD_FRAME,
    ParameterSpec,
    declare_parameters,
    specs_by_name,
    velocity_joint_order,
)
from rns_ros.nodes.runner import run_node
from rns_ros.resources import default_model_config

NODE_NAME = "rns_controller"
SUMMARY = "Reactionless camera-pointing controller: twist in, joint references out (DLS / SC)."
#: Measured and integrated angles further apart than this [rad] restart the reference.
RESYNC_TOLERANCE = 0.2
#: joint_states older than this [s] are used as they are, not extrapolated.
MAX_PREDICTION_AGE = 0.1
#: Shortest interval between two ticks when commands are served at once [s]: a command flood
#: cannot make the controller compute faster than this; a change within it waits for the tick.
MIN_TICK_INTERVAL = 1e-3

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
        "Commands with a larger |angular| are rejected",
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
        "immediate_reaction",
        True,
        "Serve a changed command at once and restart the period (the hold in progress is cut "
        "short) instead of at the next tick: latency ~2 ms instead of up to one period. Wall "
        "clock only: under use_sim_time ticks stay on the period grid (reproducible lockstep)",
    ),
    ParameterSpec(
        "predict_state",
        True,
        "Extrapolate the last joint_states by their age at their measured rates before "
        "evaluating the law (the sample lags by up to one publish period)",
    ),
    ParameterSpec("twist_stamped", True, "cmd_twist is TwistStamped (false: plain Twist)"),
    ParameterSpec(
        "default_twist_frame",
        "camera",
        "Axes of unstamped commands and of an empty header.frame_id",
        choices=("world", "base", "camera"),
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
        self._gate = CommandGate(
            params["command_timeout"],
            params["stop_deceleration"],
            TwistFrame.parse(params["default_twist_frame"]),
        )
        self._frames = twist_frame_ids(
            self.robot, params["world_frame"], params["default_twist_frame"]
        )
        self._theta: np.ndarray | None = None
        self._base_position = np.zeros(3)
        self._base_orientation = np.array([0.0, 0.0, 0.0, 1.0])
        self._stopped = True
        self._predict = params["predict_state"]
        # latency is a wall-clock matter; in simulated time, commands served between ticks
        # would land while a lockstep simulator runs on (base 4e-4 instead of 2e-6 deg)
        self._immediate = (
            params["immediate_reaction"] and not self.get_parameter("use_sim_time").value
        )
        self._last_tick = -np.inf  # monotonic time of the last tick [s]
        self._last_tick_clock: float | None = None  # node-clock time of the last tick [s]
        self._served: tuple[np.ndarray, TwistFrame] | None = None  # (angular, frame) last tick
        self._theta_rate: np.ndarray | None = None
        self._theta_stamp = None

        command_qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        if params["twist_stamped"]:
            self.create_subscription(TwistStamped, "cmd_twist", self._on_stamped, command_qos)
        else:
            self.create_subscription(Twist, "cmd_twist", self._on_twist, command_qos)
        # Only the newest state matters; best effort also matches reliable publishers.
        self.create_subscription(JointState, "joint_states", self._on_joint_state, command_qos)
        self.create_subscription(Odometry, "base_odom", self._on_odom, command_qos)

        self._trajectory = params["output_interface"] == "trajectory"
        output_qos = QoSProfile(depth=1)
        if self._trajectory:
            self._output = self.create_publisher(JointTrajectory, "joint_references", output_qos)
        else:
            # ros2_control convention: data[p[i]] is model joint i (see velocity_joint_order)
            self._velocity_order = velocity_joint_order(params["joints"], self.robot.joint_names)
            self._output = self.create_publisher(Float64MultiArray, "joint_velocities", output_qos)
        self._status = self.create_publisher(DiagnosticArray, "~/status", QoSProfile(depth=10))
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self._timer = self.create_timer(self._period, self._on_tick)
        self.get_logger().info(
            f"{params['method']} reactionless control of {self.robot.name} at {params['rate']} Hz "
            f"({params['hold_correction']} hold); waiting for joint_states"
        )

    # --- inputs ---------------------------------------------------------------------------------
    def _on_stamped(self, msg: TwistStamped) -> None:
        self._take_twist(msg.twist, msg.header.frame_id)

    def _on_twist(self, msg: Twist) -> None:
        self._take_twist(msg, "")

    def _take_twist(self, twist: Twist, frame_id: str) -> None:
        angular, linear = twist.angular, twist.linear
        try:
            command = validate_twist(
                [angular.x, angular.y, angular.z],
                [linear.x, linear.y, linear.z],
                frame_id,
                self._frames,
                self._params["max_angular_speed"],
                time.monotonic(),
            )
        except InputError as exc:
            self._gate.reject(str(exc))
            self.get_logger().error(f"rejected cmd_twist: {exc}", throttle_duration_sec=1.0)
            return
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

    def _on_joint_state(self, msg: JointState) -> None:
        try:
            command = match_named_command(
                msg.name, self.robot.joint_names, positions=msg.position, velocities=msg.velocity
            )
        except InputError as exc:
            self.get_logger().error(f"ignored joint_states: {exc}", throttle_duration_sec=1.0)
            return
        if command.positions is not None:
            self._theta = command.positions
            self._theta_rate = command.velocities
            self._theta_stamp = Time.from_msg(
                msg.header.stamp, clock_type=self.get_clock().clock_type
            )

    def _on_odom(self, msg: Odometry) -> None:
        pose = msg.pose.pose
        position = np.array([pose.position.x, pose.position.y, pose.position.z])
        o = pose.orientation
        orientation = np.array([o.x, o.y, o.z, o.w])
        norm = np.linalg.norm(orientation)
        if np.all(np.isfinite(position)) and np.isfinite(norm) and norm > 0.5:
            self._base_position, self._base_orientation = position, orientation / norm

    # --- control period -------------------------------------------------------------------------
    def _on_tick(self) -> None:
        if self._theta is None:
            return  # nothing is published until the first joint state
        now = time.monotonic()
        # the previous output was held this long on the plant's clock (sim time under /clock)
        clock_now = self.get_clock().now().nanoseconds * 1e-9
        if self._last_tick_clock is not None:
            self.controller.end_hold(clock_now - self._last_tick_clock)
        self._last_tick, self._last_tick_clock = now, clock_now
        state = FreeFloatingState.compute(
            self.robot,
            self.robot.configuration(
                self._predicted_theta(), self._base_position, self._base_orientation
            ),
        )
        gate = self._gate.update(time.monotonic(), self._period)
        if self._stopped or gate.stopped:
            self.controller.resync(state)  # restart the reference where the arm is
        elif np.abs(self.controller.reference_positions - state.theta).max() > RESYNC_TOLERANCE:
            self.get_logger().warn("joint reference far from the measured angles: resynced")
            self.controller.resync(state)
        self._served = (gate.angular, gate.frame)
        omega = angular_velocity_in_world(state, gate.angular, gate.frame)
        step = self.controller.step(state, omega)
        self._stopped = gate.stopped
        velocities = np.zeros(self.robot.n) if gate.stopped else step.joint_velocity
        self._publish_output(step.reference_positions, velocities)
        self._publish_status(step, gate, self._state(step, gate))

    def _predicted_theta(self) -> np.ndarray:
        """The measured angles moved on by their age at the measured rates: joint_states lag by
        up to one publish period, and the held command is meant for where the joints are now."""
        if not self._predict or self._theta_rate is None or self._stopped:
            return self._theta
        age = (self.get_clock().now() - self._theta_stamp).nanoseconds * 1e-9
        if not 0.0 < age < MAX_PREDICTION_AGE:
            return self._theta  # clocks disagree or the state is stale: do not extrapolate
        return self._theta + age * self._theta_rate

    def _state(self, step: ControllerStep, gate: GateOutput) -> ControllerState:
        if gate.state is not ControllerState.OK:
            return gate.state
        if step.output.position_limited:
            return ControllerState.JOINT_LIMIT
        if step.output.sigma_min < self.controller.settings.gains.epsilon:
            return ControllerState.SINGULAR_REGION
        return ControllerState.OK

    def _publish_output(self, positions: np.ndarray, velocities: np.ndarray) -> None:
        if self._trajectory:
            msg = JointTrajectory()
            msg.header.stamp = self.get_clock().now().to_msg()
            msg.joint_names = list(self.robot.joint_names)
            msg.points = [
                JointTrajectoryPoint(positions=positions.tolist(), velocities=velocities.tolist())
            ]
        else:
            data = np.empty(self.robot.n)
            data[self._velocity_order] = velocities
            msg = Float64MultiArray(data=data.tolist())
        self._output.publish(msg)

    def _publish_status(
        self, step: ControllerStep, gate: GateOutput, state: ControllerState
    ) -> None:
        out = step.output
        level = {
            ControllerState.OK: DiagnosticStatus.OK,
            ControllerState.INVALID_COMMAND: DiagnosticStatus.ERROR,
        }.get(state, DiagnosticStatus.WARN)
        unachieved = out.angular_residual if not gate.stopped else np.zeros(3)
        values = {
            "state": state.value,
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
        status = DiagnosticStatus(
            level=level,
            name=f"{self.get_name()}: reactionless control",
            message=f"{state.value}: {gate.detail}" if gate.detail else state.value,
            hardware_id=self.robot.name,
            values=[KeyValue(key=key, value=_text(value)) for key, value in values.items()],
        )
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self.get_clock().now().to_msg()
        self._status.publish(msg)

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
            gate = CommandGate(updated["command_timeout"], updated["stop_deceleration"])
        except RnsError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        self._params = updated
        self.controller.configure(settings)
        self._gate.timeout, self._gate.deceleration = gate.timeout, gate.deceleration
        return SetParametersResult(successful=True)

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
            try:
                self._publish_output(self._theta, np.zeros(self.robot.n))
                # reliable QoS: give subscribers a moment to acknowledge before the process ends
                self._output.wait_for_all_acked(Duration(seconds=0.5))
            except Exception as exc:  # the context may already be shut down (Ctrl-C)
                self.get_logger().warn(f"could not publish the final zero velocity: {exc}")
        super().destroy_node()


def _text(value) -> str:
    if isinstance(value, np.ndarray):
        return " ".join(f"{x:.6g}" for x in value)
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def main(args=None) -> int:
    return run_node(
        ControllerNode, executable=NODE_NAME, summary=SUMMARY, specs=PARAMETERS, args=args
    )


if __name__ == "__main__":
    raise SystemExit(main())
