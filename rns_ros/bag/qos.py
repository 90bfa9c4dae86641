"""QoS profiles as rosbag2 (metadata version 9, ROS 2 Jazzy) stores them, and the profiles it
derives from them: the subscription a recorder asks for, the offer a player restores.

A profile is a dict with rosbag2's keys: ``history`` (``keep_last``, ``keep_all``,
``system_default``, ``unknown``), ``depth``, ``reliability`` (``reliable``, ``best_effort``, ...),
``durability`` (``volatile``, ``transient_local``, ...), ``deadline``, ``lifespan`` and
``liveliness_lease_duration`` (``{'sec': s, 'nsec': ns}``; never-ending:
``{'sec': 9223372036, 'nsec': 854775807}``), ``liveliness`` (``automatic``, ``manual_by_topic``,
...) and ``avoid_ros_namespace_conventions``. Older bags (version < 9) store the policies as
rmw's enum integers, and the list as one YAML string; :func:`parse_profiles` reads both.
"""

from __future__ import annotations

import io
from collections.abc import Iterable, Mapping
from typing import Any

import yaml

from rns_ros.core import RnsError

#: rmw's enum values -> rosbag2's names (rmw/types.h order).
HISTORY = ("system_default", "keep_last", "keep_all", "unknown")
RELIABILITY = ("system_default", "reliable", "best_effort", "unknown", "best_available")
DURABILITY = ("system_default", "transient_local", "volatile", "unknown", "best_available")
LIVELINESS = ("system_default", "automatic", "", "manual_by_topic", "unknown", "best_available")
POLICIES = {
    "history": HISTORY,
    "reliability": RELIABILITY,
    "durability": DURABILITY,
    "liveliness": LIVELINESS,
}
DURATIONS = ("deadline", "lifespan", "liveliness_lease_duration")
#: rmw's RMW_DURATION_INFINITE [ns]: INT64_MAX.
INFINITE_NS = 2**63 - 1
#: rosbag2's default offer and request when nothing else is known: rclcpp::QoS(10).
DEFAULT_DEPTH = 10


class QosError(RnsError):
    """offered_qos_profiles that are not rosbag2's QoS profiles."""


