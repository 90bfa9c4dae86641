"""A run's recorded topics as an MCAP file that ``ros2 bag``, Foxglove and PlotJuggler open.

The file is what ``ros2 bag record -s mcap`` writes: profile ``ros2``, every channel's messages
in the ROS 2 wire encoding (``cdr``, the bytes rclpy serializes), and per message type one schema
in the ``ros2msg`` encoding: the type's ``.msg`` text followed by the ``.msg`` text of every type
it uses, each after a line of 80 ``=`` and a ``MSG: pkg/Type`` line (rosbag2's
"complete message definition"). The ``.msg`` files come from the installed interface packages'
``share/<pkg>/msg/`` (the PyPI wheels install them under the environment's prefix).

Each message's log and publish time is when this process received it, on the wall clock [ns],
as ``ros2 bag record`` stamps them; the messages' own header stamps are the simulation's.
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Callable, Iterable
from pathlib import Path

from rns_ros.core import RnsError
from rns_ros.harness import TopicLog

#: The line that separates the definitions of a ros2msg schema.
SEPARATOR = "=" * 80
#: .msg field types that are not messages.
PRIMITIVE_TYPES = frozenset(
    {"bool", "byte", "char", "float32", "float64", "string", "wstring"}
    | {f"{sign}int{bits}" for sign in ("", "u") for bits in (8, 16, 32, 64)}
)


def msg_file(type_name: str) -> Path:
    """The installed ``.msg`` file of ``'pkg/Type'`` or ``'pkg/msg/Type'``.

    Raises:
        RnsError: no package share folder holds it.
    """
    from ament_index_python.packages import PackageNotFoundError, get_package_share_directory

    package, *_, name = type_name.split("/")
    shares = []
    with contextlib.suppress(PackageNotFoundError):  # a Jazzy install's, or one on the path
        shares.append(Path(get_package_share_directory(package)))
    shares.append(Path(sys.prefix) / "share" / package)  # the wheels' prefix
    for share in shares:
        path = share / "msg" / f"{name}.msg"
        if path.is_file():
            return path
    raise RnsError(f"no .msg definition of {type_name} installed (looked in {shares})")


def msg_dependencies(text: str, package: str) -> list[str]:
    """The message types (``'pkg/Type'``) the fields of the ``.msg`` ``text`` use, sorted;
    a type without a package is ``package``'s."""
    found = set()
    for line in text.splitlines():
        words = line.split("#", 1)[0].split()
        if len(words) < 2 or "=" in words[0]:
            continue
        kind = words[0].split("[", 1)[0].split("<=", 1)[0]
        if kind in PRIMITIVE_TYPES:
            continue
        found.add(kind if "/" in kind else f"{package}/{kind}")
    return sorted(found)


def message_definition(type_name: str) -> str:
    """rosbag2's complete ``ros2msg`` definition of ``'pkg/msg/Type'``: its ``.msg`` text, then
    each type it uses, depth first, once, after the separator and a ``MSG: pkg/Type`` line."""
    seen: set[str] = set()

    def text_of(name: str) -> str:
        text = msg_file(name).read_text()
        for dependency in msg_dependencies(text, name.split("/")[0]):
            if dependency not in seen:
                seen.add(dependency)
                text += f"\n{SEPARATOR}\nMSG: {dependency}\n{text_of(dependency)}"
        return text

    return text_of(type_name)


def ros_type_name(msg_type: type) -> str:
    """``'pkg/msg/Type'`` of a generated message class."""
    return f"{msg_type.__module__.split('.')[0]}/msg/{msg_type.__name__}"


def write_mcap(
    path: Path, logs: Iterable[TopicLog], resolve: Callable[[str], str] = lambda name: name
) -> dict[str, int]:
    """Write the messages of ``logs`` to the MCAP file ``path`` in receipt order; one channel
    per log, named ``resolve(log.topic)`` (the absolute name, remaps applied). Empty logs get no
    channel. Returns the messages written per channel.
    """
    from mcap.well_known import MessageEncoding, Profile, SchemaEncoding
    from mcap.writer import CompressionType, Writer
    from rclpy.serialization import serialize_message

    # receipt times are monotonic: one offset puts them on the wall clock
    offset = time.time_ns() - time.monotonic_ns()
    counts: dict[str, int] = {}
    rows = []
    with open(path, "wb") as stream:
        writer = Writer(stream, compression=CompressionType.ZSTD)
        writer.start(profile=Profile.ROS2, library="rns_ros")
        schemas: dict[str, int] = {}
        for log in logs:
            messages = log.messages
            if not messages:
                continue
            type_name = ros_type_name(log.msg_type or type(messages[0]))
            if type_name not in schemas:
                schemas[type_name] = writer.register_schema(
                    name=type_name,
                    encoding=SchemaEncoding.ROS2,
                    data=message_definition(type_name).encode(),
                )
            topic = resolve(log.topic)
            channel = writer.register_channel(
                topic=topic, message_encoding=MessageEncoding.CDR, schema_id=schemas[type_name]
            )
            counts[topic] = len(messages)
            for sequence, (msg, received) in enumerate(zip(messages, log.received, strict=True)):
                stamp = round(received * 1e9) + offset
                rows.append((stamp, channel, sequence, serialize_message(msg)))
        rows.sort(key=lambda row: row[:3])
        for stamp, channel, sequence, data in rows:
            writer.add_message(
                channel_id=channel, log_time=stamp, publish_time=stamp, sequence=sequence, data=data
            )
        writer.finish()
    return counts


def record_mcap(args, name: str, logs: Iterable[TopicLog], resolve: Callable[[str], str]):
    """``<output>/<name>.mcap`` of ``logs`` (see :func:`write_mcap`); its path, or None with
    ``--no-record``."""
    if args.no_record:
        return None
    args.output.mkdir(parents=True, exist_ok=True)
    path = (args.output / f"{name}.mcap").resolve()
    write_mcap(path, logs, resolve)
    return str(path)
