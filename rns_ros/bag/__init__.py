"""Bags as ``ros2 bag`` writes and reads them (rosbag2 folders of MCAP files, ROS 2 Jazzy's
metadata version 9): definitions, CDR content, QoS profiles, metadata, the writer, the reader,
and the recorder and player nodes of ``rns_bag``. See docs/bag.md."""

from rns_ros.bag.metadata import BagError, BagMetadata, FileInfo, TopicInfo
from rns_ros.bag.reader import Bag, BagMessage, open_bag
from rns_ros.bag.writer import BagWriter, McapFile

__all__ = [
    "Bag",
    "BagError",
    "BagMessage",
    "BagMetadata",
    "BagWriter",
    "FileInfo",
    "McapFile",
    "TopicInfo",
    "open_bag",
]
