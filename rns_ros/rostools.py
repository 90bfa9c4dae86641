"""``rns_param`` and ``rns_topic``: ``ros2 param`` / ``ros2 topic`` for a PyPI-only install.

ros2cli is not on PyPI, so whoever installed rns_ros from wheels has no ``ros2`` command. These
two console scripts cover what operating the rns_ros nodes needs, built only on rclpy and the
installed message packages::

    rns_param list [NODE]                 parameter names (of every node without NODE)
    rns_param get NODE NAME               "Double value is: 0.2"
    rns_param set NODE NAME VALUE         VALUE is YAML like ros2 param: true, 3, 0.5, sc, [1, 2]
    rns_param describe NODE NAME...       description, type, ranges, constraints, read-only
    rns_topic list                        topic names with their types
    rns_topic echo TOPIC [--once] [--count N]
    rns_topic hz TOPIC [--window N]

They join the ROS domain of the environment like ``ros2`` does (``ROS_DOMAIN_ID``,
``ROS_AUTOMATIC_DISCOVERY_RANGE``, ``RMW_IMPLEMENTATION``). Exit codes: 0 on success and after
Ctrl-C; 1 when the node, parameter or topic is not found within ``--timeout`` (one line on
stderr) or ``set`` is refused (``Setting parameter failed: <the node's reason>`` on stdout, as
ros2 prints it); 2 for bad usage or a ROS environment rcl rejects (one line on stderr).

Only the standard library is imported at module level: rclpy loads inside :func:`param_main` /
:func:`topic_main` after their Ctrl-C handler is in place, so an early Ctrl-C is a quiet exit.
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import signal
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import Any, NoReturn

#: Seconds to wait for a node's parameter services or a topic to show up in the graph.
DEFAULT_TIMEOUT = 5.0
#: Seconds of discovery after the first other node showed up, before listing the graph.
DEFAULT_SPIN_TIME = 0.5
#: ``rns_topic echo`` shortens longer strings and arrays, as ``ros2 topic echo`` does.
TRUNCATE_LENGTH = 128
#: ``rns_topic hz`` default window: arrival intervals the statistics are taken over.
DEFAULT_WINDOW = 10000


class UsageError(Exception):
    """The command line is wrong (exit code 2)."""


class ToolError(Exception):
    """The request could not be carried out: node or topic not found, value refused (exit 1)."""


class _InterruptError(Exception):
    """Ctrl-C arrived (exit code 0)."""


class _Parser(argparse.ArgumentParser):
    """argparse that reports a usage error as one exception instead of usage text + exit."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(message)


