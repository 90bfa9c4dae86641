"""Uniform scaling of a joint velocity to the speed and position limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rns_ros.control.joint_limits import (
    position_limit_scale,
    scale_to_joint_limits,
    uniform_speed_scale,
)
from rns_ros.core.config import load_model


def test_uniform_speed_scale():
    assert uniform_speed_scale(np.array([0.5, -0.2]), np.array([1.0, 1.0])) == 1.0
    assert uniform_speed_scale(np.array([2.0, -4.0]), np.array([1.0, 2.0])) == 0.5


def test_position_limit_scale_matches_the_distance_left():
    lower, upper = np.array([-1.0, -1.0]), np.array([1.0, 1.0])
    theta = np.array([0.9, 0.0])
    # joint 0 has 0.1 rad left and would move 0.4 rad: s = 0.25
    assert position_limit_scale(theta, np.array([4.0, 1.0]), lower, upper, 0.1) == pytest.approx(
        0.25
    )
    # moving away from the limit is never restricted
    assert position_limit_scale(theta, np.array([-4.0, 1.0]), lower, upper, 0.1) == 1.0
    # at the limit and pushing into it: halt
    at_limit = np.array([1.0, 0.0])
    assert position_limit_scale(at_limit, np.array([0.1, 0.0]), lower, upper, 0.1) == 0.0


def test_scaling_keeps_the_direction_and_meets_every_limit(robot):
    theta = 0.5 * (robot.lower_limits + robot.upper_limits)
    theta_dot = 3.0 * robot.velocity_limits * np.linspace(-1.0, 1.0, robot.n)
    scaled, scale, position_limited = scale_to_joint_limits(robot, theta, theta_dot, 0.01)
    assert not position_limited
    np.testing.assert_allclose(scaled, scale * theta_dot, rtol=1e-15)
    assert np.all(np.abs(scaled) <= robot.velocity_limits * (1 + 1e-12))
    assert scale == pytest.approx(1.0 / 3.0)
    # a joint at its upper limit, moving up: the whole motion halts
    theta[0] = robot.upper_limits[0]
    scaled, scale, position_limited = scale_to_joint_limits(robot, theta, np.abs(theta_dot), 0.01)
    assert position_limited
    assert scale == 0.0
    assert not np.any(scaled)


def test_absent_bounds_are_skipped_and_give_no_nan():
    """A joint without a bound (+-inf, a continuous joint) never restricts the scale; the finite
    bounds of the other joints still do, with the same numbers as without it."""
    inf = np.inf
    assert uniform_speed_scale(np.array([5.0, 0.0]), np.array([inf, inf])) == 1.0
    assert uniform_speed_scale(np.array([5.0, -4.0]), np.array([inf, 2.0])) == 0.5
    assert uniform_speed_scale(np.array([0.0, -4.0]), np.array([inf, 2.0])) == 0.5
    unbounded = (np.array([-inf, -1.0]), np.array([inf, 1.0]))
    theta = np.array([1e6, 0.9])
    assert position_limit_scale(theta, np.array([1e3, 0.0]), *unbounded, 0.1) == 1.0
    assert position_limit_scale(theta, np.array([-1e3, 4.0]), *unbounded, 0.1) == pytest.approx(
        0.25
    )
    assert position_limit_scale(theta, np.zeros(2), *unbounded, 0.1) == 1.0


def test_an_arm_with_continuous_joints_is_scaled_by_its_speed_limits_only():
    robot = load_model(Path(__file__).resolve().parents[1] / "data/arms/cont6/model.yaml")
    assert np.all(np.isinf(robot.lower_limits))
    assert np.all(np.isinf(robot.upper_limits))
    theta = np.array([50.0, -50.0, 0.0, 1e4, 3.0, -3.0])  # [rad] far past any +-pi
    theta_dot = 2.0 * robot.velocity_limits * np.linspace(-1.0, 1.0, robot.n)
    scaled, scale, position_limited = scale_to_joint_limits(robot, theta, theta_dot, 0.01)
    assert not position_limited
    assert scale == pytest.approx(0.5)
    np.testing.assert_allclose(scaled, 0.5 * theta_dot, rtol=1e-15)
