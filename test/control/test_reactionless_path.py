"""Reactionless elbow paths by arc length (rns_ros.control.reactionless_path)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rns_ros.control.reactionless_path import positioning_null_vector, reactionless_path
from rns_ros.core.state import FreeFloatingState


def test_path_is_reactionless_through_a_turning_point(robot, relative_coupling):
    """From the partial-deployment goal [90 50 0 -300 0 20 0] deg the default arm's elbow path
    turns back smoothly at theta_4 ~ -197.3 deg (n_4 passes 0): followed by arc length it passes
    the turning point with a continuous unit tangent (no 1/n_4) and stays reactionless. (The
    Phase III start's turn at -145.4 deg is a near rank drop of M~_P where n swings; see
    test_three_phase_reaches_goal_reactionlessly.)"""
    start = np.deg2rad([90.0, 50.0, 0.0, -300.0, 0.0, 20.0, 0.0])
    path = reactionless_path(robot, start, -math.pi, max_arc=3.6, stop_at_turning_point=False)
    assert path.turning_points, "expected a turning point of theta_4 on this path"
    assert path.turn_kinks[0] < 0.05
    turn = np.argmax(path.theta[:, 3])
    assert 5 < turn < path.arc.size - 5  # passed, not stopped at
    assert path.theta[-1, 3] < path.theta[turn, 3] - 0.01  # theta_4 went back down
    np.testing.assert_allclose(np.linalg.norm(path.tangent[:, :4], axis=1), 1.0, atol=1e-12)
    assert np.abs(np.diff(path.tangent, axis=0)).max() < 0.1  # sign-continuous, no blow-up
    for k in range(turn - 5, turn + 6):
        assert relative_coupling(path.theta[k], path.tangent[k]) < 1e-12
    np.testing.assert_allclose(path.theta[:, 4:], np.tile(start[4:], (path.arc.size, 1)))


def test_positioning_null_vector_spans_the_kernel_of_the_positioning_coupling(robot):
    rng = np.random.default_rng(11)
    for _ in range(10):
        theta = rng.uniform(robot.lower_limits, robot.upper_limits)
        n = positioning_null_vector(robot, theta)
        state = FreeFloatingState.compute(robot, robot.configuration(theta))
        block = state.coupling_angular_momentum_matrix[:, robot.subchains.positioning]
        assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-12)
        assert np.abs(block @ n).max() < 1e-10 * np.abs(block).max()
