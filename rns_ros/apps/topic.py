"""``rns_topic``: ``ros2 topic`` for a PyPI-only install, with ros2cli Jazzy's arguments and output.

::

    rns_topic list [-t] [-v] [-c] [-a]        topic names (with [types]: -t)
    rns_topic echo TOPIC [TYPE] [--once] [--field F] [--csv] [--filter EXPR] [--qos-profile P]
    rns_topic hz TOPIC [--window N]
    rns_topic pub TOPIC TYPE ['YAML'] [-1 | -t N] [-r HZ] [-w N] [--max-wait-time-secs SEC]

Domain, exit codes and Ctrl-C: :mod:`rns_ros.tool_session`.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import Any

from rns_ros.ros_messages import (  # noqa: F401  (message_to_dict: part of this module's API)
    TRUNCATE_LENGTH,
    import_interface,
    message_from_fields,
    message_to_csv,
    message_to_dict,
    message_to_yaml,
    parse_fields,
)
from rns_ros.tool_qos import (
    ECHO_QOS_PROFILE,
    PUB_QOS_PROFILE,
    add_qos_arguments,
    configured_qos,
    echo_qos,
    subscription_qos,
)
from rns_ros.tool_session import (
    DEFAULT_TIMEOUT,
    ToolError,
    ToolSession,
    UsageError,
    add_listing_arguments,
    count,
    is_hidden,
    positive_int,
    positive_rate,
    positive_seconds,
    rcl_one_line,
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
#: Seconds between ``pub``'s "Waiting for at least N matching subscription(s)..." lines (ros2's).
WAIT_NOTE_PERIOD = 1.0


def _expanded(session: ToolSession, topic: str) -> str:
    """``topic`` as the graph names it (``x`` -> ``/x``, ``~/x`` -> ``/<node>/x``)."""
    from rclpy.expand_topic_name import expand_topic_name

    try:
        return expand_topic_name(topic, session.node.get_name(), session.node.get_namespace())
    except ValueError as exc:
        raise UsageError(rcl_one_line(exc)) from None


def _topic_type(session: ToolSession, topic: str, timeout: float) -> tuple[str, Any]:
    """(expanded name, message class) of ``topic`` once it is in the graph, else ToolError."""
    topic = _expanded(session, topic)
    types: list[str] = []

    def known() -> bool:
        types[:] = dict(session.node.get_topic_names_and_types()).get(topic, [])
        return bool(types)

    if not session.spin_until(known, timeout):
        raise ToolError(
            f"topic {topic} not found within {timeout:g} s, its type unknown (see `rns_topic "
            "list`, give TYPE, or check ROS_DOMAIN_ID and ROS_AUTOMATIC_DISCOVERY_RANGE)"
        )
    if len(types) > 1:
        raise ToolError(f"topic {topic} has more than one type: {', '.join(types)}")
    return topic, import_interface(types[0])


def _topic_parser() -> argparse.ArgumentParser:
    parser, commands, common = tool_parser(
        "rns_topic",
        "List, print, time and publish ROS 2 topics with the arguments of `ros2 topic` (which is "
        "not on PyPI). Joins the domain of ROS_DOMAIN_ID / ROS_AUTOMATIC_DISCOVERY_RANGE.",
        "exit codes: 0 ok or Ctrl-C; 1 topic not found, its type not installed or (pub) no "
        "subscription matched in --max-wait-time-secs; 2 bad usage or a message that does not "
        "fit its type",
        "wait this long for TOPIC (list: any node) to appear",
    )
    listing = commands.add_parser(
        "list",
        parents=[common],
        help="topic names (-t: and types)",
        description="Waits up to --timeout for the first other node, then --spin-time more.",
    )
    add_listing_arguments(listing, "topic")
    listing.add_argument(
        "-v", "--verbose", action="store_true", help="publishers and subscribers of each topic"
    )
    _add_echo_parser(commands)
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
    _add_pub_parser(commands)
    return parser


def _add_echo_parser(commands) -> None:
    echo = commands.add_parser(
        "echo",
        help="print messages as YAML (or CSV)",
        description="Print the messages of TOPIC as `ros2 topic echo` does: YAML documents "
        "ended by ---. TYPE is learnt from the graph when not given.",
    )
    echo.add_argument("topic", metavar="TOPIC")
    echo.add_argument(
        "message_type", metavar="TYPE", nargs="?", help="message type, e.g. std_msgs/msg/String"
    )
    add_qos_arguments(echo, "subscribe", ECHO_QOS_PROFILE)
    echo.add_argument(
        "--csv", action="store_true", help="one line of comma-separated values per message"
    )
    echo.add_argument(
        "--field", metavar="FIELD", help="print this field only; '.' selects sub-fields "
        "(e.g. pose.pose.position)",
    )  # fmt: skip
    echo.add_argument(
        "-f",
        "--full-length",
        action="store_true",
        help="do not shorten strings and arrays longer than --truncate-length",
    )
    echo.add_argument(
        "-l",
        "--truncate-length",
        type=count,
        default=TRUNCATE_LENGTH,
        metavar="N",
        help=f"length strings and arrays are cut to (default {TRUNCATE_LENGTH})",
    )
    echo.add_argument("--no-arr", action="store_true", help="don't print array fields")
    echo.add_argument("--no-str", action="store_true", help="don't print string fields")
    echo.add_argument(
        "--flow-style", action="store_true", help="each message as one flow-style YAML line"
    )
    echo.add_argument(
        "--no-lost-messages", action="store_true", help="don't report when a message is lost"
    )
    echo.add_argument("--raw", action="store_true", help="print the serialized bytes")
    echo.add_argument(
        "--filter",
        dest="filter_expr",
        metavar="EXPR",
        help="print only messages for which this Python expression of m (the message, or "
        "its --field) is true, e.g. 'm.data > 0'",
    )
    echo.add_argument("--once", action="store_true", help="print one message and exit")
    echo.add_argument("--count", type=positive_int, metavar="N", help="exit after N messages")
    echo.add_argument(
        "--timeout",
        type=positive_seconds,
        metavar="SEC",
        help="exit after SEC (code 0); without TYPE also how long TOPIC may take to appear "
        f"(default {DEFAULT_TIMEOUT:g} s for that)",
    )
    echo.add_argument(
        "-i",
        "--include-message-info",
        action="store_true",
        help="print each message's info (timestamps, sequence numbers) too",
    )


def _add_pub_parser(commands) -> None:
    pub = commands.add_parser(
        "pub",
        help="publish a message given as YAML",
        description="Publish TYPE on TOPIC, filled from the YAML mapping of its fields, like "
        "`ros2 topic pub` (e.g. rns_topic pub --once /ptp_goal sensor_msgs/msg/JointState "
        "'{name: [joint_1], position: [0.5]}'). A Time field takes `now`, a Header `auto`. "
        "--once / --times first wait for a subscription, as long as it takes unless "
        "--max-wait-time-secs.",
    )
    pub.add_argument("topic", metavar="TOPIC")
    pub.add_argument("type", metavar="TYPE", help="message type, e.g. std_msgs/msg/Bool")
    pub.add_argument(
        "values", metavar="YAML", nargs="?", default="{}", help="the fields (default '{}')"
    )
    pub.add_argument("--stdin", action="store_true", help="read the YAML from standard input")
    pub.add_argument(
        "-r",
        "--rate",
        type=positive_rate,
        default=DEFAULT_PUB_RATE,
        metavar="HZ",
        help=f"publishing rate (default {DEFAULT_PUB_RATE:g})",
    )
    pub.add_argument(
        "-p",
        "--print",
        type=count,
        default=1,
        metavar="N",
        help="print every N-th message (0: none; default 1)",
    )
    times = pub.add_mutually_exclusive_group()
    times.add_argument("-1", "--once", action="store_true", help="publish one message and exit")
    times.add_argument(
        "-t",
        "--times",
        type=count,
        default=0,
        metavar="N",
        help="publish N messages and exit (0: until Ctrl-C)",
    )
    pub.add_argument(
        "-w",
        "--wait-matching-subscriptions",
        type=count,
        default=None,
        metavar="N",
        help="subscriptions to wait for before publishing (default 1 with --once / --times, "
        "else 0)",
    )
    pub.add_argument(
        "--max-wait-time-secs",
        type=positive_seconds,
        default=None,
        metavar="SEC",
        help="give up (exit 1) when the subscriptions did not match within SEC (default: wait "
        "as long as it takes)",
    )
    pub.add_argument(
        "--keep-alive",
        type=seconds,
        default=DEFAULT_KEEP_ALIVE,
        metavar="SEC",
        help=f"stay this long after the last message (default {DEFAULT_KEEP_ALIVE:g})",
    )
    pub.add_argument("-n", "--node-name", metavar="NAME", help="name of the publishing node")
    add_qos_arguments(pub, "publish", PUB_QOS_PROFILE)


def _topic_list(args, session: ToolSession) -> int:
    session.discover(args.spin_time, args.timeout)
    topics = [
        (name, types)
        for name, types in sorted(session.node.get_topic_names_and_types())
        if args.include_hidden or not is_hidden(name)
    ]
    if args.count:
        print(len(topics))
    elif args.verbose:
        for publishers in (True, False):
            print(_endpoint_counts(session, topics, publishers))
    else:
        for name, types in topics:
            print(f"{name} [{', '.join(types)}]" if args.show_types else name)
    sys.stdout.flush()
    return 0


def _endpoint_counts(session: ToolSession, topics, publishers: bool) -> str:
    """``ros2 topic list -v``'s block of published (or subscribed) topics with their counts."""
    kind = "publisher" if publishers else "subscriber"
    lines = [("Published" if publishers else "Subscribed") + " topics:"]
    for name, types in topics:
        n = (
            session.node.count_publishers(name)
            if publishers
            else session.node.count_subscribers(name)
        )
        if n:
            lines.append(f" * {name} [{', '.join(types)}] {n} {kind}{'s' if n > 1 else ''}")
    return "\n".join(lines) + "\n"


