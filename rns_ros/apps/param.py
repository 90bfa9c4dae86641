"""``rns_param``: ``ros2 param`` for a PyPI-only install, with ros2cli Jazzy's arguments and
output.

::

    rns_param list [NODE]                 parameter names (of every node without NODE)
    rns_param get NODE NAME               "Double value is: 0.2"
    rns_param set NODE NAME VALUE         VALUE is YAML like ros2 param: true, 3, 0.5, sc, [1, 2]
    rns_param describe NODE NAME...       description, type, ranges, constraints, read-only
    rns_param dump NODE                   every parameter as a params file (/NODE: ros__parameters:)
    rns_param load NODE FILE              set the parameters of a params file, one by one

Domain, exit codes and Ctrl-C: :mod:`rns_ros.tool_session`.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import Any

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

#: Seconds after which a parameter service call without reply is made again (:func:`_call`).
ASK_AGAIN_AFTER = 1.0
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
    return _adapted(_parse_yaml_value(text), declared, text)


def _adapted(value, declared: int, text: str):
    """``value`` (a ParameterValue) as the ``declared`` ParameterType takes it (0: as it is): an
    integer (array) for a double (array) parameter as a double (array), anything for a string
    parameter as ``text``, an empty array as an empty one of the declared type."""
    from rcl_interfaces.msg import ParameterType as T
    from rcl_interfaces.msg import ParameterValue

    if declared == T.PARAMETER_STRING and value.type != T.PARAMETER_STRING:
        return ParameterValue(type=T.PARAMETER_STRING, string_value=text)
    if declared == T.PARAMETER_DOUBLE and value.type == T.PARAMETER_INTEGER:
        return ParameterValue(type=T.PARAMETER_DOUBLE, double_value=float(value.integer_value))
    if declared == T.PARAMETER_DOUBLE_ARRAY and value.type == T.PARAMETER_INTEGER_ARRAY:
        return ParameterValue(
            type=T.PARAMETER_DOUBLE_ARRAY,
            double_array_value=[float(v) for v in value.integer_array_value],
        )
    arrays = {
        T.PARAMETER_BYTE_ARRAY: "byte_array_value",
        T.PARAMETER_BOOL_ARRAY: "bool_array_value",
        T.PARAMETER_INTEGER_ARRAY: "integer_array_value",
        T.PARAMETER_DOUBLE_ARRAY: "double_array_value",
        T.PARAMETER_STRING_ARRAY: "string_array_value",
    }
    if declared in arrays and value.type in arrays and not len(getattr(value, arrays[value.type])):
        return ParameterValue(type=declared)
    return value


def _parse_yaml_value(text: str):
    """ros2 param's typing of ``text`` (see :func:`parse_parameter_value`), without its crashes."""
    import yaml

    from rns_ros.core.errors import ConfigError
    from rns_ros.core.yaml_input import load_yaml

    try:
        value = load_yaml(text, "VALUE")
    except yaml.YAMLError:
        value = text
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    return _python_value(value, text)


def _python_value(value, text: str):
    """``value`` (what YAML made of ``text``) as a ParameterValue typed as ros2 param types it;
    anything else (a mapping, a date, null, a mixed list) as the string ``text``."""
    from rcl_interfaces.msg import ParameterType, ParameterValue

    # bool is an int in Python: test it first, everywhere
    if isinstance(value, bool):
        return ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=value)
    if isinstance(value, int):
        return ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=value)
    if isinstance(value, float):
        return ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value)
    if isinstance(value, list):
        if value and all(isinstance(v, bytes) for v in value):  # !!binary items
            return ParameterValue(
                type=ParameterType.PARAMETER_BYTE_ARRAY, byte_array_value=list(value)
            )
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
        "exit codes: 0 ok (also when the node refuses a value: 'Setting parameter failed' on "
        "stderr, as ros2) or Ctrl-C; 1 node / parameter not found; 2 bad usage",
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
    dump = commands.add_parser(
        "dump",
        parents=[common],
        help="every parameter of NODE as a params file",
        description="Print every parameter of NODE as ros2 param dump does: the YAML of a "
        "params file (/NODE: ros__parameters: ...), for `rns_param load` or --params-file.",
    )
    dump.add_argument("node", metavar="NODE")
    dump.add_argument(
        "--output-dir",
        type=Path,
        metavar="DIR",
        help="write DIR/<node>.yaml instead of printing (Humble's option; Jazzy's ros2 prints "
        "only, to be redirected)",
    )
    load = commands.add_parser(
        "load",
        parents=[common],
        help="set the parameters of a params file on NODE",
        description="Set every parameter of NODE's section of FILE (a params file, as `dump` "
        "writes it), one by one, reporting each as ros2 param load does.",
    )
    load.add_argument("node", metavar="NODE")
    load.add_argument("file", type=Path, metavar="FILE")
    load.add_argument(
        "--use-wildcard",
        action="store_true",
        help="also load the file's '/**' section (NODE's own section overrides it)",
    )
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


