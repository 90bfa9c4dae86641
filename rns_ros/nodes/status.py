"""Helpers shared by the nodes' status reporting: diagnostic levels, key/value text, and the
names the ROS graph gives to message types and nodes."""

from __future__ import annotations

import numpy as np


def type_name(msg_type) -> str:
    """'geometry_msgs/msg/TwistStamped' for the class TwistStamped (the graph's spelling)."""
    module = msg_type.__module__.split(".")
    return f"{module[0]}/msg/{msg_type.__name__}"


def node_names(infos) -> list[str]:
    """Fully qualified node names of graph endpoint infos (``get_publishers_info_by_topic``)."""
    return [
        f"{info.node_namespace.rstrip('/')}/{info.node_name}" if info.node_name else "?"
        for info in infos
    ]


def other_publishers(node, topic: str) -> list[str]:
    """Nodes other than ``node`` that publish on ``topic`` (resolved name), from the graph."""
    me = f"{node.get_namespace().rstrip('/')}/{node.get_name()}"
    return [name for name in node_names(node.get_publishers_info_by_topic(topic)) if name != me]


def level_rank(level) -> int:
    """DiagnosticStatus.level (bytes in rclpy) as an int, for max()."""
    return level[0] if isinstance(level, bytes) else int(level)


def status_text(value) -> str:
    """A DiagnosticStatus value: arrays space-separated, floats with 6 significant digits."""
    if isinstance(value, np.ndarray):
        return " ".join(f"{x:.6g}" for x in value)
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)
