"""due_ticks: the period instants a /clock reading passes, on a grid from the first reading."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from rns_ros.core.errors import ConfigError
from rns_ros.nodes.clock_ticks import MAX_TICKS, ClockTicks, due_ticks

PERIOD = 10_000_000  # 10 ms [ns]


def test_the_first_reading_starts_the_grid():
    assert due_ticks(None, 1_230_000_000, PERIOD) == [1_230_000_000]


def test_a_repeated_or_in_between_reading_is_no_tick():
    assert due_ticks(1_000_000_000, 1_000_000_000, PERIOD) == []
    assert due_ticks(1_000_000_000, 1_005_000_000, PERIOD) == []  # 5 ms into the period


def test_one_or_two_passed_instants_come_in_order_on_the_grid():
    assert due_ticks(1_000_000_000, 1_010_000_000, PERIOD) == [1_010_000_000]
    # two /clock messages handed over at once: the one in between is not skipped
    assert due_ticks(1_000_000_000, 1_020_000_000, PERIOD) == [1_010_000_000, 1_020_000_000]
    # a reading a nanosecond short of the instant (summed float steps) counts as on it
    assert due_ticks(1_000_000_000, 1_009_999_999, PERIOD) == [1_010_000_000]


def test_far_behind_or_backwards_the_grid_restarts_at_the_reading():
    assert due_ticks(1_000_000_000, 1_000_000_000 + (MAX_TICKS + 1) * PERIOD, PERIOD) == [
        1_000_000_000 + (MAX_TICKS + 1) * PERIOD
    ]
    assert due_ticks(2_000_000_000, 500_000_000, PERIOD) == [500_000_000]  # a reset clock


@given(steps=st.lists(st.integers(0, 2), min_size=1, max_size=60))
def test_a_clock_advancing_at_most_two_periods_per_reading_ticks_every_instant_once(steps):
    """Repeated readings, single and double steps: every grid instant is served exactly once,
    in order."""
    last, now, served = None, 0, []
    for step in [0, *steps]:  # the grid starts at the first reading, 0
        now += step * PERIOD
        for tick in due_ticks(last, now, PERIOD):
            served.append(tick)
            last = tick
    assert served == list(range(0, now + 1, PERIOD))


def test_the_period_must_be_positive():
    with pytest.raises(ConfigError, match="period"):
        ClockTicks(None, 0.0, print)
