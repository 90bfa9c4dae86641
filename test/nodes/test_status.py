"""CommanderWatch on a stand-in node: who commands the joints, and when it warns."""

from __future__ import annotations

from types import SimpleNamespace

from rns_ros.nodes.status import CommanderWatch


class _Node:
    """The calls CommanderWatch makes on an rclpy node, with a graph the test sets."""

    def __init__(self, name: str, publishers: list[str]) -> None:
        self.name, self.publishers, self.warnings = name, publishers, []

    def get_name(self):
        return self.name

    def get_namespace(self):
        return "/"

    def get_publishers_info_by_topic(self, topic):
        return [SimpleNamespace(node_name=n, node_namespace="/") for n in self.publishers]

    def get_logger(self):
        return SimpleNamespace(warn=self.warnings.append)


def test_a_publishing_node_warns_once_for_each_new_set_of_commanders():
    node = _Node("rns_controller", ["rns_controller"])
    watch = CommanderWatch(node, "/joint_references", "run one", publishes=True)
    assert watch.check() == []
    assert node.warnings == []
    node.publishers = ["rns_controller", "rns_ptp"]
    assert watch.check() == ["/rns_ptp"]
    assert watch.check() == ["/rns_ptp"]  # the same set: no second warning
    assert len(node.warnings) == 1
    assert "2 nodes command the joints on /joint_references" in node.warnings[0]
    assert "/rns_ptp" in node.warnings[0]
    assert node.warnings[0].endswith("run one")
    node.publishers = ["rns_controller", "rns_ptp", "teleop"]
    assert watch.check() == ["/rns_ptp", "/teleop"]
    assert len(node.warnings) == 2
    node.publishers = ["rns_controller"]
    assert watch.check() == []
    assert len(node.warnings) == 2


def test_a_publisher_not_yet_in_the_graph_still_counts_itself():
    node = _Node("rns_ptp", ["rns_controller"])
    watch = CommanderWatch(node, "/joint_references", "one at a time", publishes=True)
    assert watch.check() == ["/rns_controller"]
    assert watch.commanders == ["/rns_ptp", "/rns_controller"]
    assert len(node.warnings) == 1


def test_a_subscriber_warns_from_two_publishers_on():
    node = _Node("rns_simulator", ["rns_controller"])
    watch = CommanderWatch(node, "/joint_references", "newest wins", publishes=False)
    assert watch.check() == ["/rns_controller"]
    assert node.warnings == []
    node.publishers = ["rns_controller", "rns_ptp"]
    watch.check()
    assert watch.commanders == ["/rns_controller", "/rns_ptp"]
    assert len(node.warnings) == 1
