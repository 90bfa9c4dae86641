"""What ``rns_param``, ``rns_topic`` and ``rns_service`` share: a private ROS session, exit codes.

ros2cli is not on PyPI, so whoever installed rns_ros from wheels has no ``ros2`` command; the
console scripts (:mod:`rns_ros.apps.param`, :mod:`.topic`, :mod:`.service`) cover what
operating the rns_ros nodes needs, built only on rclpy and the installed message packages. They
join the ROS domain of the environment like ``ros2`` does (``ROS_DOMAIN_ID``,
``ROS_AUTOMATIC_DISCOVERY_RANGE``, ``RMW_IMPLEMENTATION``). Arguments and output are ros2cli
Jazzy's for the commands a teleop session uses (docs/ros2_integration.md lists what differs).
Exit codes: 0 on success and after Ctrl-C; 1 when the node, parameter, topic or service is not
found within ``--timeout`` or the request cannot be carried out (one line on stderr); 2 for bad
usage or a ROS environment rcl rejects (one line on stderr). A parameter the node refuses is
exit code 0 with ``Setting parameter failed: <the node's reason>`` on stderr, as with ros2.

Only the standard library is imported at module level: rclpy loads inside :func:`run_tool` after
its Ctrl-C handler is in place, so an early Ctrl-C is a quiet exit.
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from typing import NoReturn

from rns_ros.resources import apply_loopback_profile

#: Seconds to wait for a node's parameter services or a topic to show up in the graph.
DEFAULT_TIMEOUT = 5.0
#: Seconds of discovery after the first other node showed up, before listing the graph.
DEFAULT_SPIN_TIME = 0.5


class UsageError(Exception):
    """The command line is wrong (exit code 2)."""


class ToolError(Exception):
    """The request could not be carried out: node or topic not found, value refused (exit 1)."""


class _InterruptError(Exception):
    """Ctrl-C arrived (exit code 0)."""


class ToolParser(argparse.ArgumentParser):
    """argparse that reports a usage error as one exception instead of usage text + exit."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(message)


class ToolSession:
    """A private rclpy Context with one hidden node and an executor, torn down in :meth:`close`.

    ``stop`` is set by Ctrl-C; every wait below reads it at least every 50 ms.
    """

    def __init__(self, program: str, stop: threading.Event, node_name: str | None = None) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions

        self.stop = stop
        apply_loopback_profile()  # with localhost discovery, DDS sockets on 127.0.0.1 too
        self.context = rclpy.Context()
        # rclpy's own SIGINT handler would tear the Context down under a running wait; ours only
        # sets `stop`. The domain and discovery range come from the environment, like ros2.
        rclpy.init(
            args=[program], context=self.context, signal_handler_options=SignalHandlerOptions.NO
        )
        self.executor = SingleThreadedExecutor(context=self.context)
        # A leading underscore hides the node from `ros2 node list`, like ros2cli's own nodes.
        self.node = rclpy.create_node(
            node_name or f"_{program}_{os.getpid()}",
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
        [s]), then until the graph (nodes, topics, services) has not changed for ``spin_time``
        [s] (at most ``timeout`` more).

        A fixed spin time alone is not enough: a new DDS participant is usually matched within
        0.1 s on loopback, but now and then only at the next periodic announcement, ~3 s later;
        and on a loaded machine a node's endpoints come well after the node itself.
        """
        me = self.node.get_fully_qualified_name()

        def others() -> bool:
            return any(
                namespace.rstrip("/") + "/" + name != me
                for name, namespace in self.node.get_node_names_and_namespaces()
            )

        self.spin_until(others, timeout)
        end = time.monotonic() + timeout
        last, quiet_since = self._graph(), time.monotonic()

        def settled() -> bool:
            nonlocal last, quiet_since
            graph, now = self._graph(), time.monotonic()
            if graph != last:
                last, quiet_since = graph, now
            return now - quiet_since >= spin_time or now >= end

        self.spin_until(settled, None)

    def _graph(self) -> tuple:
        """What discovery has found so far: node, topic and service names with their types."""
        return (
            sorted(self.node.get_node_names_and_namespaces()),
            sorted((name, tuple(types)) for name, types in self.node.get_topic_names_and_types()),
            sorted((name, tuple(types)) for name, types in self.node.get_service_names_and_types()),
        )

    def close(self) -> None:
        import rclpy

        self.executor.remove_node(self.node)
        self.node.destroy_node()
        self.executor.shutdown()
        rclpy.try_shutdown(context=self.context)


def absolute_name(name: str) -> str:
    """``rns_controller`` -> ``/rns_controller`` (the tools' node lives in the root namespace)."""
    return name if name.startswith("/") else "/" + name


def seconds(text: str) -> float:
    """argparse type: a non-negative finite number of seconds."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"expected seconds >= 0, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return value


def positive_rate(text: str) -> float:
    """argparse type: a finite rate > 0 [Hz]."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a rate > 0 Hz, got {text!r}")
    return value


