"""rns_bag as a user runs it: ``rns_simulator`` started by hand, ``rns_bag record`` stopped by
Ctrl-C, the folder read by rosbags' rosbag2 Reader (a reader nobody on the project wrote),
``rns_bag info`` against what that reader counts, ``rns_bag play`` driving a subscriber of this
test, and one line with exit code 2 for what is not right. Counts and contents, never rates.
Domain: ROS_DOMAIN_ID, loopback only."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections import Counter
from pathlib import Path

import pytest

from rns_ros.apps.bag import format_size, main
from rns_ros.bag import BagWriter, open_bag

pytestmark = pytest.mark.slow

BIN = Path(sys.executable).parent
DOMAIN = os.environ.get("ROS_DOMAIN_ID", "43")
ENV = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "ROS_DOMAIN_ID": DOMAIN}
ENV.pop("ROS_STATIC_PEERS", None)


def _wait_for(path: Path, pattern: str, process: subprocess.Popen, timeout: float) -> str:
    """The text of ``path`` once it matches ``pattern`` (the process still running)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        text = path.read_text() if path.exists() else ""
        if re.search(pattern, text, re.MULTILINE):
            return text
        assert process.poll() is None, f"{process.args[0]} ended: {text}"
        time.sleep(0.2)
    raise AssertionError(f"no {pattern!r} within {timeout} s: {path.read_text()}")


def _stop(process: subprocess.Popen) -> int:
    if process.poll() is None:
        process.send_signal(signal.SIGINT)  # Ctrl-C
    try:
        return process.wait(timeout=60)
    except subprocess.TimeoutExpired:
        process.kill()
        raise


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A stack started by hand (rns_simulator) and two recorders stopped by Ctrl-C: the state
    topics, and the latched robot model topics joined after they were published."""
    tmp = tmp_path_factory.mktemp("bag")
    logs = {name: tmp / f"{name}.log" for name in ("simulator", "states", "model")}
    with open(logs["simulator"], "w") as log:
        simulator = subprocess.Popen([str(BIN / "rns_simulator")], env=ENV, stdout=log,
                                     stderr=subprocess.STDOUT)  # fmt: skip
    processes = [simulator]
    try:
        _wait_for(logs["simulator"], "publishing at", simulator, 120)
        commands = {
            "states": ["/joint_states", "/base_odom"],
            "model": ["/tf_static", "/robot_description"],
        }
        recorders = {}
        for name, topics in commands.items():
            with open(logs[name], "w") as log:
                recorders[name] = subprocess.Popen(
                    [str(BIN / "rns_bag"), "record", "-o", str(tmp / name), *topics],
                    env=ENV, stdout=log, stderr=subprocess.STDOUT,
                )  # fmt: skip
            processes.append(recorders[name])
        for name, topics in commands.items():
            for topic in topics:
                _wait_for(logs[name], f"^rns_bag: subscribed to {topic} ", recorders[name], 60)
        time.sleep(2.0)  # some messages
        codes = {name: _stop(process) for name, process in recorders.items()}
    finally:
        for process in reversed(processes):
            _stop(process)
    return tmp, codes, {name: path.read_text() for name, path in logs.items()}


def _reader_counts(folder: Path) -> tuple[Counter, dict]:
    """Messages per topic as rosbags' rosbag2 Reader counts and decodes them (Jazzy types)."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_JAZZY)
    counts, last = Counter(), {}
    with Reader(folder) as reader:
        for connection, _stamp, raw in reader.messages():
            last[connection.topic] = typestore.deserialize_cdr(raw, connection.msgtype)
            counts[connection.topic] += 1
    return counts, last


def test_record_stops_on_ctrl_c_and_leaves_a_bag_rosbags_reads(recorded):
    from rosbags.interfaces import QosDurability, QosReliability
    from rosbags.rosbag2 import Reader

    tmp, codes, logs = recorded
    assert codes == {"states": 0, "model": 0}, logs
    assert "Traceback" not in logs["states"] + logs["model"]
    folder = tmp / "states"
    assert sorted(p.name for p in folder.iterdir()) == ["metadata.yaml", "states_0.mcap"]
    with Reader(folder) as reader:
        offered = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
        types = {c.topic: c.msgtype for c in reader.connections}
    assert types == {"/joint_states": "sensor_msgs/msg/JointState",
                     "/base_odom": "nav_msgs/msg/Odometry"}  # fmt: skip
    for profiles in offered.values():  # the simulator's state publishers (discovery tells no
        # history depth: as rosbag2 records the graph's profiles)
        assert [(q.reliability, q.durability) for q in profiles] == [
            (QosReliability.RELIABLE, QosDurability.VOLATILE)
        ]
    counts, last = _reader_counts(folder)
    assert counts["/joint_states"] > 20
    assert counts["/base_odom"] > 20
    assert list(last["/joint_states"].name) == [f"joint_{i}" for i in range(1, 8)]
    assert len(last["/joint_states"].position) == 7


