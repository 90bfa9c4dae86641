"""``rns_service``: ``ros2 service`` for a PyPI-only install, with ros2cli Jazzy's arguments
and output.

::

    rns_service list [-t] [-c] [-a]           service names (with [types]: -t)
    rns_service call SERVICE TYPE ['YAML']    e.g. /rns_simulator/reset std_srvs/srv/Trigger

``call`` fills the request from the YAML mapping of its fields, as ``ros2 service call`` does,
waits for the service as long as it takes (``--timeout`` limits it) printing ``waiting for service
to become available...``, then prints the request and the response as ros2 does; ``-r HZ``
repeats the call. Domain, exit codes and Ctrl-C: :mod:`rns_ros.tool_session`; a response
arriving is exit code 0 whatever it says (``success: false`` included), as with ros2.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence

from rns_ros.ros_messages import import_interface, message_from_yaml
from rns_ros.tool_session import (
    ToolError,
    ToolSession,
    UsageError,
    add_listing_arguments,
    is_hidden,
    positive_rate,
    positive_seconds,
    rcl_one_line,
    run_tool,
    tool_parser,
)


def _service_parser():
    parser, commands, common = tool_parser(
        "rns_service",
        "List and call ROS 2 services with the arguments of `ros2 service` (which is not on "
        "PyPI). Joins the domain of ROS_DOMAIN_ID / ROS_AUTOMATIC_DISCOVERY_RANGE.",
        "exit codes: 0 a response arrived, or Ctrl-C; 1 service not found within --timeout, of "
        "another type, or its type not installed; 2 bad usage or a request that does not fit "
        "its type",
        "wait this long for any node to appear",
    )
    listing = commands.add_parser("list", parents=[common], help="service names (-t: and types)")
    add_listing_arguments(listing, "service")
    call = commands.add_parser(
        "call",
        help="call a service with a request given as YAML",
        description="Call SERVICE of TYPE with the request filled from the YAML mapping of its "
        "fields, like `ros2 service call` (e.g. rns_service call /rns_ptp/cancel "
        "std_srvs/srv/Trigger). A Time field takes `now`, a Header `auto`. Waits for the "
        "service and its response as long as they take, unless --timeout.",
    )
    call.add_argument("service", metavar="SERVICE")
    call.add_argument("type", metavar="TYPE", help="service type, e.g. std_srvs/srv/Trigger")
    call.add_argument(
        "values", metavar="YAML", nargs="?", default="{}", help="the request (default '{}')"
    )
    call.add_argument("--stdin", action="store_true", help="read the YAML from standard input")
    call.add_argument(
        "-r", "--rate", type=positive_rate, metavar="HZ", help="repeat the call at this rate"
    )
    call.add_argument(
        "--timeout",
        type=positive_seconds,
        metavar="SEC",
        help="give up (exit 1) when the service or a response takes longer than SEC (default: "
        "wait as long as it takes, as ros2)",
    )
    return parser


def _service_list(args, session: ToolSession) -> int:
    session.discover(args.spin_time, args.timeout)
    me = session.node.get_fully_qualified_name()
    services = [
        (name, types)
        for name, types in sorted(session.node.get_service_names_and_types())
        if not name.startswith(me + "/") and (args.include_hidden or not is_hidden(name))
    ]
    if args.count:
        print(len(services))
    else:
        for name, types in services:
            print(f"{name} [{', '.join(types)}]" if args.show_types else name)
    sys.stdout.flush()
    return 0


def _service_call(args, session: ToolSession) -> int:
    srv_type = import_interface(args.type, "srv")
    if args.stdin and args.values != "{}":
        raise UsageError("give the YAML either as an argument or with --stdin, not both")
    request = message_from_yaml(
        sys.stdin.read() if args.stdin else args.values,
        srv_type.Request,
        lambda: session.node.get_clock().now().to_msg(),
    )
    try:
        service = session.node.resolve_service_name(args.service)
    except ValueError as exc:  # rclpy's name errors
        raise UsageError(rcl_one_line(exc)) from None
    type_name = f"{srv_type.__module__.split('.')[0]}/srv/{srv_type.__name__}"
    client = session.node.create_client(srv_type, service)

    def ready() -> bool:
        if client.service_is_ready():
            return True
        # the graph lists clients' types too: another type there may be only ours' neighbour
        types = dict(session.node.get_service_names_and_types()).get(service, [])
        if any(t != type_name for t in types):
            offered = _server_types(session, service)
            if offered and type_name not in offered:
                raise ToolError(f"service {service} has type {', '.join(offered)}, not {type_name}")
        return False

    if not client.service_is_ready():
        print("waiting for service to become available...", flush=True)
        if not session.spin_until(ready, args.timeout):
            raise ToolError(
                f"service {service} not found within {args.timeout:g} s (see `rns_service "
                "list`; check ROS_DOMAIN_ID and ROS_AUTOMATIC_DISCOVERY_RANGE)"
            )
    while True:
        print(f"requester: making request: {request!r}\n", flush=True)
        sent = time.monotonic()
        future = client.call_async(request)
        if not session.spin_until(future.done, args.timeout):
            raise ToolError(f"no response from {service} within {args.timeout:g} s")
        print(f"response:\n{future.result()!r}\n", flush=True)
        if args.rate is None:
            return 0
        due = sent + 1.0 / args.rate
        session.spin_until(lambda due=due: time.monotonic() >= due, None)


def _server_types(session: ToolSession, service: str) -> list[str]:
    """Types of ``service`` as its servers offer it (every node's)."""
    offered = set()
    for name, namespace in session.node.get_node_names_and_namespaces():
        for server, types in session.node.get_service_names_and_types_by_node(name, namespace):
            if server == service:
                offered.update(types)
    return sorted(offered)


def service_main(argv: Sequence[str] | None = None) -> int:
    """``rns_service list|call [SERVICE TYPE [YAML]]``; returns the exit code."""
    commands = {"list": _service_list, "call": _service_call}
    return run_tool(
        "rns_service", _service_parser(), argv, lambda args, s: commands[args.command](args, s)
    )


if __name__ == "__main__":
    raise SystemExit(service_main())
