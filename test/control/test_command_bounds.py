"""bound_joint_command: every joint command published stays finite, within the URDF limits and
max_reference_error of the measured angles, within the velocity limits, and is not pushed past a
limit over its horizon."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rns_ros.control.command_bounds import (
    DEFAULT_MAX_REFERENCE_ERROR,
    CommandBounds,
    bound_joint_command,
)
from rns_ros.core import ConfigError
from rns_ros.core.errors import InputError

#: Three joints: revolute [-1, 2] rad at 0.5 rad/s, continuous at 1 rad/s, revolute [-pi, pi]
#: without a velocity limit.
BOUNDS = CommandBounds(
    lower=np.array([-1.0, -math.inf, -math.pi]),
    upper=np.array([2.0, math.inf, math.pi]),
    velocity=np.array([0.5, 1.0, math.inf]),
    max_reference_error=DEFAULT_MAX_REFERENCE_ERROR,
)
PERIOD = 0.01


def _values(bound: float):
    """Finite values within +-bound, NaN and +-inf."""
    return st.one_of(
        st.floats(-bound, bound),
        st.sampled_from([math.nan, math.inf, -math.inf]),
    )


def _arrays(bound: float):
    return st.lists(_values(bound), min_size=3, max_size=3).map(np.array)


def _measured():
    """Measured angles: inside the limits, or beyond them (a robot past its soft limits)."""
    return st.lists(st.floats(-5.0, 5.0), min_size=3, max_size=3).map(np.array)


def _assert_bounded(bounded, measured, horizon):
    e = BOUNDS.max_reference_error
    p, v = bounded.positions, bounded.velocities
    assert np.isfinite(p).all()
    assert np.isfinite(v).all()
    for end in (p, p + horizon * v):  # point 0 and where the held velocity takes it
        assert np.all(end >= BOUNDS.lower)
        assert np.all(end <= BOUNDS.upper)
        # within e of the measured angle, unless the limits leave no such position
        low = np.clip(measured - e, BOUNDS.lower, BOUNDS.upper)
        high = np.clip(measured + e, BOUNDS.lower, BOUNDS.upper)
        assert np.all(end >= low)
        assert np.all(end <= high)
    assert np.all(np.abs(v) <= BOUNDS.velocity)


@settings(max_examples=300, deadline=None)
@given(
    positions=_arrays(1e7),
    velocities=_arrays(1e7),
    measured=_measured(),
    horizon=st.sampled_from([PERIOD, 2 * PERIOD, 0.5]),
)
def test_every_command_is_finite_within_its_bounds_and_a_stop_when_it_was_not_finite(
    positions, velocities, measured, horizon
):
    bounded = bound_joint_command(positions, velocities, measured, BOUNDS, horizon)
    _assert_bounded(bounded, measured, horizon)
    finite = np.isfinite(positions).all() and np.isfinite(velocities).all()
    assert bounded.non_finite is not finite
    if not finite:
        assert np.all(bounded.velocities == 0.0)
        assert bounded.clipped_joint is None


@settings(max_examples=200, deadline=None)
@given(
    measured=st.lists(st.floats(-0.5, 1.5), min_size=3, max_size=3).map(np.array),
    offset=st.lists(st.floats(-0.2, 0.2), min_size=3, max_size=3).map(np.array),
    fraction=st.floats(-1.0, 1.0),
)
def test_a_command_within_its_bounds_passes_unchanged(measured, offset, fraction):
    """Positions within e of the measured angles and the limits, velocities that stay there:
    exactly what was asked (the law's outputs in normal operation)."""
    positions = measured + offset
    velocities = fraction * np.array([0.5, 1.0, 3.0]) * 0.01  # far from every limit
    bounded = bound_joint_command(positions, velocities, measured, BOUNDS, PERIOD)
    assert np.array_equal(bounded.positions, positions)
    assert np.array_equal(bounded.velocities, velocities)
    assert not bounded.non_finite
    assert bounded.clipped_joint is None


def test_a_reference_far_from_the_measured_angles_is_clipped_to_them_and_named():
    """The issue's wild command: a reference 9.3e4 rad away (a held interval of 1e6 s)."""
    measured = np.array([0.5, 100.0, 3.0])
    positions = np.array([0.5, 100.0 + 9.3e4, 3.0])
    bounded = bound_joint_command(positions, np.zeros(3), measured, BOUNDS, PERIOD)
    assert bounded.positions[1] == pytest.approx(100.25)  # continuous: e of the measured
    assert bounded.clipped_joint == 1
    assert bounded.positions[2] == 3.0  # within [pi - ..., pi]: unchanged


def test_a_joint_at_a_limit_is_not_pushed_past_it_and_may_leave_it():
    measured = np.array([2.0, 0.0, -math.pi])
    positions = np.array([2.0, 0.0, -math.pi])
    into = bound_joint_command(positions, np.array([0.3, 0.0, -2.0]), measured, BOUNDS, PERIOD)
    assert into.velocities[0] == 0.0
    assert into.velocities[2] == 0.0
    away = bound_joint_command(positions, np.array([-0.3, 0.0, 2.0]), measured, BOUNDS, PERIOD)
    assert away.velocities[0] == -0.3
    assert away.velocities[2] == 2.0


def test_velocities_are_bounded_by_the_urdf_limits_and_the_room_left_over_the_horizon():
    measured = np.zeros(3)
    bounded = bound_joint_command(np.zeros(3), np.array([5.0, -5.0, 5.0]), measured, BOUNDS, 0.1)
    # joint 1: its limit 1 rad/s; joint 2 (no limit): the room to measured + e in 0.1 s
    assert bounded.velocities[0] == 0.5
    assert bounded.velocities[1] == -1.0
    assert bounded.velocities[2] == pytest.approx(DEFAULT_MAX_REFERENCE_ERROR / 0.1)
    assert bounded.velocities[2] * 0.1 <= DEFAULT_MAX_REFERENCE_ERROR


def test_a_measured_angle_beyond_a_limit_leaves_the_command_at_the_limit():
    measured = np.array([2.6, 0.0, 0.0])  # 0.6 rad past the upper limit
    bounded = bound_joint_command(np.array([2.6, 0.0, 0.0]), np.zeros(3), measured, BOUNDS, PERIOD)
    assert bounded.positions[0] == 2.0


def test_a_non_finite_command_is_a_stop_at_the_measured_angle_where_a_position_is_unknown():
    measured = np.array([0.1, 0.2, 0.3])
    positions = np.array([0.15, math.nan, 0.3])
    bounded = bound_joint_command(positions, np.array([0.1, 0.1, 0.1]), measured, BOUNDS, PERIOD)
    assert bounded.non_finite
    assert np.array_equal(bounded.positions, [0.15, 0.2, 0.3])
    assert np.all(bounded.velocities == 0.0)


def test_bad_shapes_horizons_and_bounds_are_named():
    with pytest.raises(InputError, match="velocities must have shape"):
        bound_joint_command(np.zeros(3), np.zeros(2), np.zeros(3), BOUNDS, PERIOD)
    with pytest.raises(ConfigError, match="horizon"):
        bound_joint_command(np.zeros(3), np.zeros(3), np.zeros(3), BOUNDS, 0.0)
    with pytest.raises(ConfigError, match="max_reference_error"):
        CommandBounds(BOUNDS.lower, BOUNDS.upper, BOUNDS.velocity, 0.0)
    with pytest.raises(ConfigError, match=r"lower limit 3\.0 rad is above"):
        CommandBounds(np.array([3.0, 0, 0]), BOUNDS.upper, BOUNDS.velocity, 0.25)
    with pytest.raises(ConfigError, match="velocity limit must be > 0"):
        CommandBounds(BOUNDS.lower, BOUNDS.upper, np.array([0.0, 1, 1]), 0.25)


def test_the_bounds_of_the_default_robot_are_its_urdf_limits(robot):
    bounds = CommandBounds.of(robot, 0.25)
    assert np.array_equal(bounds.lower, robot.lower_limits)
    assert np.array_equal(bounds.upper, robot.upper_limits)
    assert np.array_equal(bounds.velocity, robot.velocity_limits)