def test_latched_topics_published_before_the_recorder_are_recorded(recorded):
    from rosbags.interfaces import QosDurability
    from rosbags.rosbag2 import Reader

    tmp, _, _ = recorded
    counts, last = _reader_counts(tmp / "model")
    assert counts == {"/tf_static": 1, "/robot_description": 1}
    assert last["/robot_description"].data.lstrip().startswith("<?xml") or "<robot" in (
        last["/robot_description"].data
    )
    with Reader(tmp / "model") as reader:
        assert {c.ext.offered_qos_profiles[0].durability for c in reader.connections} == {
            QosDurability.TRANSIENT_LOCAL
        }


def test_info_describes_the_bag_as_the_reader_counts_it(recorded):
    tmp, _, _ = recorded
    folder = tmp / "states"
    done = subprocess.run([str(BIN / "rns_bag"), "info", str(folder)], env=ENV,
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr
    counts, _ = _reader_counts(folder)
    text = done.stdout
    shown = {
        topic: int(count)
        for topic, count in re.findall(r"Topic: (\S+) \| Type: \S+ \| Count: (\d+) \|", text)
    }
    assert shown == dict(counts)
    assert re.search(rf"^Messages: +{sum(counts.values())}$", text, re.MULTILINE)
    assert re.search(r"^Files: +states_0\.mcap$", text, re.MULTILINE)
    assert re.search(r"^Storage id: +mcap$", text, re.MULTILINE)
    assert re.search(r"^ROS Distro: +jazzy$", text, re.MULTILINE)
    size = sum(path.stat().st_size for path in folder.glob("*.mcap"))
    assert re.search(rf"^Bag size: +{re.escape(format_size(size))}$", text, re.MULTILINE)
    assert "Serialization Format: cdr" in text


def _in_order(part: list[bytes], whole: list[bytes]) -> bool:
    """Every item of ``part`` is in ``whole``, in the same order."""
    items = iter(whole)
    return all(any(item == candidate for candidate in items) for item in part)


def test_in_order_tells_a_reordering_or_an_alien_message():
    assert _in_order([b"a", b"c"], [b"a", b"b", b"c"])
    assert not _in_order([b"c", b"a"], [b"a", b"b", b"c"])
    assert not _in_order([b"a", b"x"], [b"a", b"b", b"c"])


def test_play_drives_a_subscriber_with_the_recorded_messages(recorded):
    """The recorded messages arrive at a subscriber of this process byte for byte, in their
    order, every one published, and /clock carries the bag's times. How many the subscriber
    gets depends on how this machine schedules it: the player keeps the recorded keep-last
    history (as ros2 bag play), so a subscriber that falls behind loses the oldest."""
    import rclpy
    from builtin_interfaces.msg import Time  # noqa: F401 - the clock's field type
    from nav_msgs.msg import Odometry
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import JointState

    tmp, _, _ = recorded
    bag = open_bag(tmp / "states")
    stored = {"/joint_states": [], "/base_odom": []}
    for message in bag.messages():
        stored[message.topic].append(bytes(message.data))
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(DOMAIN))
    received = {topic: [] for topic in stored}
    clocks = []
    try:
        node = rclpy.create_node("bag_play_listener", context=context)
        deep = QoSProfile(depth=10_000, reliability=ReliabilityPolicy.RELIABLE)
        for topic, kind in (("/joint_states", JointState), ("/base_odom", Odometry)):
            node.create_subscription(kind, topic, received[topic].append, deep, raw=True)
        node.create_subscription(
            Clock, "/clock", clocks.append,
            QoSProfile(depth=10_000, reliability=ReliabilityPolicy.BEST_EFFORT),
        )  # fmt: skip
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        stop = threading.Event()
        spinner = threading.Thread(
            target=lambda: [executor.spin_once(timeout_sec=0.05) for _ in iter(stop.is_set, True)],
            daemon=True,
        )
        spinner.start()
        done = subprocess.run(
            [str(BIN / "rns_bag"), "play", str(tmp / "states"), "--delay", "4", "--rate", "2",
             "--clock", "50"],
            env=ENV, capture_output=True, text=True, timeout=240,
        )  # fmt: skip
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline and any(
            len(received[t]) < len(stored[t]) for t in stored
        ):
            time.sleep(0.1)
        stop.set()
        spinner.join(timeout=10)
    finally:
        rclpy.try_shutdown(context=context)
    assert done.returncode == 0, done.stderr
    total = sum(map(len, stored.values()))
    assert f"rns_bag: published {total} messages" in done.stdout
    for topic in stored:
        assert received[topic], topic
        assert _in_order(received[topic], stored[topic]), topic
    start, end = bag.metadata.starting_time_ns, bag.metadata.end_ns
    stamps = [c.clock.sec * 10**9 + c.clock.nanosec for c in clocks]
    assert stamps, "no /clock"
    assert stamps == sorted(stamps)
    assert start <= stamps[0]
    assert stamps[-1] <= end  # held at a late message's time, never past the bag's end


