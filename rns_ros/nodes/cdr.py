"""Fixed-layout messages as CDR bytes: pre-serialized publishing and raw reading.

A state stream repeats one layout at every message: the simulator's ``joint_states`` always
names the same joints, ``base_odom`` always carries the same frame ids, the controller's
JointTrajectory always has the same three points of n values each. Only the stamp and the
float64 values change. rclpy converts each message from Python to C and serializes it on every
``publish``; at a lockstep run's thousand periods per second that conversion was a large part
of the nodes' CPU (an Odometry: ~27 us to convert, ~3 us to publish its bytes).

:class:`SerializedTemplate` serializes the message once with ``rclpy.serialization`` and finds
where each value lands in the bytes (by writing distinct marker values and locating them), then
writes new values there with numpy and hands the bytes to ``Publisher.publish``, which sends
serialized messages as they are. Subscribers receive the same type on the same topic: nothing
in the interface changes. The layout is checked once at construction: values written through
the template must read back (deserialized, since rclpy leaves the padding bytes undefined) as
the message they were filled into. A message it cannot place (a marker found twice, a slot not
contiguous) raises :class:`TemplateError`, and the caller publishes messages the usual way.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable, Mapping, Sequence
from typing import NamedTuple

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from geometry_msgs.msg import TwistStamped, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from rns_ros.bag.cdr import installed_layout
from rns_ros.bag.definitions import DefinitionError
from rns_ros.core.errors import InputError, RnsError
from rns_ros.nodes.robot_io import trajectory_end

#: Stamp markers (sec, nanosec): unlikely byte patterns in any other field.
_MARK_SEC, _MARK_NANOSEC = 0x5A17C0DE, 0x3B9AC9FF - 0x1234


class TemplateError(RnsError):
    """A message's layout could not be captured in a template (publish messages instead)."""


class MalformedMessageError(InputError):
    """Received bytes that are not a message of the subscribed type (truncated, corrupt, or
    of another type): anyone on the domain may send them, so the node rejects them and goes on."""


def deserialize_or_reject(data: bytes, message_type: type):
    """``data`` deserialized as ``message_type`` by rclpy.

    Raises:
        MalformedMessageError: they are not one (rclpy's RMWError, or any other failure).
    """
    try:
        return deserialize_message(data, message_type)
    except Exception as exc:  # rclpy raises RMWError; a broken buffer must never end a node
        raise MalformedMessageError(
            f"{len(data)} bytes that are not a {message_type.__name__} ({type(exc).__name__})"
        ) from None


Filler = Callable[[object, Mapping[str, np.ndarray]], None]


def _markers(slot: int, size: int, family: int = 0) -> np.ndarray:
    """``size`` float64 values no other slot (nor a small integer or a name) serializes to:
    tiny negative numbers with full mantissas (no runs of zero bytes to match across fields).
    ``family`` 0 or 1: two disjoint sets, to tell a slot from stale padding bytes."""
    base = np.pi if family == 0 else np.e
    return np.array([-(base + slot * 64 + i) * 2.0**-1000 for i in range(size)])


#: A second stamp marker, for the same reason.
_MARK_SEC_B, _MARK_NANOSEC_B = 0x2B0D1CE5, 0x3B9AC9FF - 0x4321


