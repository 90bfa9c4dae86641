"""The Jazzy ``main()`` idiom shared by all rns_ros nodes, and ``--help`` from parameters."""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Callable, Sequence

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args

from rns_ros.core.errors import RnsError
from rns_ros.nodes.parameters import ParameterSpec


def parameter_help(executable: str, summary: str, specs: Sequence[ParameterSpec]) -> str:
    """Text for ``<executable> --help``: what the node does and every parameter."""
    lines = [
        f"usage: {executable} [--ros-args -p NAME:=VALUE ... --params-file FILE -r FROM:=TO]",
        "",
        summary,
        "",
        "parameters (defaults mirror config/*.yaml):",
    ]
    for spec in specs:
        limits = ""
        if spec.choices:
            limits = f" one of {list(spec.choices)}"
        elif spec.low is not None:
            limits = f" in [{spec.low}, {spec.high}]"
        lines.append(f"  {spec.name} = {spec.default!r}{limits} {spec.unit}".rstrip())
        lines.append(f"      {spec.description}")
    return "\n".join(lines)


def run_node(
    factory: Callable[[], Node],
    *,
    executable: str,
    summary: str,
    specs: Sequence[ParameterSpec],
    args: Sequence[str] | None = None,
) -> int:
    """Create the node, spin it until Ctrl-C or shutdown, tear down cleanly; return an exit code.

    Bad parameters (:class:`RnsError`) are reported in one line and give exit code 2.
    """
    argv = list(sys.argv if args is None else args)
    if {"-h", "--help"} & set(remove_ros_args(argv)[1:]):
        print(parameter_help(executable, summary, specs))
        return 0
    # rclpy's own SIGINT handler would shut the Context down before destroy_node() runs, and a
    # node could no longer publish its final zero command. Ctrl-C and SIGTERM only set a flag
    # that the spin loop reads: an exception raised from a signal handler can land inside
    # rclpy's C++ argument conversion, which turns it into a RuntimeError (exit code 1 seen in
    # CI). The Context is shut down last, in `finally`.
    rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    stop = threading.Event()
    previous = {
        signum: signal.signal(signum, lambda _signum, _frame: stop.set())
        for signum in (signal.SIGINT, signal.SIGTERM)
    }
    node = executor = None
    try:
        node = factory()
        # The events executor: rclpy's wait-set executors cost ~0.6 ms of CPU per wake-up here,
        # and the multi-threaded one kept the controller at 90 % of a core with output stalls of
        # up to 1.5 s (scripts/benchmark.py --only latency); this one ticks steadily.
        executor = EventsExecutor()
        executor.add_node(node)
        while rclpy.ok() and not stop.is_set():
            # bounded waits: the stop flag is read at least every 0.1 s
            executor.spin_once(timeout_sec=0.1)
    except RnsError as exc:
        print(f"{executable}: {exc}", file=sys.stderr)
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
