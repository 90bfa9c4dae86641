"""Bags read back: a rosbag2 folder (``metadata.yaml`` and its MCAP files) or one MCAP file.

A folder is described by its ``metadata.yaml``, as ``ros2 bag info DIR`` does; a single MCAP
file by its summary and its ``rosbag2`` metadata record, as rosbag2's MCAP plugin reads it
(counts and times from the summary's statistics, each topic's QoS and type hash from its
channel's metadata). Messages come in receipt (log time) order, file after file.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import yaml

from rns_ros.bag.metadata import (
    METADATA_FILE,
    NO_START,
    BagError,
    BagMetadata,
    FileInfo,
    TopicInfo,
    metadata_from_dict,
    read_metadata,
)
from rns_ros.bag.qos import QosError, parse_profiles

MCAP_MAGIC = b"\x89MCAP0\r\n"


class BagMessage(NamedTuple):
    """One stored message: its topic, serialized bytes and times [ns since the epoch]."""

    topic: str
    data: bytes
    log_time: int
    publish_time: int


@dataclass
class Bag:
    """A bag opened for reading (:func:`open_bag`)."""

    path: Path
    metadata: BagMetadata
    files: list[Path]

    @property
    def topics(self) -> dict[str, TopicInfo]:
        return {topic.name: topic for topic in self.metadata.topics}

    def definitions(self) -> dict[str, tuple[str, str]]:
        """Message type -> (schema encoding, definition text), from the files' schemas."""
        found: dict[str, tuple[str, str]] = {}
        for path in self.files:
            with _reader(path) as reader:
                for schema in reader.get_summary().schemas.values():
                    found.setdefault(schema.name, (schema.encoding, schema.data.decode()))
        return found

    def messages(self, topics: Iterable[str] | None = None) -> Iterator[BagMessage]:
        """The messages of ``topics`` (default: all) in log time order, file after file.

        Raises:
            BagError: a file cannot be read.
        """
        wanted = None if topics is None else list(topics)
        for path in self.files:
            with _reader(path) as reader:
                try:
                    for _schema, channel, message in reader.iter_messages(
                        topics=wanted, log_time_order=True
                    ):
                        yield BagMessage(
                            channel.topic, message.data, message.log_time, message.publish_time
                        )
                except Exception as exc:  # the mcap reader raises its own errors and EOFError
                    raise BagError(f"{path}: cannot read its messages ({exc})") from None


@contextlib.contextmanager
def _reader(path: Path):
    """An MCAP reader of ``path`` with its summary checked.

    Raises:
        BagError: not an MCAP file, or one not closed (no summary).
    """
    from mcap.reader import make_reader

    try:
        stream = open(path, "rb")  # noqa: SIM115 - closed below
    except OSError as exc:
        raise BagError(f"cannot read {path}: {exc.strerror or exc}") from None
    with stream:
        if stream.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
            raise BagError(f"{path}: not an MCAP file")
        stream.seek(0)
        reader = make_reader(stream)
        try:
            summary = reader.get_summary()
        except Exception as exc:  # a file cut short
            raise BagError(f"{path}: cannot read its summary ({exc})") from None
        if summary is None:
            raise BagError(f"{path}: the MCAP file was not closed (no summary; `mcap recover`)")
        yield reader


def _file_metadata(path: Path) -> BagMetadata:
    """A single MCAP file's metadata, as rosbag2's MCAP plugin reads it."""
    with _reader(path) as reader:
        summary = reader.get_summary()
        metadata = None
        with contextlib.suppress(Exception):  # a file without the record is still a bag
            for record in reader.iter_metadata():
                if record.name == "rosbag2" and "serialized_metadata" in record.metadata:
                    node = yaml.safe_load(record.metadata["serialized_metadata"])
                    metadata = metadata_from_dict(node, f"{path} (rosbag2 record)")
        if metadata is None:
            metadata = BagMetadata(ros_distro="")
        statistics = summary.statistics
        counts = statistics.channel_message_counts if statistics else {}
        topics = []
        for channel in summary.channels.values():
            schema = summary.schemas.get(channel.schema_id)
            try:
                profiles = parse_profiles(channel.metadata.get("offered_qos_profiles"))
            except QosError as exc:
                raise BagError(f"{path}: {channel.topic}: {exc}") from None
            topics.append(
                TopicInfo(
                    name=channel.topic,
                    type=schema.name if schema else "",
                    serialization_format=channel.message_encoding,
                    offered_qos_profiles=profiles,
                    type_description_hash=channel.metadata.get("topic_type_hash", ""),
                    message_count=counts.get(channel.id, 0),
                )
            )
        metadata.topics = topics
        count = statistics.message_count if statistics else 0
        start = statistics.message_start_time if count else NO_START
        metadata.starting_time_ns = start
        metadata.duration_ns = statistics.message_end_time - start if count else 0
        metadata.files = [
            FileInfo(path.name, start, metadata.duration_ns, count),
        ]
        metadata.storage_identifier = "mcap"
    return metadata


def open_bag(path: Path | str) -> Bag:
    """The bag at ``path``: a rosbag2 folder with ``metadata.yaml``, or one MCAP file.

    Raises:
        BagError: no such path, not a bag, a storage other than MCAP, a file of the folder
            missing.
    """
    path = Path(path)
    if path.is_dir():
        if not (path / METADATA_FILE).is_file() and any(path.glob("*.mcap")):
            raise BagError(f"{path}: no {METADATA_FILE} (open one of its .mcap files instead)")
        metadata = read_metadata(path)
        if metadata.storage_identifier != "mcap":
            raise BagError(
                f"{path}: storage {metadata.storage_identifier!r} is not supported (only mcap)"
            )
        if metadata.compression_mode:
            raise BagError(f"{path}: {metadata.compression_mode} compression is not supported")
        files = [path / name for name in metadata.relative_file_paths]
        missing = [str(item) for item in files if not item.is_file()]
        if missing:
            raise BagError(f"{path}: its file {missing[0]} is missing")
    elif path.is_file():
        metadata = _file_metadata(path)
        files = [path]
    elif path.exists():
        raise BagError(f"{path}: not a bag folder or an MCAP file")
    else:
        raise BagError(f"{path}: no such bag folder or file")
    metadata.bag_size = sum(item.stat().st_size for item in files)
    return Bag(path, metadata, files)