class SerializedTemplate:
    """The CDR bytes of ``message`` with writable float64 slots and, optionally, its stamp.

    Args:
        message: a message with its fixed content set (names, frame ids); the template keeps
            its own copy of the bytes, so the message may be reused or dropped.
        sizes: {slot name: number of float64 values}; ``fill`` writes them into a message.
        fill: ``fill(message, values)`` sets every slot of ``message`` from ``values`` (arrays
            of the sizes above). It must not change the layout (name lists, string fields).
        stamp: ``stamp(message, sec, nanosec)`` sets the message's stamp, or None for none.

    Raises:
        TemplateError: a slot or the stamp not found exactly once, or not contiguous, or values
            written through the template do not read back (through rclpy) as the message
            filled with them.
    """

    def __init__(
        self,
        message,
        sizes: Mapping[str, int],
        fill: Filler,
        stamp: Callable[[object, int, int], None] | None = None,
    ) -> None:
        self._sizes = dict(sizes)
        # Padding bytes of a serialization are not defined (they may hold a marker from an
        # earlier serialization): a slot is where both marker families serialize to.
        families = []
        for family, marks in ((0, (_MARK_SEC, _MARK_NANOSEC)), (1, (_MARK_SEC_B, _MARK_NANOSEC_B))):
            markers = {
                name: _markers(k, size, family)
                for k, (name, size) in enumerate(self._sizes.items())
            }
            fill(message, markers)
            if stamp is not None:
                stamp(message, *marks)
            families.append((bytes(serialize_message(message)), markers, marks))
        (data, markers, _), (data_b, markers_b, _) = families
        # rclpy's serializer sizes its buffer by an estimate: a few bytes past the content
        # would go on the wire, which strict CDR readers (rosbags) refuse
        self._buffer = bytearray(data[: _content_size(type(message), data)])
        self._slots: dict[str, np.ndarray] = {}
        for name, values in markers.items():
            offset = _find_once(
                (data, data_b),
                (values.astype("<f8").tobytes(), markers_b[name].astype("<f8").tobytes()),
                name,
            )
            self._slots[name] = np.frombuffer(
                self._buffer, dtype="<f8", count=values.size, offset=offset
            )
        self._stamp: tuple[np.ndarray, np.ndarray] | None = None
        if stamp is not None:
            patterns = tuple(
                np.array([sec], "<i4").tobytes() + np.array([nanosec], "<u4").tobytes()
                for sec, nanosec in ((_MARK_SEC, _MARK_NANOSEC), (_MARK_SEC_B, _MARK_NANOSEC_B))
            )
            offset = _find_once((data, data_b), patterns, "stamp")
            self._stamp = (
                np.frombuffer(self._buffer, dtype="<i4", count=1, offset=offset),
                np.frombuffer(self._buffer, dtype="<u4", count=1, offset=offset + 4),
            )
        self._check(message, fill, stamp)

    def _check(self, message, fill: Filler, stamp) -> None:
        rng = np.random.default_rng(7)
        values = {name: rng.standard_normal(size) for name, size in self._sizes.items()}
        fill(message, values)
        if stamp is not None:
            stamp(message, 1_234_567, 890_123_456)
        # compared as messages: the padding bytes of a serialization are not defined
        written = deserialize_message(
            self.serialize(values, (1_234_567, 890_123_456)), type(message)
        )
        if written != message:
            raise TemplateError(
                f"{type(message).__name__}: the template's bytes do not read back as the values "
                "written"
            )

    def serialize(
        self, values: Mapping[str, np.ndarray], stamp: tuple[int, int] | None = None
    ) -> bytes:
        """The message's CDR bytes with ``values`` ({slot: float64 array of its size}) and
        ``stamp`` (sec, nanosec) written in; slots not given keep their last values."""
        for name, array in values.items():
            self._slots[name][:] = array
        if stamp is not None and self._stamp is not None:
            self._stamp[0][0], self._stamp[1][0] = stamp
        return bytes(self._buffer)


def _content_size(message_type: type, data: bytes) -> int:
    """Bytes of ``data``'s CDR content (what a publish of the message puts on the wire)."""
    type_name = f"{message_type.__module__.split('.')[0]}/msg/{message_type.__name__}"
    try:
        size = installed_layout(type_name).content_size(data)
    except DefinitionError as exc:
        raise TemplateError(f"{type_name}: {exc}") from None
    if size is None:
        raise TemplateError(f"{type_name}: the serialized message does not walk as its type")
    return size


def _find_once(data: tuple[bytes, bytes], patterns: tuple[bytes, bytes], label: str) -> int:
    """The one offset where each serialization in ``data`` holds its pattern."""
    found = [_offsets(blob, pattern) for blob, pattern in zip(data, patterns, strict=True)]
    common = found[0] & found[1]
    if len(common) != 1:
        raise TemplateError(f"slot {label!r} not found exactly once in the serialized message")
    return common.pop()


