"""``rns_topic``: ``ros2 topic`` for a PyPI-only install.

::

    rns_topic list                        topic names with their types
    rns_topic echo TOPIC [--once] [--count N]
    rns_topic hz TOPIC [--window N]
    rns_topic pub TOPIC TYPE ['YAML'] [--once | --times N] [--rate HZ]

Domain, exit codes and Ctrl-C: :mod:`rns_ros.tool_session`.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections import deque
from collections.abc import Sequence
from typing import Any

from rns_ros.ros_messages import (  # noqa: F401  (message_to_dict: part of this module's API)
    TRUNCATE_LENGTH,
    import_interface,
    message_from_fields,
    message_to_dict,
    message_to_yaml,
    parse_fields,
)
from rns_ros.tool_session import (
    ToolError,
    ToolSession,
    absolute_name,
    add_listing_arguments,
    positive_int,
    run_tool,
    seconds,
    tool_parser,
)

#: ``rns_topic hz`` default window: arrival intervals the statistics are taken over.
DEFAULT_WINDOW = 10000
#: ``rns_topic pub`` default rate [Hz] (ros2 topic pub's).
DEFAULT_PUB_RATE = 1.0
#: Seconds ``rns_topic pub`` stays after its last message of ``--once`` / ``--times`` (ros2's
#: ``--keep-alive``), once every matched subscription acknowledged it.
DEFAULT_KEEP_ALIVE = 0.1


def _topic_type(session: ToolSession, topic: str, timeout: float) -> tuple[str, Any]:
    """(absolute name, message class) of ``topic`` once it is in the graph, else ToolError."""
    topic = absolute_name(topic)
    types: list[str] = []

    def known() -> bool:
        types[:] = dict(session.node.get_topic_names_and_types()).get(topic, [])
        return bool(types)

    if not session.spin_until(known, timeout):
        raise ToolError(
            f"topic {topic} not found within {timeout:g} s (see `rns_topic list`; check "
            "ROS_DOMAIN_ID and ROS_AUTOMATIC_DISCOVERY_RANGE)"
        )
    if len(types) > 1:
        raise ToolError(f"topic {topic} has more than one type: {', '.join(types)}")
    return topic, import_interface(types[0])


def _subscription_qos(session: ToolSession, topic: str):
    """QoS that matches every publisher of ``topic`` and gets what they offer.

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


def _topic_parser() -> argparse.ArgumentParser:
    parser, commands, common = tool_parser(
        "rns_topic",
        "List, print and time ROS 2 topics, like `ros2 topic` (which is not on PyPI). Joins the "
        "domain of ROS_DOMAIN_ID / ROS_AUTOMATIC_DISCOVERY_RANGE.",
        "exit codes: 0 ok or Ctrl-C; 1 topic not found, its type not installed or (pub) no "
        "subscription matched; 2 bad usage or a message that does not fit its type",
        "wait this long for TOPIC (list: any node) to appear",
    )
    listing = commands.add_parser(
        "list",
        parents=[common],
        help="topic names and types",
        description="Waits up to --timeout for the first other node, then --spin-time more.",
    )
    add_listing_arguments(listing)
    echo = commands.add_parser("echo", parents=[common], help="print messages as YAML")
    echo.add_argument("topic", metavar="TOPIC")
    echo.add_argument("--once", action="store_true", help="print one message and exit")
    echo.add_argument("--count", type=positive_int, metavar="N", help="exit after N messages")
    echo.add_argument(
        "--full-length",
        action="store_true",
        help=f"do not shorten strings and arrays longer than {TRUNCATE_LENGTH}",
    )
    hz = commands.add_parser("hz", parents=[common], help="publishing rate, every second")
    hz.add_argument("topic", metavar="TOPIC")
    hz.add_argument(
        "-w",
        "--window",
        type=positive_int,
        default=DEFAULT_WINDOW,
        metavar="N",
        help=f"intervals the statistics cover (default {DEFAULT_WINDOW})",
    )
    hz.add_argument(
        "--duration",
        type=seconds,
        metavar="SEC",
        help="exit after SEC seconds (default: run until Ctrl-C)",
    )
    _add_pub_parser(commands, common)
    return parser


