"""rns_ros.runs.mcap_recording: a run's topics as MCAP (ROS 2 profile, CDR) read back with the
mcap library and decoded by mcap-ros2-support from the schemas we wrote, as Foxglove and
PlotJuggler decode them; the schemas are the installed .msg definitions. The file grows while
the run goes on: what a killed process leaves is read back to its last chunk, and a write that
fails (file-size limit) leaves no file."""

from __future__ import annotations

import textwrap

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import TwistStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import serialize_message
from rns_testing import run_with_file_size_limit
from sensor_msgs.msg import JointState

from rns_ros.bag.definitions import SEPARATOR, message_definition, msg_dependencies, msg_file
from rns_ros.harness import TopicLog
from rns_ros.runs.mcap_recording import McapRecording


def _log(topic: str, messages: list, raw: bool = False) -> TopicLog:
    """A log as Harness.record fills it (``raw``: the serialized bytes, deserialized on read)."""
    log = TopicLog(topic, type(messages[0]) if raw else None)
    for msg in messages:
        if raw:
            log._append_raw(serialize_message(msg))
        else:
            log._append(msg)
    return log


def _joint_state(k: int) -> JointState:
    msg = JointState(name=["joint_1", "joint_2"], position=[0.1 * k, -0.2], velocity=[k, 0.0])
    msg.header.stamp.sec, msg.header.stamp.nanosec = k, 5
    return msg


@pytest.fixture
def recording(tmp_path):
    odom = Odometry(child_frame_id="base_link")
    odom.pose.pose.orientation.z, odom.pose.pose.orientation.w = 0.6, 0.8
    status = DiagnosticArray(
        status=[DiagnosticStatus(name="rns_ptp", values=[KeyValue(key="state", value="MOVING")])]
    )
    twist = TwistStamped()
    twist.twist.angular.z = -0.1
    logs = [
        _log("joint_states", [_joint_state(k) for k in range(3)], raw=True),
        _log("base_odom", [odom, odom]),
        _log("rns_ptp/status", [status]),
        _log("cmd_twist", [twist] * 4, raw=True),
    ]
    path = tmp_path / "run.mcap"
    with McapRecording(path, lambda name: "/" + name) as recording:
        for log in logs:
            recording.add(log)
        recording.add(TopicLog("nothing_arrived", JointState))
    assert recording.close() == str(path)
    assert recording.problem is None
    return path, recording.counts


def _read(path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    stream = open(path, "rb")  # noqa: SIM115  (closed by the caller's fixture teardown)
    return stream, make_reader(stream, decoder_factories=[DecoderFactory()])


def test_topics_and_counts_read_back(recording):
    path, counts = recording
    stream, reader = _read(path)
    with stream:
        summary = reader.get_summary()
        header = reader.get_header()
    assert header.profile == "ros2"
    topics = {c.id: c.topic for c in summary.channels.values()}
    written = {topics[cid]: n for cid, n in summary.statistics.channel_message_counts.items()}
    expected = {"/joint_states": 3, "/base_odom": 2, "/rns_ptp/status": 1, "/cmd_twist": 4}
    assert written == expected == counts  # an empty log has no messages
    assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
    assert {s.encoding for s in summary.schemas.values()} == {"ros2msg"}
    assert {s.name for s in summary.schemas.values()} == {
        "sensor_msgs/msg/JointState",
        "nav_msgs/msg/Odometry",
        "diagnostic_msgs/msg/DiagnosticArray",
        "geometry_msgs/msg/TwistStamped",
    }


def test_one_decoded_message_per_type_has_the_values_sent(recording):
    path, _ = recording
    stream, reader = _read(path)
    first = {}
    with stream:
        for _schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=True):
            first.setdefault(channel.topic, (message, decoded))
    _, joints = first["/joint_states"]
    assert list(joints.name) == ["joint_1", "joint_2"]
    assert list(joints.position) == [0.0, -0.2]
    assert (joints.header.stamp.sec, joints.header.stamp.nanosec) == (0, 5)
    _, odom = first["/base_odom"]
    assert (odom.child_frame_id, odom.pose.pose.orientation.z) == ("base_link", 0.6)
    assert len(odom.pose.covariance) == 36
    _, status = first["/rns_ptp/status"]
    assert (status.status[0].values[0].key, status.status[0].values[0].value) == ("state", "MOVING")
    _, twist = first["/cmd_twist"]
    assert twist.twist.angular.z == -0.1
    times = [first[topic][0].log_time for topic in first]
    assert all(t > 1.6e18 for t in times)  # wall clock [ns], after 2020


