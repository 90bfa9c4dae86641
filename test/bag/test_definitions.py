"""rns_ros.bag.definitions: the installed definitions as rosbag2 stores them; the type hashes
compared with rosbags' own RIHS01 computation."""

from __future__ import annotations

import pytest

from rns_ros.bag.definitions import (
    DefinitionError,
    Field,
    message_definition,
    msg_file,
    parse_definition,
    type_description_hash,
)

TYPES = [
    "sensor_msgs/msg/JointState",
    "nav_msgs/msg/Odometry",
    "tf2_msgs/msg/TFMessage",
    "std_msgs/msg/String",
    "diagnostic_msgs/msg/DiagnosticArray",
    "geometry_msgs/msg/TwistStamped",
    "std_msgs/msg/Float64MultiArray",
]


@pytest.mark.parametrize("name", TYPES)
def test_the_type_hash_is_the_one_rosbags_computes(name):
    from rosbags.typesys import Stores, get_typestore

    assert type_description_hash(name) == get_typestore(Stores.ROS2_JAZZY).hash_rihs01(name)
    assert type_description_hash(name).startswith("RIHS01_")


def test_a_type_without_a_description_has_no_hash_and_no_definition():
    assert type_description_hash("rns_missing_msgs/msg/Thing") == ""
    with pytest.raises(DefinitionError, match="rns_missing_msgs/msg/Thing"):
        message_definition("rns_missing_msgs/msg/Thing")


@pytest.mark.parametrize("name", TYPES)
def test_every_type_of_a_definition_is_parsed(name):
    types = parse_definition(name, message_definition(name))
    package, _, short = name.split("/")
    assert f"{package}/{short}" in types
    for fields in types.values():
        for field in fields:
            assert field.kind in types or "/" not in field.kind


def test_fields_arrays_bounds_and_constants():
    text = (
        "# a comment\n"
        "uint8 OK=0\n"
        'string NAME = "x"\n'
        "string<=10 short_name\n"
        "Header header  # same package\n"
        "geometry_msgs/Point[] points\n"
        "geometry_msgs/msg/Point[3] corners\n"
        "float64[<=4] values 1.0\n"
        "string[2] pair\n"
    )
    (fields,) = parse_definition("pkg/msg/T", text).values()
    assert fields == (
        Field("short_name", "string"),
        Field("header", "pkg/Header"),
        Field("points", "geometry_msgs/Point", sequence=True),
        Field("corners", "geometry_msgs/Point", length=3),
        Field("values", "float64", sequence=True),
        Field("pair", "string", length=2),
    )


def test_a_section_without_its_name_is_refused():
    with pytest.raises(DefinitionError, match="MSG:"):
        parse_definition("pkg/T", "int32 a\n" + "=" * 80 + "\nint32 b\n")


def test_msg_files_come_from_the_share_folders():
    assert msg_file("sensor_msgs/JointState").name == "JointState.msg"
