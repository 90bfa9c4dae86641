"""rns_ros.bag.reader: a bag folder described by its metadata.yaml, one MCAP file by its summary
and rosbag2 record (as rosbag2's MCAP plugin reads it), and one line for what is not a bag."""

from __future__ import annotations

import pytest
import yaml
from bag_messages import sample_messages, type_name
from rclpy.serialization import serialize_message

from rns_ros.bag import BagError, BagWriter, open_bag
from rns_ros.bag.qos import profile

START = 1_700_000_000_000_000_000


@pytest.fixture
def bag(tmp_path):
    folder = tmp_path / "b"
    messages = sample_messages()
    with BagWriter(folder, max_bag_duration=0.05) as writer:
        stamp = START
        for name, msgs in messages.items():
            topic = writer.add_topic(name, type_name(msgs[0]), [profile(depth=3)])
            for msg in msgs:
                writer.write(topic, serialize_message(msg), stamp)
                stamp += 20_000_000
    return folder, messages


def test_a_folder_reads_its_messages_in_time_order_over_its_files(bag):
    folder, messages = bag
    opened = open_bag(folder)
    assert len(opened.files) > 2
    got = list(opened.messages())
    assert [m.log_time for m in got] == sorted(m.log_time for m in got)
    assert len(got) == opened.metadata.message_count == sum(map(len, messages.values()))
    assert opened.topics["/base_odom"].offered_qos_profiles == [profile(depth=3)]
    assert {m.topic for m in opened.messages(["/tf"])} == {"/tf"}
    assert opened.metadata.bag_size == sum(path.stat().st_size for path in opened.files)
    assert opened.definitions()["sensor_msgs/msg/JointState"][0] == "ros2msg"


def test_one_mcap_file_is_a_bag_of_its_own(bag):
    folder, _ = bag
    opened = open_bag(folder / "b_0.mcap")
    meta = opened.metadata
    assert meta.relative_file_paths == ["b_0.mcap"]
    assert (meta.version, meta.ros_distro) == (9, "jazzy")  # from its rosbag2 record
    assert meta.message_count == len(list(opened.messages())) > 0
    first = next(iter(opened.messages()))
    assert meta.starting_time_ns == first.log_time
    assert all(t.offered_qos_profiles == [profile(depth=3)] for t in meta.topics)


def _problem(path) -> str:
    with pytest.raises(BagError) as caught:
        open_bag(path)
    return str(caught.value)


def test_what_is_not_a_bag_is_one_line(tmp_path, bag):
    folder, _ = bag
    assert _problem(tmp_path / "nothing") == f"{tmp_path / 'nothing'}: no such bag folder or file"
    (tmp_path / "notes.txt").write_text("hello")
    assert _problem(tmp_path / "notes.txt") == f"{tmp_path / 'notes.txt'}: not an MCAP file"
    (tmp_path / "empty").mkdir()
    assert "not a bag folder (no metadata.yaml)" in _problem(tmp_path / "empty")
    half = tmp_path / "half.mcap"
    half.write_bytes((folder / "b_0.mcap").read_bytes()[:200])
    assert "half.mcap" in _problem(half)
    meta = folder / "metadata.yaml"
    text = meta.read_text()
    meta.write_text(text.replace("storage_identifier: mcap", "storage_identifier: sqlite3"))
    assert "storage 'sqlite3' is not supported" in _problem(folder)
    meta.write_text("rosbag2_bagfile_information: [")
    assert "not YAML" in _problem(folder)
    meta.write_text(yaml.safe_dump({"rosbag2_bagfile_information": {"version": 9}}))
    assert "no 'topics_with_message_count'" in _problem(folder)
    meta.write_text(text)
    (folder / "b_1.mcap").unlink()
    assert "b_1.mcap is missing" in _problem(folder)
    meta.unlink()
    assert "no metadata.yaml (open one of its .mcap files instead)" in _problem(folder)
