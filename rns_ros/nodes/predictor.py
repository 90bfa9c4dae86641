"""rns_predictor: the predictive display's arm, on the ground side of a delayed link.

The operator's twists act on board at their stamp + ``execution_delay`` (D, rns_controller's
time tags); the telemetry comes back another downlink delay later. This node runs the on-board
loop ahead on the ground (:class:`rns_ros.ground.predictor.PredictedArm`, the law and gate of
rns_controller with the same parameters), so the arm it publishes is where the spacecraft's arm
will be once the commands given so far have acted: on-board time now + D. Each telemetry
sample, when it arrives, is compared with what was predicted for its stamp (the prediction
error) and, past ``resync_deg`` / ``resync_rad``, the prediction restarts from it.

Run it in the ground's namespace (``-r __ns:=/ground``), beside ``rns_link``:

Subscribes:
    cmd_twist              geometry_msgs/TwistStamped, the operator's (stamped with the issue
                           time; frames as rns_controller takes them)
    rns_controller/camera_goal
                           geometry_msgs/PoseStamped, the operator's camera goal (world frame,
                           stamped with the issue time): predicted from its stamp + D with
                           rns_controller's goal law (goal_gain, goal_max_speed,
                           goal_tolerance), as the spacecraft turns to it on arrival
    joint_states           sensor_msgs/JointState, the telemetry (by joint name)
    base_odom              nav_msgs/Odometry, the telemetry; paired with joint_states by stamp
Publishes:
    predicted/joint_states sensor_msgs/JointState, one per predicted control period, stamped
                           with the on-board time it stands for: up to the newest twist or goal
                           stamp + D (twists come in stamp order; the later ones are not known
                           yet), or now + D once the operator has been silent for
                           ``command_timeout``
    predicted/base_odom    nav_msgs/Odometry, the same instant
    ~/status               diagnostic_msgs/DiagnosticArray every ``status_period``: the last and
                           largest prediction errors (camera, base [deg], joints [rad]), the
                           re-anchorings, the telemetry's age (the round trip as seen here)

Before the first telemetry nothing is predicted (WAITING_FOR_TELEMETRY); twists given meanwhile
are kept and act once it comes.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseStamped, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState

from rns_ros.control.controller import max_hold
from rns_ros.control.teleop import twist_frame_ids, validate_twist
from rns_ros.control.time_tags import TimeTags
from rns_ros.core.commands import match_joint_state
from rns_ros.core.errors import InputError
from rns_ros.ground.predictor import (
    GRID_TOLERANCE_S,
    GateSettings,
    PredictedArm,
    PredictorSettings,
)
from rns_ros.nodes import predictor_parameters
from rns_ros.nodes.controller_parameters import controller_settings
from rns_ros.nodes.controller_requests import camera_goal_rotation, goal_settings
from rns_ros.nodes.parameters import declare_parameters, load_node_model
from rns_ros.nodes.robot_io import StampPairs, base_pose
from rns_ros.nodes.runner import run_node
from rns_ros.nodes.sim_clock import stamp_from_seconds

#: Every sample counts (a twist is one instant of the operator's stream; telemetry pairs by
#: stamp): best effort (matches any sender), deep enough for 10 s of a 100 Hz stream while
#: the prediction catches up.
INPUT_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT)
#: Predicted ticks per timer call at most: a prediction that fell behind catches up over
#: several calls, and the twists and telemetry are taken in between.
MAX_TICKS_PER_CALL = 50


def _seconds(stamp) -> float:
    return stamp.sec + 1e-9 * stamp.nanosec


def _stamp_ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


class PredictorNode(Node):
    """ROS 2 wrapper of :class:`PredictedArm` (module docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(predictor_parameters.NODE_NAME, **node_kwargs)
        params = declare_parameters(self, predictor_parameters.PARAMETERS)
        self.robot = load_node_model(self, params["model_config"])
        self._settings = PredictorSettings(
            controller=controller_settings(params),
            gate=GateSettings(
                params["command_timeout"], params["stop_deceleration"], params["start_acceleration"]
            ),
            goal=goal_settings(params),
            time_tags=TimeTags(params["execution_delay"]),
            resync_deg=params["resync_deg"],
            resync_rad=params["resync_rad"],
            history=params["history"],
            simulation_step=1.0 / params["rate"],
        )
        self._frames = twist_frame_ids(
            self.robot, params["world_frame"], params["default_twist_frame"]
        )
        self._max_speed = params["max_angular_speed"]
        self._world_frame = params["world_frame"]
        self.arm: PredictedArm | None = None
        # the operator's twists and goals before the first telemetry, each to give the arm
        self._early: list[Callable[[PredictedArm], None]] = []
        self._telemetry_pairs = StampPairs()  # joint_states and base_odom by stamp
        self.newest_telemetry = -math.inf  # [s]
        self.newest_command = -math.inf  # [s], the newest twist or goal stamp
        self.twists = 0  # valid twists taken
        self.goals = 0  # valid camera goals taken
        self._command_received = -math.inf  # [s, monotonic] of the newest
        # [s, monotonic]: this process's last tick, and its first tick after it stalled
        self._last_tick = self._awake_since = -math.inf
        # ticks further apart on the steady clock: this process stalled (as rns_controller's)
        self._stall = max_hold(self._settings.controller.period)
        self.create_subscription(TwistStamped, "cmd_twist", self._on_twist, INPUT_QOS)
        # goals are rare and must not be missed: reliable, as rns_controller takes them
        self.create_subscription(PoseStamped, "rns_controller/camera_goal", self._on_goal, 10)
        self.create_subscription(JointState, "joint_states", self._on_joints, INPUT_QOS)
        self.create_subscription(Odometry, "base_odom", self._on_odom, INPUT_QOS)
        self._joints_pub = self.create_publisher(JointState, "predicted/joint_states", 10)
        self._odom_pub = self.create_publisher(Odometry, "predicted/base_odom", 10)
        self._status_pub = self.create_publisher(DiagnosticArray, "~/status", QoSProfile(depth=10))
        self.create_timer(self._settings.controller.period, self._on_tick)
        self.create_timer(params["status_period"], self._on_status)
        self.get_logger().info(
            f"predicting {self.robot.name} {params['execution_delay']:g} s ahead "
            f"({params['method']} at {params['rate']:g} Hz); waiting for "
            f"{self.resolve_topic_name('joint_states')}"
        )

    def now_s(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    # --- inputs --------------------------------------------------------------------------------
    def _on_twist(self, msg: TwistStamped) -> None:
        stamp = _seconds(msg.header.stamp)
        a, v = msg.twist.angular, msg.twist.linear
        try:
            command = validate_twist(
                [a.x, a.y, a.z],
                [v.x, v.y, v.z],
                msg.header.frame_id,
                self._frames,
                self._max_speed,
                stamp,
            )
        except InputError as exc:
            self.get_logger().error(f"cmd_twist ignored: {exc}", throttle_duration_sec=1.0)
            return
        self.twists += 1
        self._give(stamp, lambda arm: arm.command(stamp, command.angular, command.frame))

    def _on_goal(self, msg: PoseStamped) -> None:
        """The operator's camera goal (world frame, stamped with its issue time; unstamped:
        now), predicted from its stamp + D as rns_controller turns to it once it arrives."""
        try:
            rotation = camera_goal_rotation(msg, self._world_frame)
        except InputError as exc:
            self.get_logger().error(f"camera goal ignored: {exc}", throttle_duration_sec=1.0)
            return
        stamp = _seconds(msg.header.stamp) or self.now_s()
        self.goals += 1
        self._give(stamp, lambda arm: arm.goal(stamp, rotation))

    def _give(self, stamp: float, give: Callable[[PredictedArm], None]) -> None:
        """An operator input stamped ``stamp`` [s]: to the arm, or kept until the first
        telemetry (the newest 1000)."""
        self.newest_command = max(self.newest_command, stamp)
        self._command_received = time.monotonic()
        if self.arm is None:
            self._early.append(give)
            del self._early[:-1000]
        else:
            give(self.arm)

    def _on_joints(self, msg: JointState) -> None:
        try:
            named, _ = match_joint_state(msg.name, self.robot.joint_names, positions=msg.position)
        except InputError as exc:
            self.get_logger().error(f"joint_states ignored: {exc}", throttle_duration_sec=1.0)
            return
        if named.positions is None or not np.all(np.isfinite(named.positions)):
            self.get_logger().error(
                "joint_states ignored: no finite positions", throttle_duration_sec=1.0
            )
            return
        stamp = _stamp_ns(msg.header.stamp)
        self._pair(self._telemetry_pairs.joints(stamp, np.asarray(named.positions, dtype=float)))

    def _on_odom(self, msg: Odometry) -> None:
        p, o = msg.pose.pose.position, msg.pose.pose.orientation
        pose = base_pose(np.array([p.x, p.y, p.z, o.x, o.y, o.z, o.w]))
        if pose is None:
            self.get_logger().error(
                "base_odom ignored: not a finite pose", throttle_duration_sec=1.0
            )
            return
        self._pair(self._telemetry_pairs.pose(_stamp_ns(msg.header.stamp), pose))

    def _pair(self, pair) -> None:
        """A telemetry sample once its joint_states and base_odom are both in."""
        if pair is not None:
            stamp, theta, (position, orientation) = pair
            self._telemetry(stamp * 1e-9, self.robot.configuration(theta, position, orientation))

    def _telemetry(self, stamp: float, q: np.ndarray) -> None:
        self.newest_telemetry = max(self.newest_telemetry, stamp)
        if self.arm is None:
            self.arm = PredictedArm(self.robot, self._settings, q, stamp)
            for give in self._early:
                give(self.arm)
            self._early.clear()
            self.get_logger().info(f"first telemetry at {stamp:.3f} s: predicting")
            return
        error = self.arm.telemetry(stamp, q)
        if error is not None and error.resynced:
            self.get_logger().info(
                f"re-anchored at {stamp:.3f} s: predicted camera {error.camera_deg:.4f} deg, "
                f"base {error.base_deg:.4f} deg, joints {error.joints_rad:.2e} rad off",
                throttle_duration_sec=1.0,
            )

    # --- outputs -------------------------------------------------------------------------------
    def _horizon(self) -> float:
        """How far the prediction may go now [s, on-board time]: the newest command's stamp + D,
        since twists come in stamp order and the ones after it are not known yet (a prediction
        past it would be redone when they come); once the operator has been silent for
        ``command_timeout``, now + D (the gate then stops the arm as the spacecraft's does).
        Silent on the node clock and on the wall clock alike, the wall clock counting from this
        process's first tick after a stall of its own: on a busy machine /clock may be taken
        while twists still wait in the queue."""
        delay = self._settings.time_tags.execution_delay
        now, timeout = self.now_s(), self._settings.gate.command_timeout
        silent = now - self.newest_command > timeout
        # wall silence counts while this process ran: after a stall of its own, the twists of
        # meanwhile still wait in the queue (the executor runs this timer before them)
        heard = max(self._command_received, self._awake_since)
        if silent and time.monotonic() - heard > timeout:
            return now + delay
        return min(now, self.newest_command) + delay

    def _on_tick(self) -> None:
        """Predict up to the horizon, publishing every predicted tick (at most
        :data:`MAX_TICKS_PER_CALL` per call: the subscriptions are served in between)."""
        steady = time.monotonic()
        if steady - self._last_tick > self._stall:
            self._awake_since = steady
        self._last_tick = steady
        arm = self.arm
        if arm is None:
            return
        horizon = self._horizon()
        for _ in range(MAX_TICKS_PER_CALL):
            if arm.time + arm.period > horizon + GRID_TOLERANCE_S:
                break
            arm.advance(arm.time + arm.period)
            self._publish(arm.q, arm.time)

    def _publish(self, q: np.ndarray, t: float) -> None:
        """The predicted configuration ``q`` (7 + n,) of on-board time ``t`` [s]."""
        stamp = stamp_from_seconds(t)
        joints = JointState(name=list(self.robot.joint_names), position=q[7:].tolist())
        joints.header.stamp = stamp
        self._joints_pub.publish(joints)
        odom = Odometry()
        odom.header.stamp, odom.header.frame_id = stamp, self._world_frame
        odom.child_frame_id = self.robot.base_link
        p, o = odom.pose.pose.position, odom.pose.pose.orientation
        p.x, p.y, p.z = (float(x) for x in q[:3])
        o.x, o.y, o.z, o.w = (float(x) for x in q[3:7])
        self._odom_pub.publish(odom)

    def _on_status(self) -> None:
        arm = self.arm
        values = {
            "predicted_time": "-" if arm is None else f"{arm.time:.3f}",
            "twists": str(self.twists),
            "goals": str(self.goals),
        }
        if arm is not None and arm.errors:
            last, worst = arm.errors[-1], arm.worst
            values.update(
                {
                    "prediction_error_camera_deg": f"{last.camera_deg:.6g}",
                    "prediction_error_base_deg": f"{last.base_deg:.6g}",
                    "prediction_error_joints_rad": f"{last.joints_rad:.6g}",
                    "max_prediction_error_camera_deg": f"{worst.camera_deg:.6g}",
                    "max_prediction_error_base_deg": f"{worst.base_deg:.6g}",
                    "max_prediction_error_joints_rad": f"{worst.joints_rad:.6g}",
                    "compared": str(arm.compared),
                    "resynced": str(arm.resyncs),
                }
            )
        if math.isfinite(self.newest_telemetry):
            values["telemetry_age_s"] = f"{self.now_s() - self.newest_telemetry:.3f}"
        status = DiagnosticStatus(
            name=self.get_fully_qualified_name(),
            level=DiagnosticStatus.WARN if self.arm is None else DiagnosticStatus.OK,
            message="WAITING_FOR_TELEMETRY" if self.arm is None else "PREDICTING",
            values=[KeyValue(key=key, value=value) for key, value in values.items()],
        )
        message = DiagnosticArray(status=[status])
        message.header.stamp = self.get_clock().now().to_msg()
        self._status_pub.publish(message)


def main(args=None) -> int:
    return run_node(PredictorNode, predictor_parameters, args)


if __name__ == "__main__":
    raise SystemExit(main())