def _field_path(text: str | None) -> list[str] | None:
    """``--field a.b`` as ['a', 'b'] (None: the whole message)."""
    if text is None:
        return None
    path = [name for name in text.split(".") if name]
    if not path:
        raise UsageError(f"Invalid field value '{text}'")
    return path


def _select(msg: Any, path: list[str] | None) -> Any:
    """The ``--field`` of ``msg``, or ToolError naming the field, as ros2 does."""
    for name in path or ():
        try:
            msg = getattr(msg, name)
        except AttributeError as exc:
            raise ToolError(f"Invalid field '{'.'.join(path)}': {exc}") from None
    return msg


def message_filter(expr: str | None) -> Callable[[Any], bool] | None:
    """``--filter EXPR`` as a test of ``m`` (None: every message passes), as ros2 evaluates it:
    Python with its builtins. A syntax error is a usage error; an expression that raises on a
    message ends the echo (ToolError, one line)."""
    if not expr:
        return None
    try:
        code = compile(expr, "--filter", "eval")
    except SyntaxError as exc:
        raise UsageError(f"--filter {expr!r} is not a Python expression: {exc.msg}") from None

    def keep(m) -> bool:
        try:
            # m among the globals: generator expressions in EXPR see it too
            return bool(eval(code, {"m": m}))
        except Exception as exc:
            raise ToolError(
                f"--filter {expr!r} failed on a message: {type(exc).__name__}: {exc}"
            ) from None

    return keep


