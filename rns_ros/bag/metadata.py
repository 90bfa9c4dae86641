"""A bag's metadata as rosbag2 (version 9, ROS 2 Jazzy) writes it: ``metadata.yaml`` in the bag
folder, and the same fields serialized into each MCAP file's ``rosbag2`` metadata record.

``metadata.yaml`` holds one key, ``rosbag2_bagfile_information``, with ``version``,
``storage_identifier``, ``duration`` (``nanoseconds``), ``starting_time``
(``nanoseconds_since_epoch``), ``message_count``, ``topics_with_message_count`` (each a
``topic_metadata``: ``name``, ``type``, ``serialization_format``, ``offered_qos_profiles``,
``type_description_hash``; and its ``message_count``), ``compression_format``,
``compression_mode``, ``relative_file_paths``, ``files`` (per file: ``path``, ``starting_time``,
``duration``, ``message_count``), ``custom_data`` and ``ros_distro``. Times are nanoseconds since
the epoch on the recorder's clock; a bag without messages starts at INT64_MAX, as rosbag2's does.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import yaml

from rns_ros.bag.qos import QosError, dump_yaml, parse_profiles
from rns_ros.core import RnsError

#: The metadata version of ROS 2 Jazzy's rosbag2.
VERSION = 9
METADATA_FILE = "metadata.yaml"
ROOT_KEY = "rosbag2_bagfile_information"
#: rosbag2's starting time of a bag without messages (std::chrono::nanoseconds::max()).
NO_START = 2**63 - 1
#: The distribution recorded when ROS_DISTRO is not set (the PyPI wheels are Jazzy's).
DEFAULT_DISTRO = "jazzy"


class BagError(RnsError):
    """A bag that cannot be read or written: one line naming the bag and the problem."""


@dataclass
class TopicInfo:
    """One topic of a bag: ``topic_metadata`` and its ``message_count``."""

    name: str
    type: str
    offered_qos_profiles: list[dict[str, Any]] = field(default_factory=list)
    type_description_hash: str = ""
    serialization_format: str = "cdr"
    message_count: int = 0

    def to_dict(self) -> dict[str, Any]:
        return {
            "topic_metadata": {
                "name": self.name,
                "type": self.type,
                "serialization_format": self.serialization_format,
                "offered_qos_profiles": [dict(item) for item in self.offered_qos_profiles],
                "type_description_hash": self.type_description_hash,
            },
            "message_count": self.message_count,
        }


@dataclass
class FileInfo:
    """One storage file of a bag: its name in the folder, first message [ns since the epoch],
    the span to its last [ns] and its messages."""

    path: str
    starting_time_ns: int = NO_START
    duration_ns: int = 0
    message_count: int = 0

    def add(self, stamp_ns: int) -> None:
        """Count one message received at ``stamp_ns``."""
        end = self.end_ns if self.message_count else stamp_ns
        self.starting_time_ns = min(self.starting_time_ns, stamp_ns)
        self.duration_ns = max(end, stamp_ns) - self.starting_time_ns
        self.message_count += 1

    @property
    def end_ns(self) -> int:
        return self.starting_time_ns + self.duration_ns

    def to_dict(self) -> dict[str, Any]:
        return {
            "path": self.path,
            "starting_time": {"nanoseconds_since_epoch": self.starting_time_ns},
            "duration": {"nanoseconds": self.duration_ns},
            "message_count": self.message_count,
        }


@dataclass
class BagMetadata:
    """What ``metadata.yaml`` holds; ``bag_size`` [bytes] is not stored (the files tell it)."""

    topics: list[TopicInfo] = field(default_factory=list)
    files: list[FileInfo] = field(default_factory=list)
    starting_time_ns: int = NO_START
    duration_ns: int = 0
    version: int = VERSION
    storage_identifier: str = "mcap"
    compression_format: str = ""
    compression_mode: str = ""
    custom_data: dict[str, str] | None = None
    ros_distro: str = field(default_factory=lambda: os.environ.get("ROS_DISTRO") or DEFAULT_DISTRO)
    bag_size: int = 0

    @property
    def relative_file_paths(self) -> list[str]:
        return [item.path for item in self.files]

    @property
    def message_count(self) -> int:
        return sum(topic.message_count for topic in self.topics)

    @property
    def end_ns(self) -> int:
        return self.starting_time_ns + self.duration_ns

    def summarize_files(self) -> None:
        """The bag's start and duration from its files' (after writing)."""
        counted = [item for item in self.files if item.message_count]
        if counted:
            self.starting_time_ns = min(item.starting_time_ns for item in counted)
            self.duration_ns = max(item.end_ns for item in counted) - self.starting_time_ns

    def to_dict(self) -> dict[str, Any]:
        """The fields in rosbag2's order (``YAML::convert<BagMetadata>::encode``)."""
        return {
            "version": self.version,
            "storage_identifier": self.storage_identifier,
            "duration": {"nanoseconds": self.duration_ns},
            "starting_time": {"nanoseconds_since_epoch": self.starting_time_ns},
            "message_count": self.message_count,
            "topics_with_message_count": [topic.to_dict() for topic in self.topics],
            "compression_format": self.compression_format,
            "compression_mode": self.compression_mode,
            "relative_file_paths": self.relative_file_paths,
            "files": [item.to_dict() for item in self.files],
            "custom_data": dict(self.custom_data) if self.custom_data else None,
            "ros_distro": self.ros_distro,
        }

    def serialized(self) -> str:
        """The YAML of the MCAP ``rosbag2`` record's ``serialized_metadata``."""
        return dump_yaml(self.to_dict())

    def file_text(self) -> str:
        """The text of ``metadata.yaml``."""
        return dump_yaml({ROOT_KEY: self.to_dict()})

    def copy(self) -> BagMetadata:
        return replace(
            self,
            topics=[replace(topic) for topic in self.topics],
            files=[replace(item) for item in self.files],
        )