def _closure(msg_type) -> set[str]:
    """Every message type ``msg_type`` uses, from the generated class (not the .msg text)."""
    from rosidl_parser.definition import AbstractNestedType, NamespacedType

    found = set()
    for slot in msg_type.SLOT_TYPES:
        inner = slot.value_type if isinstance(slot, AbstractNestedType) else slot
        if isinstance(inner, NamespacedType):
            module = __import__(".".join(inner.namespaces), fromlist=[inner.name])
            found.add(f"{inner.namespaces[0]}/{inner.name}")
            found |= _closure(getattr(module, inner.name))
    return found


@pytest.mark.parametrize("msg_type", [JointState, Odometry, DiagnosticArray, TwistStamped])
def test_the_schema_is_the_ros2_msg_definition(recording, msg_type):
    """rosbag2's complete definition: the type's .msg text first, then each type it uses once,
    after a line of 80 '=' and 'MSG: pkg/Type', with that type's .msg text."""
    path, _ = recording
    stream, reader = _read(path)
    with stream:
        schemas = {s.name: s.data.decode() for s in reader.get_summary().schemas.values()}
    name = f"{msg_type.__module__.split('.')[0]}/msg/{msg_type.__name__}"
    text = schemas[name]
    parts = text.split(f"\n{SEPARATOR}\nMSG: ")
    assert parts[0] == msg_file(name).read_text()
    dependencies = {}
    for part in parts[1:]:
        dependency, body = part.split("\n", 1)
        assert dependency not in dependencies
        dependencies[dependency] = body
    assert set(dependencies) == _closure(msg_type)
    for dependency, body in dependencies.items():
        assert msg_file(dependency).read_text() == body


def test_msg_dependencies_skip_comments_constants_and_primitives():
    text = (
        "# std_msgs/Header in a comment\n"
        "uint8 OK=0\n"
        "string<=10 short_name\n"
        "Header header  # same package\n"
        "geometry_msgs/Point[] points\n"
        "geometry_msgs/Point[3] corners\n"
        "float64[<=4] values\n"
    )
    assert msg_dependencies(text, "std_msgs") == ["geometry_msgs/Point", "std_msgs/Header"]