def positive_rate(text: str) -> float:
    """argparse type: a finite rate > 0 [Hz]."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a rate > 0 Hz, got {text!r}")
    return value


def _add_pub_parser(commands, common: argparse.ArgumentParser) -> None:
    pub = commands.add_parser(
        "pub",
        parents=[common],
        help="publish a message given as YAML",
        description="Publish TYPE on TOPIC, filled from the YAML mapping of its fields, like "
        "`ros2 topic pub` (e.g. rns_topic pub --once /ptp_goal sensor_msgs/msg/JointState "
        "'{name: [joint_1], position: [0.5]}'). A Time field takes `now`, a Header `auto`. "
        "--once / --times first wait up to --timeout for a subscription to match.",
    )
    pub.add_argument("topic", metavar="TOPIC")
    pub.add_argument("type", metavar="TYPE", help="message type, e.g. std_msgs/msg/Bool")
    pub.add_argument(
        "values", metavar="YAML", nargs="?", default="{}", help="the fields (default '{}')"
    )
    count = pub.add_mutually_exclusive_group()
    count.add_argument("-1", "--once", action="store_true", help="publish one message and exit")
    count.add_argument(
        "-t", "--times", type=positive_int, metavar="N", help="publish N messages and exit"
    )
    pub.add_argument(
        "-r",
        "--rate",
        type=positive_rate,
        default=DEFAULT_PUB_RATE,
        metavar="HZ",
        help=f"publishing rate (default {DEFAULT_PUB_RATE:g})",
    )
    pub.add_argument(
        "-p", "--print", type=positive_int, default=1, metavar="N", help="print every N-th message"
    )
    pub.add_argument(
        "-w",
        "--wait-matching-subscriptions",
        type=int,
        default=None,
        metavar="N",
        help="subscriptions to wait for before publishing (default 1 with --once / --times, "
        "else 0)",
    )
    pub.add_argument(
        "--keep-alive",
        type=seconds,
        default=DEFAULT_KEEP_ALIVE,
        metavar="SEC",
        help=f"stay this long after the last message (default {DEFAULT_KEEP_ALIVE:g})",
    )
    pub.add_argument("--qos-depth", type=positive_int, default=10, metavar="N")
    pub.add_argument("--qos-reliability", choices=("reliable", "best_effort"), default="reliable")
    pub.add_argument(
        "--qos-durability", choices=("volatile", "transient_local"), default="volatile"
    )


def _topic_list(args, session: ToolSession) -> int:
    session.discover(args.spin_time, args.timeout)
    for name, types in sorted(session.node.get_topic_names_and_types()):
        print(f"{name} [{', '.join(types)}]")
    sys.stdout.flush()
    return 0


def _topic_echo(args, session: ToolSession) -> int:
    topic, msg_type = _topic_type(session, args.topic, args.timeout)
    limit = 1 if args.once else args.count
    truncate = None if args.full_length else TRUNCATE_LENGTH
    printed = 0

    def on_message(msg) -> None:
        nonlocal printed
        if limit is not None and printed >= limit:
            return  # more may be queued in the same spin
        printed += 1
        sys.stdout.write(message_to_yaml(msg, truncate) + "---\n")
        sys.stdout.flush()

    session.node.create_subscription(msg_type, topic, on_message, _subscription_qos(session, topic))
    session.spin_until(lambda: limit is not None and printed >= limit, None)
    return 0


class RateStats:
    """Arrival times of one topic -> rate and interval statistics over the last ``window``
    intervals, as ``ros2 topic hz`` computes them (population standard deviation)."""

    def __init__(self, window: int = DEFAULT_WINDOW) -> None:
        self.intervals: deque[float] = deque(maxlen=window)
        self.last: float | None = None
        self.count = 0

    def add(self, stamp: float) -> None:
        """One message received at ``stamp`` [s] (monotonic)."""
        if self.last is not None:
            self.intervals.append(stamp - self.last)
        self.last = stamp
        self.count += 1

    def summary(self) -> str | None:
        """The two lines ros2 topic hz prints, or None before two messages arrived."""
        n = len(self.intervals)
        if n == 0:
            return None
        mean = sum(self.intervals) / n
        std = math.sqrt(sum((d - mean) ** 2 for d in self.intervals) / n)
        rate = 1.0 / mean if mean > 0 else math.inf
        return (
            f"average rate: {rate:.3f}\n"
            f"\tmin: {min(self.intervals):.3f}s max: {max(self.intervals):.3f}s "
            f"std dev: {std:.5f}s window: {n + 1}"
        )


def _topic_hz(args, session: ToolSession) -> int:
    topic, msg_type = _topic_type(session, args.topic, args.timeout)
    stats = RateStats(args.window)
    # raw: only arrival times matter, skip deserialising (as ros2 topic hz does)
    session.node.create_subscription(
        msg_type,
        topic,
        lambda _data: stats.add(time.monotonic()),
        _subscription_qos(session, topic),
        raw=True,
    )
    end = None if args.duration is None else time.monotonic() + args.duration
    next_report = time.monotonic() + 1.0
    reported = 0
    while True:
        wake = min(next_report, end or math.inf)
        session.spin_until(lambda wake=wake: time.monotonic() >= wake, None)
        if time.monotonic() >= next_report:
            next_report += 1.0
            if stats.count == reported:
                print("no new messages" if stats.count else f"waiting for messages on {topic}")
            else:
                reported = stats.count
                print(stats.summary() or "waiting for a second message")
            sys.stdout.flush()
        if end is not None and time.monotonic() >= end:
            break
    return 0


def _type_name(msg_type: type) -> str:
    """``'pkg/msg/Type'`` of a message class, as the graph names it."""
    return f"{msg_type.__module__.split('.')[0]}/msg/{msg_type.__name__}"


def _check_graph_type(session: ToolSession, topic: str, msg_type: type) -> None:
    """ToolError if the other publishers and subscriptions of ``topic`` all have another type
    (DDS would never match them with ours)."""
    me = session.node.get_name()
    endpoints = [
        *session.node.get_publishers_info_by_topic(topic),
        *session.node.get_subscriptions_info_by_topic(topic),
    ]
    types = sorted({e.topic_type for e in endpoints if e.node_name != me})
    if types and _type_name(msg_type) not in types:
        raise ToolError(f"topic {topic} has type {', '.join(types)}, not {_type_name(msg_type)}")


def _topic_pub(args, session: ToolSession) -> int:
    from rclpy.duration import Duration
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    msg_type = import_interface(args.type, "msg")
    values = parse_fields(args.values)

    def message():
        return message_from_fields(
            values, msg_type, lambda: session.node.get_clock().now().to_msg()
        )

    message()  # a message that does not fit its type is a usage error before any waiting
    topic = absolute_name(args.topic)
    limit = 1 if args.once else args.times
    wait = args.wait_matching_subscriptions
    if wait is None:
        wait = 1 if limit is not None else 0
    qos = QoSProfile(
        depth=args.qos_depth,
        reliability=ReliabilityPolicy.RELIABLE
        if args.qos_reliability == "reliable"
        else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL
        if args.qos_durability == "transient_local"
        else DurabilityPolicy.VOLATILE,
    )
    publisher = session.node.create_publisher(msg_type, topic, qos)

    def matched() -> bool:
        _check_graph_type(session, topic, msg_type)
        return publisher.get_subscription_count() >= wait

    if wait > 0 and not session.spin_until(matched, args.timeout):
        raise ToolError(
            f"{publisher.get_subscription_count()} of {wait} subscription(s) to {topic} matched "
            f"within {args.timeout:g} s (is the subscribing node running? check ROS_DOMAIN_ID "
            "and ROS_AUTOMATIC_DISCOVERY_RANGE)"
        )
    _check_graph_type(session, topic, msg_type)
    print("publisher: beginning loop", flush=True)
    start, published = time.monotonic(), 0
    while limit is None or published < limit:
        due = start + published / args.rate
        session.spin_until(lambda due=due: time.monotonic() >= due, None)
        msg = message()
        publisher.publish(msg)
        published += 1
        if published % args.print == 0:
            print(f"publishing #{published}: {msg!r}\n", flush=True)
    # a reliable publisher leaves once every matched subscription has the messages
    deadline = time.monotonic() + args.timeout
    while not publisher.wait_for_all_acked(Duration(nanoseconds=50_000_000)):
        if time.monotonic() >= deadline:
            raise ToolError(
                f"the messages to {topic} were not acknowledged within {args.timeout:g} s"
            )
        session.spin_for(0.0)  # reads the Ctrl-C flag
    session.spin_for(args.keep_alive)
    return 0


def topic_main(argv: Sequence[str] | None = None) -> int:
    """``rns_topic list|echo|hz|pub [TOPIC] [TYPE YAML]``; returns the exit code."""
    commands = {"list": _topic_list, "echo": _topic_echo, "hz": _topic_hz, "pub": _topic_pub}
    return run_tool(
        "rns_topic", _topic_parser(), argv, lambda args, s: commands[args.command](args, s)
    )


if __name__ == "__main__":
    raise SystemExit(topic_main())
