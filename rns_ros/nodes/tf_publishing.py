"""/tf and /tf_static of the simulated robot, as robot_state_publisher publishes them: world ->
base from the simulated base pose and one transform per moving joint on /tf; the fixed and held
joints once on /tf_static (transient local, so late subscribers get them).

tf2_msgs has no PyPI wheel: ``make venv`` generates it (scripts/build_msgs.sh); a full Jazzy
install has its own. Without it the simulator runs on, says so once, and publishes no TF.
"""

from __future__ import annotations

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from geometry_msgs.msg import TransformStamped
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from rns_ros.core import FreeFloatingModel
from rns_ros.core.link_tree import LinkEdge, edge_transforms, link_edges

#: /tf_static as tf2_ros' StaticTransformBroadcaster offers it.
STATIC_QOS = QoSProfile(
    depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
)


def _transform(parent: str, child: str, row: np.ndarray, stamp: TimeMsg) -> TransformStamped:
    """TransformStamped parent -> child from a row [x, y, z, qx, qy, qz, qw]."""
    msg = TransformStamped()
    msg.header.stamp = stamp
    msg.header.frame_id = parent
    msg.child_frame_id = child
    t, r = msg.transform.translation, msg.transform.rotation
    t.x, t.y, t.z = (float(v) for v in row[:3])
    r.x, r.y, r.z, r.w = (float(v) for v in row[3:7])
    return msg


class TfPublisher:
    """Publishes ``robot``'s link tree; :meth:`create` returns None without tf2_msgs."""

    def __init__(self, node: Node, robot: FreeFloatingModel, world_frame: str, message_type):
        self._robot, self._world_frame, self._type = robot, world_frame, message_type
        self._data = robot.model.createData()  # reused by every /tf message
        edges = link_edges(robot)
        self._moving: tuple[LinkEdge, ...] = tuple(e for e in edges if not e.static)
        static = tuple(e for e in edges if e.static)
        self._tf_pub = node.create_publisher(message_type, "/tf", 100)
        self._static_pub = node.create_publisher(message_type, "/tf_static", STATIC_QOS)
        stamp = node.get_clock().now().to_msg()
        rows = edge_transforms(robot, static, robot.configuration(robot.initial_theta))
        self._static_pub.publish(
            message_type(
                transforms=[
                    _transform(e.parent, e.child, row, stamp)
                    for e, row in zip(static, rows, strict=True)
                ]
            )
        )

    @classmethod
    def create(cls, node: Node, robot: FreeFloatingModel, world_frame: str) -> TfPublisher | None:
        try:
            from tf2_msgs.msg import TFMessage
        except ImportError:
            node.get_logger().warn(
                "tf2_msgs is not installed: /tf and /tf_static are not published "
                "(`make venv` generates it: scripts/build_msgs.sh)"
            )
            return None
        return cls(node, robot, world_frame, TFMessage)

    def publish(self, q: np.ndarray, stamp: TimeMsg) -> None:
        """world -> base and the moving joints at configuration q (7 + n,), stamped ``stamp``."""
        base = np.concatenate([q[:3], q[3:7]])
        transforms = [_transform(self._world_frame, self._robot.base_link, base, stamp)]
        rows = edge_transforms(self._robot, self._moving, q, self._data)
        transforms += [
            _transform(e.parent, e.child, row, stamp)
            for e, row in zip(self._moving, rows, strict=True)
        ]
        self._tf_pub.publish(self._type(transforms=transforms))