def _call(session: ToolSession, request: Callable[[], Any], what: str, timeout: float):
    """The reply to the parameter service call ``request()`` (a future), or ToolError after
    ``timeout`` [s]. Unanswered after :data:`ASK_AGAIN_AFTER`, the call is made again: a server
    that answers before our response reader matched it loses the reply (rmw_fastrtps: "failed to
    send response (timeout)"), and every parameter call here can be repeated."""
    deadline = time.monotonic() + timeout
    while True:
        future = request()
        left = deadline - time.monotonic()
        if session.spin_until(future.done, max(0.0, min(ASK_AGAIN_AFTER, left))):
            return future.result()
        if time.monotonic() >= deadline:
            raise ToolError(f"no reply to {what} within {timeout:g} s")


def _format_value(value) -> str:
    """A ParameterValue as ros2 param get prints it: Python's ``str`` of the value, so arrays
    are Python lists (``['joint_1', 'joint_2']``, ``[0.5, 1.0]``, ``[True, False]``)."""
    from rclpy.parameter import parameter_value_to_python

    return str(parameter_value_to_python(value))


def _param_list(args, session: ToolSession) -> int:
    if args.node is not None:
        node_name = absolute_name(args.node)
        client = _parameter_client(session, node_name, args.timeout)
        response = _call(session, client.list_parameters, "list_parameters", args.timeout)
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
            response = _call(session, client.list_parameters, "list_parameters", args.timeout)
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
    response = _call(
        session, partial(client.get_parameters, [args.name]), "get_parameters", args.timeout
    )
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
    ask = partial(client.get_parameter_types, [args.name])
    types = _call(session, ask, "get_parameter_types", args.timeout).types
    value = parse_parameter_value(args.value, declared=types[0] if types else 0)
    ask = partial(client.set_parameters, [ParameterMsg(name=args.name, value=value)])
    response = _call(session, ask, "set_parameters", args.timeout)
    result = response.results[0] if response.results else None
    if result is None or not result.successful:
        reason = result.reason if result is not None and result.reason else "no reason given"
        if not types or types[0] == 0:  # rclpy's reason then names no parameter
            reason += f" (parameter {args.name!r} is not declared on {node_name})"
        print(f"Setting parameter failed: {reason}", file=sys.stderr, flush=True)
        return 0  # as ros2: the refusal is on stderr
    reason = f": {result.reason}" if result.reason else ""
    print(f"Set parameter successful{reason}", flush=True)
    return 0


def _param_describe(args, session: ToolSession) -> int:
    node_name = absolute_name(args.node)
    client = _parameter_client(session, node_name, args.timeout)
    ask = partial(client.describe_parameters, list(args.names))
    response = _call(session, ask, "describe_parameters", args.timeout)
    if len(response.descriptors) != len(args.names):
        # rclpy answers nothing at all when one name is undeclared: say which
        ask = partial(client.get_parameter_types, list(args.names))
        types = _call(session, ask, "get_types", args.timeout)
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


def _param_dump(args, session: ToolSession) -> int:
    import yaml
    from rclpy.parameter import parameter_value_to_python

    from rns_ros.cli import make_output_folder

    node_name = absolute_name(args.node)
    client = _parameter_client(session, node_name, args.timeout)
    listed = _call(session, client.list_parameters, "list_parameters", args.timeout)
    names = sorted(listed.result.names)
    values = []
    if names:
        ask = partial(client.get_parameters, names)
        values = _call(session, ask, "get_parameters", args.timeout).values
    tree: dict = {}
    for name, value in zip(names, values, strict=True):
        _insert(tree, name, parameter_value_to_python(value))
    text = yaml.safe_dump({node_name: {"ros__parameters": tree}}, default_flow_style=False)
    if args.output_dir is None:
        print(text, flush=True)  # with ros2's blank line after it
        return 0
    if problem := make_output_folder(args.output_dir):
        raise UsageError(f"--output-dir {str(args.output_dir)!r} {problem}")
    path = args.output_dir / (node_name.lstrip("/").replace("/", "__") + ".yaml")
    print("Saving to: ", path, flush=True)
    try:
        path.write_text(text)
    except OSError as exc:
        raise ToolError(f"cannot write {path}: {exc.strerror or exc}") from None
    return 0