def _offsets(data: bytes, pattern: bytes) -> set[int]:
    offsets, start = set(), data.find(pattern)
    while start >= 0:
        offsets.add(start)
        start = data.find(pattern, start + 1)
    return offsets


# --- reading: the fields a control loop needs, straight from the CDR bytes --------------------
#
# A raw subscription hands over the serialized message; deserializing it into Python objects
# cost 20 us (JointState) to 70 us (Odometry) per message, more than the callbacks using it.
# The readers below take what the nodes use with numpy views. They read little-endian plain CDR
# (what Fast DDS sends on this hardware); anything else (big-endian, parameter lists, an
# unexpected size) their ``parse`` declines and rclpy deserializes.

_U32, _STAMP = struct.Struct("<I"), struct.Struct("<iI")
_LITTLE_ENDIAN_CDR = b"\x00\x01"  # CDR_LE (plain CDR; parameter lists, XCDR2: rclpy reads them)


class _Cursor:
    """Reads primitives at CDR alignment (relative to the end of the 4-byte encapsulation)."""

    __slots__ = ("data", "offset")

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.offset = 4

    def _align(self, size: int) -> None:
        self.offset += -(self.offset - 4) % size

    def u32(self) -> int:
        self._align(4)
        (value,) = _U32.unpack_from(self.data, self.offset)
        self.offset += 4
        return value

    def stamp(self) -> tuple[int, int]:
        self._align(4)
        stamp = _STAMP.unpack_from(self.data, self.offset)
        self.offset += 8
        return stamp

    def string(self) -> bytes:
        """The string's bytes without its terminating NUL."""
        size = self.u32()
        if size == 0:
            return b""
        end = self.offset + size
        if end > len(self.data):
            raise ValueError("string beyond the message")
        value = self.data[self.offset : end - 1]
        self.offset = end
        return value

    def strings(
        self, previous: tuple[bytes, tuple[str, ...]] | None = None
    ) -> tuple[bytes, tuple[str, ...]]:
        """A sequence of strings, as (its bytes, the decoded strings). A stream repeats one list
        (joint names): when the bytes from here start with ``previous``'s, it is taken as is,
        neither parsed nor decoded (the same tuple)."""
        start = self.offset
        if previous is not None and self.data.startswith(previous[0], start):
            self.offset = start + len(previous[0])
            return previous
        values = tuple(self.string().decode("utf-8", "replace") for _ in range(self.u32()))
        return self.data[start : self.offset], values

    def doubles(self, count: int | None = None) -> np.ndarray:
        """``count`` float64 values, or a sequence (its length first) when None."""
        if count is None:
            count = self.u32()
        if count == 0:
            return np.empty(0)
        self._align(8)
        end = self.offset + 8 * count
        if end > len(self.data):
            raise ValueError("array beyond the message")
        values = np.frombuffer(self.data, dtype="<f8", count=count, offset=self.offset)
        self.offset = end
        return values


def _cursor(data: bytes) -> _Cursor | None:
    return _Cursor(data) if len(data) >= 4 and data[:2] == _LITTLE_ENDIAN_CDR else None


class JointStateFields(NamedTuple):
    """The fields of a sensor_msgs/JointState that the nodes read.

    Attributes:
        stamp: (sec, nanosec) of the header.
        names: joint names (a stream repeats them: the same tuple while they do not change).
        position, velocity, effort: read-only float64 arrays, each (0,) or (len(names),).
    """

    stamp: tuple[int, int]
    names: tuple[str, ...]
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray


