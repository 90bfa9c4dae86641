"""ROS messages as YAML both ways, and interface types by name: what the PyPI-only tools share.

``rns_topic echo`` prints messages as YAML or CSV; ``rns_topic pub`` and ``rns_service call`` fill a
message from the YAML text of the command line, as ros2cli does (``"{data: true}"``,
``"{name: [joint_1], position: [0.5]}"``). ros2cli's own converter (rosidl_runtime_py) is not
among the PyPI wheels, so this module holds a strict one: an unknown field, a value of the wrong
kind or out of range is a :class:`~rns_ros.tool_session.UsageError` naming the field (exit 2).
As in ros2cli, a ``builtin_interfaces/Time`` field given as ``now`` is the current time and a
``std_msgs/Header`` given as ``auto`` is stamped now with an empty frame id.
"""

from __future__ import annotations

import array
import functools
import importlib
from collections.abc import Callable
from typing import Any

from rns_ros.tool_session import ToolError, UsageError

#: ``rns_topic echo`` shortens longer strings and arrays, as ``ros2 topic echo`` does.
TRUNCATE_LENGTH = 128
#: The YAML words ros2cli accepts for "stamp it now".
NOW, AUTO = "now", "auto"
_FLOATING = ("float", "double", "long double")
_TIME, _HEADER = "builtin_interfaces/Time", "std_msgs/Header"


def message_to_dict(
    msg: Any,
    truncate: int | None = TRUNCATE_LENGTH,
    *,
    no_arr: bool = False,
    no_str: bool = False,
) -> Any:
    """A ROS message as plain dicts / lists / scalars (field order kept) for YAML output, as
    ``ros2 topic echo`` converts it (rosidl_runtime_py's ``message_to_ordereddict``).

    Strings and sequences longer than ``truncate`` end in ``'...'`` (None: full length);
    ``no_arr``: every array or sequence field is its abbreviation
    (``<sequence type: double, length: 7>``), ``no_str``: every string is its length
    (``<string length: <4>>``). A ``byte`` field is its integer value (ros2: a one-character
    string).
    """
    if _is_message(msg):
        fields = msg.get_fields_and_field_types()
        return {
            name: _field_to_plain(getattr(msg, name), slot, truncate, no_arr, no_str)
            for name, slot in zip(fields, msg.SLOT_TYPES, strict=True)
        }
    return _field_to_plain(msg, None, truncate, no_arr, no_str)


def _is_message(value: Any) -> bool:
    return hasattr(value, "get_fields_and_field_types")


def _field_to_plain(value: Any, slot: Any, truncate, no_arr: bool, no_str: bool) -> Any:
    """One field's ``value`` for :func:`message_to_dict` (``slot``: its rosidl type, None for
    the items of a sequence)."""
    options = {"truncate": truncate, "no_arr": no_arr, "no_str": no_str}
    if _is_message(value):
        return message_to_dict(value, truncate, no_arr=no_arr, no_str=no_str)
    if isinstance(value, bytes):  # `byte` fields (length 1) and byte sequences
        value = list(value)
        if len(value) == 1:
            return value[0]
    if isinstance(value, str):
        if no_str:
            return f"<string length: <{len(value)}>>"
        if truncate is not None and len(value) > truncate:
            return value[:truncate] + "..."
        return value
    value = _plain_sequence(value)
    if isinstance(value, list | tuple):
        if no_arr and slot is not None:
            return _abbreviated(value, slot)
        return _items(value, truncate, functools.partial(_field_to_plain, slot=None, **options))
    return value


def _items(value: list | tuple, truncate: int | None, convert: Callable[[Any], Any]) -> list:
    """The items of a sequence converted, cut after ``truncate`` with a last ``"..."``."""
    cut = truncate is not None and len(value) > truncate
    items = [convert(item) for item in (value[:truncate] if cut else value)]
    return [*items, "..."] if cut else items


def _plain_sequence(value: Any) -> Any:
    """numpy arrays (fixed-size fields) and array.array (numeric sequences) as lists, numpy
    scalars as Python numbers; anything else as it is."""
    if isinstance(value, array.array) or getattr(value, "ndim", 0) >= 1:
        return value.tolist()
    if getattr(value, "ndim", None) == 0 and hasattr(value, "item"):
        return value.item()
    return value


def _abbreviated(value, slot) -> str:
    """What ``--no-arr`` prints for an array or sequence field, as ros2 does."""
    from rosidl_parser.definition import Array, BoundedSequence

    element = _element_type_name(slot.value_type)
    if isinstance(slot, Array):
        return f"<array type: {element}[{slot.size}]>"
    if isinstance(slot, BoundedSequence):
        return f"<sequence type: {element}[{slot.maximum_size}], length: {len(value)}>"
    return f"<sequence type: {element}, length: {len(value)}>"


def _element_type_name(value_type) -> str:
    from rosidl_parser.definition import (
        AbstractString,
        AbstractWString,
        BasicType,
        NamedType,
        NamespacedType,
    )

    if isinstance(value_type, BasicType):
        return value_type.typename
    if isinstance(value_type, AbstractString):
        return "string"
    if isinstance(value_type, AbstractWString):
        return "wstring"
    if isinstance(value_type, NamedType):
        return value_type.name
    if isinstance(value_type, NamespacedType):
        return "/".join(value_type.namespaced_name())
    return "unknown"


