"""due_ticks: the period instants a /clock reading passes, on a grid from the first reading."""

from __future__ import annotations

import pytest
import rclpy
from hypothesis import given
from hypothesis import strategies as st
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock

from rns_ros.core.errors import ConfigError
from rns_ros.nodes.clock_ticks import MAX_TICKS, ClockTicks, due_ticks
from rns_ros.nodes.sim_clock import stamp_from_seconds

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


def test_max_ticks_must_be_positive():
    with pytest.raises(ConfigError, match="max_ticks"):
        ClockTicks(None, 0.01, print, max_ticks=0)


def test_a_sim_time_node_ticks_on_the_clock_its_time_source_sets(ros):
    """In a node with use_sim_time, /clock (read by rclpy's TimeSource, no subscription of
    ClockTicks' own) ticks the grid: one instant per period passed, none for a repeated reading,
    missed ones up to max_ticks caught up in order, a clock set back restarts the grid; destroy
    stops the ticks."""
    node = ros.add(
        rclpy.create_node(
            "ticking",
            context=ros.context,
            parameter_overrides=[Parameter("use_sim_time", value=True)],
        )
    )
    served: list[int] = []
    ticks = ClockTicks(node, 0.01, lambda t: served.append(t.nanoseconds), max_ticks=3)
    readers = node.get_subscriptions_info_by_topic("/clock")
    assert [info.node_name for info in readers].count("ticking") == 1  # the TimeSource's only
    clock = ros.probe().create_publisher(Clock, "/clock", 10)
    seconds = [1.0, 1.01, 1.01, 1.015, 1.04, 1.1, 0.5]
    expected = [
        [1_000_000_000],
        [1_010_000_000],
        [],
        [],
        [1_020_000_000, 1_030_000_000, 1_040_000_000],
        [1_100_000_000],  # six periods on: more than max_ticks, the grid restarts
        [500_000_000],  # set back (a reset)
    ]
    ros.spin_until(lambda: node.count_publishers("/clock") > 0, timeout=5.0)
    for t, due in zip(seconds, expected, strict=True):
        before = len(served)
        clock.publish(Clock(clock=stamp_from_seconds(t)))
        now = round(t * 1e9)
        assert ros.spin_until(lambda now=now: node.get_clock().now().nanoseconds == now, 5.0)
        assert served[before:] == due, t
    ticks.destroy()
    clock.publish(Clock(clock=stamp_from_seconds(0.6)))
    assert ros.spin_until(lambda: node.get_clock().now().nanoseconds == 600_000_000, 5.0)
    assert served[-1] == 500_000_000
