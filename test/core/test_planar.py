"""The planar two-DoF model of thesis Fig. 3.1: rank, joint-2 dominance, and the r ~ 0.945 m
bifurcation of section 3.2.2."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from rns_ros.core import ConfigError, FreeFloatingState
from rns_ros.core.planar import planar_2dof_model


def _coupling(robot, theta) -> np.ndarray:
    """The only non-zero row of M~_omega_m (about z), shape (2,) [kg m^2]."""
    state = FreeFloatingState.compute(robot, robot.configuration(theta))
    return state.coupling_angular_momentum_matrix[2]


def test_parameters_of_fig_3_1():
    robot = planar_2dof_model(0.0)
    assert robot.model.inertias[1].mass == pytest.approx(1000.0)
    assert robot.model.inertias[1].inertia[2, 2] == pytest.approx(667.0)
    for joint in (2, 3):
        assert robot.model.inertias[joint].mass == pytest.approx(100.0)
        assert robot.model.inertias[joint].inertia[2, 2] == pytest.approx(8.33)


def test_attachment_follows_eq_3_6():
    robot = planar_2dof_model(1.5, np.pi / 3)
    pin.forwardKinematics(robot.model, robot.data, robot.neutral())
    assert np.allclose(
        robot.data.oMi[2].translation, [1.5 * np.cos(np.pi / 3), 1.5 * np.sin(np.pi / 3), 0.0]
    )


def test_planar_reaction_null_space_has_one_dof():
    robot = planar_2dof_model(0.5)
    state = FreeFloatingState.compute(robot, robot.configuration([0.3, 1.1]))
    assert np.allclose(state.coupling_angular_momentum_matrix[:2], 0.0, atol=1e-9)
    assert state.reaction_null_space_rank == 1


def test_reactionless_motion_is_mostly_joint_2_when_attached_at_the_com():
    """Section 3.2.1 (r = 0): the null vector n(theta) is dominated by Joint 2 everywhere."""
    robot = planar_2dof_model(0.0)
    for theta_2 in np.linspace(-np.pi, np.pi, 25):
        row = _coupling(robot, [0.0, theta_2])
        null = np.array([row[1], -row[0]]) / np.linalg.norm(row)
        assert abs(null[1]) > abs(null[0])


def _smallest_coupling(attach_distance: float) -> float:
    """min over theta of |M~_omega_m(theta)|: grid search, then damped Gauss-Newton on M~ = 0."""
    robot = planar_2dof_model(attach_distance)
    grid = np.linspace(-np.pi, np.pi, 24, endpoint=False)
    starts = sorted((np.linalg.norm(_coupling(robot, [a, b])), a, b) for a in grid for b in grid)[
        :3
    ]
    best = starts[0][0]
    for _, a, b in starts:
        theta, value = np.array([a, b]), _coupling(robot, [a, b])
        for _ in range(40):
            step = 1e-6
            jacobian = np.column_stack(
                [
                    (_coupling(robot, theta + step * e) - _coupling(robot, theta - step * e))
                    / (2 * step)
                    for e in np.eye(2)
                ]
            )
            delta = np.linalg.solve(jacobian.T @ jacobian + 1e-6 * np.eye(2), -jacobian.T @ value)
            candidate = _coupling(robot, theta + delta)
            if np.linalg.norm(candidate) >= np.linalg.norm(value):
                break
            theta, value = theta + delta, candidate
        best = min(best, float(np.linalg.norm(value)))
    return best


def test_fixed_points_appear_near_r_0_945():
    """Section 3.2.2: reactionless fixed points (M~_omega_m = 0) exist only for r >~ 0.945 m."""
    assert _smallest_coupling(0.5) > 10.0
    assert _smallest_coupling(0.93) > 0.1
    assert _smallest_coupling(0.95) < 1e-8
    assert _smallest_coupling(1.5) < 1e-8


def test_bad_attachment_is_rejected():
    with pytest.raises(ConfigError, match="attach_distance"):
        planar_2dof_model(-1.0)
    with pytest.raises(ConfigError, match="link_mass"):
        planar_2dof_model(0.5, link_mass=0.0)
