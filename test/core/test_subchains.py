"""Predominant wrist motion (4.2) and elbow null vector (4.3) span the reaction null space (4.4)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from rns_testing import SATELLITE_OBSERVATION_DEG, configurations, vectors

from rns_ros.core import FreeFloatingState, ModelError, subchain_decomposition
from rns_ros.core.planar import planar_2dof_model

SETTINGS = settings(max_examples=40, deadline=None)


def _decompose(robot, config):
    """State and decomposition; skips configurations where M~_P is near rank loss."""
    position, quaternion, theta = config
    state = FreeFloatingState.compute(robot, robot.configuration(theta, position, quaternion))
    parts = subchain_decomposition(robot, state)
    sigma = parts.positioning_singular_values
    assume(sigma[-1] > 1e-3 * sigma[0])
    return state, parts


@SETTINGS
@given(configurations(), vectors(3, 1.0))
def test_predominant_wrist_motion_is_reactionless(robot, config, wrist_velocity):
    state, parts = _decompose(robot, config)
    theta_dot = parts.predominant_wrist_motion(wrist_velocity)
    assert parts.wrist_map.shape == (4, 3)
    assert np.allclose(theta_dot[4:], wrist_velocity)
    assert np.abs(state.coupling_angular_momentum_matrix @ theta_dot).max() < 1e-9


@SETTINGS
@given(configurations())
def test_elbow_motion_is_reactionless_and_orthogonal_to_wrist_motion(robot, config):
    state, parts = _decompose(robot, config)
    assert parts.elbow_null_vectors.shape == (4, 1)
    elbow = parts.elbow_motion(1.0)
    assert np.linalg.norm(elbow) == pytest.approx(1.0)
    assert elbow[3] >= 0.0  # sign convention: elbow entry non-negative
    assert np.abs(state.coupling_angular_momentum_matrix @ elbow).max() < 1e-9
    for axis in np.eye(3):
        assert abs(elbow @ parts.predominant_wrist_motion(axis)) < 1e-10


@SETTINGS
@given(configurations())
def test_wrist_and_elbow_motions_span_the_reaction_null_space(robot, config):
    state, parts = _decompose(robot, config)
    basis = np.column_stack(
        [parts.predominant_wrist_motion(axis) for axis in np.eye(3)] + [parts.elbow_motion(1.0)]
    )
    assert np.linalg.matrix_rank(basis, tol=1e-8) == 4
    # every column lies in ker(M~), so P_RNS reproduces it (eq. 4.4)
    assert np.allclose(state.reaction_null_space_projector @ basis, basis, atol=1e-9)


def test_wrist_motion_needs_only_small_positioning_compensation(robot):
    """Section 4.1.2: the light wrist is compensated by small positioning-joint motion."""
    state = FreeFloatingState.compute(
        robot, robot.configuration(np.deg2rad(SATELLITE_OBSERVATION_DEG))
    )
    parts = subchain_decomposition(robot, state)
    assert np.linalg.norm(parts.wrist_map, 2) < 0.3  # 0.24 on the identified geometry


def test_subchains_require_configuration():
    planar = planar_2dof_model(0.5)
    state = FreeFloatingState.compute(planar, planar.configuration([0.1, 0.2]))
    with pytest.raises(ModelError, match="no subchains configured"):
        subchain_decomposition(planar, state)


def test_straight_arm_is_a_positioning_coupling_singularity(inferred_robot):
    """theta = 0 on the first, inferred geometry (no shoulder offset): joints 1 and 3 are
    coaxial, M~_P drops to rank 2 and ker(M~_P) becomes 2-D."""
    robot = inferred_robot
    state = FreeFloatingState.compute(robot, robot.neutral())
    parts = subchain_decomposition(robot, state)
    sigma = parts.positioning_singular_values
    assert sigma[-1] < 1e-9 * sigma[0]
    assert parts.elbow_null_vectors.shape == (4, 2)
    coupling_p = state.coupling_angular_momentum_matrix[:, :4]
    assert np.allclose(coupling_p @ parts.elbow_null_vectors, 0.0, atol=1e-9)
