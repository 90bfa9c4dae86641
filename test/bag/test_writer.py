"""rns_ros.bag.writer: a rosbag2 folder as ``ros2 bag record -s mcap`` lays it out, read back by
readers nobody on the project wrote: rosbags' rosbag2 Reader and AnyReader with the ROS 2 Jazzy
typestore, and the PyPI ``mcap`` reader with the ``mcap_ros2`` decoder. The messages go in as
rclpy serializes them (rmw_serialize: some with bytes after their content)."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import textwrap
from collections import Counter
from pathlib import Path

import pytest
import yaml
from bag_messages import same_fields, sample_messages, type_name
from rclpy.serialization import serialize_message

from rns_ros.bag import BagError, BagWriter
from rns_ros.bag.definitions import message_definition, type_description_hash
from rns_ros.bag.qos import parse_profiles, profile

START = 1_700_000_000_000_000_000  # [ns since the epoch]
LATCHED = profile(depth=1, durability="transient_local")


def _offers(topic: str) -> list[dict]:
    return [LATCHED] if topic in ("/tf_static", "/robot_description") else [profile()]


def _write(folder: Path, step_ns: int = 10_000_000, **options) -> dict[str, list]:
    """Every sample message into a bag at ``folder``, topics interleaved, ``step_ns`` apart."""
    messages = sample_messages()
    with BagWriter(folder, **options) as writer:
        topics = {
            name: writer.add_topic(name, type_name(msgs[0]), _offers(name))
            for name, msgs in messages.items()
        }
        stamp = START
        for k in range(max(len(msgs) for msgs in messages.values())):
            for name, msgs in messages.items():
                if k < len(msgs):
                    writer.write(topics[name], serialize_message(msgs[k]), stamp, stamp - 5)
                    stamp += step_ns
    assert writer.problem is None
    return messages


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bags") / "session"
    return folder, _write(folder)


@pytest.fixture(scope="module")
def typestore():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


def test_the_folder_holds_metadata_and_one_mcap_file(bag):
    folder, messages = bag
    assert sorted(path.name for path in folder.iterdir()) == ["metadata.yaml", "session_0.mcap"]
    info = yaml.safe_load((folder / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    total = sum(len(msgs) for msgs in messages.values())
    assert (info["version"], info["storage_identifier"], info["ros_distro"]) == (9, "mcap", "jazzy")
    assert info["relative_file_paths"] == ["session_0.mcap"]
    assert info["message_count"] == total
    assert info["starting_time"] == {"nanoseconds_since_epoch": START}
    assert info["duration"] == {"nanoseconds": (total - 1) * 10_000_000}
    assert (info["compression_format"], info["compression_mode"], info["custom_data"]) == (
        "",
        "",
        None,
    )
    assert info["files"] == [
        {
            "path": "session_0.mcap",
            "starting_time": {"nanoseconds_since_epoch": START},
            "duration": {"nanoseconds": (total - 1) * 10_000_000},
            "message_count": total,
        }
    ]
    topics = {item["topic_metadata"]["name"]: item for item in info["topics_with_message_count"]}
    assert {name: item["message_count"] for name, item in topics.items()} == {
        name: len(msgs) for name, msgs in messages.items()
    }
    odom = topics["/base_odom"]["topic_metadata"]
    assert odom["type"] == "nav_msgs/msg/Odometry"
    assert odom["serialization_format"] == "cdr"
    assert odom["type_description_hash"] == type_description_hash("nav_msgs/msg/Odometry")
    assert odom["offered_qos_profiles"] == [profile()]  # a list in version 9, not a string
    assert topics["/tf_static"]["topic_metadata"]["offered_qos_profiles"] == [LATCHED]


def test_rosbags_reader_decodes_every_message_with_the_jazzy_typestore(bag, typestore):
    from rosbags.interfaces import QosDurability
    from rosbags.rosbag2 import Reader

    folder, messages = bag
    decoded: dict[str, list] = {}
    with Reader(folder) as reader:
        assert reader.message_count == sum(len(msgs) for msgs in messages.values())
        durability = {c.topic: c.ext.offered_qos_profiles[0].durability for c in reader.connections}
        for connection, _stamp, raw in reader.messages():
            msg = typestore.deserialize_cdr(raw, connection.msgtype)
            decoded.setdefault(connection.topic, []).append(msg)
    assert durability["/tf_static"] == QosDurability.TRANSIENT_LOCAL
    assert durability["/joint_states"] == QosDurability.VOLATILE
    assert set(decoded) == set(messages)
    for topic, msgs in messages.items():
        assert len(decoded[topic]) == len(msgs)
        for ours, theirs in zip(msgs, decoded[topic], strict=True):
            same_fields(ours, theirs, topic)


def test_rosbags_anyreader_decodes_every_message(bag, typestore):
    from rosbags.highlevel import AnyReader

    folder, messages = bag
    counts = Counter()
    with AnyReader([folder], default_typestore=typestore) as reader:
        for connection, _stamp, raw in reader.messages():
            msg = reader.deserialize(raw, connection.msgtype)
            same_fields(messages[connection.topic][counts[connection.topic]], msg)
            counts[connection.topic] += 1
    assert counts == {topic: len(msgs) for topic, msgs in messages.items()}


def test_the_mcap_reader_decodes_every_message_and_sees_rosbag2s_layout(bag):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    folder, messages = bag
    counts = Counter()
    with open(folder / "session_0.mcap", "rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        assert reader.get_header().profile == "ros2"
        for schema in summary.schemas.values():
            assert schema.encoding == "ros2msg"
            assert schema.data.decode() == message_definition(schema.name)
        for channel in summary.channels.values():
            assert channel.message_encoding == "cdr"
            assert set(channel.metadata) == {"offered_qos_profiles", "topic_type_hash"}
            assert parse_profiles(channel.metadata["offered_qos_profiles"]) == _offers(
                channel.topic
            )
            assert channel.metadata["topic_type_hash"].startswith("RIHS01_")
        (record,) = [m for m in reader.iter_metadata() if m.name == "rosbag2"]
        stored = yaml.safe_load(record.metadata["serialized_metadata"])
        assert (stored["version"], stored["message_count"]) == (9, sum(map(len, messages.values())))
        for _schema, channel, message, msg in reader.iter_decoded_messages(log_time_order=True):
            same_fields(messages[channel.topic][counts[channel.topic]], msg, channel.topic)
            assert message.publish_time == message.log_time - 5
            counts[channel.topic] += 1
    assert counts == {topic: len(msgs) for topic, msgs in messages.items()}


def test_a_split_by_duration_spreads_the_messages_over_files(tmp_path, typestore):
    from rosbags.rosbag2 import Reader

    folder = tmp_path / "split"
    messages = _write(folder, step_ns=400_000_000, max_bag_duration=1.0)
    total = sum(len(msgs) for msgs in messages.values())
    info = yaml.safe_load((folder / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    # a file takes messages until one is more than 1 s after its first: 3 at 0.4 s apart
    expected = [3] * (total // 3) + ([total % 3] if total % 3 else [])
    assert [item["message_count"] for item in info["files"]] == expected
    assert info["relative_file_paths"] == [f"split_{i}.mcap" for i in range(len(expected))]
    assert sorted(p.name for p in folder.iterdir()) == sorted(
        ["metadata.yaml", *info["relative_file_paths"]]
    )
    with Reader(folder) as reader:
        decoded = [typestore.deserialize_cdr(raw, c.msgtype) for c, _, raw in reader.messages()]
    assert len(decoded) == total


def test_a_split_by_size_keeps_each_file_near_the_size(tmp_path):
    folder = tmp_path / "sized"
    with BagWriter(folder, max_bag_size=4096) as writer:
        topic = writer.add_topic("/energy", "std_msgs/msg/Float64MultiArray", [profile()])
        payload = serialize_message(
            sample_messages()["/energy"][0].__class__(data=[float(i) for i in range(200)])
        )
        for k in range(100):
            writer.write(topic, payload, START + k)
    files = sorted(folder.glob("sized_*.mcap"))
    assert len(files) > 3
    info = yaml.safe_load((folder / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert sum(item["message_count"] for item in info["files"]) == 100
    # split once the data reached the size; each file's summary (schemas, indexes, the
    # rosbag2 record) comes after it, as in rosbag2
    sizes = [path.stat().st_size for path in files]
    assert all(4096 <= size < 3 * 4096 for size in sizes[:-1])


def test_bad_splits_and_an_occupied_folder_are_refused(tmp_path):
    with pytest.raises(BagError, match="at least 1024"):
        BagWriter(tmp_path / "a", max_bag_size=100)
    with pytest.raises(BagError, match="max-bag-duration"):
        BagWriter(tmp_path / "a", max_bag_duration=-1.0)
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "notes.txt").write_text("mine")
    with pytest.raises(BagError, match="not empty"):
        BagWriter(tmp_path / "full")


def test_replace_removes_the_earlier_bag_and_nothing_else(tmp_path):
    folder = tmp_path / "run"
    _write(folder, max_bag_duration=0.001)
    assert len(list(folder.glob("run_*.mcap"))) > 2
    (folder / "notes.txt").write_text("mine")
    with BagWriter(folder, replace=True) as writer:
        writer.write(writer.add_topic("/a", "std_msgs/msg/String"), serialize_message(
            sample_messages()["/robot_description"][0]), START)  # fmt: skip
    assert sorted(p.name for p in folder.iterdir()) == ["metadata.yaml", "notes.txt", "run_0.mcap"]


def test_a_folder_that_cannot_be_made_is_a_problem_and_leaves_nothing(tmp_path):
    (tmp_path / "file").write_text("")
    writer = BagWriter(tmp_path / "file" / "bag")
    assert writer.close() is None
    assert writer.problem.startswith(f"cannot write {tmp_path / 'file' / 'bag'}: ")
    assert writer.problem.endswith("; the bag is removed")
    assert (tmp_path / "file").is_file()


def test_the_file_size_limit_removes_the_whole_bag(tmp_path):
    """Under ``ulimit -f`` the writes fail (EFBIG): every file written and the folder made are
    removed, close() claims no bag."""
    folder = tmp_path / "limited"
    script = textwrap.dedent(
        f"""
        from rclpy.serialization import serialize_message
        from sensor_msgs.msg import JointState
        from rns_ros.bag import BagWriter
        writer = BagWriter({str(folder)!r}, flush_period=0.0)
        topic = writer.add_topic("/joint_states", "sensor_msgs/msg/JointState")
        for k in range(3000):
            msg = JointState(name=["j"] * 50, position=[k] * 50)
            writer.write(topic, serialize_message(msg), k)
        print(writer.close(), writer.problem)
        """
    )
    limit = 64 * 1024

    def limited() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    done = subprocess.run(
        [sys.executable, "-c", script], preexec_fn=limited, capture_output=True, text=True,
        timeout=120, env={**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"},
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f"None cannot write {folder}: File too large; the bag is removed")
    assert not folder.exists()