def positive_seconds(text: str) -> float:
    """argparse type: a finite number of seconds > 0."""
    value = seconds(text)
    if value == 0:
        raise argparse.ArgumentTypeError(f"expected seconds > 0, got {text!r}")
    return value


def count(text: str) -> int:
    """argparse type: an integer >= 0."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return value


def run_tool(
    program: str,
    parser: argparse.ArgumentParser,
    argv: Sequence[str] | None,
    body: Callable,
    node_name: Callable[[argparse.Namespace], str | None] = lambda _args: None,
) -> int:
    """Parse ``argv``, run ``body(args, session)`` under the exit-code contract (module docstring).
    ``node_name(args)``: the session node's name (None: a hidden one of its own).

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
        from rclpy.exceptions import NameValidationException
        from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
        from rclpy.validate_node_name import validate_node_name

        name = node_name(args)
        try:
            if name is not None:  # before rcl, which warns twice about a node it did not make
                validate_node_name(name)
            session = ToolSession(program, stop, name)
        except NameValidationException as exc:
            print(f"{program}: invalid node name {name!r}: {rcl_one_line(exc)}", file=sys.stderr)
            return 2
        except (_rclpy.RCLError, _rclpy.RMWError, _rclpy.RCUtilsError, ValueError) as exc:
            # e.g. ROS_DOMAIN_ID=abc, or an unknown RMW_IMPLEMENTATION
            print(f"{program}: cannot join ROS: {rcl_one_line(exc)}", file=sys.stderr)
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


def rcl_one_line(error: BaseException) -> str:
    """rcl's message on one line, without its C source locations."""
    text = str(error).split(", at /")[0]
    # rcl's name validation appends a line with a caret under the bad character
    return " ".join(text.split()).removesuffix(" ^")


def add_listing_arguments(listing: argparse.ArgumentParser, what: str) -> None:
    """The options of ``rns_topic list`` / ``rns_service list`` (``what``: topic or service),
    ros2's ``-t``, ``-c`` and ``-a`` with our ``--spin-time``."""
    listing.add_argument(
        "-t", "--show-types", action="store_true", help=f"additionally show the {what} type"
    )
    counts = ("-c", "--count-topics", "--count") if what == "topic" else ("-c", "--count-services")
    listing.add_argument(
        *counts,
        dest="count",
        action="store_true",
        help=f"only display the number of {what}s discovered",
    )
    listing.add_argument(
        "-a",
        f"--include-hidden-{what}s",
        *(["--all"] if what == "topic" else []),
        dest="include_hidden",
        action="store_true",
        help=f"consider hidden {what}s as well (a name part starting with '_')",
    )
    listing.add_argument(
        "--spin-time",
        type=seconds,
        default=DEFAULT_SPIN_TIME,
        metavar="SEC",
        help=f"discovery time after the first node appeared (default {DEFAULT_SPIN_TIME:g})",
    )


def is_hidden(name: str) -> bool:
    """A hidden topic or service (a name part starting with '_'), as ros2 lists them."""
    return any(part.startswith("_") for part in name.split("/"))


def _timeout_parser(what: str) -> argparse.ArgumentParser:
    """The ``--timeout SEC`` option every subcommand shares (a parent parser)."""
    common = ToolParser(add_help=False)
    common.add_argument(
        "--timeout",
        type=seconds,
        default=DEFAULT_TIMEOUT,
        metavar="SEC",
        help=f"{what} (default {DEFAULT_TIMEOUT:g})",
    )
    return common


def tool_parser(
    prog: str, description: str, epilog: str, timeout_help: str
) -> tuple[argparse.ArgumentParser, argparse._SubParsersAction, argparse.ArgumentParser]:
    """A tool's parser, its subcommands and the parent parser of their shared ``--timeout SEC``
    (``timeout_help`` says what it waits for)."""
    common = _timeout_parser(timeout_help)
    parser = ToolParser(prog=prog, description=description, epilog=epilog)
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    return parser, commands, common
