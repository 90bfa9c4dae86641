"""The Jazzy ``main()`` idiom shared by all rns_ros nodes, ``--help`` from parameters, and the
last words of a node going down (a final zero command, its worker thread stopped)."""

from __future__ import annotations

import ctypes
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Protocol

import rclpy
from rclpy.duration import Duration
from rclpy.exceptions import NameValidationException, ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future
from rclpy.utilities import remove_ros_args

from rns_ros.cli import (
    STOP_WITH_PARENT,
    check_domain_id_environment,
    describe_ros_error,
    one_line,
    startup_interrupted,
)
from rns_ros.core.errors import RnsError
from rns_ros.nodes.parameters import ParameterSpec, warn_unknown_parameters
from rns_ros.nodes.realtime import schedule_node
from rns_ros.resources import apply_loopback_profile

#: What rcl / rclpy raise at start-up on a user's mistake rather than a bug: unparsable ROS
#: arguments or params file (RCLInvalidROSArgsError is an RCLError), an unknown --ros-args flag,
#: a bad ROS_DOMAIN_ID, a built-in parameter (use_sim_time) of the wrong type, a bad node name.
ROS_STARTUP_ERRORS = (
    _rclpy.RCLError,
    _rclpy.UnknownROSArgsError,
    _rclpy.RMWError,
    _rclpy.RCUtilsError,
    ParameterException,
    NameValidationException,
)


class NodeParameters(Protocol):
    """What a node's parameters module defines (e.g. :mod:`rns_ros.nodes.ptp_parameters`)."""

    NODE_NAME: str
    SUMMARY: str
    PARAMETERS: tuple[ParameterSpec, ...]


def parameter_help(executable: str, summary: str, specs: Sequence[ParameterSpec]) -> str:
    """Text for ``<executable> --help``: what the node does and every parameter."""
    lines = [
        f"usage: {executable} [--ros-args -p NAME:=VALUE ... --params-file FILE -r FROM:=TO]",
        "",
        summary,
        "",
        "parameters (defaults mirror config/*.yaml; [run time]: can be changed while the node "
        "runs, e.g. rns_param set /NODE NAME VALUE; the others are read at start-up):",
    ]
    for spec in specs:
        limits = ""
        if spec.choices:
            limits = f" one of {list(spec.choices)}"
        elif spec.low is not None:
            limits = f" in [{spec.low}, {spec.high}]"
        when = "" if spec.read_only else " [run time]"
        lines.append(f"  {spec.name} = {spec.default!r}{limits} {spec.unit}".rstrip() + when)
        lines.append(f"      {spec.description}")
    return "\n".join(lines)


def answer_help(parameters: NodeParameters, argv: Sequence[str]) -> int | None:
    """Exit code 0 after printing ``--help`` (``-h``), 2 after one line naming unparsable ROS
    arguments; None when the node is to start."""
    try:
        if {"-h", "--help"} & set(remove_ros_args(list(argv))[1:]):
            print(parameter_help(parameters.NODE_NAME, parameters.SUMMARY, parameters.PARAMETERS))
            return 0
    except ROS_STARTUP_ERRORS as exc:
        print(f"{parameters.NODE_NAME}: {describe_ros_error(exc)}", file=sys.stderr)
        return 2
    return None


def start_node(executable: str, factory: Callable[[], Node], argv: Sequence[str]) -> Node | None:
    """rclpy.init (without rclpy's signal handlers) and ``factory()``; None after printing one
    line ``<executable>: <problem>`` when rcl rejects the ROS arguments, params file or
    environment (:data:`ROS_STARTUP_ERRORS`). Overrides naming no parameter of the node are
    logged with the closest valid name. :class:`RnsError` from the factory propagates. With
    localhost discovery the DDS sockets go on the loopback interface
    (:func:`~rns_ros.resources.apply_loopback_profile`)."""
    try:
        check_domain_id_environment()
        apply_loopback_profile()
        rclpy.init(args=list(argv), signal_handler_options=SignalHandlerOptions.NO)
        node = factory()
    except ROS_STARTUP_ERRORS as exc:
        print(f"{executable}: {describe_ros_error(exc)}", file=sys.stderr)
        return None
    warn_unknown_parameters(node)
    return node


#: prctl option: the signal the kernel sends this process when its parent ends (Linux).
PR_SET_PDEATHSIG = 1