# --- shared ROS session ---------------------------------------------------------------------------
class _Session:
    """A private rclpy Context with one hidden node and an executor, torn down in :meth:`close`.

    ``stop`` is set by Ctrl-C; every wait below reads it at least every 50 ms.
    """

    def __init__(self, program: str, stop: threading.Event) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions

        self.stop = stop
        self.context = rclpy.Context()
        # rclpy's own SIGINT handler would tear the Context down under a running wait; ours only
        # sets `stop`. The domain and discovery range come from the environment, like ros2.
        rclpy.init(
            args=[program], context=self.context, signal_handler_options=SignalHandlerOptions.NO
        )
        self.executor = SingleThreadedExecutor(context=self.context)
        # A leading underscore hides the node from `ros2 node list`, like ros2cli's own nodes.
        self.node = rclpy.create_node(
            f"_{program}_{os.getpid()}",
            context=self.context,
            start_parameter_services=False,
        )
        self.executor.add_node(self.node)

    def spin_until(self, done: Callable[[], bool], timeout: float | None) -> bool:
        """Spin until ``done()`` or ``timeout`` [s] (None: forever); raise on Ctrl-C."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while not done():
            if self.stop.is_set():
                raise _InterruptError
            if deadline is not None and time.monotonic() >= deadline:
                return False
            self.executor.spin_once(timeout_sec=0.05)
        return True

    def spin_for(self, duration: float) -> None:
        """Spin for ``duration`` [s] (discovery); raise on Ctrl-C."""
        deadline = time.monotonic() + duration
        self.spin_until(lambda: time.monotonic() >= deadline, None)

    def discover(self, spin_time: float, timeout: float) -> None:
        """Let discovery fill the graph: spin until another node shows up (at most ``timeout``
        [s]), then ``spin_time`` [s] more for the rest.

        A fixed spin time alone is not enough: a new DDS participant is usually matched within
        0.1 s on loopback, but now and then only at the next periodic announcement, ~3 s later.
        """
        me = self.node.get_fully_qualified_name()

        def others() -> bool:
            return any(
                namespace.rstrip("/") + "/" + name != me
                for name, namespace in self.node.get_node_names_and_namespaces()
            )

        self.spin_until(others, timeout)
        self.spin_for(spin_time)

    def close(self) -> None:
        import rclpy

        self.executor.remove_node(self.node)
        self.node.destroy_node()
        self.executor.shutdown()
        rclpy.try_shutdown(context=self.context)


def _absolute(name: str) -> str:
    """``rns_controller`` -> ``/rns_controller`` (the tools' node lives in the root namespace)."""
    return name if name.startswith("/") else "/" + name


def _timeout(text: str) -> float:
    """argparse type: a non-negative finite number of seconds."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"expected seconds >= 0, got {text!r}")
    return value


def _positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return value


def _run(
    program: str, parser: argparse.ArgumentParser, argv: Sequence[str] | None, body: Callable
) -> int:
    """Parse ``argv``, run ``body(args, session)`` under the exit-code contract (module docstring).

    Ctrl-C and SIGTERM set a flag (installed before rclpy is imported) instead of raising inside
    rclpy's C extension, where a KeyboardInterrupt can surface as a RuntimeError.
    """
    stop = threading.Event()
    previous = {}
    if threading.current_thread() is threading.main_thread():
        for signum in (signal.SIGINT, signal.SIGTERM):
            previous[signum] = signal.signal(signum, lambda _signum, _frame: stop.set())
    session = None
    try:
        try:
            args = parser.parse_args(list(sys.argv[1:] if argv is None else argv))
        except UsageError as exc:
            print(f"{program}: {exc} (see {program} --help)", file=sys.stderr)
            return 2
        except SystemExit as exc:  # --help
            return exc.code if isinstance(exc.code, int) else 0
        if stop.is_set():
            return 0
        from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

        try:
            session = _Session(program, stop)
        except (_rclpy.RCLError, _rclpy.RMWError, _rclpy.RCUtilsError, ValueError) as exc:
            # e.g. ROS_DOMAIN_ID=abc, or an unknown RMW_IMPLEMENTATION
            print(f"{program}: cannot join ROS: {_one_line(exc)}", file=sys.stderr)
            return 2
        return body(args, session)
    except UsageError as exc:
        print(f"{program}: {exc}", file=sys.stderr)
        return 2
    except ToolError as exc:
        print(f"{program}: {exc}", file=sys.stderr)
        return 1
    except (_InterruptError, KeyboardInterrupt):
        return 0
    except BrokenPipeError:
        # `rns_topic echo ... | head`: the reader left; no traceback at interpreter exit either
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    finally:
        if session is not None:
            session.close()
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def _one_line(error: BaseException) -> str:
    """rcl's message on one line, without its C source locations."""
    text = str(error).split(", at /")[0]
    # rcl's name validation appends a line with a caret under the bad character
    return " ".join(text.split()).removesuffix(" ^")


# --- rns_param ------------------------------------------------------------------------------------
_TYPE_NAMES = {
    0: "not set",
    1: "boolean",
    2: "integer",
    3: "double",
    4: "string",
    5: "byte array",
    6: "boolean array",
    7: "integer array",
    8: "double array",
    9: "string array",
}
_GET_LABELS = {
    1: "Boolean value is",
    2: "Integer value is",
    3: "Double value is",
    4: "String value is",
    5: "Byte values are",
    6: "Boolean values are",
    7: "Integer values are",
    8: "Double values are",
    9: "String values are",
}


def parse_parameter_value(text: str, declared: int = 0):
    """``VALUE`` of ``rns_param set`` as an ``rcl_interfaces/ParameterValue``, typed like
    ``ros2 param set`` does: YAML bool / int / float, a homogeneous YAML list, else a string.

    ``declared`` is the parameter's current ``ParameterType`` (0: unknown). Where ros2 would send
    a value the node then rejects for its type, this one adapts: an integer (array) for a double
    (array) parameter is sent as a double (``epsilon 1``), anything for a string parameter as the
    text typed (``frame_id 123``), and a list mixing integers and floats is a double array. Text
    that is not valid YAML, or YAML of another kind (a mapping, a date, null), is a string.
    """
    from rcl_interfaces.msg import ParameterType, ParameterValue

    if declared == ParameterType.PARAMETER_STRING:
        return ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=text)
    value = _parse_yaml_value(text)
    if declared == ParameterType.PARAMETER_DOUBLE and value.type == ParameterType.PARAMETER_INTEGER:
        return ParameterValue(
            type=ParameterType.PARAMETER_DOUBLE, double_value=float(value.integer_value)
        )
    if (
        declared == ParameterType.PARAMETER_DOUBLE_ARRAY
        and value.type == ParameterType.PARAMETER_INTEGER_ARRAY
    ):
        return ParameterValue(
            type=ParameterType.PARAMETER_DOUBLE_ARRAY,
            double_array_value=[float(v) for v in value.integer_array_value],
        )
    return value