def _insert(tree: dict, name: str, value) -> None:
    """``a.b.c`` as tree[a][b][c], the nesting of a params file."""
    *groups, leaf = name.split(".")
    for group in groups:
        tree = tree.setdefault(group, {})
        if not isinstance(tree, dict):
            raise ToolError(f"parameter {name!r} is inside {group!r}, which has a value itself")
    tree[leaf] = value


def _param_load(args, session: ToolSession) -> int:
    from rcl_interfaces.msg import Parameter as ParameterMsg

    node_name = absolute_name(args.node)
    entries = file_parameters(args.file, node_name, args.use_wildcard)
    client = _parameter_client(session, node_name, args.timeout)
    names = list(entries)
    if not names:
        return 0
    types = _call(
        session, partial(client.get_parameter_types, names), "get_types", args.timeout
    ).types
    declared = dict(zip(names, types, strict=False))
    parameters = []
    for name, value in entries.items():
        # typed as ros2 param load types it: the YAML text of the value, read again
        typed = _adapted(_python_value(value, str(value)), declared.get(name, 0), str(value))
        parameters.append(ParameterMsg(name=name, value=typed))
    ask = partial(client.set_parameters, parameters)
    results = _call(session, ask, "set_parameters", args.timeout).results
    for name, result in zip(names, results, strict=False):
        reason = f": {result.reason}" if result.reason else ""
        if result.successful:
            print(f"Set parameter {name} successful{reason}", flush=True)
            continue
        if not declared.get(name):  # rclpy's reason then names no parameter
            reason += f" (parameter {name!r} is not declared on {node_name})"
        print(f"Set parameter {name} failed{reason}", file=sys.stderr, flush=True)
    return 0


def file_parameters(path: Path, node_name: str, use_wildcard: bool = False) -> dict:
    """{parameter name: value} of ``node_name``'s section of the params file ``path`` (with
    ``use_wildcard`` its ``/**`` section first, the node's own overriding it), nested groups
    joined with '.', as ros2 param load reads it.

    Raises:
        UsageError: the file is unreadable, not YAML or not a params file.
        ToolError: the file has no section for ``node_name``.
    """
    from rns_ros.core.errors import ConfigError
    from rns_ros.core.yaml_input import read_yaml_file

    try:
        document = read_yaml_file(path, "parameter file")
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    if not isinstance(document, dict):
        raise UsageError(f"{path}: not a params file (a mapping of node names to ros__parameters)")
    wildcard = ["/**"] if use_wildcard and "/**" in document else []
    keys = [key for key in (node_name, node_name.lstrip("/")) if key in document]
    if not keys and not wildcard:
        known = ", ".join(str(key) for key in document) or "none"
        raise ToolError(f"{path} has no section for {node_name} (its sections: {known})")
    merged: dict = {}
    for key in wildcard + keys:
        section = document[key]
        if not (isinstance(section, dict) and isinstance(section.get("ros__parameters"), dict)):
            raise UsageError(
                f"{path}: section {key} is not a params file's (ros__parameters: {{NAME: VALUE}})"
            )
        merged.update(section["ros__parameters"])
    flat: dict = {}
    _flatten("", merged, flat)
    return flat


def _flatten(prefix: str, group: dict, flat: dict) -> None:
    for name, value in group.items():
        if isinstance(value, dict):
            _flatten(f"{prefix}{name}.", value, flat)
        else:
            flat[f"{prefix}{name}"] = value


def param_main(argv: Sequence[str] | None = None) -> int:
    """``rns_param list|get|set|describe|dump|load NODE [NAME] [VALUE]``; returns the exit
    code."""
    commands = {
        "list": _param_list,
        "get": _param_get,
        "set": _param_set,
        "describe": _param_describe,
        "dump": _param_dump,
        "load": _param_load,
    }
    return run_tool(
        "rns_param", _param_parser(), argv, lambda args, s: commands[args.command](args, s)
    )


if __name__ == "__main__":
    raise SystemExit(param_main())