def stop_with_parent(env: Mapping[str, str] | None = None) -> bool:
    """When ``STOP_WITH_PARENT`` (:mod:`rns_ros.cli`) names this process's parent, have the
    kernel send it SIGINT once the parent ends (Linux ``prctl(PR_SET_PDEATHSIG)``): a node
    started by ``rns_demo`` or a test stops and closes its files, as on Ctrl-C, when that
    process is killed outright, instead of running on unseen. A named process already gone is
    the same SIGINT at once. Returns whether the kernel watches the parent."""
    text = (os.environ if env is None else env).get(STOP_WITH_PARENT, "")
    if not sys.platform.startswith("linux") or not text.isdigit():
        return False
    parent = int(text)
    if os.getppid() != parent:  # started through another process, or the parent ended
        try:
            os.kill(parent, 0)
        except ProcessLookupError:
            os.kill(os.getpid(), signal.SIGINT)
        except OSError:
            pass
        return False
    try:
        armed = ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGINT) == 0
    except (OSError, AttributeError):
        return False
    if armed and os.getppid() != parent:  # it ended between the two looks
        os.kill(os.getpid(), signal.SIGINT)
    return armed


def run_node(
    factory: Callable[[], Node],
    parameters: NodeParameters,
    args: Sequence[str] | None = None,
) -> int:
    """The ``main()`` of a node: create it, spin it until Ctrl-C or shutdown, tear down cleanly;
    return an exit code. ``parameters`` names the node and its parameters (``--help``).

    Exit codes: 0 after Ctrl-C / SIGTERM (also during start-up) or shutdown; 2 with one line
    ``<NODE_NAME>: <problem>`` on stderr for a start-up failure: bad parameters, model or
    configuration (:class:`RnsError`), or ROS arguments / params file / environment that rcl
    rejects (:data:`ROS_STARTUP_ERRORS`). Parameter overrides that name no parameter of the node
    are logged as warnings naming the closest valid name.
    """
    # rclpy's own SIGINT handler would shut the Context down before destroy_node() runs, and a
    # node could no longer publish its final zero command. Ctrl-C and SIGTERM only set a flag
    # that the spin loop reads: an exception raised from a signal handler can land inside
    # rclpy's C++ argument conversion, which turns it into a RuntimeError (exit code 1). The
    # handlers go in first, so Ctrl-C during rclpy.init or the node's construction is a
    # clean exit too. The Context is shut down last, in `finally`.
    stop = threading.Event()
    previous = {
        signum: signal.signal(signum, lambda _signum, _frame: stop.set())
        for signum in (signal.SIGINT, signal.SIGTERM)
    }
    if startup_interrupted():  # Ctrl-C while the imports ran (rns_ros.cli)
        stop.set()
    stop_with_parent()
    executable = parameters.NODE_NAME
    node = executor = None
    try:
        argv = list(sys.argv if args is None else args)
        code = answer_help(parameters, argv)
        if code is not None:
            return code
        if stop.is_set():
            return 0
        node = start_node(executable, factory, argv)
        if node is None:
            return 2
        # The events executor: rclpy's wait-set executors cost far more CPU per wake-up and stall
        # the output under load (scripts/benchmark.py --only latency); this one ticks steadily.
        executor = EventsExecutor()
        executor.add_node(node)
        # the node's own process only: a node embedded in a host process leaves its scheduling
        wanted = getattr(node, "realtime_scheduling", None)
        if wanted is not None:
            schedule_node(node, *wanted())
        # the executor dispatches in C++ for up to 0.1 s per call rather than returning to this
        # loop after each event: less CPU per received message
        never = Future()
        while rclpy.ok() and not stop.is_set():
            # bounded waits: the stop flag is read at least every 0.1 s
            executor.spin_until_future_complete(never, timeout_sec=0.1)
    except RnsError as exc:
        print(f"{executable}: {one_line(exc)}", file=sys.stderr)
        return 2
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        if executor is not None:
            executor.shutdown()
        rclpy.try_shutdown()
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    return 0


def publish_last(
    node: Node,
    publish: Callable[[], None],
    what: str,
    *,
    acked_by: Publisher | None = None,
    timeout: float = 0.5,
) -> None:
    """A node's last message (a zero command) from ``destroy_node``: ``publish()``, then up to
    ``timeout`` [s] for the reliable subscribers of ``acked_by`` to acknowledge it. The Context
    may already be going down (a second signal): a failure is logged as a warning."""
    try:
        publish()
        if acked_by is not None:
            acked_by.wait_for_all_acked(Duration(seconds=timeout))
    except Exception as exc:  # the Context may already be shut down
        node.get_logger().warn(f"could not publish the final {what}: {exc}")


def publish_copies(publish: Callable[[], None], count: int, gap: float) -> None:
    """``publish()`` ``count`` times, ``gap`` [s] apart: best effort may drop one copy."""
    for i in range(count):
        if i:
            time.sleep(gap)
        publish()


def stop_worker(thread: threading.Thread, *events: threading.Event, timeout: float = 2.0) -> None:
    """Set ``events`` (the worker's stop and wake-up flags), then join ``thread`` for up to
    ``timeout`` [s]."""
    for event in events:
        event.set()
    if thread.is_alive():
        thread.join(timeout=timeout)