def _parse_yaml_value(text: str):
    """ros2 param's typing of ``text`` (see :func:`parse_parameter_value`), without its crashes."""
    import yaml
    from rcl_interfaces.msg import ParameterType, ParameterValue

    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        value = text
    # bool is an int in Python: test it first, everywhere
    if isinstance(value, bool):
        return ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=value)
    if isinstance(value, int):
        return ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=value)
    if isinstance(value, float):
        return ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value)
    if isinstance(value, list):
        if all(isinstance(v, bool) for v in value):
            return ParameterValue(type=ParameterType.PARAMETER_BOOL_ARRAY, bool_array_value=value)
        if all(isinstance(v, int) and not isinstance(v, bool) for v in value):
            return ParameterValue(
                type=ParameterType.PARAMETER_INTEGER_ARRAY, integer_array_value=value
            )
        if all(isinstance(v, int | float) and not isinstance(v, bool) for v in value):
            return ParameterValue(
                type=ParameterType.PARAMETER_DOUBLE_ARRAY,
                double_array_value=[float(v) for v in value],
            )
        if all(isinstance(v, str) for v in value):
            return ParameterValue(
                type=ParameterType.PARAMETER_STRING_ARRAY, string_array_value=value
            )
    if isinstance(value, str):
        return ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=value)
    return ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=text)


def _timeout_parser(what: str) -> argparse.ArgumentParser:
    """The ``--timeout SEC`` option every subcommand shares (a parent parser)."""
    common = _Parser(add_help=False)
    common.add_argument(
        "--timeout",
        type=_timeout,
        default=DEFAULT_TIMEOUT,
        metavar="SEC",
        help=f"{what} (default {DEFAULT_TIMEOUT:g})",
    )
    return common