def test_the_stored_content_is_as_long_as_a_normal_publish_on_the_wire():
    """What a publisher that serializes the message itself sends (rclpy's publish of a message
    object), received raw, is exactly as long as the content the writer keeps of
    rclpy.serialization's buffer (which for some types is longer)."""
    import rclpy
    from bag_messages import sample_messages, type_name
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSProfile
    from rclpy.serialization import serialize_message

    from rns_ros.bag.cdr import CdrLayout
    from rns_ros.bag.definitions import message_definition, parse_definition

    messages = [msg for msgs in sample_messages().values() for msg in msgs]
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(DOMAIN))
    wire: dict[int, bytes] = {}
    try:
        node = rclpy.create_node("bag_wire_check", context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        qos = QoSProfile(depth=10)
        publishers = {}
        for k, msg in enumerate(messages):
            topic = f"/bag_wire_check_{k}"
            node.create_subscription(type(msg), topic, lambda d, k=k: wire.setdefault(k, d), qos,
                                     raw=True)  # fmt: skip
            publishers[k] = node.create_publisher(type(msg), topic, qos)
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline and len(wire) < len(messages):
            for k, msg in enumerate(messages):
                if k not in wire and publishers[k].get_subscription_count():
                    publishers[k].publish(msg)
            executor.spin_once(timeout_sec=0.1)
    finally:
        rclpy.try_shutdown(context=context)
    assert len(wire) == len(messages)
    longer = 0
    for k, msg in enumerate(messages):
        name = type_name(msg)
        data = serialize_message(msg)
        content = CdrLayout(name, parse_definition(name, message_definition(name))).content(data)
        assert len(content) == len(wire[k]), name
        longer += len(data) > len(content)
    assert longer > 0  # the case the writer is for: JointState among them


def _one_line(argv: list[str], capsys) -> str:
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.splitlines()) == 1, err
    return err.strip()


def test_bad_input_is_one_line_and_exit_code_2(tmp_path, capsys):
    assert _one_line(["info", str(tmp_path / "none")], capsys) == (
        f"rns_bag: {tmp_path / 'none'}: no such bag folder or file"
    )
    (tmp_path / "notes.txt").write_text("not a bag")
    assert _one_line(["play", str(tmp_path / "notes.txt")], capsys) == (
        f"rns_bag: {tmp_path / 'notes.txt'}: not an MCAP file"
    )
    # a bag whose type is not installed here
    with BagWriter(tmp_path / "alien") as writer:
        topic = writer.add_topic("/thing", "rns_missing_msgs/msg/Thing", definition="int32 x\n",
                                 type_hash="")  # fmt: skip
        writer.write(topic, b"\x00\x01\x00\x00\x07\x00\x00\x00", 1)
    assert _one_line(["play", str(tmp_path / "alien")], capsys) == (
        "rns_bag: /thing: message type rns_missing_msgs/msg/Thing is not installed"
    )
    assert main(["info", str(tmp_path / "alien")]) == 0  # describing it needs no type
    assert "Type: rns_missing_msgs/msg/Thing | Count: 1" in capsys.readouterr().out
    for rate in ("0", "-1", "nan"):
        assert "--rate must be" in _one_line(["play", str(tmp_path / "alien"), "-r", rate], capsys)
    assert "--rate must be a number" in _one_line(["play", "x", "--rate", "fast"], capsys)
    assert "--clock must be" in _one_line(["play", str(tmp_path / "alien"), "--clock", "-5"],
                                          capsys)  # fmt: skip
    assert "--topics" not in _one_line(["play", str(tmp_path / "alien"), "--topics", "/x"], capsys)
    assert "already exists" in _one_line(["record", "-o", str(tmp_path), "/a"], capsys)
    assert "-a for all" in _one_line(["record", "-o", str(tmp_path / "new")], capsys)
    assert "not both" in _one_line(["record", "-a", "/a", "-o", str(tmp_path / "new")], capsys)
    assert "at least 1024" in _one_line(
        ["record", "-b", "10", "-o", str(tmp_path / "new"), "/a"], capsys
    )
    assert not (tmp_path / "new").exists()


def test_the_console_script_says_one_line_without_a_traceback(tmp_path):
    done = subprocess.run([str(BIN / "rns_bag"), "info", str(tmp_path)], env=ENV,
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert done.returncode == 2
    assert done.stderr == f"rns_bag: {tmp_path}: not a bag folder (no metadata.yaml)\n"
