"""rclpy's side of bags: QoS profiles both ways, the offers of a topic's publishers, message
classes by type name."""

from __future__ import annotations

import importlib
from typing import Any

from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    LivelinessPolicy,
    QoSProfile,
    ReliabilityPolicy,
)

from rns_ros.bag import qos as bag_qos
from rns_ros.bag.definitions import full_type_name
from rns_ros.bag.metadata import BagError


def _ns(value: Duration) -> int:
    return min(int(value.nanoseconds), bag_qos.INFINITE_NS)


def profile_of(qos: QoSProfile) -> dict[str, Any]:
    """An rclpy profile in rosbag2's form (:mod:`rns_ros.bag.qos`)."""
    return bag_qos.profile(
        history=qos.history.name.lower(),
        depth=qos.depth,
        reliability=qos.reliability.name.lower(),
        durability=qos.durability.name.lower(),
        deadline_ns=_ns(qos.deadline),
        lifespan_ns=_ns(qos.lifespan),
        liveliness=qos.liveliness.name.lower(),
        liveliness_lease_ns=_ns(qos.liveliness_lease_duration),
        avoid_ros_namespace_conventions=qos.avoid_ros_namespace_conventions,
    )


def _policy(enum, name: str):
    return enum.__members__.get(name.upper(), enum.SYSTEM_DEFAULT)


def qos_of(profile: dict[str, Any]) -> QoSProfile:
    """rosbag2's profile as an rclpy QoSProfile; unknown policies as the system default, and
    durations left unspecified where the profile has none or a never-ending one."""
    history = _policy(HistoryPolicy, profile["history"])
    qos = QoSProfile(
        history=history,
        depth=max(int(profile["depth"]), 1),
        reliability=_policy(ReliabilityPolicy, profile["reliability"]),
        durability=_policy(DurabilityPolicy, profile["durability"]),
        liveliness=_policy(LivelinessPolicy, profile["liveliness"]),
        avoid_ros_namespace_conventions=bool(profile["avoid_ros_namespace_conventions"]),
    )
    for key, attribute in (
        ("deadline", "deadline"),
        ("lifespan", "lifespan"),
        ("liveliness_lease_duration", "liveliness_lease_duration"),
    ):
        nanoseconds = bag_qos.nanoseconds(profile[key])
        if 0 < nanoseconds < bag_qos.INFINITE_NS:
            setattr(qos, attribute, Duration(nanoseconds=nanoseconds))
    return qos


def offered_profiles(node: Node, topic: str) -> list[dict[str, Any]]:
    """The QoS each publisher of ``topic`` offers, in rosbag2's form (the graph as ``node``
    sees it now)."""
    return [profile_of(info.qos_profile) for info in node.get_publishers_info_by_topic(topic)]


def message_class(type_name: str) -> type:
    """The generated Python class of ``'pkg/msg/Type'``.

    Raises:
        BagError: the package or the type is not installed.
    """
    package, kind, name = [*full_type_name(type_name).split("/"), "", ""][:3]
    try:
        module = importlib.import_module(f"{package}.{kind}")
        cls = getattr(module, name)
    except (ImportError, AttributeError, ValueError):
        raise BagError(f"message type {type_name} is not installed") from None
    if not hasattr(cls, "_TYPE_SUPPORT"):
        raise BagError(f"{type_name} is not a message type")
    return cls
