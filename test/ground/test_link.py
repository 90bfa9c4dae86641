"""The space link, one direction: delay, jitter, loss, bandwidth, outages, order."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rns_ros.core.errors import ConfigError
from rns_ros.ground.link import LinkChannel, LinkSettings, parse_outages, parse_topic


def _stream(channel: LinkChannel, times, size: int = 0) -> None:
    for k, t in enumerate(times):
        channel.send(float(t), k, size)


def test_a_fixed_delay_gives_every_message_back_that_much_later():
    channel = LinkChannel(LinkSettings(delay=3.0))
    _stream(channel, np.arange(0.0, 1.0, 0.01))  # 100 Hz for 1 s
    assert channel.deliver(2.999) == []
    assert channel.in_flight == 100
    arrivals = channel.deliver(10.0)
    assert [item.message for item in arrivals] == list(range(100))
    assert all(item.arrival - item.sent == pytest.approx(3.0, abs=1e-12) for item in arrivals)
    assert channel.counts.max_delay == pytest.approx(3.0)
    assert channel.in_flight == 0


def test_messages_come_out_as_they_fall_due():
    channel = LinkChannel(LinkSettings(delay=1.0))
    _stream(channel, [0.0, 0.5, 1.0])
    assert [item.message for item in channel.deliver(1.5)] == [0, 1]
    assert channel.next_arrival() == pytest.approx(2.0)
    assert [item.message for item in channel.deliver(2.0)] == [2]
    assert channel.next_arrival() == math.inf


@given(
    gaps=st.lists(st.floats(0.0, 0.2), min_size=1, max_size=60),
    delay=st.floats(0.0, 5.0),
    jitter=st.floats(0.0, 2.0),
    seed=st.integers(0, 2**16),
)
@settings(max_examples=60, deadline=None)
def test_jitter_never_reorders_and_stays_within_its_bound(gaps, delay, jitter, seed):
    channel = LinkChannel(LinkSettings(delay=delay, jitter=jitter, seed=seed))
    times = np.cumsum(gaps)
    _stream(channel, times)
    arrivals = channel.deliver(math.inf)
    assert [item.message for item in arrivals] == list(range(len(times)))
    received = np.array([item.arrival for item in arrivals])
    assert np.all(np.diff(received) >= 0.0)
    assert np.all(received >= times + delay - 1e-12)
    # a message waits at most for its own jitter or for the one before it
    bound = np.maximum.accumulate(times + delay + jitter)
    assert np.all(received <= bound + 1e-12)


def test_the_same_seed_gives_the_same_link():
    def run(seed):
        channel = LinkChannel(LinkSettings(delay=0.5, jitter=0.3, loss=0.2, seed=seed))
        _stream(channel, np.arange(0.0, 5.0, 0.01))
        return [(item.arrival, item.message) for item in channel.deliver(math.inf)]

    assert run(7) == run(7)
    assert run(7) != run(8)


def test_loss_is_drawn_per_message_at_the_set_probability():
    channel = LinkChannel(LinkSettings(loss=0.1, seed=3))
    sent = 20000
    _stream(channel, np.arange(sent) * 1e-3)
    lost = channel.counts.lost
    # binomial(20000, 0.1): standard deviation 42; five of them
    assert abs(lost - 0.1 * sent) < 5 * math.sqrt(sent * 0.1 * 0.9)
    assert len(channel.deliver(math.inf)) == sent - lost == channel.counts.delivered


def test_a_bandwidth_cap_queues_messages_behind_each_other():
    # ten 1000-byte messages at once over 10 kB/s: one leaves every 0.1 s
    channel = LinkChannel(LinkSettings(delay=2.0, bandwidth=10_000.0))
    _stream(channel, [0.0] * 10, size=1000)
    received = [item.arrival for item in channel.deliver(math.inf)]
    assert received == pytest.approx(2.0 + 0.1 * np.arange(1, 11), abs=1e-12)
    # a message sent once the queue has drained waits only for its own air time
    channel.send(5.0, "late", 1000)
    assert channel.deliver(math.inf)[0].arrival == pytest.approx(7.1)


def test_an_outage_loses_what_is_sent_inside_it_and_nothing_else():
    channel = LinkChannel(LinkSettings(delay=1.0, outages=((2.0, 4.0),)))
    times = np.arange(0.0, 6.0, 0.5)
    _stream(channel, times)
    received = [item.sent for item in channel.deliver(math.inf)]
    assert received == [t for t in times if not 2.0 <= t < 4.0]
    assert channel.counts.lost == channel.counts.lost_in_outage == 4
    assert channel.settings.down(3.99)
    assert not channel.settings.down(4.0)


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"delay": -0.1}, r"link delay must be in \[0, 600\] s, got -0.1"),
        ({"delay": math.nan}, r"link delay must be in \[0, 600\] s, got nan"),
        ({"jitter": 601.0}, r"link jitter must be in \[0, 600\] s, got 601.0"),
        ({"loss": 1.0}, r"link loss must be in \[0, 1\), got 1.0"),
        ({"bandwidth": -5.0}, r"link bandwidth must be >= 0 B/s \(0: no cap\), got -5.0"),
        ({"outages": ((3.0, 2.0),)}, r"link outage must be \(start, end\) .* got \(3.0, 2.0\)"),
        ({"outages": ((0.0, math.inf),)}, r"link outage must be \(start, end\) with finite"),
    ],
)
def test_bad_settings_name_the_value_and_the_range(values, message):
    with pytest.raises(ConfigError, match=message):
        LinkSettings(**values)


def test_outages_and_topics_are_read_from_their_text():
    assert parse_outages("10:12, 30:31.5") == ((10.0, 12.0), (30.0, 31.5))
    assert parse_outages("") == ()
    with pytest.raises(ConfigError, match=r"outage '10-12' is not 'start:end'"):
        parse_outages("10-12")
    with pytest.raises(ConfigError, match=r"link outage must be \(start, end\)"):
        parse_outages("12:10")
    assert parse_topic("cmd_twist:geometry_msgs/msg/TwistStamped") == (
        "cmd_twist",
        "geometry_msgs/msg/TwistStamped",
    )
    for bad in ("cmd_twist", ":geometry_msgs/msg/Twist", "x:geometry_msgs/Twist", "x:a/srv/B"):
        with pytest.raises(ConfigError, match="must be 'topic:package/msg/Type'"):
            parse_topic(bad)
