"""``rns_param``: ``ros2 param`` for a PyPI-only install.

::

    rns_param list [NODE]                 parameter names (of every node without NODE)
    rns_param get NODE NAME               "Double value is: 0.2"
    rns_param set NODE NAME VALUE         VALUE is YAML like ros2 param: true, 3, 0.5, sc, [1, 2]
    rns_param describe NODE NAME...       description, type, ranges, constraints, read-only

Domain, exit codes and Ctrl-C: :mod:`rns_ros.tool_session`.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from rns_ros.tool_session import (
    DEFAULT_SPIN_TIME,
    ToolError,
    ToolSession,
    UsageError,
    absolute_name,
    rcl_one_line,
    run_tool,
    seconds,
    tool_parser,
)

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

    Raises:
        UsageError: ``text`` is YAML over a limit of :mod:`rns_ros.core.yaml_input` (aliases).
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

    from rns_ros.core.errors import ConfigError
    from rns_ros.core.yaml_input import load_yaml

    try:
        value = load_yaml(text, "VALUE")
    except yaml.YAMLError:
        value = text
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
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


def _param_parser() -> argparse.ArgumentParser:
    parser, commands, common = tool_parser(
        "rns_param",
        "Inspect and change parameters of running ROS 2 nodes, like `ros2 param` (which is not "
        "on PyPI). Joins the domain of ROS_DOMAIN_ID / ROS_AUTOMATIC_DISCOVERY_RANGE.",
        "exit codes: 0 ok or Ctrl-C; 1 node / parameter not found, value refused; 2 bad usage",
        "wait this long for the node and each reply",
    )
    listing = commands.add_parser(
        "list", parents=[common], help="names of the parameters of NODE (or of every node)"
    )
    listing.add_argument("node", nargs="?", metavar="NODE")
    listing.add_argument(
        "--spin-time",
        type=seconds,
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


def _parameter_client(session: ToolSession, node_name: str, timeout: float):
    """An AsyncParameterClient of ``node_name`` whose services are up, else ToolError."""
    from rclpy.exceptions import NameValidationException
    from rclpy.parameter_client import AsyncParameterClient

    node_name = absolute_name(node_name)
    try:
        client = AsyncParameterClient(session.node, node_name)
    except NameValidationException as exc:
        raise UsageError(f"invalid node name {node_name!r}: {rcl_one_line(exc)}") from None
    if not session.spin_until(client.services_are_ready, timeout):
        raise ToolError(
            f"node {node_name} not found within {timeout:g} s (no parameter services; check the "
            "name with `rns_param list`, ROS_DOMAIN_ID and ROS_AUTOMATIC_DISCOVERY_RANGE)"
        )
    return client


def _call(session: ToolSession, future, what: str, timeout: float):
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


def _param_list(args, session: ToolSession) -> int:
    if args.node is not None:
        node_name = absolute_name(args.node)
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


def _param_get(args, session: ToolSession) -> int:
    node_name = absolute_name(args.node)
    client = _parameter_client(session, node_name, args.timeout)
    response = _call(session, client.get_parameters([args.name]), "get_parameters", args.timeout)
    if not response.values or response.values[0].type == 0:
        raise ToolError(f"parameter {args.name!r} is not set on {node_name}")
    value = response.values[0]
    text = _format_value(value)
    print(text if args.hide_type else f"{_GET_LABELS[value.type]}: {text}", flush=True)
    return 0


def _param_set(args, session: ToolSession) -> int:
    from rcl_interfaces.msg import Parameter as ParameterMsg

    node_name = absolute_name(args.node)
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


def _param_describe(args, session: ToolSession) -> int:
    node_name = absolute_name(args.node)
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
    return run_tool(
        "rns_param", _param_parser(), argv, lambda args, s: commands[args.command](args, s)
    )


if __name__ == "__main__":
    raise SystemExit(param_main())