class _NamedStreamReader:
    """Reads one stream of serialized messages that start with a header and a name list:
    ``reader(data)`` is their fields (rclpy deserializes what :meth:`parse` declines; bytes that
    are not the message raise :class:`MalformedMessageError`). It keeps the last name list, which
    a stream repeats, to skip parsing it."""

    def __init__(self) -> None:
        self._names: tuple[bytes, tuple[str, ...]] | None = None

    def __call__(self, data: bytes):
        fields = self.parse(data)
        return self._from_message(data) if fields is None else fields

    def parse(self, data: bytes):
        """The fields read from the bytes, or None (not plain little-endian CDR, or cut)."""
        cursor = _cursor(data)
        if cursor is None:
            return None
        try:
            stamp = cursor.stamp()
            cursor.string()  # frame_id
            self._names = cursor.strings(self._names)
            return self._rest(cursor, stamp, self._names[1])
        except (ValueError, IndexError, struct.error):
            return None

    def _rest(self, cursor: _Cursor, stamp: tuple[int, int], names: tuple[str, ...]):
        raise NotImplementedError

    def _from_message(self, data: bytes):
        raise NotImplementedError


class JointStateReader(_NamedStreamReader):
    """:class:`JointStateFields` of serialized sensor_msgs/JointState messages of one stream."""

    def _rest(self, cursor, stamp, names) -> JointStateFields:
        position, velocity, effort = cursor.doubles(), cursor.doubles(), cursor.doubles()
        return JointStateFields(stamp, names, position, velocity, effort)

    def _from_message(self, data: bytes) -> JointStateFields:
        return joint_state_fields(deserialize_or_reject(data, JointState))


class TrajectoryFields(NamedTuple):
    """The fields of a trajectory_msgs/JointTrajectory that the simulator reads: ``stamp``
    (sec, nanosec), ``names``, ``points`` (how many), the first point's ``positions``,
    ``velocities``, ``accelerations`` (read-only float64, each (0,) or (len(names),); all (0,)
    without points), and ``velocity_end`` [s]: the time after the stamp at which the first
    point's velocity ends, the time_from_start of the first later point whose velocities are
    empty or all zero (the streamed shape of :func:`rns_ros.nodes.robot_io.streamed_trajectory`:
    point 1 at two periods, where joint_trajectory_controller has the arm at rest);
    ``math.inf`` when no later point is (a one-point trajectory)."""

    stamp: tuple[int, int]
    names: tuple[str, ...]
    points: int
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    velocity_end: float


class JointTrajectoryReader(_NamedStreamReader):
    """:class:`TrajectoryFields` of serialized trajectory_msgs/JointTrajectory messages of one
    stream."""

    def __call__(self, data: bytes) -> TrajectoryFields:
        """The fields of ``data``: read from the bytes, or by rclpy when they are not plain
        little-endian CDR.

        Raises:
            MalformedMessageError: plain little-endian CDR the parser declines (cut or corrupt:
                rclpy would fill the points it cannot read with defaults, and a cut streamed
                trajectory would lose its point at rest), or bytes rclpy cannot read.
        """
        fields = self.parse(data)
        if fields is not None:
            return fields
        if _cursor(data) is not None:
            raise MalformedMessageError(
                f"{len(data)} bytes that are not a JointTrajectory (cut or corrupt CDR)"
            )
        return self._from_message(data)

    def _rest(self, cursor, stamp, names) -> TrajectoryFields:
        points = cursor.u32()
        empty = np.empty(0)
        first, velocity_end = (empty,) * 3, math.inf
        if points:
            first = (cursor.doubles(), cursor.doubles(), cursor.doubles())
            cursor.doubles()  # effort
            cursor.stamp()  # time_from_start (a Duration: the layout of a Time)
        # every later point is walked, so a message cut anywhere is declined (rclpy rejects it)
        for _ in range(1, points):
            at_rest, (sec, nanosec) = self._later_point(cursor)
            if at_rest and velocity_end == math.inf:
                velocity_end = sec + 1e-9 * nanosec
        return TrajectoryFields(stamp, names, points, *first, velocity_end)

    @staticmethod
    def _later_point(cursor: _Cursor) -> tuple[bool, tuple[int, int]]:
        """Past a trajectory_msgs/JointTrajectoryPoint (positions, velocities, accelerations,
        effort: float64 sequences; time_from_start: int32 sec, uint32 nanosec) at ``cursor``:
        (its velocities are empty or all zero, time_from_start (sec, nanosec)); the arrays are
        not read. Walked inline: a cursor call per field doubled the reader's time."""
        data, offset, size = cursor.data, cursor.offset, len(cursor.data)
        at_rest = True
        for field in range(4):
            offset += -(offset - 4) % 4
            (count,) = _U32.unpack_from(data, offset)
            offset += 4
            if count:
                offset += -(offset - 4) % 8
                start, offset = offset, offset + 8 * count
                if offset > size:
                    raise ValueError("array beyond the message")
                if field == 1 and data[start:offset].strip(b"\x00"):  # not all +0.0
                    values = np.frombuffer(data, dtype="<f8", count=count, offset=start)
                    at_rest = not values.any()  # -0.0 is zero too
        offset += -(offset - 4) % 4
        time_from_start = _STAMP.unpack_from(data, offset)
        cursor.offset = offset + 8
        return at_rest, time_from_start

    def _from_message(self, data: bytes) -> TrajectoryFields:
        return trajectory_fields(deserialize_or_reject(data, JointTrajectory))