def _get(node: Any, key: str, kind: type, where: str):
    if not isinstance(node, dict) or key not in node:
        raise BagError(f"{where}: no {key!r}")
    value = node[key]
    if kind is int and (isinstance(value, bool) or not isinstance(value, int)):
        raise BagError(f"{where}: {key} must be an integer, got {value!r}")
    if kind is not int and not isinstance(value, kind):
        raise BagError(f"{where}: {key} must be a {kind.__name__}, got {value!r}")
    return value


def metadata_from_dict(node: Any, where: str) -> BagMetadata:
    """The metadata of rosbag2's fields (``metadata.yaml``'s root, or an MCAP record's YAML).

    Raises:
        BagError: a field missing or of the wrong kind (``where`` names the source).
    """
    version = _get(node, "version", int, where)
    topics = []
    for item in _get(node, "topics_with_message_count", list, where):
        meta = _get(item, "topic_metadata", dict, where)
        try:
            profiles = parse_profiles(meta.get("offered_qos_profiles"))
        except QosError as exc:
            raise BagError(f"{where}: {meta.get('name')}: {exc}") from None
        topics.append(
            TopicInfo(
                name=_get(meta, "name", str, where),
                type=_get(meta, "type", str, where),
                serialization_format=_get(meta, "serialization_format", str, where),
                offered_qos_profiles=profiles,
                type_description_hash=str(meta.get("type_description_hash") or ""),
                message_count=_get(item, "message_count", int, where),
            )
        )
    paths = _get(node, "relative_file_paths", list, where)
    files = []
    for item in node.get("files") or [{"path": path} for path in paths]:
        files.append(
            FileInfo(
                path=_get(item, "path", str, where),
                starting_time_ns=int(
                    (item.get("starting_time") or {}).get("nanoseconds_since_epoch", NO_START)
                ),
                duration_ns=int((item.get("duration") or {}).get("nanoseconds", 0)),
                message_count=int(item.get("message_count", 0)),
            )
        )
    return BagMetadata(
        topics=topics,
        files=files,
        starting_time_ns=int(
            _get(_get(node, "starting_time", dict, where), "nanoseconds_since_epoch", int, where)
        ),
        duration_ns=int(_get(_get(node, "duration", dict, where), "nanoseconds", int, where)),
        version=version,
        storage_identifier=_get(node, "storage_identifier", str, where),
        compression_format=str(node.get("compression_format") or ""),
        compression_mode=str(node.get("compression_mode") or ""),
        custom_data={str(k): str(v) for k, v in (node.get("custom_data") or {}).items()} or None,
        ros_distro=str(node.get("ros_distro") or ""),
    )


def read_metadata(folder: Path) -> BagMetadata:
    """``folder/metadata.yaml``.

    Raises:
        BagError: missing, unreadable, or not rosbag2's metadata.
    """
    path = Path(folder) / METADATA_FILE
    try:
        node = yaml.safe_load(path.read_text())
    except FileNotFoundError:
        raise BagError(f"{folder}: not a bag folder (no {METADATA_FILE})") from None
    except OSError as exc:
        raise BagError(f"cannot read {path}: {exc.strerror or exc}") from None
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        raise BagError(f"{path}: not YAML ({one_line_yaml(exc)})") from None
    if not isinstance(node, dict) or ROOT_KEY not in node:
        raise BagError(f"{path}: not rosbag2 metadata (no {ROOT_KEY})")
    return metadata_from_dict(node[ROOT_KEY], str(path))


def one_line_yaml(error: Exception) -> str:
    """A YAML error's first line."""
    return str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
