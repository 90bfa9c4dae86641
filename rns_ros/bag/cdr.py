"""Where a serialized ROS 2 message ends: its CDR content, walked from the message definition.

A message as a publisher that serializes it itself (rclcpp's and rclpy's ``publish``) puts it on
the wire, and as ``ros2 bag record`` stores it then, is exactly its CDR content: the 4-byte
encapsulation header (``00 01``: little-endian plain CDR, ``00 00``: big-endian) and the fields,
each aligned to its own size counted from the end of the header (XCDR1), without padding after
the last field. ``rclpy.serialization.serialize_message`` (``rmw_serialize`` of rmw_fastrtps)
sizes its buffer by the type support's size estimate instead, which for some types (a
``sensor_msgs/JointState``: 4 bytes, an empty one: 8) is larger than the content; the bytes after
it are left as the buffer held them. A node that publishes such bytes as they are puts them on
the wire, and a reader that checks the length (rosbags allows 3 bytes of alignment after the
content) refuses the message. :meth:`CdrLayout.content` cuts them off.
"""

from __future__ import annotations

import functools
import struct
from collections.abc import Callable, Mapping

from rns_ros.bag.definitions import (
    DefinitionError,
    Field,
    full_type_name,
    message_definition,
    parse_definition,
)

#: Bytes of each primitive in CDR (each aligned to its size).
PRIMITIVE_SIZES = {
    "bool": 1, "byte": 1, "char": 1, "int8": 1, "uint8": 1,
    "int16": 2, "uint16": 2, "int32": 4, "uint32": 4, "float32": 4,
    "int64": 8, "uint64": 8, "float64": 8,
}  # fmt: skip
#: Encapsulation identifiers (the first two bytes) -> struct byte order: plain CDR (XCDR1).
BYTE_ORDERS = {b"\x00\x00": ">", b"\x00\x01": "<"}
HEADER = 4  # the encapsulation header; CDR alignment counts from its end

# A step: (data, position in data [bytes], byte order) -> position after the value.
Step = Callable[[bytes, int, str], int]


class _OutsideError(Exception):
    """A length read past the end of the bytes: they are not a message of the type."""


def _align(position: int, size: int) -> int:
    offset = position - HEADER
    return HEADER + (offset + size - 1) // size * size


def _count(data: bytes, position: int, order: str) -> int:
    """The uint32 at ``position`` (a string length or sequence count)."""
    if position + 4 > len(data):
        raise _OutsideError
    return struct.unpack_from(order + "I", data, position)[0]


class CdrLayout:
    """How a message type lies in CDR, compiled once from its parsed definition.

    Args:
        type_name: ``'pkg/Type'`` or ``'pkg/msg/Type'``.
        types: every type of its definition (:func:`rns_ros.bag.definitions.parse_definition`).

    Raises:
        DefinitionError: a type the definition uses is not in ``types``, or a ``wstring``
            (whose width differs between CDR implementations).
    """

    def __init__(self, type_name: str, types: Mapping[str, tuple[Field, ...]]) -> None:
        package, *_, name = type_name.split("/")
        self.type_name = type_name
        self._types = types
        self._compiled: dict[str, Step] = {}
        self._step = self._message(f"{package}/{name}", ())

    def content_size(self, data: bytes) -> int | None:
        """Bytes of the message's CDR content, header included; None when ``data`` is not a
        plain-CDR message of the type (another encapsulation, lengths past its end)."""
        order = BYTE_ORDERS.get(bytes(data[:2]))
        if order is None:
            return None
        try:
            end = self._step(data, HEADER, order)
        except (_OutsideError, struct.error):
            return None
        return end if end <= len(data) else None

    def content(self, data: bytes) -> bytes:
        """``data`` without the bytes after its CDR content (``data`` itself when there are
        none, or when it cannot be walked as the type: then it is stored as received)."""
        size = self.content_size(data)
        return data if size is None or size >= len(data) else bytes(data[:size])

    # --- compiling --------------------------------------------------------------------------
    def _message(self, kind: str, stack: tuple[str, ...]) -> Step:
        if kind in self._compiled:
            return self._compiled[kind]
        if kind in stack:
            raise DefinitionError(f"{self.type_name}: {kind} contains itself")
        if kind not in self._types:
            raise DefinitionError(f"{self.type_name}: the definition lacks {kind}")
        fields = self._types[kind]
        if not fields:  # an empty message carries one placeholder byte
            return lambda _data, position, _order: position + 1
        steps = [self._field(field, (*stack, kind)) for field in fields]

        def walk(data: bytes, position: int, order: str) -> int:
            for step in steps:
                position = step(data, position, order)
            return position

        self._compiled[kind] = walk
        return walk

    def _element(self, kind: str, stack: tuple[str, ...]) -> Step:
        if kind in PRIMITIVE_SIZES:
            size = PRIMITIVE_SIZES[kind]
            return lambda _data, position, _order: _align(position, size) + size
        if kind == "string":

            def string(data: bytes, position: int, order: str) -> int:
                position = _align(position, 4)
                return position + 4 + _count(data, position, order)  # the length counts the NUL

            return string
        if kind == "wstring":
            raise DefinitionError(f"{self.type_name}: wstring fields are not supported")
        return self._message(kind, stack)

    def _field(self, field: Field, stack: tuple[str, ...]) -> Step:
        element = self._element(field.kind, stack)
        size = PRIMITIVE_SIZES.get(field.kind)
        if field.length is not None:
            length = field.length
            if size is not None:  # contiguous values, aligned once
                return lambda _data, position, _order: _align(position, size) + length * size
            return _repeat(element, lambda *_: length)
        if field.sequence:

            def count(data: bytes, position: int, order: str) -> tuple[int, int]:
                position = _align(position, 4)
                return _count(data, position, order), position + 4

            if size is not None:

                def values(data: bytes, position: int, order: str) -> int:
                    n, position = count(data, position, order)
                    return position if n == 0 else _align(position, size) + n * size

                return values
            return _counted(element, count)
        return element


def _repeat(element: Step, times: Callable[..., int]) -> Step:
    def repeat(data: bytes, position: int, order: str) -> int:
        for _ in range(times()):
            position = element(data, position, order)
            if position > len(data):
                raise _OutsideError
        return position

    return repeat


def _counted(element: Step, count: Callable[[bytes, int, str], tuple[int, int]]) -> Step:
    def sequence(data: bytes, position: int, order: str) -> int:
        n, position = count(data, position, order)
        for _ in range(n):
            position = element(data, position, order)
            if position > len(data):
                raise _OutsideError
        return position

    return sequence


@functools.cache
def installed_layout(type_name: str) -> CdrLayout:
    """The :class:`CdrLayout` of an installed message type (``'pkg/msg/Type'``), built once.

    Raises:
        DefinitionError: its definition is not installed or cannot be laid out.
    """
    type_name = full_type_name(type_name)
    return CdrLayout(type_name, parse_definition(type_name, message_definition(type_name)))