class OdometryFields(NamedTuple):
    """The fields of a nav_msgs/Odometry that the nodes read: ``stamp`` (sec, nanosec),
    ``pose`` (7,) position x y z and orientation x y z w, ``twist`` (6,) linear x y z and
    angular x y z (read-only float64)."""

    stamp: tuple[int, int]
    pose: np.ndarray
    twist: np.ndarray


def read_odometry(data: bytes) -> OdometryFields:
    """A serialized nav_msgs/Odometry's fields (rclpy deserializes what
    :func:`parse_odometry` declines).

    Raises:
        MalformedMessageError: the bytes are not an Odometry.
    """
    fields = parse_odometry(data)
    return odometry_fields(deserialize_or_reject(data, Odometry)) if fields is None else fields


def parse_odometry(data: bytes) -> OdometryFields | None:
    """A serialized nav_msgs/Odometry's fields read from the bytes, or None (not plain
    little-endian CDR, or cut)."""
    cursor = _cursor(data)
    if cursor is None:
        return None
    try:
        stamp = cursor.stamp()
        cursor.string()  # frame_id
        cursor.string()  # child_frame_id
        pose = cursor.doubles(7)
        cursor.doubles(36)  # covariance
        twist = cursor.doubles(6)
        return OdometryFields(stamp, pose, twist)
    except (ValueError, IndexError, struct.error):
        return None


class TwistFields(NamedTuple):
    """The fields of a geometry_msgs/TwistStamped: ``stamp`` (sec, nanosec), ``frame_id``,
    ``linear`` (3,) [m/s] and ``angular`` (3,) [rad/s] (read-only float64)."""

    stamp: tuple[int, int]
    frame_id: str
    linear: np.ndarray
    angular: np.ndarray


def read_twist_stamped(data: bytes) -> TwistFields:
    """A serialized geometry_msgs/TwistStamped's fields (rclpy deserializes what
    :func:`parse_twist_stamped` declines).

    Raises:
        MalformedMessageError: the bytes are not a TwistStamped.
    """
    fields = parse_twist_stamped(data)
    if fields is None:
        return twist_stamped_fields(deserialize_or_reject(data, TwistStamped))
    return fields


def parse_twist_stamped(data: bytes) -> TwistFields | None:
    """A serialized geometry_msgs/TwistStamped's fields read from the bytes, or None (not plain
    little-endian CDR, or cut)."""
    cursor = _cursor(data)
    if cursor is None:
        return None
    try:
        stamp = cursor.stamp()
        frame_id = cursor.string().decode("utf-8", "replace")
        twist = cursor.doubles(6)
    except (ValueError, IndexError, struct.error):
        return None
    return TwistFields(stamp, frame_id, twist[:3], twist[3:])


def twist_stamped_fields(message: TwistStamped) -> TwistFields:
    """The :class:`TwistFields` of a deserialized message."""
    stamp, twist = message.header.stamp, message.twist
    return TwistFields(
        (stamp.sec, stamp.nanosec),
        message.header.frame_id,
        np.array(_xyz(twist.linear)),
        np.array(_xyz(twist.angular)),
    )


