"""rns_attitude_control: hold the base attitude with the reaction wheels (thesis chapter 5).

The conventional practice the thesis compares reactionless control against: the arm moves by
any law (typically ``rns_controller`` with ``method: conventional``) and the wheels cancel its
reaction. The law is :class:`rns_ros.control.attitude.AttitudeControlLaw` (eq. 5.14 feed-forward
+ PD on the attitude error, clipped to ``torque_limit``); this node only converts messages.

Subscribes:
    joint_states      sensor_msgs/JointState (by joint name, other joints ignored): theta, and
                      theta_dot when no fresh joint reference is there
    base_odom         nav_msgs/Odometry: base attitude and angular velocity (base axes); the
                      first one sets the attitude to hold (``~/hold`` sets it again)
    wheel_states      sensor_msgs/JointState of rns_simulator: wheel rates relative to the base,
                      for the wheels' momentum H = I_r (phi_dot + omega^B)
    joint_references  trajectory_msgs/JointTrajectory of the arm's controller: theta_dot_ref for
                      the feed-forward (older than ``reference_timeout``: measured rates instead)
Publishes:
    wheel_torque      geometry_msgs/Vector3Stamped, motor torques of the x, y, z wheels [N m],
                      frame_id = base link, every period; zero when the state is stale and on
                      shutdown
    ~/status          diagnostic_msgs/DiagnosticArray every period: state (WAITING_FOR_STATE,
                      OK, SATURATED [WARN], STALE_STATE [ERROR]), attitude error [deg], torque,
                      feed-forward, feedback [N m], saturated time [s], coupling momentum
Service:
    ~/hold            std_srvs/Trigger: hold the current attitude from now on

Input ages (state_timeout, reference_timeout) are receipt times on the node clock under
``use_sim_time`` (simulated time: a delayed or paused simulation ages nothing), else monotonic
wall time (:class:`InputClock`). Under ``use_sim_time`` a /clock that stands still for
``clock_timeout`` of wall time with no state meanwhile (a dead simulator) is a stale state.
"""

from __future__ import annotations

import math
import time

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Vector3Stamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from rns_ros.control.attitude import AttitudeControlLaw, AttitudeGains
from rns_ros.core import FreeFloatingState
from rns_ros.core.commands import ExtraJointsReport, match_joint_state, match_named_command
from rns_ros.core.errors import InputError
from rns_ros.core.validation import Choice
from rns_ros.nodes import attitude_control_parameters
from rns_ros.nodes.cdr import odometry_fields
from rns_ros.nodes.input_clock import InputClock
from rns_ros.nodes.parameters import declare_parameters, load_node_model
from rns_ros.nodes.robot_io import base_pose, measured_state_problem
from rns_ros.nodes.runner import publish_last, run_node
from rns_ros.nodes.status import status_text
from rns_ros.sim.reaction_wheels import WHEEL_NAMES


class AttitudeState(Choice):
    WAITING_FOR_STATE = "WAITING_FOR_STATE"
    OK = "OK"
    SATURATED = "SATURATED"
    STALE_STATE = "STALE_STATE"


LEVELS = {
    AttitudeState.WAITING_FOR_STATE: DiagnosticStatus.WARN,
    AttitudeState.SATURATED: DiagnosticStatus.WARN,
    AttitudeState.STALE_STATE: DiagnosticStatus.ERROR,
}


