"""The matrices of the reactionless law: J-bar on a full state, the stacked A on ArmKinematics."""

from __future__ import annotations

import numpy as np
import pytest
from rns_testing import SATELLITE_OBSERVATION_DEG

from rns_ros.control.law_matrices import (
    determinant_3x3,
    restricted_jacobian,
    stacked_jacobian,
)
from rns_ros.core import FreeFloatingState

THETA_0 = np.deg2rad(SATELLITE_OBSERVATION_DEG)


def test_restricted_jacobian_singular_values_and_determinant(robot):
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    jacobian = restricted_jacobian(state)
    sigma = np.linalg.svd(jacobian.matrix, compute_uv=False)
    assert jacobian.sigma_min == pytest.approx(sigma[-1], rel=1e-10)
    assert jacobian.determinant == pytest.approx(np.prod(sigma**2), rel=1e-10)
    # J-bar moves only in the reaction null space: M~ J-bar^T = 0
    coupling = state.coupling_angular_momentum_matrix
    assert np.abs(coupling @ jacobian.matrix.T).max() < 1e-10


def test_schur_block_of_the_stacked_inverse_is_the_restricted_gram_inverse(robot):
    """(A A^T)^-1 holds S^-1 = (J-bar J-bar^T)^-1 as its upper-left 3 x 3 block, and
    E - A^+ A is P_RNS (E - J-bar^+ J-bar)."""
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    stacked = stacked_jacobian(state.arm_kinematics(THETA_0), 400.0)
    jacobian = restricted_jacobian(state)
    inverse = np.linalg.inv(stacked.gram)
    np.testing.assert_allclose(inverse[:3, :3], np.linalg.inv(jacobian.gram), rtol=1e-8)
    a = stacked.matrix
    projector = np.eye(robot.n) - a.T @ inverse @ a
    restricted_pinv = np.linalg.pinv(jacobian.matrix)
    expected = jacobian.projector @ (np.eye(robot.n) - restricted_pinv @ jacobian.matrix)
    np.testing.assert_allclose(projector, expected, atol=1e-10)
    coupling = np.linalg.det(state.coupling_angular_momentum_matrix @ a[3:].T * 400.0)
    assert stacked.coupling_determinant * 400.0**6 == pytest.approx(coupling, rel=1e-9)


def test_stacked_jacobian_declines_a_coupling_singularity(robot):
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    arm = state.arm_kinematics(THETA_0)
    rank_two = arm.coupling_angular_momentum_matrix.copy()
    rank_two[2] = rank_two[0] + rank_two[1]
    assert stacked_jacobian(arm._replace(coupling_angular_momentum_matrix=rank_two), 400.0) is None


def test_determinant_3x3():
    rng = np.random.default_rng(3)
    factor = rng.normal(size=(3, 4))
    matrix = factor @ factor.T
    assert determinant_3x3(matrix.tolist()) == pytest.approx(np.linalg.det(matrix), rel=1e-12)
