"""rns_ros.bag.player on an injected clock: the messages go out at their bag times and /clock
carries the bag's time, also when the player runs late (a stall, as a busy machine makes one).
The publishers are replaced by recorders, so nothing here depends on DDS delivery."""

from __future__ import annotations

import itertools
import os

import pytest
import rclpy
from rclpy.serialization import serialize_message
from sensor_msgs.msg import JointState

import rns_ros.bag.player as player_module
from rns_ros.bag import BagWriter, open_bag
from rns_ros.bag.player import Player
from rns_ros.bag.qos import profile

START = 1_700_000_000_000_000_000  # [ns since the epoch]
STEP = 100_000_000  # [ns] between recorded messages
COUNT = 10
STALL = 0.45  # [s] of wall time the player loses while publishing message STALLED
STALLED = 3


class FakeTime:
    """``time.monotonic`` and ``time.sleep`` on a clock of the test's own [s]."""

    def __init__(self) -> None:
        self.now = 0.0

    def monotonic(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.now += max(seconds, 0.0)


class Recorder:
    """A publisher that appends (kind, bag time [ns]) to a shared list of events."""

    def __init__(self, events: list, kind: str, times: dict[bytes, int] | None = None) -> None:
        self.events, self.kind, self.times = events, kind, times
        self.stall = None  # (FakeTime, index of the publish that stalls)

    def publish(self, message) -> None:
        if self.kind == "clock":
            self.events.append(("clock", message.clock.sec * 10**9 + message.clock.nanosec))
            return
        self.events.append(("message", self.times[bytes(message)]))
        if self.stall is not None and sum(e[0] == "message" for e in self.events) == self.stall[1]:
            self.stall[0].now += STALL


@pytest.fixture
def bag(tmp_path):
    """COUNT joint states STEP apart on /joint_states; each message's bytes -> its bag time."""
    with BagWriter(tmp_path / "bag") as writer:
        topic = writer.add_topic("/joint_states", "sensor_msgs/msg/JointState", [profile()])
        for k in range(COUNT):
            data = serialize_message(JointState(name=["j"], position=[float(k)]))
            writer.write(topic, data, START + k * STEP, START + k * STEP)
    bag = open_bag(tmp_path / "bag")
    times = {bytes(message.data): message.log_time for message in bag.messages()}
    assert sorted(times.values()) == [START + k * STEP for k in range(COUNT)]
    return bag, times


@pytest.fixture
def context():
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(os.environ.get("ROS_DOMAIN_ID", "43")))
    yield context
    rclpy.try_shutdown(context=context)


def _play(bag, times, context, monkeypatch, stall: bool) -> list:
    clock = FakeTime()
    monkeypatch.setattr(player_module, "time", clock)
    player = Player(bag, rate=2.0, clock_hz=50.0, context=context)
    events: list = []
    messages = Recorder(events, "message", times)
    if stall:
        messages.stall = (clock, STALLED)
    player.publishers = {"/joint_states": messages}
    player.clock = Recorder(events, "clock")
    try:
        assert player.play_once() == COUNT
    finally:
        player.close()
    return events


@pytest.mark.parametrize("stall", [False, True], ids=["on_time", "late"])
def test_the_clock_never_runs_ahead_of_a_message_still_to_come(bag, context, monkeypatch, stall):
    """Every /clock stamp is at most the bag time of each message published after it, the
    stamps never go back, and the last is at most the bag's end: a subscriber on the bag's
    time never gets a message older than its clock. With a stall of STALL s after message
    STALLED, the next messages are late by up to that: the clock waits for them."""
    bag, times = bag
    events = _play(bag, times, context, monkeypatch, stall)
    published = [t for kind, t in events if kind == "message"]
    assert published == sorted(times.values())
    stamps = [t for kind, t in events if kind == "clock"]
    assert stamps == sorted(stamps)
    assert stamps[0] >= START
    assert stamps[-1] <= bag.metadata.end_ns
    for k, (kind, stamp) in enumerate(events):
        if kind == "clock":
            later = [t for kind_, t in events[k + 1 :] if kind_ == "message"]
            assert all(stamp <= t for t in later), (stamp - START, [t - START for t in later])
    if not stall:  # a clock each 20 ms of wall time (50 Hz) is 40 ms of bag time at rate 2
        assert max(b - a for a, b in itertools.pairwise(stamps)) <= 40_000_000 + 1