class AttitudeControlNode(Node):
    """ROS 2 wrapper of :class:`AttitudeControlLaw` (see the module docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(attitude_control_parameters.NODE_NAME, **node_kwargs)
        params = declare_parameters(self, attitude_control_parameters.PARAMETERS)
        self.robot = load_node_model(self, params["model_config"])
        self.gains = AttitudeGains(
            natural_frequency=params["natural_frequency"],
            damping_ratio=params["damping_ratio"],
            torque_limit=params["torque_limit"],
            feedforward=params["feedforward"],
        )
        self.law: AttitudeControlLaw | None = None  # made at the first base_odom
        self._wheel_inertia = params["wheel_inertia"]
        self._timeout = params["state_timeout"]
        self._reference_timeout = params["reference_timeout"]
        self._period = 1.0 / params["rate"]
        self._theta: np.ndarray | None = None
        self._theta_dot = np.zeros(self.robot.n)
        self._pose: tuple[np.ndarray, np.ndarray] | None = None
        self._omega = np.zeros(3)
        self._wheel_speeds: np.ndarray | None = None
        self._reference: np.ndarray | None = None
        # receipt times [s] on the input clock (simulated time under use_sim_time); the
        # monotonic receipt time of the newest state of any stream [s] (the /clock watch)
        self._input_clock = InputClock(self, params["clock_timeout"], self._on_clock_stopped)
        self._clock_timeout = params["clock_timeout"]
        self._received = {"joints": -math.inf, "odom": -math.inf, "wheels": -math.inf}
        self._state_received_wall = -math.inf
        self._reference_received = -math.inf
        self._reference_time = 0.0  # [s], stamp of the newest joint_references
        self._feedforward_fresh = False  # the feed-forward's source: joint_references
        self._saturated_time = 0.0
        self._stopped = True  # no torque is being applied

        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        self._extra_joints = ExtraJointsReport()  # joint_states names beyond the model's
        self.create_subscription(JointState, "joint_states", self._on_joint_state, qos)
        self.create_subscription(Odometry, "base_odom", self._on_odom, qos)
        self.create_subscription(JointState, "wheel_states", self._on_wheels, qos)
        self.create_subscription(JointTrajectory, "joint_references", self._on_reference, qos)
        self._torque_pub = self.create_publisher(
            Vector3Stamped, "wheel_torque", QoSProfile(depth=1)
        )
        self._status_pub = self.create_publisher(DiagnosticArray, "~/status", QoSProfile(depth=10))
        self.create_service(Trigger, "~/hold", self._on_hold)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self.create_timer(self._period, self._on_tick)
        self.get_logger().info(
            f"holding the base of {self.robot.name} with reaction wheels at {params['rate']} Hz "
            f"(omega_n {self.gains.natural_frequency} rad/s, limit {self.gains.torque_limit} N m)"
        )

    # --- inputs ---------------------------------------------------------------------------------
    def _matched(self, topic: str, names, model_names, required: str = "", **values):
        """:func:`match_named_command` of a message (with ``required`` values), or None after
        logging why it is ignored."""
        try:
            command = match_named_command(names, model_names, **values)
            if required and getattr(command, required) is None:
                raise InputError(f"{topic} has no {required}")
        except InputError as exc:
            self._ignore(topic, exc)
            return None
        return command

    def _ignore(self, topic: str, exc: InputError) -> None:
        self.get_logger().error(f"ignored {topic}: {exc}", throttle_duration_sec=1.0)

    def _on_joint_state(self, msg: JointState) -> None:
        """theta (and theta_dot) by joint name; joints beyond the model's are ignored
        (reported once per set)."""
        try:
            state, extras = match_joint_state(
                msg.name, self.robot.joint_names, positions=msg.position, velocities=msg.velocity
            )
            if state.positions is None:
                raise InputError("joint_states has no positions")
        except InputError as exc:
            self._ignore("joint_states", exc)
            return
        note = self._extra_joints.note(extras)
        if note is not None:
            self.get_logger().info(note)
        self._theta = state.positions
        if state.velocities is not None:
            self._theta_dot = state.velocities
        self._note_receipt("joints", msg.header.stamp)

    def _on_odom(self, msg: Odometry) -> None:
        pose = base_pose(odometry_fields(msg).pose)
        w = msg.twist.twist.angular
        omega = np.array([w.x, w.y, w.z])
        if pose is None or not np.isfinite(omega).all():
            self.get_logger().error("ignored base_odom: not finite", throttle_duration_sec=1.0)
            return
        self._pose, self._omega = pose, omega
        self._note_receipt("odom", msg.header.stamp)

    def _on_wheels(self, msg: JointState) -> None:
        command = self._matched(
            "wheel_states", msg.name, WHEEL_NAMES, "velocities", velocities=msg.velocity
        )
        if command is None:
            return
        self._wheel_speeds = command.velocities
        self._note_receipt("wheels", msg.header.stamp)

    def _note_receipt(self, stream: str, stamp) -> None:
        """A state of ``stream`` received now (header ``stamp``)."""
        self._received[stream] = self._input_clock.receipt_time(stamp.sec + 1e-9 * stamp.nanosec)
        self._state_received_wall = time.monotonic()

    def _on_reference(self, msg: JointTrajectory) -> None:
        if not msg.points:
            return
        command = self._matched(
            "joint_references",
            msg.joint_names,
            self.robot.joint_names,
            velocities=msg.points[0].velocities,
        )
        if command is not None and command.velocities is not None:
            self._reference = command.velocities
            stamp = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
            self._reference_received = self._input_clock.receipt_time(stamp or None)
            # the sender's stamp times the derivative of eq. (5.14); unstamped: receipt time
            self._reference_time = stamp if stamp > 0.0 else self._now()

    def _on_hold(self, _request, response):
        if self._pose is None:
            response.success, response.message = False, "no base_odom yet"
            return response
        self.law = AttitudeControlLaw(self._rotation(), self.gains)
        response.success, response.message = True, "holding the current base attitude"
        return response

    def _now(self) -> float:
        """Node clock [s] (sim time with use_sim_time)."""
        return self.get_clock().now().nanoseconds * 1e-9

    # --- control --------------------------------------------------------------------------------
    def _rotation(self) -> np.ndarray:
        return FreeFloatingState.compute(
            self.robot, self.robot.configuration(self._theta, *self._pose)
        ).base_rotation

    def _on_tick(self) -> None:
        now = self._input_clock.now()
        if self._theta is None or self._pose is None or self._wheel_speeds is None:
            self._publish_status(AttitudeState.WAITING_FOR_STATE, "waiting for the robot state")
            return
        for stream, topic in (("odom", "base_odom"), ("wheels", "wheel_states")):
            age = now - self._received[stream]
            if age > self._timeout:
                self._stale(f"{topic} {age:.3f} s old (state_timeout {self._timeout} s)")
                return
        problem = measured_state_problem(
            now, [], "joint_states", self._received["joints"], None, self._timeout
        )
        if problem is not None:
            self._stale(problem[1])
            return
        state = FreeFloatingState.compute(
            self.robot, self.robot.configuration(self._theta, *self._pose)
        )
        if self.law is None:
            self.law = AttitudeControlLaw(state.base_rotation, self.gains)
        fresh = now - self._reference_received <= self._reference_timeout
        if fresh != self._feedforward_fresh:
            self.law.restart_rate()  # references and measured rates run on different clocks
            self._feedforward_fresh = fresh
        rates = self._reference if fresh else self._theta_dot
        wheel_momentum = self._wheel_inertia * (self._wheel_speeds + self._omega)
        command = self.law.step(
            self._reference_time if fresh else self._now(),
            state,
            rates,
            self._omega,
            wheel_momentum,
        )
        if not np.isfinite(command.torque).all():
            self._stale("non-finite torque")  # never published
            return
        self._publish_torque(command.torque)
        saturated = bool(command.saturated.any())
        self._saturated_time += self._period if saturated else 0.0
        self._publish_status(
            AttitudeState.SATURATED if saturated else AttitudeState.OK,
            f"wheels {[n for n, s in zip(WHEEL_NAMES, command.saturated, strict=True) if s]} at "
            f"the {self.gains.torque_limit} N m limit: the base turns"
            if saturated
            else "holding",
            {
                "attitude_error_deg": math.degrees(command.attitude_error),
                "torque": command.torque,
                "feedforward": command.feedforward,
                "feedback": command.feedback,
                "coupling_momentum": command.coupling_momentum,
                "feedforward_source": "joint_references" if fresh else "joint_states",
            },
        )

    def _on_clock_stopped(self, still: float) -> None:
        """use_sim_time: /clock has stood still for ``still`` [s] of wall time. When no state
        came for as long either (a dead simulator), the wheels go off as on a stale state, from
        here: the sim-time control timer that would do it has stopped too. Before the first
        complete state nothing is commanded and nothing changes."""
        waiting = self._theta is None or self._pose is None or self._wheel_speeds is None
        quiet = time.monotonic() - self._state_received_wall
        if waiting or quiet < self._input_clock.timeout:
            return
        reason = (
            f"/clock stood still for {still:.3f} s (clock_timeout {self._clock_timeout} s wall "
            "time)"
        )
        self.get_logger().error(
            f"STALE_STATE: {reason}; wheel torque zero", throttle_duration_sec=5.0
        )
        self._stale(reason)

    def _apply_parameters(self, parameters) -> None:
        """After a set: the run-time parameters (clock_timeout) take their new values."""
        for parameter in parameters:
            if parameter.name == "clock_timeout":
                self._clock_timeout = parameter.value
                self._input_clock.set_clock_timeout(parameter.value)

    def _stale(self, reason: str) -> None:
        if not self._stopped:
            self._publish_torque(np.zeros(3))
            self._stopped = True
            if self.law is not None:
                self.law.reset(self.law.reference)  # no feed-forward across the gap
        self._publish_status(AttitudeState.STALE_STATE, f"{reason}; wheel torque zero")

    def _publish_torque(self, torque: np.ndarray) -> None:
        msg = Vector3Stamped()
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.header.frame_id = self.robot.base_link
        msg.vector.x, msg.vector.y, msg.vector.z = (float(x) for x in torque)
        self._torque_pub.publish(msg)
        self._stopped = not np.any(torque)

    def _publish_status(self, state: AttitudeState, detail: str, values: dict | None = None):
        values = {"state": state.value, **(values or {})}
        values["saturated_time_s"] = self._saturated_time
        status = DiagnosticStatus(
            level=LEVELS.get(state, DiagnosticStatus.OK),
            name=f"{self.get_name()}: base attitude with reaction wheels",
            message=f"{state.value}: {detail}",
            hardware_id=self.robot.name,
            values=[KeyValue(key=k, value=status_text(v)) for k, v in values.items()],
        )
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self.get_clock().now().to_msg()
        self._status_pub.publish(msg)

    def destroy_node(self) -> None:
        """Motors off: one zero torque, then tear down."""
        publish_last(
            self,
            lambda: self._publish_torque(np.zeros(3)),
            "zero torque",
            acked_by=self._torque_pub,
        )
        super().destroy_node()


def main(args=None) -> int:
    return run_node(AttitudeControlNode, attitude_control_parameters, args)


if __name__ == "__main__":
    raise SystemExit(main())
