"""The QoS options of ``rns_topic`` and ``rns_bag``'s kind of tools, as ros2cli Jazzy has them:
``--qos-profile`` and the ``--qos-*`` overrides, and the QoS that matches a topic's publishers."""

from __future__ import annotations

import argparse
import copy

from rns_ros.tool_session import ToolSession, UsageError

#: rclpy's QoS presets and policies by short key (``QoSPresetProfiles.short_keys()`` and the
#: policies'), the choices of ros2's ``--qos-*`` options; spelled out because the parser is built
#: before rclpy is imported.
QOS_PROFILES = (
    "unknown",
    "default",
    "system_default",
    "sensor_data",
    "services_default",
    "parameters",
    "parameter_events",
    "action_status_default",
    "best_available",
)
QOS_HISTORY = ("system_default", "keep_last", "keep_all", "unknown")
QOS_RELIABILITY = ("system_default", "reliable", "best_effort", "unknown", "best_available")
QOS_DURABILITY = ("system_default", "transient_local", "volatile", "unknown", "best_available")
QOS_LIVELINESS = ("system_default", "automatic", "manual_by_topic", "unknown", "best_available")
#: The QoS preset of ``echo`` and of ``pub`` without ``--qos-profile`` (ros2's).
ECHO_QOS_PROFILE, PUB_QOS_PROFILE = "sensor_data", "default"


def subscription_qos(session: ToolSession, topic: str):
    """QoS that matches every publisher of ``topic`` and gets what they offer (``hz``).

    Reliable only if every publisher is (a reliable reader matches no best-effort writer);
    transient local only if every publisher is, so latched messages (robot_description) arrive.
    """
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    publishers = session.node.get_publishers_info_by_topic(topic)
    qos = QoSProfile(
        depth=10,
        reliability=ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.VOLATILE,
    )
    if publishers and all(
        p.qos_profile.reliability == ReliabilityPolicy.RELIABLE for p in publishers
    ):
        qos.reliability = ReliabilityPolicy.RELIABLE
    if publishers and all(
        p.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for p in publishers
    ):
        qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
    return qos


def add_qos_arguments(parser: argparse.ArgumentParser, verb: str, profile: str) -> None:
    """ros2's ``--qos-*`` options (``verb``: subscribe or publish; ``profile``: the preset)."""
    adapted = "; default: what every publisher offers" if verb == "subscribe" else ""
    parser.add_argument(
        "--qos-profile",
        choices=QOS_PROFILES,
        default=profile,
        help=f"QoS preset profile to {verb} with (default: {profile})",
    )
    parser.add_argument(
        "--qos-depth", metavar="N", type=int, help=f"queue size to {verb} with (overrides the "
        "profile's)",
    )  # fmt: skip
    parser.add_argument(
        "--qos-history", choices=QOS_HISTORY, help="history (overrides the profile's)"
    )
    parser.add_argument(
        "--qos-reliability",
        choices=QOS_RELIABILITY,
        help=f"reliability (overrides the profile's{adapted})",
    )
    parser.add_argument(
        "--qos-durability",
        choices=QOS_DURABILITY,
        help=f"durability (overrides the profile's{adapted})",
    )
    parser.add_argument(
        "--qos-liveliness", choices=QOS_LIVELINESS, help="liveliness (overrides the profile's)"
    )
    parser.add_argument(
        "--qos-liveliness-lease-duration-seconds",
        type=float,
        metavar="SEC",
        help="liveliness lease duration (overrides the profile's)",
    )


def qos_overridden(args) -> bool:
    """Whether a ``--qos-*`` policy option was given (``--qos-profile`` alone is not)."""
    return any(
        value is not None
        for value in (
            args.qos_reliability,
            args.qos_durability,
            args.qos_depth,
            args.qos_history,
            args.qos_liveliness,
            args.qos_liveliness_lease_duration_seconds,
        )
    )


def configured_qos(args):
    """The ``--qos-profile`` preset with the ``--qos-*`` overrides, as ros2 builds it (a depth
    <= 0 keeps the preset's; transient local with depth 0 gets depth 1)."""
    from rclpy.duration import Duration
    from rclpy.qos import (
        DurabilityPolicy,
        HistoryPolicy,
        LivelinessPolicy,
        QoSPresetProfiles,
        ReliabilityPolicy,
    )

    # rclpy hands out the preset object itself: a copy keeps the preset intact
    qos = copy.copy(QoSPresetProfiles.get_from_short_key(args.qos_profile))
    if args.qos_history:
        qos.history = HistoryPolicy.get_from_short_key(args.qos_history)
    if args.qos_durability:
        qos.durability = DurabilityPolicy.get_from_short_key(args.qos_durability)
    if args.qos_reliability:
        qos.reliability = ReliabilityPolicy.get_from_short_key(args.qos_reliability)
    if args.qos_liveliness:
        qos.liveliness = LivelinessPolicy.get_from_short_key(args.qos_liveliness)
    lease = args.qos_liveliness_lease_duration_seconds
    if lease and lease >= 0:
        qos.liveliness_lease_duration = Duration(seconds=lease)
    if args.qos_depth and args.qos_depth >= 0:
        qos.depth = args.qos_depth
    elif qos.durability == DurabilityPolicy.TRANSIENT_LOCAL and qos.depth == 0:
        qos.depth = 1
    policies = {
        "history": HistoryPolicy,
        "reliability": ReliabilityPolicy,
        "durability": DurabilityPolicy,
        "liveliness": LivelinessPolicy,
    }
    unknown = [name for name, kind in policies.items() if getattr(qos, name) == kind.UNKNOWN]
    if unknown:  # rcl refuses them, with a page of C error state
        raise UsageError(f"QoS {', '.join(unknown)} 'unknown': no endpoint can be created with it")
    return qos


def echo_qos(args, session: ToolSession, topic: str):
    """ros2 topic echo's QoS: the options' if a policy is given, else the preset made reliable
    (transient local) if every publisher of ``topic`` is, so it matches them all."""
    from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

    qos = configured_qos(args)
    publishers = session.node.get_publishers_info_by_topic(topic)
    if qos_overridden(args) or not publishers:
        return qos
    for policy, strong, weak in (
        ("reliability", ReliabilityPolicy.RELIABLE, ReliabilityPolicy.BEST_EFFORT),
        ("durability", DurabilityPolicy.TRANSIENT_LOCAL, DurabilityPolicy.VOLATILE),
    ):
        offering = sum(getattr(p.qos_profile, policy) == strong for p in publishers)
        if offering == len(publishers):
            setattr(qos, policy, strong)
            continue
        if offering:
            kind = type(strong).__name__.removesuffix("Policy")
            print(
                f"Some, but not all, publishers are offering QoS{kind}Policy.{strong.name}. "
                f"Falling back to QoS{kind}Policy.{weak.name} as it will connect to all "
                "publishers"
            )
        setattr(qos, policy, weak)
    return qos
