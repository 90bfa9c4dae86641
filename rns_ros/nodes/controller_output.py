"""The joint command output of rns_controller (:class:`rns_ros.nodes.robot_io.JointCommand` on
the ``output_interface`` chosen), bounded just before it is published
(:func:`rns_ros.control.command_bounds.bound_joint_command`), and the record of recent outputs
for the prediction."""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from rclpy.node import Node
from rclpy.qos import QoSProfile

from rns_ros.control.command_bounds import BoundedCommand, CommandBounds, bound_joint_command
from rns_ros.control.prediction import PublishedOutput
from rns_ros.nodes.cdr import (
    SerializedTemplate,
    TemplateError,
    joint_trajectory_template,
    split_stamp,
)
from rns_ros.nodes.robot_io import JointCommand, hold_end_positions


class JointOutput:
    """Publishes the joint commands of ``node`` on the ``interface`` given.

    Args:
        node: the controller node.
        interface: ``trajectory``, ``velocity`` or ``position`` (:class:`JointCommand`).
        joint_names: the model's joints, in model order.
        joints: the ``joints`` parameter (order of the Float64MultiArray interfaces).
        period: the control period T [s].
        keep: outputs newer than this [s] before the newest stay in :attr:`recent`.
        bounds: what every command published stays within (:class:`CommandBounds`).
    """

    def __init__(
        self,
        node: Node,
        interface: str,
        joint_names: Sequence[str],
        joints: Sequence[str],
        period: float,
        keep: float,
        bounds: CommandBounds,
    ) -> None:
        self._keep = keep
        self.bounds = bounds
        self.command = JointCommand(interface, joint_names, joints, period)
        self.publisher = node.create_publisher(
            self.command.message_type, self.command.topic, QoSProfile(depth=1)
        )
        self._template: SerializedTemplate | None = None
        if interface == "trajectory":
            try:
                # pre-serialized: converting the message costs more than publishing it
                self._template = joint_trajectory_template(joint_names, self.command.horizon)
            except TemplateError as exc:
                node.get_logger().warn(f"{exc}: publishing JointTrajectory messages")
        #: what was published recently (node clock), for the prediction
        self.recent: deque[PublishedOutput] = deque()

    def publish(
        self,
        positions: np.ndarray,
        velocities: np.ndarray,
        measured: np.ndarray,
        planned: int,
        lead: float,
    ) -> BoundedCommand:
        """One joint command: ``positions`` [rad], ``velocities`` [rad/s] (n,), model order,
        bounded around the newest ``measured`` angles [rad] (n,) (a command with a NaN/Inf
        becomes a stop), planned at ``planned`` [ns] on the node clock and stamped ``lead`` [s]
        later (a plant acting from the stamp starts it there). :attr:`recent` keeps ``planned``
        and the velocities published. Returns what was published."""
        bounded = bound_joint_command(
            positions, velocities, measured, self.bounds, self.command.bound_horizon
        )
        positions, velocities = bounded.positions, bounded.velocities
        stamp_ns = planned + round(lead * 1e9)
        seconds = planned * 1e-9
        self.recent.append(PublishedOutput(seconds, velocities))
        while self.recent and self.recent[0].time < seconds - self._keep:
            self.recent.popleft()
        sec, nanosec = split_stamp(stamp_ns)
        if self._template is not None:
            values = {
                "positions": positions,
                "velocities": velocities,
                "end_positions": hold_end_positions(positions, velocities, self.command.horizon),
            }
            self.publisher.publish(self._template.serialize(values, (sec, nanosec)))
            return bounded
        stamp = TimeMsg(sec=sec, nanosec=nanosec)
        self.publisher.publish(self.command.message(stamp, positions, velocities))
        return bounded
