"""Helpers shared by the nodes' status reporting: diagnostic levels, key/value text, the names
the ROS graph gives to message types and nodes, and who commands the joints."""

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


class CommanderWatch:
    """Who commands the joints on one topic, read from the ROS graph; one warning for each new
    set of two or more commanders.

    Args:
        node: the watching node.
        topic: resolved name of the command topic.
        consequence: what two commanders do, the end of the warning.
        publishes: the node itself publishes on ``topic`` (a commander); else it subscribes.
    """

    def __init__(self, node, topic: str, consequence: str, *, publishes: bool) -> None:
        self._node, self._topic, self._consequence = node, topic, consequence
        self._publishes = publishes
        #: every node commanding on the topic at the last check, this one included
        self.commanders: list[str] = []

    @property
    def others(self) -> list[str]:
        """The commanders other than the watching node (at the last check)."""
        me = _full_name(self._node)
        return [name for name in self.commanders if name != me]

    def check(self) -> list[str]:
        """Read the graph; warn when two or more nodes command and the set is new. Returns
        :attr:`others`."""
        names = node_names(self._node.get_publishers_info_by_topic(self._topic))
        if self._publishes and _full_name(self._node) not in names:
            names.insert(0, _full_name(self._node))  # its publisher may not be in the graph yet
        if len(names) > 1 and set(names) != set(self.commanders):
            self._node.get_logger().warn(
                f"{len(names)} nodes command the joints on {self._topic} ({', '.join(names)}): "
                f"{self._consequence}"
            )
        self.commanders = names
        return self.others


def _full_name(node) -> str:
    return f"{node.get_namespace().rstrip('/')}/{node.get_name()}"


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