def _is_message(value: Any) -> bool:
    return hasattr(value, "get_fields_and_field_types")


def echo_text(value: Any, args, info: dict | None = None) -> str:
    """What ``echo`` prints for one message (or its ``--field``, or its raw bytes) as ros2
    does: YAML then ``---``, one CSV line, or a field's Python value then ``---``; ``info``:
    the message info of ``-i``."""
    import yaml

    truncate = None if args.full_length else args.truncate_length
    if not _is_message(value):
        if info is None:
            return f"{value}\n---\n"
        return f"---Got new message, message info:---\n{info}\n---Message data:---\n{value}\n---\n"
    if args.csv:
        line = message_to_csv(value, truncate, no_arr=args.no_arr, no_str=args.no_str)
        if info is not None:
            line = ",".join(str(x) for x in info.values()) + "," + line
        return line + "\n"
    head = "" if info is None else yaml.safe_dump(info) + "---\n"
    text = message_to_yaml(
        value, truncate, no_arr=args.no_arr, no_str=args.no_str, flow_style=args.flow_style
    )
    return head + text + "---\n"


def _topic_echo(args, session: ToolSession) -> int:
    path = _field_path(args.field)
    keep = message_filter(args.filter_expr)
    start = time.monotonic()
    if args.message_type is None:
        wait = DEFAULT_TIMEOUT if args.timeout is None else args.timeout
        topic, msg_type = _topic_type(session, args.topic, wait)
    else:
        msg_type = import_interface(args.message_type, "msg")
        topic = _expanded(session, args.topic)
        # the publishers' QoS decides ours: give discovery its time, without requiring one
        wait = DEFAULT_TIMEOUT if args.timeout is None else min(DEFAULT_TIMEOUT, args.timeout)
        session.spin_until(lambda: bool(session.node.get_publishers_info_by_topic(topic)), wait)
    _select(b"" if args.raw else msg_type(), path)  # a bad --field fails now, not per message
    deadline = None if args.timeout is None else start + args.timeout
    limit = 1 if args.once else args.count
    printed = 0

    def on_message(msg, info=None) -> None:
        nonlocal printed
        if limit is not None and printed >= limit:
            return  # more may be queued in the same spin
        value = _select(msg, path)
        if keep is not None and not keep(value):
            return
        printed += 1
        sys.stdout.write(echo_text(value, args, info))
        sys.stdout.flush()

    callback = (
        (lambda msg, info: on_message(msg, info)) if args.include_message_info else on_message
    )
    _subscribe(session, msg_type, topic, callback, echo_qos(args, session, topic), args)

    def done() -> bool:
        if limit is not None and printed >= limit:
            return True
        return deadline is not None and time.monotonic() >= deadline

    session.spin_until(done, None)
    return 0