def duration(nanoseconds: int) -> dict[str, int]:
    """A duration [ns] as rosbag2's ``{'sec', 'nsec'}``."""
    return {"sec": nanoseconds // 1_000_000_000, "nsec": nanoseconds % 1_000_000_000}


def nanoseconds(value: Mapping[str, int]) -> int:
    """rosbag2's ``{'sec', 'nsec'}`` [ns]; the never-ending values of older rmw (Foxy) as
    :data:`INFINITE_NS`."""
    sec, nsec = int(value["sec"]), int(value["nsec"])
    if (sec, nsec) in ((0x7FFFFFFF, 0xFFFFFFFF), (0x7FFFFFFF, 0x7FFFFFFF)):
        return INFINITE_NS
    return min(sec * 1_000_000_000 + nsec, INFINITE_NS)


def profile(
    *,
    history: str = "keep_last",
    depth: int = DEFAULT_DEPTH,
    reliability: str = "reliable",
    durability: str = "volatile",
    deadline_ns: int = 0,
    lifespan_ns: int = 0,
    liveliness: str = "system_default",
    liveliness_lease_ns: int = 0,
    avoid_ros_namespace_conventions: bool = False,
) -> dict[str, Any]:
    """A profile in rosbag2's form (defaults: rclcpp::QoS(10), durations unspecified)."""
    return {
        "history": history,
        "depth": int(depth),
        "reliability": reliability,
        "durability": durability,
        "deadline": duration(deadline_ns),
        "lifespan": duration(lifespan_ns),
        "liveliness": liveliness,
        "liveliness_lease_duration": duration(liveliness_lease_ns),
        "avoid_ros_namespace_conventions": bool(avoid_ros_namespace_conventions),
    }


def _policy(key: str, value: Any) -> str:
    names = POLICIES[key]
    if isinstance(value, bool) or not isinstance(value, int | str):
        raise QosError(f"offered_qos_profiles: {key} {value!r} is not a policy")
    if isinstance(value, int):
        return names[value] if 0 <= value < len(names) and names[value] else "unknown"
    value = value.lower()
    return value if value in names else "unknown"


def parse_profiles(value: str | list | None) -> list[dict[str, Any]]:
    """``offered_qos_profiles`` of a bag (a list, or the YAML string of one; version 9 names or
    older integer policies) as profiles in rosbag2's version-9 form.

    Raises:
        QosError: not a list of profiles.
    """
    if value is None or value == "":
        return []
    if isinstance(value, str):
        try:
            value = yaml.safe_load(value)
        except yaml.YAMLError as exc:
            raise QosError(f"offered_qos_profiles is not YAML: {exc}") from None
        if value is None:
            return []
    if not isinstance(value, list):
        raise QosError(f"offered_qos_profiles must be a list, got {type(value).__name__}")
    profiles = []
    for item in value:
        try:
            profiles.append(
                profile(
                    history=_policy("history", item["history"]),
                    depth=int(item["depth"]),
                    reliability=_policy("reliability", item["reliability"]),
                    durability=_policy("durability", item["durability"]),
                    deadline_ns=nanoseconds(item["deadline"]),
                    lifespan_ns=nanoseconds(item["lifespan"]),
                    liveliness=_policy("liveliness", item["liveliness"]),
                    liveliness_lease_ns=nanoseconds(item["liveliness_lease_duration"]),
                    avoid_ros_namespace_conventions=bool(item["avoid_ros_namespace_conventions"]),
                )
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise QosError(f"offered_qos_profiles: a profile without a valid {exc}") from None
    return profiles


class _Dumper(yaml.SafeDumper):
    """Block YAML with sequences indented under their key, as yaml-cpp writes them."""

    def increase_indent(self, flow: bool = False, indentless: bool = False):
        return super().increase_indent(flow, False)


def dump_yaml(value: Any) -> str:
    """``value`` as block YAML in rosbag2's layout (keys in the given order)."""
    stream = io.StringIO()
    yaml.dump(value, stream, Dumper=_Dumper, sort_keys=False, default_flow_style=False)
    return stream.getvalue()


def profiles_yaml(profiles: Iterable[Mapping[str, Any]]) -> str:
    """The MCAP channel's ``offered_qos_profiles``: the list as a YAML string, as rosbag2's
    MCAP plugin writes it (``[]`` for none)."""
    profiles = [dict(item) for item in profiles]
    return dump_yaml(profiles).rstrip("\n") if profiles else "[]"


def request_profile(offers: list[Mapping[str, Any]], min_depth: int = 0) -> dict[str, Any]:
    """The subscription rosbag2 asks a topic's publishers for (``adapt_request_to_offers``):
    reliable when every publisher is, transient local when every publisher is (so a late
    recorder still gets what they hold); history keep_last of the deepest offer, at least
    ``min_depth``, keep_all when every offer is one deep (rosbag2 fears drops then)."""
    if not offers:
        return profile(depth=max(DEFAULT_DEPTH, min_depth))
    depth = max(int(item["depth"]) for item in offers)
    reliable = all(item["reliability"] == "reliable" for item in offers)
    latched = all(item["durability"] == "transient_local" for item in offers)
    return profile(
        history="keep_last" if depth > 1 or min_depth > 1 else "keep_all",
        depth=max(depth, min_depth),
        reliability="reliable" if reliable else "best_effort",
        durability="transient_local" if latched else "volatile",
    )


def playback_profile(offers: list[Mapping[str, Any]]) -> dict[str, Any]:
    """The offer rosbag2's player restores (``adapt_offer_to_recorded_offers``): the recorded
    publishers' profile when they agree on every policy that decides whether a subscriber
    matches (reliability, durability, deadline, liveliness and its lease), history keep_last
    of :data:`DEFAULT_DEPTH`; the default offer when they differ or none was recorded."""
    if not offers:
        return profile()
    keys = ("reliability", "durability", "deadline", "liveliness", "liveliness_lease_duration")
    first = offers[0]
    if any(any(item[key] != first[key] for key in keys) for item in offers[1:]):
        return profile()
    return {**first, "history": "keep_last", "depth": DEFAULT_DEPTH}