def message_to_yaml(
    msg: Any,
    truncate: int | None = TRUNCATE_LENGTH,
    *,
    no_arr: bool = False,
    no_str: bool = False,
    flow_style: bool = False,
) -> str:
    """``msg`` as the YAML ``ros2 topic echo`` prints (without the ``---`` separator): block
    style, or one flow-style line with ``flow_style``; the options of :func:`message_to_dict`."""
    import yaml

    return yaml.safe_dump(
        message_to_dict(msg, truncate, no_arr=no_arr, no_str=no_str),
        sort_keys=False,
        default_flow_style=flow_style,
        allow_unicode=True,
        width=1 << 30,  # no line folding
    )


def message_to_csv(
    msg: Any, truncate: int | None = TRUNCATE_LENGTH, *, no_arr: bool = False, no_str: bool = False
) -> str:
    """``msg`` as the one line of comma-separated values ``ros2 topic echo --csv`` prints: every
    field depth first, sequences item by item; the options of :func:`message_to_dict`."""
    fields = msg.get_fields_and_field_types()
    return ",".join(
        _csv_value(getattr(msg, name), slot, truncate, no_arr, no_str)
        for name, slot in zip(fields, msg.SLOT_TYPES, strict=True)
    )


def _csv_value(value: Any, slot: Any, truncate, no_arr: bool, no_str: bool) -> str:
    if _is_message(value):
        return message_to_csv(value, truncate, no_arr=no_arr, no_str=no_str)
    if isinstance(value, bytes) and len(value) == 1:
        return str(value[0])  # a `byte`: its integer value, as in the YAML
    if isinstance(value, bytes):
        value = list(value)
    value = _plain_sequence(value)
    if isinstance(value, list | tuple):
        if no_arr and slot is not None:
            return _abbreviated(value, slot)
        options = {"truncate": truncate, "no_arr": no_arr, "no_str": no_str}
        convert = functools.partial(_csv_value, slot=None, **options)
        return ",".join(_items(value, truncate, convert))
    if isinstance(value, str):
        if no_str:
            return f"<string length: <{len(value)}>>"
        if truncate is not None and len(value) > truncate:
            return value[:truncate] + "..."
    return str(value)


def import_interface(type_name: str, kind: str = "msg"):
    """The class of ``'pkg/msg/Type'`` (``kind`` ``msg``) or ``'pkg/srv/Type'`` (``srv``); the
    short form ``'pkg/Type'`` is accepted, as ros2cli does.

    Raises:
        UsageError: the name is not of that form.
        ToolError: the package or the type is not installed in this Python.
    """
    parts = type_name.split("/")
    if len(parts) == 2:
        parts.insert(1, kind)
    if len(parts) != 3 or not all(parts) or parts[1] != kind:
        example = "std_msgs/msg/Bool" if kind == "msg" else "std_srvs/srv/Trigger"
        raise UsageError(f"cannot interpret {type_name!r} as a {kind} type (e.g. {example})")
    package, _, name = parts
    try:
        return getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ImportError, AttributeError):
        raise ToolError(
            f"{kind} type {package}/{kind}/{name} is not installed in this Python (its package "
            f"{package} is not among the PyPI wheels, or has no such type)"
        ) from None


def parse_fields(text: str) -> dict:
    """The YAML mapping ``text`` of a message's fields ({} for empty text).

    Raises:
        UsageError: ``text`` is not YAML, not a mapping, or over a limit of
            :mod:`rns_ros.core.yaml_input` (aliases, size).
    """
    import yaml

    from rns_ros.core.errors import ConfigError
    from rns_ros.core.yaml_input import load_yaml

    try:
        values = load_yaml(text, "the message")
    except yaml.YAMLError as exc:
        problem = " ".join(str(getattr(exc, "problem", None) or exc).split())
        raise UsageError(f"cannot parse the message {_short(text)} as YAML: {problem}") from None
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    if values is None:
        return {}
    if not isinstance(values, dict):
        raise UsageError(
            "the message must be a YAML mapping of field names, e.g. '{data: true}', "
            f"got {_short(text)}"
        )
    return values


def _short(value: Any) -> str:
    """``repr(value)`` cut for a message (:func:`rns_ros.core.validation.short_repr`)."""
    from rns_ros.core.validation import short_repr

    return short_repr(value)


def message_from_fields(values: dict, msg_type: type, now: Callable[[], Any]) -> Any:
    """A ``msg_type`` message filled from ``values`` (fields left out keep their defaults);
    ``now()`` gives the ``builtin_interfaces/Time`` that ``now`` / ``auto`` stand for (called
    again for each message, so a repeated message is stamped anew, as ros2 topic pub does).

    Raises:
        UsageError: ``values`` names a field the type lacks, or gives a value the field does
            not take (the message names the field).
    """
    msg = msg_type()
    _fill(msg, values, "", now)
    return msg


