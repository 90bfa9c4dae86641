"""``rns_topic``: ``ros2 topic`` for a PyPI-only install.

::

    rns_topic list                        topic names with their types
    rns_topic echo TOPIC [--once] [--count N]
    rns_topic hz TOPIC [--window N]

Domain, exit codes and Ctrl-C: :mod:`rns_ros.tool_session`.
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
import time
from collections import deque
from collections.abc import Sequence
from typing import Any

from rns_ros.tool_session import (
    DEFAULT_SPIN_TIME,
    ToolError,
    ToolSession,
    absolute_name,
    positive_int,
    run_tool,
    seconds,
    tool_parser,
)

#: ``rns_topic echo`` shortens longer strings and arrays, as ``ros2 topic echo`` does.
TRUNCATE_LENGTH = 128
#: ``rns_topic hz`` default window: arrival intervals the statistics are taken over.
DEFAULT_WINDOW = 10000


def message_to_dict(msg: Any, truncate: int | None = TRUNCATE_LENGTH) -> Any:
    """A ROS message as plain dicts / lists / scalars (field order kept) for YAML output.

    Strings and sequences longer than ``truncate`` end in ``'...'`` (None: full length), as
    ``ros2 topic echo`` prints them; a ``byte`` field is its integer value.
    """
    if hasattr(msg, "get_fields_and_field_types"):
        return {
            field: message_to_dict(getattr(msg, field), truncate)
            for field in msg.get_fields_and_field_types()
        }
    if isinstance(msg, bytes):  # `byte` fields (length 1) and byte sequences
        msg = list(msg)
        if len(msg) == 1:
            return msg[0]
    if hasattr(msg, "tolist"):  # numpy arrays (fixed size), array.array (sequences), numpy scalars
        msg = msg.tolist()
    if isinstance(msg, list | tuple):
        items = [message_to_dict(item, truncate) for item in msg]
        if truncate is not None and len(items) > truncate:
            items = [*items[:truncate], "..."]
        return items
    if isinstance(msg, str) and truncate is not None and len(msg) > truncate:
        return msg[:truncate] + "..."
    return msg


def message_to_yaml(msg: Any, truncate: int | None = TRUNCATE_LENGTH) -> str:
    """``msg`` as the block YAML ``ros2 topic echo`` prints (without the ``---`` separator)."""
    import yaml

    return yaml.safe_dump(
        message_to_dict(msg, truncate),
        sort_keys=False,
        default_flow_style=False,
        allow_unicode=True,
        width=1 << 30,  # no line folding
    )


def import_message(type_name: str):
    """The message class of ``'pkg/msg/Type'`` (as the graph names it), or ToolError."""
    parts = type_name.split("/")
    if len(parts) != 3 or not all(parts):
        raise ToolError(f"cannot interpret the message type {type_name!r}")
    package, kind, name = parts
    try:
        cls = getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ImportError, AttributeError):
        raise ToolError(
            f"message type {type_name} is not installed in this Python (its package "
            f"{package} is not among the PyPI wheels)"
        ) from None
    return cls


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
    return topic, import_message(types[0])


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
        "exit codes: 0 ok or Ctrl-C; 1 topic not found or its type not installed; 2 bad usage",
        "wait this long for TOPIC (list: any node) to appear",
    )
    listing = commands.add_parser(
        "list",
        parents=[common],
        help="topic names and types",
        description="Waits up to --timeout for the first other node, then --spin-time more.",
    )
    listing.add_argument(
        "-t",
        "--show-types",
        action="store_true",
        help="accepted for ros2 compatibility: types are always shown",
    )
    listing.add_argument(
        "--spin-time",
        type=seconds,
        default=DEFAULT_SPIN_TIME,
        metavar="SEC",
        help=f"discovery time after the first node appeared (default {DEFAULT_SPIN_TIME:g})",
    )
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
    return parser


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


def topic_main(argv: Sequence[str] | None = None) -> int:
    """``rns_topic list|echo|hz [TOPIC]``; returns the exit code."""
    commands = {"list": _topic_list, "echo": _topic_echo, "hz": _topic_hz}
    return run_tool(
        "rns_topic", _topic_parser(), argv, lambda args, s: commands[args.command](args, s)
    )


if __name__ == "__main__":
    raise SystemExit(topic_main())
