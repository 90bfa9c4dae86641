"""The joint command output of rns_controller: JointTrajectory on joint_references or
Float64MultiArray on joint_velocities, and the record of recent outputs for the prediction."""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from rclpy.node import Node
from rclpy.qos import QoSProfile
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from rns_ros.control.prediction import PublishedOutput
from rns_ros.nodes.cdr import (
    SerializedTemplate,
    TemplateError,
    joint_trajectory_template,
    split_stamp,
)
from rns_ros.nodes.parameters import velocity_joint_order
from rns_ros.nodes.robot_io import joint_command


class JointOutput:
    """Publishes the joint commands of ``node`` on the ``interface`` given.

    Args:
        node: the controller node.
        interface: ``trajectory`` (JointTrajectory on joint_references, one point: positions
            and velocities) or ``velocity`` (Float64MultiArray of velocities on
            joint_velocities, in the order of ``joints``).
        joint_names: the model's joints, in model order.
        joints: the ``joints`` parameter (velocity interface only).
        keep: outputs newer than this [s] before the newest stay in :attr:`recent`.
    """

    def __init__(
        self,
        node: Node,
        interface: str,
        joint_names: Sequence[str],
        joints: Sequence[str],
        keep: float,
    ) -> None:
        self._joint_names, self._keep = list(joint_names), keep
        qos = QoSProfile(depth=1)
        self._velocity_order = None  # JointTrajectory output
        self._template: SerializedTemplate | None = None
        if interface == "trajectory":
            self.publisher = node.create_publisher(JointTrajectory, "joint_references", qos)
            try:
                # pre-serialized: converting the message costs more than publishing it
                self._template = joint_trajectory_template(self._joint_names)
            except TemplateError as exc:
                node.get_logger().warn(f"{exc}: publishing JointTrajectory messages")
        else:
            # ros2_control convention: data[p[i]] is model joint i (see velocity_joint_order)
            self._velocity_order = velocity_joint_order(joints, self._joint_names)
            self.publisher = node.create_publisher(Float64MultiArray, "joint_velocities", qos)
        #: what was published recently (node clock), for the prediction
        self.recent: deque[PublishedOutput] = deque()

    def publish(
        self, positions: np.ndarray, velocities: np.ndarray, planned: int, lead: float
    ) -> None:
        """One joint command: ``positions`` [rad], ``velocities`` [rad/s] (n,), model order,
        planned at ``planned`` [ns] on the node clock and stamped ``lead`` [s] later (a plant
        acting from the stamp starts it there). :attr:`recent` keeps ``planned``."""
        stamp_ns = planned + round(lead * 1e9)
        seconds = planned * 1e-9
        self.recent.append(PublishedOutput(seconds, velocities))
        while self.recent and self.recent[0].time < seconds - self._keep:
            self.recent.popleft()
        if self._template is not None:
            values = {"positions": positions, "velocities": velocities}
            self.publisher.publish(self._template.serialize(values, split_stamp(stamp_ns)))
            return
        sec, nanosec = split_stamp(stamp_ns)
        self.publisher.publish(
            joint_command(
                TimeMsg(sec=sec, nanosec=nanosec),
                self._joint_names,
                positions,
                velocities,
                self._velocity_order,
            )
        )