def message_from_yaml(text: str, msg_type: type, now: Callable[[], Any]) -> Any:
    """:func:`message_from_fields` of :func:`parse_fields` ``(text)``."""
    return message_from_fields(parse_fields(text), msg_type, now)


def _type_name(msg: Any) -> str:
    """``'pkg/Type'`` of a message instance (as its fields' types are written)."""
    module = type(msg).__module__.split(".")
    return f"{module[0]}/{type(msg).__name__}"


def _fill(msg: Any, values: dict, path: str, now: Callable[[], Any]) -> None:
    fields = msg.get_fields_and_field_types()
    slot_types = dict(zip(fields, msg.SLOT_TYPES, strict=True))
    for name, value in values.items():
        where = f"{path}{name}"
        if name not in fields:
            known = ", ".join(fields) or "none"
            raise UsageError(f"{_type_name(msg)} has no field {where!r} (its fields: {known})")
        current = getattr(msg, name)
        if hasattr(current, "get_fields_and_field_types"):
            setattr(msg, name, _nested(current, value, where, now))
        else:
            # rclpy's setters check types only with ROS_PYTHON_CHECK_FIELDS set (off in Jazzy),
            # and a value that does not fit would fail later, in the C serializer
            setattr(msg, name, _converted(slot_types[name], value, where, now, fields[name]))


def _nested(current: Any, value: Any, where: str, now: Callable[[], Any]) -> Any:
    """A message field's new value from ``value`` (a mapping, or ``now`` / ``auto``)."""
    kind = _type_name(current)
    if kind == _TIME and value == NOW:
        return now()
    if kind == _HEADER and value == AUTO:
        return type(current)(stamp=now())
    if not isinstance(value, dict):
        raise UsageError(
            f"field {where!r} is a {kind}: give a mapping of its fields, not {_short(value)}"
        )
    _fill(current, value, where + ".", now)
    return current


def _integer_range(typename: str) -> tuple[int, int]:
    """Bounds of an IDL integer type (``int8``, ``unsigned long``, ...)."""
    bits = {"short": 16, "long": 32, "long long": 64}
    unsigned = typename.startswith(("uint", "unsigned"))
    name = typename.removeprefix("unsigned ").removeprefix("u")
    n = bits[name] if name in bits else int(name.removeprefix("int"))
    return (0, 2**n - 1) if unsigned else (-(2 ** (n - 1)), 2 ** (n - 1) - 1)


def _converted(slot_type: Any, value: Any, where: str, now: Callable[[], Any], kind: str) -> Any:
    """``value`` checked against a primitive, string, array or sequence field (``kind``: its
    type as the message names it) and converted as rclpy stores it: integers for floating-point
    fields become floats, a ``byte`` an int in [0, 255] becomes bytes; sequences of messages are
    built element by element."""
    from rosidl_parser.definition import (
        INTEGER_TYPES,
        AbstractGenericString,
        AbstractNestedType,
        Array,
        BasicType,
        BoundedSequence,
        NamespacedType,
    )

    def bad(why: str) -> UsageError:
        return UsageError(f"bad value {_short(value)} for field {where!r} ({kind}): {why}")

    if isinstance(slot_type, AbstractNestedType):
        if not isinstance(value, list):
            raise bad("give a YAML list")
        if isinstance(slot_type, Array) and len(value) != slot_type.size:
            raise bad(f"give exactly {slot_type.size} values")
        if isinstance(slot_type, BoundedSequence) and len(value) > slot_type.maximum_size:
            raise bad(f"give at most {slot_type.maximum_size} values")
        element = slot_type.value_type
        if isinstance(element, NamespacedType):
            cls = getattr(importlib.import_module(".".join(element.namespaces)), element.name)
            return [_nested(cls(), item, f"{where}[{i}]", now) for i, item in enumerate(value)]
        return [
            _converted(element, item, f"{where}[{i}]", now, kind) for i, item in enumerate(value)
        ]
    if isinstance(slot_type, AbstractGenericString):
        if isinstance(value, list | dict) or value is None:
            raise bad("give a string")
        text = str(value)  # a number given for a string field, as ros2 converts it
        limit = getattr(slot_type, "maximum_size", None)
        if limit is not None and len(text) > limit:
            raise bad(f"at most {limit} characters")
        return text
    typename = slot_type.typename if isinstance(slot_type, BasicType) else ""
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if typename == "boolean":
        if not isinstance(value, bool):
            raise bad("give true or false")
        return value
    if typename in _FLOATING:
        if not number:
            raise bad("give a number")
        return float(value)
    if typename == "octet":  # rclpy keeps a byte as bytes of length 1
        if not (isinstance(value, int) and not isinstance(value, bool) and 0 <= value <= 255):
            raise bad("give an integer in [0, 255]")
        return bytes([value])
    if typename in ("char", "wchar"):
        if not (isinstance(value, str) and len(value) == 1):
            raise bad("give one character")
        return value
    if typename in INTEGER_TYPES:
        low, high = _integer_range(typename)
        if not (isinstance(value, int) and not isinstance(value, bool) and low <= value <= high):
            raise bad(f"give an integer in [{low}, {high}]")
        return value
    raise bad("this field type is not supported here")