def _subscribe(session: ToolSession, msg_type, topic: str, callback, qos, args) -> None:
    """``echo``'s subscription, reporting lost messages as ros2 does unless
    ``--no-lost-messages``; a QoS rclpy refuses is a usage error."""
    from rclpy.event_handler import SubscriptionEventCallbacks, UnsupportedEventTypeError

    def lost(status) -> None:
        print(
            f"A message was lost!!!\n\ttotal count change:{status.total_count_change}"
            f"\n\ttotal count: {status.total_count}",
            end="---\n",
            flush=True,
        )

    events = None if args.no_lost_messages else SubscriptionEventCallbacks(message_lost=lost)
    try:
        try:
            session.node.create_subscription(
                msg_type, topic, callback, qos, event_callbacks=events, raw=args.raw
            )
        except UnsupportedEventTypeError:  # an RMW without the message-lost event
            session.node.create_subscription(msg_type, topic, callback, qos, raw=args.raw)
    except (ValueError, RuntimeError) as exc:  # rcl's errors are RuntimeErrors
        raise UsageError(f"cannot subscribe to {topic}: {rcl_one_line(exc)}") from None


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
        subscription_qos(session, topic),
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

    msg_type = import_interface(args.type, "msg")
    if args.stdin and args.values != "{}":
        raise UsageError("give the YAML either as an argument or with --stdin, not both")
    values = parse_fields(sys.stdin.read() if args.stdin else args.values)

    def message():
        return message_from_fields(
            values, msg_type, lambda: session.node.get_clock().now().to_msg()
        )

    message()  # a message that does not fit its type is a usage error before any waiting
    times = 1 if args.once else args.times
    wait = args.wait_matching_subscriptions
    if wait is None:
        wait = 1 if times else 0
    if wait == 0 and args.max_wait_time_secs is not None:
        raise UsageError(
            "--max-wait-time-secs is only effective with --wait-matching-subscriptions, "
            "--once or --times"
        )
    topic = _expanded(session, args.topic)
    try:
        publisher = session.node.create_publisher(msg_type, topic, configured_qos(args))
    except (ValueError, RuntimeError) as exc:  # rcl's errors are RuntimeErrors
        raise UsageError(f"cannot publish on {topic}: {rcl_one_line(exc)}") from None
    _wait_for_subscriptions(session, publisher, topic, msg_type, wait, args.max_wait_time_secs)
    _check_graph_type(session, topic, msg_type)
    print("publisher: beginning loop", flush=True)
    start, published = time.monotonic(), 0
    while not times or published < times:
        due = start + published / args.rate
        session.spin_until(lambda due=due: time.monotonic() >= due, None)
        msg = message()
        publisher.publish(msg)
        published += 1
        if args.print and published % args.print == 0:
            print(f"publishing #{published}: {msg!r}\n", flush=True)
    # a reliable publisher leaves once every matched subscription has the messages
    deadline = time.monotonic() + DEFAULT_TIMEOUT
    while not publisher.wait_for_all_acked(Duration(nanoseconds=50_000_000)):
        if time.monotonic() >= deadline:
            raise ToolError(
                f"the messages to {topic} were not acknowledged within {DEFAULT_TIMEOUT:g} s"
            )
        session.spin_for(0.0)  # reads the Ctrl-C flag
    session.spin_for(args.keep_alive)
    return 0


