"""A space link between the ground and the spacecraft, one direction at a time.

No ROS here: :class:`LinkChannel` takes messages with their send time and gives them back when
they arrive; ``rns_link`` moves them between the ground's and the spacecraft's topics.

A message of ``size`` bytes sent at t_s [s] (the link's clock) is

* lost when t_s falls in a scheduled outage [start, end) (no contact: nothing is radiated), else
  with probability ``loss`` (an independent draw per message);
* radiated once the link is free: b = max(t_s, f), where f is when the previous message
  finished, and it takes size / bandwidth seconds (bandwidth 0: no cap);
* received at a = max(b + size / bandwidth + delay + u jitter, a_prev), u ~ U[0, 1): one-way
  delay plus jitter, but never before the message sent before it (order is kept, as a single
  radio channel keeps it).

The message is returned as given: its header stamp, the issue time the spacecraft judges it by,
is the sender's.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from rns_ros.core.errors import ConfigError

#: Largest one-way delay or jitter accepted [s]: a lunar link's round trip is ~2.6 s, a
#: relayed low-orbit link's several seconds; ten minutes leaves room for Mars-like tests.
MAX_DELAY_S = 600.0
#: Largest number of scheduled outages.
MAX_OUTAGES = 100


@dataclass(frozen=True)
class LinkSettings:
    """One direction of the link.

    Attributes:
        delay: one-way delay d [s], in [0, :data:`MAX_DELAY_S`].
        jitter: extra delay u j, u ~ U[0, 1) per message [s], in [0, :data:`MAX_DELAY_S`].
        loss: probability that a message is lost [-], in [0, 1).
        bandwidth: bytes per second the link carries; 0 means no cap [B/s], >= 0.
        outages: scheduled loss of contact, (start, end) pairs [s] on the link's clock,
            start < end; a message sent inside one is lost.
        seed: seed of the loss and jitter draws (the same seed, the same link).
    """

    delay: float = 0.0
    jitter: float = 0.0
    loss: float = 0.0
    bandwidth: float = 0.0
    outages: tuple[tuple[float, float], ...] = field(default=())
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("delay", "jitter"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value <= MAX_DELAY_S):
                raise ConfigError(f"link {name} must be in [0, {MAX_DELAY_S:g}] s, got {value!r}")
        if not (math.isfinite(self.loss) and 0.0 <= self.loss < 1.0):
            raise ConfigError(f"link loss must be in [0, 1), got {self.loss!r}")
        if not (math.isfinite(self.bandwidth) and self.bandwidth >= 0.0):
            raise ConfigError(
                f"link bandwidth must be >= 0 B/s (0: no cap), got {self.bandwidth!r}"
            )
        if len(self.outages) > MAX_OUTAGES:
            raise ConfigError(f"at most {MAX_OUTAGES} link outages, got {len(self.outages)}")
        for outage in self.outages:
            start, end = (float(value) for value in outage)
            if not (math.isfinite(start) and math.isfinite(end) and start < end):
                raise ConfigError(
                    "a link outage must be (start, end) with finite start < end [s], "
                    f"got {outage!r}"
                )

    def down(self, t: float) -> bool:
        """Whether time ``t`` [s] falls in a scheduled outage."""
        return any(start <= t < end for start, end in self.outages)


class Arrival(NamedTuple):
    """A message out of the link: received at ``arrival`` [s], sent at ``sent`` [s]."""

    arrival: float
    sent: float
    message: Any


@dataclass
class LinkCounts:
    """What one direction has carried so far.

    Attributes:
        sent: messages given to the link.
        delivered: messages received.
        lost: messages lost (outage or random loss).
        lost_in_outage: of ``lost``, those sent in a scheduled outage.
        last_delay: receive minus send time of the newest delivered message [s] (NaN: none yet).
        max_delay: the largest of them [s] (NaN: none yet).
    """

    sent: int = 0
    delivered: int = 0
    lost: int = 0
    lost_in_outage: int = 0
    last_delay: float = math.nan
    max_delay: float = math.nan


class LinkChannel:
    """One direction of the link (module docstring): :meth:`send`, then :meth:`deliver`."""

    def __init__(self, settings: LinkSettings) -> None:
        self.settings = settings
        self.counts = LinkCounts()
        self._rng = np.random.default_rng(settings.seed)
        self._queue: deque[Arrival] = deque()
        self._free_at = -math.inf  # when the radio finishes the message before [s]
        self._last_arrival = -math.inf

    @property
    def in_flight(self) -> int:
        """Messages sent and neither delivered nor lost."""
        return len(self._queue)

    def send(self, t: float, message: Any, size: int = 0) -> bool:
        """Give ``message`` of ``size`` bytes to the link at time ``t`` [s]; False when lost."""
        settings, counts = self.settings, self.counts
        counts.sent += 1
        # one draw of each per message, lost or not: the same seed gives the same link
        lose, u = self._rng.random(2)
        if settings.down(t):
            counts.lost += 1
            counts.lost_in_outage += 1
            return False
        if lose < settings.loss:
            counts.lost += 1
            return False
        start = max(t, self._free_at)
        airtime = size / settings.bandwidth if settings.bandwidth > 0.0 else 0.0
        self._free_at = start + airtime
        arrival = max(self._free_at + settings.delay + u * settings.jitter, self._last_arrival)
        self._last_arrival = arrival
        self._queue.append(Arrival(arrival, t, message))
        return True

    def deliver(self, t: float) -> list[Arrival]:
        """The messages received by time ``t`` [s], in the order they were sent."""
        due = []
        while self._queue and self._queue[0].arrival <= t:
            due.append(self._queue.popleft())
        counts = self.counts
        for item in due:
            delay = item.arrival - item.sent
            counts.delivered += 1
            counts.last_delay = delay
            counts.max_delay = (
                delay if math.isnan(counts.max_delay) else max(counts.max_delay, delay)
            )
        return due

    def next_arrival(self) -> float:
        """When the next message is received [s] (inf: nothing in flight)."""
        return self._queue[0].arrival if self._queue else math.inf


def parse_outages(text: str) -> tuple[tuple[float, float], ...]:
    """Scheduled outages written ``'start:end,start:end'`` [s] (empty: none), checked as
    :class:`LinkSettings` checks them.

    Raises:
        ConfigError: naming the bad pair.
    """
    outages = []
    for item in (part.strip() for part in text.split(",")):
        if not item:
            continue
        try:
            start, end = (float(value) for value in item.split(":"))
        except ValueError:
            raise ConfigError(
                f"outage {item!r} is not 'start:end' in seconds (e.g. '10:12.5')"
            ) from None
        outages.append((start, end))
    LinkSettings(outages=tuple(outages))  # the range checks
    return tuple(outages)


def parse_topic(spec: str) -> tuple[str, str]:
    """``'topic:package/msg/Type'`` as (topic, type name).

    Raises:
        ConfigError: not of that form.
    """
    topic, _, type_name = spec.partition(":")
    parts = type_name.split("/")
    if not topic.strip() or len(parts) != 3 or parts[1] != "msg" or not all(parts):
        raise ConfigError(
            f"link topic {spec!r} must be 'topic:package/msg/Type' "
            "(e.g. 'cmd_twist:geometry_msgs/msg/TwistStamped')"
        )
    return topic.strip(), type_name