def joint_state_fields(message: JointState) -> JointStateFields:
    """The :class:`JointStateFields` of a deserialized message."""
    stamp = message.header.stamp
    return JointStateFields(
        (stamp.sec, stamp.nanosec),
        tuple(message.name),
        np.asarray(message.position, dtype=float),
        np.asarray(message.velocity, dtype=float),
        np.asarray(message.effort, dtype=float),
    )


def trajectory_fields(message: JointTrajectory) -> TrajectoryFields:
    """The :class:`TrajectoryFields` of a deserialized message."""
    stamp = message.header.stamp
    first = message.points[0] if message.points else JointTrajectoryPoint()
    at_rest = (
        point.time_from_start
        for point in message.points[1:]
        if not np.any(np.asarray(point.velocities, dtype=float))
    )
    end = next(at_rest, None)
    return TrajectoryFields(
        (stamp.sec, stamp.nanosec),
        tuple(message.joint_names),
        len(message.points),
        *(
            np.asarray(values, dtype=float)
            for values in (first.positions, first.velocities, first.accelerations)
        ),
        math.inf if end is None else end.sec + 1e-9 * end.nanosec,
    )


def odometry_fields(message: Odometry) -> OdometryFields:
    """The :class:`OdometryFields` of a deserialized message."""
    stamp, pose, twist = message.header.stamp, message.pose.pose, message.twist.twist
    p, o = pose.position, pose.orientation
    return OdometryFields(
        (stamp.sec, stamp.nanosec),
        np.array([p.x, p.y, p.z, o.x, o.y, o.z, o.w]),
        np.array([*_xyz(twist.linear), *_xyz(twist.angular)]),
    )


def _xyz(vector) -> tuple[float, float, float]:
    return vector.x, vector.y, vector.z


def split_stamp(nanoseconds: int) -> tuple[int, int]:
    """(sec, nanosec) of a builtin_interfaces/Time at ``nanoseconds`` [ns] since its epoch."""
    sec, nanosec = divmod(int(nanoseconds), 1_000_000_000)
    return sec, nanosec


def _header_stamp(message, sec: int, nanosec: int) -> None:
    message.header.stamp = TimeMsg(sec=sec, nanosec=nanosec)


def _set_xyz(vector, values) -> None:
    vector.x, vector.y, vector.z = (float(x) for x in values)


def joint_state_template(
    names: Sequence[str], frame_id: str = "", effort: bool = False
) -> SerializedTemplate:
    """sensor_msgs/JointState of ``names``: slots ``position``, ``velocity`` [, ``effort``],
    each (len(names),); an empty effort when ``effort`` is False."""
    n = len(names)
    fields = ("position", "velocity", "effort") if effort else ("position", "velocity")
    message = JointState(name=list(names))
    message.header.frame_id = frame_id

    def fill(msg, values) -> None:
        for field in fields:
            setattr(msg, field, [float(x) for x in values[field]])

    return SerializedTemplate(message, dict.fromkeys(fields, n), fill, _header_stamp)


def odometry_template(frame_id: str, child_frame_id: str) -> SerializedTemplate:
    """nav_msgs/Odometry: slots ``pose`` (position x y z, orientation x y z w) and ``twist``
    (linear x y z, angular x y z); zero covariances."""
    message = Odometry(child_frame_id=child_frame_id)
    message.header.frame_id = frame_id

    def fill(msg, values) -> None:
        pose, twist = msg.pose.pose, msg.twist.twist
        _set_xyz(pose.position, values["pose"][:3])
        o = pose.orientation
        o.x, o.y, o.z, o.w = (float(x) for x in values["pose"][3:])
        _set_xyz(twist.linear, values["twist"][:3])
        _set_xyz(twist.angular, values["twist"][3:])

    return SerializedTemplate(message, {"pose": 7, "twist": 6}, fill, _header_stamp)


