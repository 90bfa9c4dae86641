"""rns_ros.bag.cdr: where a serialized message's CDR content ends, checked against rosbags'
serializer (an implementation nobody on the project wrote) and against the bytes a stock
publisher puts on the wire (a normal rclpy publish: the exact content)."""

from __future__ import annotations

import struct

import pytest
from bag_messages import same_fields, sample_messages, type_name
from rclpy.serialization import serialize_message
from sensor_msgs.msg import JointState

from rns_ros.bag.cdr import CdrLayout
from rns_ros.bag.definitions import DefinitionError, message_definition, parse_definition


@pytest.fixture(scope="module")
def typestore():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


def _layout(name: str) -> CdrLayout:
    return CdrLayout(name, parse_definition(name, message_definition(name)))


MESSAGES = [msg for messages in sample_messages().values() for msg in messages]


@pytest.mark.parametrize("msg", MESSAGES, ids=[type_name(m).split("/")[-1] for m in MESSAGES])
def test_the_content_is_what_rosbags_serializes_and_decodes(msg, typestore):
    name = type_name(msg)
    data = serialize_message(msg)  # rmw_serialize: its size estimate, maybe bytes after
    content = _layout(name).content(data)
    assert content == data[: len(content)]
    decoded = typestore.deserialize_cdr(content, name)  # rosbags checks the length
    same_fields(msg, decoded)
    assert len(content) == len(bytes(typestore.serialize_cdr(decoded, name)))


def test_a_joint_state_loses_the_bytes_after_its_content():
    """7 joints: rclpy serializes 244 bytes, the content ends at 240 (rosbags refuses 244)."""
    msg = JointState(
        name=[f"joint_{i}" for i in range(1, 8)], position=[0.1] * 7, velocity=[0.2] * 7
    )
    data = serialize_message(msg)
    assert len(data) == 244
    assert len(_layout("sensor_msgs/msg/JointState").content(data)) == 240


def test_big_endian_bytes_are_walked_in_their_byte_order(typestore):
    name = "sensor_msgs/msg/JointState"
    layout = _layout(name)
    msg = JointState(name=["ab", "c"], position=[1.0, 2.0])
    decoded = typestore.deserialize_cdr(layout.content(serialize_message(msg)), name)
    big = bytes(typestore.serialize_cdr(decoded, name, little_endian=False))
    assert big[:2] == b"\x00\x00"
    assert layout.content_size(big) == len(big)
    assert layout.content(big + b"\xff" * 5) == big


def test_bytes_that_are_not_the_type_are_kept_as_received():
    layout = _layout("sensor_msgs/msg/JointState")
    short = serialize_message(JointState(name=["joint_1"]))[:14]
    assert layout.content_size(short) is None
    assert layout.content(short) == short
    huge = b"\x00\x01\x00\x00" + struct.pack("<iI", 1, 2) + struct.pack("<I", 10**9) + b"x" * 20
    assert layout.content(huge) == huge  # a string length past the end
    xcdr2 = b"\x00\x07\x00\x00" + b"\x00" * 40  # another encapsulation
    assert layout.content(xcdr2) == xcdr2


def test_an_empty_message_is_one_byte_and_fixed_arrays_are_contiguous():
    empty = _layout("std_msgs/msg/Empty")
    data = serialize_message(__import__("std_msgs.msg", fromlist=["Empty"]).Empty())
    assert empty.content(data) == data[:5]
    types = parse_definition("pkg/Fixed", "uint8 a\nfloat64[3] b\nstring[2] c\n")
    fixed = CdrLayout("pkg/Fixed", types)
    data = (
        b"\x00\x01\x00\x00" + b"\x05" + b"\x00" * 7 + struct.pack("<3d", 1, 2, 3)
        + struct.pack("<I", 2) + b"x\x00" + b"\x00\x00" + struct.pack("<I", 1) + b"\x00"
    )  # fmt: skip
    assert fixed.content_size(data + b"\x00\x00\x00") == len(data)


def test_wstrings_and_missing_types_are_refused():
    with pytest.raises(DefinitionError, match="wstring"):
        CdrLayout("pkg/W", parse_definition("pkg/W", "wstring name\n"))
    with pytest.raises(DefinitionError, match="lacks pkg/Other"):
        CdrLayout("pkg/A", parse_definition("pkg/A", "Other inner\n"))
