"""ClockWatch: a stopped simulated clock is reported after its timeout of wall time."""

from __future__ import annotations

import math

import pytest

from rns_ros.control.watchdog import ClockWatch
from rns_ros.core import ConfigError


class WallClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_a_clock_that_stands_still_is_reported_after_the_timeout_only():
    wall = WallClock()
    watch = ClockWatch(1.0, wall)
    assert watch.check(0) is None  # no /clock yet
    wall.now += 5.0
    assert watch.check(0) is None  # never moved: a node waiting for its simulator
    assert watch.check(10_000_000) is None  # moved at wall 105
    wall.now += 0.9
    assert watch.check(10_000_000) is None
    wall.now += 0.2
    assert watch.check(10_000_000) == pytest.approx(1.1)
    assert watch.check(20_000_000) is None  # moves again
    wall.now += 0.5
    assert watch.check(20_000_000) is None


def test_a_clock_that_goes_back_has_moved():
    wall = WallClock()
    watch = ClockWatch(0.5, wall)
    watch.check(0)
    watch.check(5_000_000_000)
    wall.now += 0.6
    assert watch.check(1_000_000) is None  # a reset: /clock is alive


@pytest.mark.parametrize("timeout", [0.0, -1.0, math.nan, math.inf])
def test_the_timeout_must_be_finite_and_positive(timeout):
    with pytest.raises(ConfigError, match="clock timeout"):
        ClockWatch(timeout)