def _wait_for_subscriptions(
    session: ToolSession, publisher, topic: str, msg_type, wait: int, max_wait: float | None
) -> None:
    """Wait until ``wait`` subscriptions matched ``publisher``, saying so every second as ros2
    does; ToolError after ``max_wait`` [s] (None: no limit) or when the topic has another type."""
    start = time.monotonic()
    next_note = start
    while publisher.get_subscription_count() < wait:
        _check_graph_type(session, topic, msg_type)
        now = time.monotonic()
        if max_wait is not None and now - start >= max_wait:
            raise ToolError(
                f"Timed out waiting for subscribers: Expected {wait} subscribers but only got "
                f"{publisher.get_subscription_count()} subscribers on {topic} (is the "
                "subscribing node running? check ROS_DOMAIN_ID and ROS_AUTOMATIC_DISCOVERY_RANGE)"
            )
        if now >= next_note:
            print(f"Waiting for at least {wait} matching subscription(s)...", flush=True)
            next_note += WAIT_NOTE_PERIOD
        step = 0.1 if max_wait is None else min(0.1, max(0.0, start + max_wait - now))
        session.spin_until(lambda: publisher.get_subscription_count() >= wait, step)


def topic_main(argv: Sequence[str] | None = None) -> int:
    """``rns_topic list|echo|hz|pub [TOPIC] [TYPE YAML]``; returns the exit code."""
    commands = {"list": _topic_list, "echo": _topic_echo, "hz": _topic_hz, "pub": _topic_pub}
    return run_tool(
        "rns_topic",
        _topic_parser(),
        argv,
        lambda args, s: commands[args.command](args, s),
        node_name=lambda args: getattr(args, "node_name", None),
    )


if __name__ == "__main__":
    raise SystemExit(topic_main())
