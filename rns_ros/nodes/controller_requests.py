"""rns_controller's operator requests besides the twist: ``~/pause`` and the camera orientation
goal (message side; the goal law is :mod:`rns_ros.control.camera_goal`).

Service:
    ~/pause               std_srvs/SetBool: true holds the arm (zero velocity, status PAUSED,
                          twists and goal wait), false resumes (the command ramps up from rest)
Subscribes:
    ~/camera_goal         geometry_msgs/PoseStamped, reliable depth 1: the camera attitude to turn
                          to (orientation only; ``header.frame_id`` the world frame or empty).
                          A non-finite or non-unit quaternion or another frame is rejected
                          (status INVALID_COMMAND naming it, the motion ramps down). A moving
                          cmd_twist cancels the goal (the operator takes over); zeros do not.
Publishes:
    ~/camera_goal_reached geometry_msgs/PoseStamped, reliable, transient local depth 1: the goal
                          as received, once the camera is within ``goal_tolerance`` of it
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from geometry_msgs.msg import PoseStamped
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_srvs.srv import SetBool

from rns_ros.control.camera_goal import CameraGoal, GoalSettings, goal_rotation
from rns_ros.control.controller import TwistFrame
from rns_ros.control.teleop import ControllerState, TwistCommand
from rns_ros.core.errors import InputError

#: A goal is one command, not a stream: none may be lost.
GOAL_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
#: The reached goal stays readable for a subscriber that comes late.
REACHED_QOS = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
#: States a goal (or a reached one) is reported in instead.
_GOAL_STATES = (ControllerState.OK, ControllerState.RAMPING, ControllerState.IDLE)


def goal_settings(params: dict) -> GoalSettings:
    """The goal law's settings from the controller's parameter values (the goal speed within
    max_angular_speed)."""
    speed = min(params["goal_max_speed"], params["max_angular_speed"])
    return GoalSettings(params["goal_gain"], speed, params["goal_tolerance"])


def camera_goal_rotation(msg: PoseStamped, world_frame: str) -> np.ndarray:
    """R_goal (world <- camera, (3, 3)) of a camera goal message: its orientation, in
    ``world_frame`` (or an empty frame_id).

    Raises:
        InputError: another frame, or not a usable quaternion (:func:`goal_rotation`).
    """
    if msg.header.frame_id not in ("", world_frame):
        raise InputError(
            f"frame_id {msg.header.frame_id!r} is not the world frame {world_frame!r} (or empty)"
        )
    o = msg.pose.orientation
    return goal_rotation([o.x, o.y, o.z, o.w])


class OperatorRequests:
    """``~/pause`` and ``~/camera_goal`` of ``node`` (module docstring).

    Args:
        node: the controller node.
        world_frame: the accepted goal frame id (besides "").
        settings: the goal law's settings.
        reject: called with the reason when a goal message is rejected (the controller's gate
            ramps the motion down and reports INVALID_COMMAND).
    """

    def __init__(
        self,
        node: Node,
        world_frame: str,
        settings: GoalSettings,
        reject: Callable[[str], None],
    ) -> None:
        self._node, self._world_frame, self._reject = node, world_frame, reject
        self.paused = False
        self.goal = CameraGoal(settings)
        self._goal_msg: PoseStamped | None = None
        self._reached_goal = False  # the newest goal was reached (until the next command)
        node.create_service(SetBool, "~/pause", self._on_pause)
        node.create_subscription(PoseStamped, "~/camera_goal", self._on_goal, GOAL_QOS)
        self._reached = node.create_publisher(PoseStamped, "~/camera_goal_reached", REACHED_QOS)

    def _on_pause(self, request: SetBool.Request, response: SetBool.Response) -> SetBool.Response:
        was, self.paused = self.paused, bool(request.data)
        if self.paused:
            response.message = "already paused" if was else "paused: zero velocity"
        else:
            response.message = "resumed" if was else "not paused"
        if was != self.paused:
            self._node.get_logger().info(f"~/pause: {response.message}")
        response.success = True
        return response

    def _on_goal(self, msg: PoseStamped) -> None:
        o = msg.pose.orientation
        try:
            rotation = camera_goal_rotation(msg, self._world_frame)
        except InputError as exc:
            self.goal.cancel()
            self._goal_msg, self._reached_goal = None, False
            self._node.get_logger().error(f"rejected camera goal: {exc}")
            self._reject(f"camera goal: {exc}")
            return
        self.goal.set(rotation)
        self._goal_msg, self._reached_goal = msg, False
        self._node.get_logger().info(
            f"camera goal (x, y, z, w) = ({o.x:.4g}, {o.y:.4g}, {o.z:.4g}, {o.w:.4g}) accepted"
        )

    def twist_taken(self, command: TwistCommand) -> None:
        """A valid operator twist: a moving one takes over from the goal."""
        if not (np.any(command.angular) or np.any(command.linear)):
            return
        self._reached_goal = False
        if self.goal.active:
            self.goal.cancel()
            self._goal_msg = None
            self._node.get_logger().info("camera goal cancelled: an operator twist took over")

    def goal_command(self, camera_rotation: np.ndarray, now: float) -> TwistCommand | None:
        """The goal's command for this period (world axes, received ``now`` [s] on the input
        clock) or None without a goal; the reached goal is published here once."""
        if not self.goal.active:
            return None
        step = self.goal.step(camera_rotation)
        if step.reached:
            self._reached_goal = True
            self._reached.publish(self._goal_msg)
            self._node.get_logger().info(
                f"camera goal reached: {step.error:.3g} rad from it (goal_tolerance "
                f"{self.goal.settings.tolerance} rad)"
            )
            self._goal_msg = None
        return TwistCommand(step.omega, np.zeros(3), TwistFrame.WORLD, now)

    def state(self, state: ControllerState, detail: str) -> tuple[ControllerState, str]:
        """The reported (state, detail) of a served tick: GOAL_ACTIVE / GOAL_REACHED instead of
        OK, RAMPING or IDLE while a goal is turned to or after it was reached."""
        if state not in _GOAL_STATES:
            return state, detail
        if self.goal.active:
            error = self.goal.error
            left = "turning" if error is None else f"{error:.4g} rad from the goal"
            return ControllerState.GOAL_ACTIVE, left
        if self._reached_goal:
            return ControllerState.GOAL_REACHED, f"within {self.goal.settings.tolerance} rad"
        return state, detail

    def values(self) -> dict:
        """Status key values of the goal: its angle left [rad] while one is active."""
        return {"goal_error": self.goal.error} if self.goal.active else {}