class _Clock:
    """A monotonic clock the test moves [s]."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _stream_messages(data: bytes) -> list:
    """Every message record of an MCAP file's bytes, read in order until they end (a file
    without summary or footer ends in the middle: what ``mcap recover`` salvages)."""
    import io

    from mcap.exceptions import McapError
    from mcap.records import Message
    from mcap.stream_reader import StreamReader

    found = []
    try:
        for record in StreamReader(io.BytesIO(data), skip_magic=False).records:
            if isinstance(record, Message):
                found.append(record)
    except (McapError, EOFError):
        pass
    return found


def test_chunks_reach_the_disk_while_the_run_goes_on(tmp_path):
    """Before close (a process killed outright leaves exactly this), the file holds every
    message received before the last flush, each decodable; later ones are in memory."""
    clock = _Clock()
    path = tmp_path / "live.mcap"
    log = TopicLog("joint_states", JointState)
    recording = McapRecording(path, flush_period=1.0, clock=clock)
    recording.add(log)
    for k in range(10):
        log._append_raw(serialize_message(_joint_state(k)))
    assert _stream_messages(path.read_bytes()) == []  # within the flush period: in memory
    clock.now = 1.0
    log._append_raw(serialize_message(_joint_state(10)))  # the period is over: written
    for k in range(11, 15):
        log._append_raw(serialize_message(_joint_state(k)))
    killed = path.read_bytes()
    messages = _stream_messages(killed)
    assert [m.sequence for m in messages] == list(range(11))
    from rclpy.serialization import deserialize_message

    assert [deserialize_message(m.data, JointState).header.stamp.sec for m in messages] == list(
        range(11)
    )
    assert recording.close() == str(path)
    assert len(_stream_messages(path.read_bytes())) == 15
    assert len(path.read_bytes()) > len(killed)


def test_messages_logged_before_the_recording_and_a_second_log_of_a_topic(tmp_path):
    early = _log("joint_states", [_joint_state(k) for k in range(3)], raw=True)
    again = _log("joint_states", [_joint_state(7)])
    path = tmp_path / "early.mcap"
    with McapRecording(path) as recording:
        recording.add(early)
        recording.add(again)  # the same topic: left out
        early._append_raw(serialize_message(_joint_state(3)))
    assert recording.counts == {"joint_states": 4}
    assert [m.sequence for m in _stream_messages(path.read_bytes())] == [0, 1, 2, 3]


def test_a_log_without_a_type_or_definition_is_refused(tmp_path):
    from rns_ros.core import RnsError

    with McapRecording(tmp_path / "x.mcap") as recording, pytest.raises(RnsError, match="type"):
        recording.add(TopicLog("unknown"))


def test_a_file_that_cannot_be_opened_is_a_problem_not_an_exception(tmp_path):
    recording = McapRecording(tmp_path)  # a folder
    recording.add(_log("joint_states", [_joint_state(0)], raw=True))
    assert recording.close() is None
    assert str(tmp_path) in recording.problem
    assert tmp_path.is_dir()


def test_the_file_size_limit_ends_the_recording_and_removes_the_file(tmp_path):
    """Under ``ulimit -f`` the writes fail (EFBIG; Python ignores SIGXFSZ): the recording stops
    without an exception, close() claims no file and removes the one it could not finish."""
    path = tmp_path / "limited.mcap"
    script = textwrap.dedent(
        f"""
        from rclpy.serialization import serialize_message
        from sensor_msgs.msg import JointState
        from rns_ros.harness import TopicLog
        from rns_ros.runs.mcap_recording import McapRecording
        log = TopicLog("joint_states", JointState)
        recording = McapRecording({str(path)!r}, flush_period=0.0)
        recording.add(log)
        for k in range(2000):
            log._append_raw(serialize_message(JointState(name=["j"] * 50, position=[k] * 50)))
        print(recording.close(), recording.problem)
        """
    )
    limit = 64 * 1024

    done = run_with_file_size_limit(script, limit, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    assert done.stdout.startswith(f"None cannot write {path}: File too large; the file is removed")
    assert not path.exists()


def test_msg_files_are_found_without_the_ament_environment(monkeypatch):
    """A console script run from the venv's bin/ alone has no AMENT_PREFIX_PATH: the wheels'
    .msg files are under the environment's prefix."""
    monkeypatch.delenv("AMENT_PREFIX_PATH", raising=False)
    path = msg_file("sensor_msgs/msg/JointState")
    assert path.is_file()
    assert path.read_text().startswith("#")
    assert "MSG: std_msgs/Header" in message_definition("sensor_msgs/msg/JointState")


def test_a_bag_folder_with_the_offers_of_each_topic_that_rosbags_reads(tmp_path):
    """``bag=True`` (rns_demo's recordings): a rosbag2 folder, each topic entered with its
    first message and the QoS its publishers offer then; every message decodes with rosbags,
    JointState included (rclpy's buffers carry bytes after its content)."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    from rns_ros.bag.qos import profile

    asked = []

    def offers(topic: str) -> list[dict]:
        asked.append(topic)
        return [profile(depth=1, durability="transient_local")] if topic == "/a" else []

    folder = tmp_path / "dls"
    folder.mkdir()
    (folder / "dls_0.mcap").write_bytes(b"an earlier run")
    with McapRecording(folder, lambda name: "/" + name, offers=offers, bag=True) as recording:
        recording.add(_log("a", [_joint_state(k) for k in range(3)], raw=True))
        recording.add(TopicLog("never", JointState))
    assert recording.close() == str(folder)
    assert asked == ["/a"]
    assert sorted(p.name for p in folder.iterdir()) == ["dls_0.mcap", "metadata.yaml"]
    typestore = get_typestore(Stores.ROS2_JAZZY)
    with Reader(folder) as reader:
        (connection,) = reader.connections
        assert connection.ext.offered_qos_profiles[0].depth == 1
        decoded = [typestore.deserialize_cdr(raw, c.msgtype) for c, _, raw in reader.messages()]
    assert [msg.header.stamp.sec for msg in decoded] == [0, 1, 2]
