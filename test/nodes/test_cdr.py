"""Pre-serialized publishing and raw reading (rns_ros.nodes.cdr) against rclpy's own CDR."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import TwistStamped, WrenchStamped
from hypothesis import given, settings
from hypothesis import strategies as st
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from rns_testing import big_endian_joint_state
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from rns_ros.nodes.cdr import (
    JointStateReader,
    JointTrajectoryReader,
    MalformedMessageError,
    SerializedTemplate,
    TemplateError,
    clock_template,
    joint_state_fields,
    joint_state_template,
    joint_trajectory_template,
    odometry_fields,
    odometry_template,
    parse_odometry,
    parse_twist_stamped,
    split_stamp,
    trajectory_fields,
    twist_stamped_fields,
    twist_stamped_template,
    wrench_template,
)
from rns_ros.nodes.robot_io import (
    TRAJECTORY_DELIVERY_MARGIN,
    duration_msg,
    streamed_trajectory,
)

# names and frame ids of any length (the padding after them varies) and any character a ROS
# string can hold (not NUL: rclpy cuts a string there)
CHARACTERS = st.characters(blacklist_characters="\x00", blacklist_categories=("Cs",))
NAMES = st.lists(st.text(CHARACTERS, min_size=1, max_size=12), min_size=1, max_size=9, unique=True)
FRAMES = st.text(CHARACTERS, max_size=10)
FINITE = st.floats(allow_nan=False, allow_infinity=False, width=64)
STAMPS = st.tuples(st.integers(-(2**31), 2**31 - 1), st.integers(0, 999_999_999))


def _values(draw, size: int) -> np.ndarray:
    return np.array(draw(st.lists(FINITE, min_size=size, max_size=size)), dtype=float)


@settings(max_examples=60, deadline=None)
@given(data=st.data(), names=NAMES, frame=FRAMES, effort=st.booleans(), stamp=STAMPS)
def test_joint_state_template_reads_back_as_the_message(data, names, frame, effort, stamp):
    template = joint_state_template(names, frame, effort=effort)
    n = len(names)
    values = {"position": _values(data.draw, n), "velocity": _values(data.draw, n)}
    if effort:
        values["effort"] = _values(data.draw, n)
    msg = deserialize_message(template.serialize(values, stamp), JointState)
    assert list(msg.name) == names
    assert msg.header.frame_id == frame
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == stamp
    for field in ("position", "velocity"):
        assert np.array_equal(getattr(msg, field), values[field])
    assert np.array_equal(msg.effort, values["effort"] if effort else [])


@settings(max_examples=40, deadline=None)
@given(data=st.data(), frame=FRAMES, child=FRAMES, stamp=STAMPS)
def test_odometry_and_wrench_templates_read_back(data, frame, child, stamp):
    pose, twist, wrench = _values(data.draw, 7), _values(data.draw, 6), _values(data.draw, 6)
    msg = deserialize_message(
        odometry_template(frame, child).serialize({"pose": pose, "twist": twist}, stamp),
        Odometry,
    )
    assert (msg.header.frame_id, msg.child_frame_id) == (frame, child)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == stamp
    fields = odometry_fields(msg)
    assert np.array_equal(fields.pose, pose)
    assert np.array_equal(fields.twist, twist)
    assert not np.any(msg.pose.covariance)
    assert not np.any(msg.twist.covariance)
    read = deserialize_message(
        wrench_template(frame).serialize({"wrench": wrench}, stamp), WrenchStamped
    )
    w = read.wrench
    got = [w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z]
    assert np.array_equal(got, wrench)
    assert read.header.frame_id == frame


@settings(max_examples=40, deadline=None)
@given(data=st.data(), names=NAMES, stamp=STAMPS)
def test_trajectory_template_reads_back_as_the_streamed_trajectory(data, names, stamp):
    n = len(names)
    positions, velocities = _values(data.draw, n), _values(data.draw, n)
    end = _values(data.draw, n)
    template = joint_trajectory_template(names, 0.02)
    msg = deserialize_message(
        template.serialize(
            {"positions": positions, "velocities": velocities, "end_positions": end}, stamp
        ),
        JointTrajectory,
    )
    assert list(msg.joint_names) == names
    assert len(msg.points) == 3
    first, stop, rest = msg.points
    assert np.array_equal(first.positions, positions)
    assert np.array_equal(first.velocities, velocities)
    assert len(first.accelerations) == 0
    assert (first.time_from_start.sec, first.time_from_start.nanosec) == (0, 0)
    assert np.array_equal(stop.positions, end)
    assert len(stop.velocities) == len(stop.accelerations) == 0
    assert (stop.time_from_start.sec, stop.time_from_start.nanosec) == (0, 20_000_000)
    assert np.array_equal(rest.positions, end)
    assert np.array_equal(rest.velocities, np.zeros(n))
    assert len(rest.accelerations) == 0
    margin = round(TRAJECTORY_DELIVERY_MARGIN * 1e9)
    assert (rest.time_from_start.sec, rest.time_from_start.nanosec) == divmod(margin, 10**9)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == stamp
    streamed = streamed_trajectory(Time(), names, np.zeros(n), np.zeros(n), 0.02)
    assert [p.time_from_start for p in msg.points] == [p.time_from_start for p in streamed.points]


def test_clock_template_round_trips_the_time():
    for nanoseconds in (0, 1, 999_999_999, 1_000_000_000, 21_340_000_000, (2**31 - 1) * 10**9):
        sec, nanosec = split_stamp(nanoseconds)
        msg = deserialize_message(clock_template().serialize({}, (sec, nanosec)), Clock)
        assert msg.clock.sec * 1_000_000_000 + msg.clock.nanosec == nanoseconds


def test_slots_not_given_keep_their_values():
    template = odometry_template("world", "base")
    pose = np.arange(7.0)
    template.serialize({"pose": pose, "twist": np.ones(6)}, (1, 2))
    msg = deserialize_message(template.serialize({"twist": np.zeros(6)}), Odometry)
    assert np.array_equal(odometry_fields(msg).pose, pose)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (1, 2)


def test_a_filler_that_changes_the_layout_or_skips_a_slot_is_refused():
    def growing(msg, values):  # a name list that grows: the layout moves
        msg.name = [*msg.name, "extra"]
        msg.position = [float(x) for x in values["position"]]

    with pytest.raises(TemplateError):
        SerializedTemplate(JointState(name=["a"]), {"position": 1}, growing)

    with pytest.raises(TemplateError, match="position"):
        SerializedTemplate(JointState(name=["a"]), {"position": 1}, lambda msg, values: None)


# --- readers --------------------------------------------------------------------------------


@settings(max_examples=80, deadline=None)
@given(
    names=NAMES,
    frame=FRAMES,
    stamp=STAMPS,
    lengths=st.tuples(*[st.integers(0, 9)] * 3),
    data=st.data(),
)
def test_joint_state_reader_agrees_with_rclpy(names, frame, stamp, lengths, data):
    msg = JointState(name=names)
    msg.header.frame_id = frame
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    for field, size in zip(("position", "velocity", "effort"), lengths, strict=True):
        setattr(msg, field, _values(data.draw, size).tolist())
    fields = JointStateReader().parse(serialize_message(msg))
    expected = joint_state_fields(msg)
    assert fields.stamp == expected.stamp
    assert fields.names == expected.names
    for got, want in zip(fields[2:], expected[2:], strict=True):
        assert np.array_equal(got, want)


def test_joint_state_reader_reuses_a_repeated_name_list_and_sees_a_new_one():
    reader = JointStateReader()
    first = reader(serialize_message(JointState(name=["a", "b"], position=[1.0, 2.0])))
    again = reader(serialize_message(JointState(name=["a", "b"], position=[3.0, 4.0])))
    assert again.names is first.names
    assert np.array_equal(again.position, [3.0, 4.0])
    other = reader(serialize_message(JointState(name=["a", "c"], position=[5.0, 6.0])))
    assert other.names == ("a", "c")
    # a longer list that starts with the cached bytes is not mistaken for them
    longer = reader(serialize_message(JointState(name=["a", "c", "d"])))
    assert longer.names == ("a", "c", "d")


#: A point's velocities: random, none, all zero, all -0.0 (zero too).
VELOCITY_KINDS = st.sampled_from(["random", "empty", "zero", "negative_zero"])


def _point_velocities(draw, kind: str, size: int) -> list[float]:
    if kind == "random":
        return _values(draw, size).tolist()
    return {"empty": [], "zero": [0.0] * size, "negative_zero": [-0.0] * size}[kind]


def _assert_same_trajectory_fields(fields, expected) -> None:
    assert fields[:3] == expected[:3]
    for got, want in zip(fields[3:6], expected[3:6], strict=True):
        assert np.array_equal(got, want)
    assert fields.velocity_end == expected.velocity_end


@settings(max_examples=80, deadline=None)
@given(names=NAMES, stamp=STAMPS, points=st.integers(0, 4), data=st.data())
def test_trajectory_reader_agrees_with_rclpy(names, stamp, points, data):
    msg = JointTrajectory(joint_names=names)
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    for _ in range(points):
        sizes = data.draw(st.tuples(*[st.integers(0, 8)] * 4))
        fields = dict(
            zip(
                ("positions", "accelerations", "effort"),
                (_values(data.draw, size).tolist() for size in sizes[1:]),
                strict=True,
            )
        )
        fields["velocities"] = _point_velocities(data.draw, data.draw(VELOCITY_KINDS), sizes[0])
        point = JointTrajectoryPoint(**fields)
        point.time_from_start.sec, point.time_from_start.nanosec = data.draw(STAMPS)
        msg.points.append(point)
    fields = JointTrajectoryReader().parse(serialize_message(msg))
    expected = trajectory_fields(msg)
    _assert_same_trajectory_fields(fields, expected)
    at_rest = [p for p in msg.points[1:] if not any(p.velocities)]
    if at_rest:
        end = at_rest[0].time_from_start
        assert fields.velocity_end == end.sec + 1e-9 * end.nanosec
    else:
        assert fields.velocity_end == math.inf


def _streamed(stamp=(12, 340_000_000), horizon=0.02, n=7):
    """Our streamed shape (robot_io.streamed_trajectory): point 1 at ``horizon`` [s]."""
    return streamed_trajectory(
        Time(sec=stamp[0], nanosec=stamp[1]),
        [f"joint_{i}" for i in range(1, n + 1)],
        np.linspace(-1.0, 1.0, n),
        np.linspace(0.1, 0.3, n),
        horizon,
    )


@pytest.mark.parametrize("horizon", [0.02, 0.002, 0.2, 1.5])
def test_a_streamed_trajectory_ends_its_velocity_at_point_1_on_both_paths(horizon):
    """The fast parser and rclpy's deserialization agree: point 0's velocity ends at point 1's
    time_from_start (two periods); the pre-serialized template says the same."""
    msg = _streamed(horizon=horizon)
    data = serialize_message(msg)
    fields = JointTrajectoryReader().parse(data)
    _assert_same_trajectory_fields(fields, trajectory_fields(msg))
    assert fields.velocity_end == pytest.approx(horizon, abs=1e-9)
    assert np.array_equal(fields.velocities, msg.points[0].velocities)
    template = joint_trajectory_template(list(msg.joint_names), horizon)
    serialized = template.serialize(
        {
            "positions": msg.points[0].positions,
            "velocities": msg.points[0].velocities,
            "end_positions": msg.points[1].positions,
        },
        (12, 340_000_000),
    )
    _assert_same_trajectory_fields(JointTrajectoryReader().parse(serialized), fields)


def test_a_one_point_trajectory_holds_its_velocity_on_both_paths():
    msg = JointTrajectory(
        joint_names=["a", "b"],
        points=[JointTrajectoryPoint(positions=[1.0, 2.0], velocities=[0.1, -0.2])],
    )
    fields = JointTrajectoryReader().parse(serialize_message(msg))
    _assert_same_trajectory_fields(fields, trajectory_fields(msg))
    assert fields.velocity_end == math.inf
    # a later point that still moves does not end it either
    moving = JointTrajectoryPoint(positions=[1.1, 1.9], velocities=[0.1, -0.2])
    moving.time_from_start = duration_msg(0.5)
    msg.points.append(moving)
    fields = JointTrajectoryReader().parse(serialize_message(msg))
    _assert_same_trajectory_fields(fields, trajectory_fields(msg))
    assert fields.velocity_end == math.inf
    # an empty trajectory: no velocity to end
    empty = JointTrajectory(joint_names=["a"])
    fields = JointTrajectoryReader().parse(serialize_message(empty))
    _assert_same_trajectory_fields(fields, trajectory_fields(empty))
    assert fields.points == 0
    assert fields.velocity_end == math.inf


def _big_endian_trajectory(msg: JointTrajectory) -> bytes:
    """``msg`` in big-endian CDR (rclpy writes little-endian only on this machine)."""
    out = bytearray(b"\x00\x00\x00\x00")  # CDR_BE

    def align(size):
        out.extend(b"\x00" * (-(len(out) - 4) % size))

    def u32(value):
        align(4)
        out.extend(struct.pack(">I", value))

    def string(text):
        raw = text.encode() + b"\x00"
        u32(len(raw))
        out.extend(raw)

    def doubles(values):
        u32(len(values))
        if len(values):
            align(8)
            out.extend(struct.pack(f">{len(values)}d", *values))

    out.extend(struct.pack(">iI", msg.header.stamp.sec, msg.header.stamp.nanosec))
    string(msg.header.frame_id)
    u32(len(msg.joint_names))
    for name in msg.joint_names:
        string(name)
    u32(len(msg.points))
    for point in msg.points:
        for values in (point.positions, point.velocities, point.accelerations, point.effort):
            doubles(values)
        align(4)
        out.extend(struct.pack(">iI", point.time_from_start.sec, point.time_from_start.nanosec))
    return bytes(out)


def test_a_big_endian_trajectory_is_read_through_rclpy_with_its_velocity_end():
    msg = _streamed()
    big = _big_endian_trajectory(msg)
    reader = JointTrajectoryReader()
    assert reader.parse(big) is None  # the parser takes little-endian CDR only
    fields = reader(big)
    _assert_same_trajectory_fields(fields, JointTrajectoryReader().parse(serialize_message(msg)))
    assert fields.velocity_end == pytest.approx(0.02, abs=1e-9)


def test_a_cut_streamed_trajectory_is_rejected_never_misread():
    """Cut anywhere before its last byte (the last point's time_from_start), a streamed
    trajectory is declined by the parser and rejected by the reader as a MalformedMessageError,
    never another exception. (rclpy would read some cuts, its missing points left at their
    defaults: a trajectory that lost its point at rest.) rclpy's buffer may end in spare
    bytes: a cut there reads right."""
    data = serialize_message(_streamed())
    whole = JointTrajectoryReader().parse(data)
    last = struct.pack("<iI", *divmod(round(TRAJECTORY_DELIVERY_MARGIN * 1e9), 10**9))
    end = data.rindex(last) + len(last)
    for cut in range(len(data)):
        if cut < end:
            assert JointTrajectoryReader().parse(data[:cut]) is None, cut
            with pytest.raises(MalformedMessageError, match="not a JointTrajectory"):
                JointTrajectoryReader()(data[:cut])
        else:
            _assert_same_trajectory_fields(JointTrajectoryReader()(data[:cut]), whole)


@settings(max_examples=40, deadline=None)
@given(data=st.data(), frame=FRAMES, child=FRAMES, stamp=STAMPS)
def test_odometry_reader_agrees_with_rclpy(data, frame, child, stamp):
    msg = Odometry(child_frame_id=child)
    msg.header.frame_id = frame
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    p, o = msg.pose.pose.position, msg.pose.pose.orientation
    p.x, p.y, p.z, o.x, o.y, o.z, o.w = _values(data.draw, 7).tolist()
    msg.pose.covariance = _values(data.draw, 36).tolist()
    t = msg.twist.twist
    t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z = _values(
        data.draw, 6
    ).tolist()
    fields, expected = parse_odometry(serialize_message(msg)), odometry_fields(msg)
    assert fields.stamp == expected.stamp
    assert np.array_equal(fields.pose, expected.pose)
    assert np.array_equal(fields.twist, expected.twist)


def test_big_endian_data_is_read_through_rclpy():
    """The parsers take plain little-endian CDR only; the readers hand anything else to rclpy,
    which reads it right."""
    big = big_endian_joint_state(["a", "b"], [1.5, -2.0])
    reader = JointStateReader()
    assert reader.parse(big) is None
    fields = reader(big)
    assert fields.names == ("a", "b")
    assert np.array_equal(fields.position, [1.5, -2.0])
    assert fields.stamp == (3, 4)


def test_parsers_decline_cut_messages_without_raising():
    whole = serialize_message(JointState(name=["a", "b"], position=[1.0, 2.0]))
    odom = serialize_message(Odometry())
    twist = serialize_message(TwistStamped())
    trajectory = serialize_message(
        JointTrajectory(joint_names=["a"], points=[JointTrajectoryPoint(positions=[1.0])])
    )
    # rclpy's buffers may end in spare bytes: a cut there still reads, and must read right
    full = JointStateReader().parse(whole)
    for cut in range(len(whole)):
        fields = JointStateReader().parse(whole[:cut])  # never an exception, never wrong values
        assert fields is None or (
            fields.names == full.names and np.array_equal(fields.position, full.position)
        )
    for cut in range(len(twist)):
        fields = parse_twist_stamped(twist[:cut])
        assert fields is None or not fields.angular.any()
    for cut in range(len(odom)):
        fields = parse_odometry(odom[:cut])
        assert fields is None or np.array_equal(fields.pose, parse_odometry(odom).pose)
    full_trajectory = JointTrajectoryReader().parse(trajectory)
    for cut in range(len(trajectory)):
        fields = JointTrajectoryReader().parse(trajectory[:cut])
        assert fields is None or np.array_equal(fields.positions, full_trajectory.positions)


@settings(max_examples=40, deadline=None)
@given(data=st.data(), frame=FRAMES, stamp=STAMPS)
def test_twist_template_and_reader_agree_with_rclpy(data, frame, stamp):
    twist = _values(data.draw, 6)
    serialized = twist_stamped_template(frame).serialize({"twist": twist}, stamp)
    msg = deserialize_message(serialized, TwistStamped)
    expected = twist_stamped_fields(msg)
    assert expected.frame_id == frame
    assert expected.stamp == stamp
    assert np.array_equal(np.concatenate((expected.linear, expected.angular)), twist)
    fields = parse_twist_stamped(serialize_message(msg))
    assert fields.stamp == expected.stamp
    assert fields.frame_id == expected.frame_id
    assert np.array_equal(fields.linear, expected.linear)
    assert np.array_equal(fields.angular, expected.angular)


def test_a_stale_marker_in_padding_bytes_is_not_taken_for_the_slot():
    """Padding bytes of a CDR serialization are not defined: they can hold a marker from an
    earlier serialization. The slot is where both marker families sit."""
    from rns_ros.nodes.cdr import TemplateError, _find_once

    a, b = b"AAAAAAAA", b"BBBBBBBB"
    true, stale = 16, 40
    blob_a = bytearray(64)
    blob_b = bytearray(64)
    blob_a[true : true + 8] = a
    blob_a[stale : stale + 8] = a  # stale copy in padding
    blob_b[true : true + 8] = b
    assert _find_once((bytes(blob_a), bytes(blob_b)), (a, b), "slot") == true
    blob_b[stale : stale + 8] = b  # both families stale at the same place: ambiguous
    with pytest.raises(TemplateError, match="not found exactly once"):
        _find_once((bytes(blob_a), bytes(blob_b)), (a, b), "slot")


@settings(max_examples=40, deadline=None)
@given(data=st.data(), names=NAMES, frame=FRAMES, effort=st.booleans(), stamp=STAMPS)
def test_templates_put_exactly_the_cdr_content_on_the_wire(data, names, frame, effort, stamp):
    """What the simulator publishes is what rosbags (an independent CDR implementation) reads
    and writes for the same message: no bytes after the content (rclpy's serializer leaves a
    few, which rosbags refuses)."""
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    n = len(names)
    values = {"position": _values(data.draw, n), "velocity": _values(data.draw, n)}
    if effort:
        values["effort"] = _values(data.draw, n)
    joints = joint_state_template(names, frame, effort=effort).serialize(values, stamp)
    decoded = store.deserialize_cdr(joints, "sensor_msgs/msg/JointState")
    assert list(decoded.name) == names
    assert len(joints) == len(store.serialize_cdr(decoded, "sensor_msgs/msg/JointState"))
    pose, twist = _values(data.draw, 7), _values(data.draw, 6)
    odom = odometry_template(frame, "base").serialize({"pose": pose, "twist": twist}, stamp)
    decoded = store.deserialize_cdr(odom, "nav_msgs/msg/Odometry")
    assert len(odom) == len(store.serialize_cdr(decoded, "nav_msgs/msg/Odometry"))
