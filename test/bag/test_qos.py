"""rns_ros.bag.qos and rns_ros.bag.ros: QoS profiles in rosbag2's version-9 form, the older
integer form, and rclpy's profiles; the request and the playback offer rosbag2 derives."""

from __future__ import annotations

import pytest
from rclpy.duration import Duration
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from rns_ros.bag.qos import (
    INFINITE_NS,
    QosError,
    parse_profiles,
    playback_profile,
    profile,
    profiles_yaml,
    request_profile,
)
from rns_ros.bag.ros import profile_of, qos_of

#: what rosbag2 of ROS 2 Iron (version 8) wrote: rmw's enum integers, as one YAML string
V8 = """- history: 3
  depth: 0
  reliability: 1
  durability: 1
  deadline:
    sec: 2147483647
    nsec: 4294967295
  lifespan:
    sec: 9223372036
    nsec: 854775807
  liveliness: 1
  liveliness_lease_duration:
    sec: 0
    nsec: 0
  avoid_ros_namespace_conventions: false"""


def test_version_8_integers_read_as_version_9_names():
    (item,) = parse_profiles(V8)
    assert (item["history"], item["reliability"], item["durability"], item["liveliness"]) == (
        "unknown", "reliable", "transient_local", "automatic",
    )  # fmt: skip
    assert item["deadline"] == {"sec": 9223372036, "nsec": 854775807}  # Foxy's infinity
    assert item["lifespan"] == {"sec": 9223372036, "nsec": 854775807}


def test_the_channel_string_reads_back_and_rosbags_reads_it():
    from rosbags.interfaces import QosDurability, QosReliability
    from rosbags.rosbag2.metadata import parse_qos

    profiles = [profile(depth=1, durability="transient_local"), profile(reliability="best_effort")]
    text = profiles_yaml(profiles)
    assert parse_profiles(text) == profiles
    theirs = parse_qos(text)
    assert [q.durability for q in theirs] == [QosDurability.TRANSIENT_LOCAL, QosDurability.VOLATILE]
    assert [q.reliability for q in theirs] == [QosReliability.RELIABLE, QosReliability.BEST_EFFORT]
    assert profiles_yaml([]) == "[]"
    assert parse_profiles("[]") == []
    assert parse_profiles("") == []


@pytest.mark.parametrize("bad", ["{a: 1}", "- {history: keep_last}", "[", "- 3"])
def test_what_is_not_a_profile_list_is_one_error(bad):
    with pytest.raises(QosError, match="offered_qos_profiles"):
        parse_profiles(bad)


def test_the_request_follows_every_publisher():
    latched = profile(depth=1, durability="transient_local")
    fast = profile(depth=10, reliability="best_effort")
    assert request_profile([latched]) == profile(history="keep_all", depth=1,
                                                 durability="transient_local")  # fmt: skip
    both = request_profile([latched, fast], min_depth=1000)
    assert (both["reliability"], both["durability"], both["depth"]) == (
        "best_effort", "volatile", 1000,
    )  # fmt: skip
    assert request_profile([]) == profile()


def test_the_playback_offer_is_the_recorded_one_when_publishers_agree():
    latched = profile(depth=1, durability="transient_local")
    assert playback_profile([latched, latched]) == {**latched, "depth": 10}
    assert playback_profile([latched, profile()]) == profile()
    assert playback_profile([]) == profile()


def test_rclpy_profiles_both_ways():
    qos = QoSProfile(
        depth=5,
        reliability=ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
        deadline=Duration(seconds=0.5),
    )
    item = profile_of(qos)
    assert (item["history"], item["depth"], item["reliability"], item["durability"]) == (
        "keep_last", 5, "best_effort", "transient_local",
    )  # fmt: skip
    assert item["deadline"] == {"sec": 0, "nsec": 500_000_000}
    back = qos_of(item)
    assert (back.history, back.depth, back.reliability, back.durability) == (
        HistoryPolicy.KEEP_LAST, 5, ReliabilityPolicy.BEST_EFFORT, DurabilityPolicy.TRANSIENT_LOCAL,
    )  # fmt: skip
    assert back.deadline.nanoseconds == 500_000_000
    never = qos_of(profile(deadline_ns=INFINITE_NS))
    assert never.deadline.nanoseconds == 0  # unspecified: never ends