def _param_parser() -> argparse.ArgumentParser:
    common = _timeout_parser("wait this long for the node and each reply")
    parser = _Parser(
        prog="rns_param",
        description="Inspect and change parameters of running ROS 2 nodes, like `ros2 param` "
        "(which is not on PyPI). Joins the domain of ROS_DOMAIN_ID / "
        "ROS_AUTOMATIC_DISCOVERY_RANGE.",
        epilog="exit codes: 0 ok or Ctrl-C; 1 node / parameter not found, value refused; "
        "2 bad usage",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    listing = commands.add_parser(
        "list", parents=[common], help="names of the parameters of NODE (or of every node)"
    )
    listing.add_argument("node", nargs="?", metavar="NODE")
    listing.add_argument(
        "--spin-time",
        type=_timeout,
        default=DEFAULT_SPIN_TIME,
        metavar="SEC",
        help="without NODE: discovery time after the first node appeared "
        f"(default {DEFAULT_SPIN_TIME:g})",
    )
    get = commands.add_parser("get", parents=[common], help="value of one parameter")
    get.add_argument("node", metavar="NODE")
    get.add_argument("name", metavar="NAME")
    get.add_argument("--hide-type", action="store_true", help="print the value only")
    set_ = commands.add_parser(
        "set",
        parents=[common],
        help="set one parameter; VALUE is YAML: true, 3, 0.5, sc, [1, 2]",
    )
    set_.add_argument("node", metavar="NODE")
    set_.add_argument("name", metavar="NAME")
    set_.add_argument("value", metavar="VALUE")
    describe = commands.add_parser(
        "describe", parents=[common], help="type, description, ranges, constraints, read-only"
    )
    describe.add_argument("node", metavar="NODE")
    describe.add_argument("names", nargs="+", metavar="NAME")
    return parser


def _parameter_client(session: _Session, node_name: str, timeout: float):
    """An AsyncParameterClient of ``node_name`` whose services are up, else ToolError."""
    from rclpy.exceptions import NameValidationException
    from rclpy.parameter_client import AsyncParameterClient

    node_name = _absolute(node_name)
    try:
        client = AsyncParameterClient(session.node, node_name)
    except NameValidationException as exc:
        raise UsageError(f"invalid node name {node_name!r}: {_one_line(exc)}") from None
    if not session.spin_until(client.services_are_ready, timeout):
        raise ToolError(
            f"node {node_name} not found within {timeout:g} s (no parameter services; check the "
            "name with `rns_param list`, ROS_DOMAIN_ID and ROS_AUTOMATIC_DISCOVERY_RANGE)"
        )
    return client


def _call(session: _Session, future, what: str, timeout: float):
    """The result of a service ``future``, or ToolError after ``timeout`` [s]."""
    if not session.spin_until(future.done, timeout):
        raise ToolError(f"no reply to {what} within {timeout:g} s")
    return future.result()


def _format_value(value) -> str:
    from rclpy.parameter import parameter_value_to_python

    python = parameter_value_to_python(value)
    if isinstance(python, list):
        return "[" + ", ".join(str(v) for v in python) + "]"
    return str(python)


def _param_list(args, session: _Session) -> int:
    if args.node is not None:
        node_name = _absolute(args.node)
        client = _parameter_client(session, node_name, args.timeout)
        response = _call(session, client.list_parameters(), "list_parameters", args.timeout)
        for name in sorted(response.result.names):
            print(f"  {name}", flush=True)
        return 0
    session.discover(args.spin_time, args.timeout)
    found = False
    for name, namespace in sorted(session.node.get_node_names_and_namespaces()):
        if name.startswith("_"):  # hidden nodes: ros2cli's and ours
            continue
        node_name = namespace.rstrip("/") + "/" + name
        try:
            client = _parameter_client(session, node_name, min(args.timeout, 1.0))
            response = _call(session, client.list_parameters(), "list_parameters", args.timeout)
        except ToolError:
            continue  # a node without parameter services (or gone meanwhile)
        found = True
        print(f"{node_name}:")
        for parameter in sorted(response.result.names):
            print(f"  {parameter}")
        sys.stdout.flush()
    if not found:
        raise ToolError(
            f"no node with parameters found within {args.timeout:g} s (ROS_DOMAIN_ID="
            f"{os.environ.get('ROS_DOMAIN_ID', '0')})"
        )
    return 0


def _param_get(args, session: _Session) -> int:
    node_name = _absolute(args.node)
    client = _parameter_client(session, node_name, args.timeout)
    response = _call(session, client.get_parameters([args.name]), "get_parameters", args.timeout)
    if not response.values or response.values[0].type == 0:
        raise ToolError(f"parameter {args.name!r} is not set on {node_name}")
    value = response.values[0]
    text = _format_value(value)
    print(text if args.hide_type else f"{_GET_LABELS[value.type]}: {text}", flush=True)
    return 0


def _param_set(args, session: _Session) -> int:
    from rcl_interfaces.msg import Parameter as ParameterMsg

    node_name = _absolute(args.node)
    client = _parameter_client(session, node_name, args.timeout)
    future = client.get_parameter_types([args.name])
    types = _call(session, future, "get_parameter_types", args.timeout).types
    value = parse_parameter_value(args.value, declared=types[0] if types else 0)
    future = client.set_parameters([ParameterMsg(name=args.name, value=value)])
    response = _call(session, future, "set_parameters", args.timeout)
    result = response.results[0] if response.results else None
    if result is None or not result.successful:
        reason = result.reason if result is not None and result.reason else "no reason given"
        if not types or types[0] == 0:  # rclpy's reason then names no parameter
            reason += f" (parameter {args.name!r} is not declared on {node_name})"
        # stdout like ros2 param; the exit code is for scripts
        print(f"Setting parameter failed: {reason}", flush=True)
        return 1
    print("Set parameter successful", flush=True)
    return 0


def _param_describe(args, session: _Session) -> int:
    node_name = _absolute(args.node)
    client = _parameter_client(session, node_name, args.timeout)
    future = client.describe_parameters(list(args.names))
    response = _call(session, future, "describe_parameters", args.timeout)
    if len(response.descriptors) != len(args.names):
        # rclpy answers nothing at all when one name is undeclared: say which
        types = _call(
            session, client.get_parameter_types(list(args.names)), "get_types", args.timeout
        )
        missing = [n for n, t in zip(args.names, types.types, strict=False) if t == 0]
        raise ToolError(f"parameter {', '.join(missing or args.names)} not declared on {node_name}")
    for descriptor in response.descriptors:
        print(f"Parameter name: {descriptor.name}")
        print(f"  Type: {_TYPE_NAMES.get(descriptor.type, descriptor.type)}")
        if descriptor.description:
            print(f"  Description: {descriptor.description}")
        print("  Constraints:")
        print(f"    Read only: {'true' if descriptor.read_only else 'false'}")
        if descriptor.dynamic_typing:
            print("    Dynamic typing: true")
        for bounds in (*descriptor.floating_point_range, *descriptor.integer_range):
            print(f"    Min value: {bounds.from_value}")
            print(f"    Max value: {bounds.to_value}")
            if bounds.step:
                print(f"    Step: {bounds.step}")
        if descriptor.additional_constraints:
            print(f"    Additional constraints: {descriptor.additional_constraints}")
    sys.stdout.flush()
    return 0


def param_main(argv: Sequence[str] | None = None) -> int:
    """``rns_param list|get|set|describe NODE [NAME] [VALUE]``; returns the exit code."""
    commands = {
        "list": _param_list,
        "get": _param_get,
        "set": _param_set,
        "describe": _param_describe,
    }
    return _run("rns_param", _param_parser(), argv, lambda args, s: commands[args.command](args, s))


# --- rns_topic ------------------------------------------------------------------------------------
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


def _topic_type(session: _Session, topic: str, timeout: float) -> tuple[str, Any]:
    """(absolute name, message class) of ``topic`` once it is in the graph, else ToolError."""
    topic = _absolute(topic)
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


def _subscription_qos(session: _Session, topic: str):
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
    common = _timeout_parser("wait this long for TOPIC (list: any node) to appear")
    parser = _Parser(
        prog="rns_topic",
        description="List, print and time ROS 2 topics, like `ros2 topic` (which is not on "
        "PyPI). Joins the domain of ROS_DOMAIN_ID / ROS_AUTOMATIC_DISCOVERY_RANGE.",
        epilog="exit codes: 0 ok or Ctrl-C; 1 topic not found or its type not installed; "
        "2 bad usage",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
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
        type=_timeout,
        default=DEFAULT_SPIN_TIME,
        metavar="SEC",
        help=f"discovery time after the first node appeared (default {DEFAULT_SPIN_TIME:g})",
    )
    echo = commands.add_parser("echo", parents=[common], help="print messages as YAML")
    echo.add_argument("topic", metavar="TOPIC")
    echo.add_argument("--once", action="store_true", help="print one message and exit")
    echo.add_argument("--count", type=_positive_int, metavar="N", help="exit after N messages")
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
        type=_positive_int,
        default=DEFAULT_WINDOW,
        metavar="N",
        help=f"intervals the statistics cover (default {DEFAULT_WINDOW})",
    )
    hz.add_argument(
        "--duration",
        type=_timeout,
        metavar="SEC",
        help="exit after SEC seconds (default: run until Ctrl-C)",
    )
    return parser


def _topic_list(args, session: _Session) -> int:
    session.discover(args.spin_time, args.timeout)
    for name, types in sorted(session.node.get_topic_names_and_types()):
        print(f"{name} [{', '.join(types)}]")
    sys.stdout.flush()
    return 0


def _topic_echo(args, session: _Session) -> int:
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


def _topic_hz(args, session: _Session) -> int:
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
    return _run("rns_topic", _topic_parser(), argv, lambda args, s: commands[args.command](args, s))


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m rns_ros.rostools param|topic ...``: either tool; returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    tools = {"param": param_main, "topic": topic_main}
    if not argv or argv[0] not in tools:
        if argv and argv[0] in ("-h", "--help"):
            print(
                "usage: python -m rns_ros.rostools {param,topic} ... (see rns_param --help, "
                "rns_topic --help)"
            )
            return 0
        print("rns_ros.rostools: expected 'param' or 'topic' first", file=sys.stderr)
        return 2
    return tools[argv[0]](argv[1:])


if __name__ == "__main__":
    raise SystemExit(main())