def wrench_template(frame_id: str) -> SerializedTemplate:
    """geometry_msgs/WrenchStamped: slot ``wrench`` (force x y z, torque x y z)."""
    message = WrenchStamped()
    message.header.frame_id = frame_id

    def fill(msg, values) -> None:
        _set_xyz(msg.wrench.force, values["wrench"][:3])
        _set_xyz(msg.wrench.torque, values["wrench"][3:])

    return SerializedTemplate(message, {"wrench": 6}, fill, _header_stamp)


def twist_stamped_template(frame_id: str) -> SerializedTemplate:
    """geometry_msgs/TwistStamped: slot ``twist`` (linear x y z, angular x y z)."""
    message = TwistStamped()
    message.header.frame_id = frame_id

    def fill(msg, values) -> None:
        _set_xyz(msg.twist.linear, values["twist"][:3])
        _set_xyz(msg.twist.angular, values["twist"][3:])

    return SerializedTemplate(message, {"twist": 6}, fill, _header_stamp)


def clock_template() -> SerializedTemplate:
    """rosgraph_msgs/Clock: the stamp only."""

    def stamp(msg, sec: int, nanosec: int) -> None:
        msg.clock = TimeMsg(sec=sec, nanosec=nanosec)

    return SerializedTemplate(Clock(), {}, lambda msg, values: None, stamp)


class _StreamedTrajectoryTemplate(SerializedTemplate):
    """The template of :func:`joint_trajectory_template`: ``end_positions`` is written into
    points 1 and 2 (slot ``rest_positions``, unless given on its own)."""

    def serialize(
        self, values: Mapping[str, np.ndarray], stamp: tuple[int, int] | None = None
    ) -> bytes:
        if "end_positions" in values and "rest_positions" not in values:
            values = {**values, "rest_positions": values["end_positions"]}
        return super().serialize(values, stamp)


def _set_duration(duration, seconds: float) -> None:
    sec, nanosec = divmod(round(seconds * 1e9), 1_000_000_000)
    duration.sec, duration.nanosec = int(sec), int(nanosec)


def joint_trajectory_template(names: Sequence[str], horizon: float) -> SerializedTemplate:
    """trajectory_msgs/JointTrajectory of ``names`` shaped as
    :func:`rns_ros.nodes.robot_io.streamed_trajectory`: point 0 at time_from_start 0 (slots
    ``positions``, ``velocities``), point 1 at ``horizon`` [s] (slot ``end_positions``, no
    velocities), point 2 at :func:`rns_ros.nodes.robot_io.trajectory_end` of ``horizon`` [s]
    with point 1's positions (slot ``rest_positions``, written with ``end_positions`` unless
    given) and zero velocities; each slot (len(names),)."""
    n = len(names)
    message = JointTrajectory(joint_names=list(names))
    message.points = [JointTrajectoryPoint(), JointTrajectoryPoint(), JointTrajectoryPoint()]
    _set_duration(message.points[1].time_from_start, horizon)
    _set_duration(message.points[2].time_from_start, trajectory_end(horizon))
    message.points[2].velocities = [0.0] * n

    def fill(msg, values) -> None:
        start, end_point, rest = msg.points
        start.positions = [float(x) for x in values["positions"]]
        start.velocities = [float(x) for x in values["velocities"]]
        end_point.positions = [float(x) for x in values["end_positions"]]
        rest.positions = [float(x) for x in values["rest_positions"]]

    sizes = {"positions": n, "velocities": n, "end_positions": n, "rest_positions": n}
    return _StreamedTrajectoryTemplate(message, sizes, fill, _header_stamp)


__all__ = [
    "JointStateFields",
    "JointStateReader",
    "JointTrajectoryReader",
    "OdometryFields",
    "SerializedTemplate",
    "TemplateError",
    "TrajectoryFields",
    "TwistFields",
    "clock_template",
    "joint_state_fields",
    "joint_state_template",
    "joint_trajectory_template",
    "odometry_fields",
    "odometry_template",
    "parse_odometry",
    "parse_twist_stamped",
    "read_odometry",
    "read_twist_stamped",
    "split_stamp",
    "trajectory_fields",
    "twist_stamped_fields",
    "twist_stamped_template",
    "wrench_template",
]
