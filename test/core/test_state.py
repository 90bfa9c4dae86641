"""FreeFloatingState and the momentum relations against independent computations.

Momentum from the inertia blocks is compared with the link-by-link sums (2.24), (2.31); Jacobians
with finite differences on the manifold; M~_omega_m with Pinocchio's centroidal momentum matrix.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import assume, given, settings
from rns_testing import SATELLITE_OBSERVATION_DEG, configurations, vectors

from rns_ros.core import FreeFloatingModel, FreeFloatingState, InputError, ModelSpec
from rns_ros.core.config import load_model_config
from rns_ros.core.conventions import base_rotation_blocks, base_twist_to_world
from rns_ros.core.integration import free_floating_velocity
from rns_ros.core.inverses import kernel_basis
from rns_ros.core.momentum import (
    base_twist_from_momentum,
    coupling_angular_momentum,
    generalized_jacobian,
    reactionless_joint_velocity,
    shift_momentum,
    spatial_momentum,
)
from rns_ros.core.state import GRAM_CONDITION_LIMIT, reaction_null_space
from rns_ros.resources import default_model_config

SETTINGS = settings(max_examples=40, deadline=None)


def _state(robot, config) -> FreeFloatingState:
    position, quaternion, theta = config
    return FreeFloatingState.compute(robot, robot.configuration(theta, position, quaternion))


def _link_sums(robot: FreeFloatingModel, q: np.ndarray, v: np.ndarray):
    """Kinetic energy (2.5), p (2.24) and l about the base origin (2.31), body by body."""
    model, data = robot.model, robot.data
    pin.forwardKinematics(model, data, q, v)
    base_position = data.oMi[1].translation
    energy, momentum, angular = 0.0, np.zeros(3), np.zeros(3)
    for joint in range(1, model.njoints):
        body, placement, twist = model.inertias[joint], data.oMi[joint], data.v[joint]
        rotation = placement.rotation
        omega = rotation @ twist.angular
        com_velocity = rotation @ (twist.linear + np.cross(twist.angular, body.lever))
        com = placement.act(body.lever)
        inertia_world = rotation @ body.inertia @ rotation.T
        energy += 0.5 * (body.mass * com_velocity @ com_velocity + omega @ inertia_world @ omega)
        momentum += body.mass * com_velocity
        angular += inertia_world @ omega + body.mass * np.cross(com - base_position, com_velocity)
    return energy, momentum, angular


@SETTINGS
@given(configurations(), vectors(13, 1.0))
def test_momentum_blocks_equal_link_by_link_sums(robot, config, v):
    state = _state(robot, config)
    base_twist = base_twist_to_world(state.base_rotation, v[:6])
    energy, p, l_base = _link_sums(robot, state.q, v)
    momentum = spatial_momentum(state, base_twist, v[6:])
    scale = 1.0 + np.abs(momentum).max()
    assert np.allclose(momentum[:3], p, atol=1e-10 * scale)
    assert np.allclose(momentum[3:], l_base, atol=1e-10 * scale)
    generalized = np.concatenate((base_twist, v[6:]))
    assert 0.5 * generalized @ state.inertia @ generalized == pytest.approx(energy, rel=1e-10)


@SETTINGS
@given(configurations())
def test_inertia_is_symmetric_positive_definite(robot, config):
    inertia = _state(robot, config).inertia
    assert np.allclose(inertia, inertia.T, atol=1e-9)
    assert np.linalg.eigvalsh(inertia).min() > 0.0


def test_linear_inertia_block_is_total_mass(robot):
    state = FreeFloatingState.compute(robot, robot.neutral())
    assert np.allclose(state.inertia_base[:3, :3], robot.total_mass * np.eye(3))  # eq. (2.9)


@SETTINGS
@given(configurations())
def test_coupling_matrices_are_eq_3_2_from_the_inertia_blocks(robot, config):
    """The state takes M~_omega_m, M~_omega from the centroidal map; eq. (3.2) from CRBA agrees."""
    state = _state(robot, config)
    m_b, m_bm = state.inertia_base, state.coupling_inertia
    m_v, m_vw, m_w = m_b[:3, :3], m_b[:3, 3:], m_b[3:, 3:]
    tilde_m_w = m_w - m_vw.T @ np.linalg.solve(m_v, m_vw)
    tilde_m_wm = m_bm[3:] - m_vw.T @ np.linalg.solve(m_v, m_bm[:3])
    scale = np.abs(tilde_m_w).max()
    assert np.allclose(state.base_rotational_inertia, tilde_m_w, atol=1e-12 * scale)
    assert np.allclose(state.coupling_angular_momentum_matrix, tilde_m_wm, atol=1e-12 * scale)


@SETTINGS
@given(configurations())
def test_reaction_null_space_projector_is_symmetric_idempotent_rank_four(robot, config):
    state = _state(robot, config)
    projector = state.reaction_null_space_projector
    assert np.allclose(projector, projector.T, atol=1e-12)
    assert np.allclose(projector @ projector, projector, atol=1e-12)
    sigma = state.coupling_singular_values
    assume(sigma[-1] > 1e-6 * sigma[0])  # away from coupling singularities (see below)
    assert state.reaction_null_space_rank == 4
    assert np.linalg.matrix_rank(projector, tol=1e-8) == 4
    assert np.allclose(state.coupling_angular_momentum_matrix @ projector, 0.0, atol=1e-9)


@SETTINGS
@given(configurations(), vectors(7, 1.0))
def test_reactionless_velocity_leaves_base_attitude_still(robot, config, theta_dot_a):
    state = _state(robot, config)
    theta_dot = reactionless_joint_velocity(state, theta_dot_a)
    base_twist = base_twist_from_momentum(state, theta_dot)
    assert np.abs(base_twist[3:]).max() < 1e-10 * (1.0 + np.abs(theta_dot).max())
    assert np.abs(coupling_angular_momentum(state, theta_dot)).max() < 1e-9


def test_generic_velocity_turns_the_base(robot):
    state = FreeFloatingState.compute(
        robot, robot.configuration(np.deg2rad(SATELLITE_OBSERVATION_DEG))
    )
    theta_dot = np.full(7, 0.1)
    omega_base = base_twist_from_momentum(state, theta_dot)[3:]
    assert np.linalg.norm(omega_base) > 1e-4  # rad/s: ~ M~_omega^-1 M~_omega_m theta_dot
    # and the projection removes exactly that: the reactionless part gives zero
    reactionless = reactionless_joint_velocity(state, theta_dot)
    assert np.linalg.norm(base_twist_from_momentum(state, reactionless)[3:]) < 1e-12


@SETTINGS
@given(configurations(), vectors(7, 1.0))
def test_momentum_solve_roundtrip(robot, config, theta_dot):
    state = _state(robot, config)
    momentum = np.array([1.0, -2.0, 0.5, 10.0, 3.0, -4.0])
    base_twist = base_twist_from_momentum(state, theta_dot, momentum)
    assert np.allclose(spatial_momentum(state, base_twist, theta_dot), momentum, atol=1e-9)


@SETTINGS
@given(configurations(), vectors(13, 1.0))
def test_momentum_shifted_to_com_is_pinocchio_centroidal_momentum(robot, config, v):
    state = _state(robot, config)
    momentum = spatial_momentum(state, base_twist_to_world(state.base_rotation, v[:6]), v[6:])
    about_com = shift_momentum(momentum, state.base_position, state.center_of_mass)
    centroidal = pin.computeCentroidalMomentum(robot.model, robot.data, state.q, v)
    assert np.allclose(about_com[:3], centroidal.linear, atol=1e-9)
    assert np.allclose(about_com[3:], centroidal.angular, atol=1e-9)


def test_base_jacobian_matches_pinocchio_base_columns(robot):
    state = FreeFloatingState.compute(
        robot,
        robot.configuration(np.deg2rad(SATELLITE_OBSERVATION_DEG), [1, 2, 3], [0.1, 0.2, 0.3, 0.9]),
    )
    full = pin.getFrameJacobian(
        robot.model, robot.data, robot.camera_frame_id, pin.LOCAL_WORLD_ALIGNED
    )
    # Pinocchio's base columns act on the base-frame twist; ours on the world twist V_b.
    thesis_base_columns = full[:, :6] @ base_rotation_blocks(state.base_rotation).T
    assert np.allclose(thesis_base_columns, state.camera.base_jacobian, atol=1e-12)


def _frame_pose(robot, q, frame_id):
    pin.framesForwardKinematics(robot.model, robot.data, q)
    placement = robot.data.oMf[frame_id]
    return placement.translation.copy(), placement.rotation.copy()


def _finite_difference_twist(robot, q, v, frame_id, step=1e-6):
    """[v; omega] (world) of a frame along the manifold curve q (+) t v, central differences."""
    p_plus, r_plus = _frame_pose(robot, pin.integrate(robot.model, q, step * v), frame_id)
    p_minus, r_minus = _frame_pose(robot, pin.integrate(robot.model, q, -step * v), frame_id)
    linear = (p_plus - p_minus) / (2 * step)
    angular = pin.log3(r_plus @ r_minus.T) / (2 * step)
    return np.concatenate((linear, angular))


@settings(max_examples=25, deadline=None)
@given(configurations(), vectors(7, 1.0))
def test_fixed_base_jacobians_match_finite_differences(robot, config, theta_dot):
    state = _state(robot, config)
    v = np.concatenate((np.zeros(6), theta_dot))
    for frame_id, frame in (
        (robot.camera_frame_id, state.camera),
        (robot.wrist_frame_id, state.wrist),
    ):
        expected = _finite_difference_twist(robot, state.q, v, frame_id)
        assert np.allclose(frame.jacobian @ theta_dot, expected, atol=1e-7)


@settings(max_examples=25, deadline=None)
@given(configurations(), vectors(7, 1.0))
def test_generalized_jacobian_matches_free_floating_finite_differences(robot, config, theta_dot):
    state = _state(robot, config)
    v = free_floating_velocity(state, theta_dot)  # base moves by momentum conservation
    expected = _finite_difference_twist(robot, state.q, v, robot.camera_frame_id)
    assert np.allclose(generalized_jacobian(state, state.camera) @ theta_dot, expected, atol=1e-7)


def test_generalized_jacobian_tends_to_fixed_base_for_heavy_base():
    urdf, spec = load_model_config(default_model_config())
    text = urdf.read_text()
    base_block = '<mass value="2550.0" />\n      <inertia ixx="6200.0" ixy="0" ixz="0" iyy="3540.0"'
    base_block += ' iyz="0" izz="7090.0" />'
    assert base_block in text
    theta = np.deg2rad(SATELLITE_OBSERVATION_DEG)
    gaps = []
    for scale in (1.0, 1e3, 1e6):
        heavy = base_block.replace("2550.0", f"{2550.0 * scale}")
        for moment in ("6200.0", "3540.0", "7090.0"):
            heavy = heavy.replace(f'"{moment}"', f'"{float(moment) * scale}"')
        robot = FreeFloatingModel.from_urdf_string(text.replace(base_block, heavy), spec)
        state = FreeFloatingState.compute(robot, robot.configuration(theta))
        gap = generalized_jacobian(state, state.camera) - state.camera.jacobian
        gaps.append(np.abs(gap).max())
    assert gaps[0] > 1e-3  # the real satellite is not a fixed base
    assert gaps[2] < 1e-6
    assert gaps[1] / gaps[2] == pytest.approx(1e3, rel=1e-2)  # the gap shrinks like 1/scale


def test_restricted_jacobian_and_determinants(robot):
    state = FreeFloatingState.compute(
        robot, robot.configuration(np.deg2rad(SATELLITE_OBSERVATION_DEG))
    )
    restricted = state.restricted_jacobian
    assert restricted.shape == (3, 7)
    assert np.allclose(restricted, state.camera.jacobian[3:] @ state.reaction_null_space_projector)
    det = state.determinants
    j_w = state.camera.jacobian[3:]
    coupling = state.coupling_angular_momentum_matrix
    assert det.kinematic == pytest.approx(np.linalg.det(j_w @ j_w.T))
    assert det.coupling == pytest.approx(np.linalg.det(coupling @ coupling.T))
    assert det.algorithmic == pytest.approx(np.linalg.det(restricted @ restricted.T))
    assert 0.0 < det.algorithmic < det.kinematic  # projecting can only shrink J's volume


def test_state_arrays_are_read_only(robot):
    state = FreeFloatingState.compute(robot, robot.neutral())
    with pytest.raises(ValueError, match="read-only"):
        state.reaction_null_space_projector[0, 0] = 1.0


def test_state_rejects_bad_configuration(robot):
    with pytest.raises(InputError, match=r"q must have shape \(14,\)"):
        FreeFloatingState.compute(robot, np.zeros(13))


def test_model_without_wrist_frame_has_no_wrist_kinematics():
    urdf, _ = load_model_config(default_model_config())
    robot = FreeFloatingModel.from_urdf(urdf, ModelSpec(camera_frame="camera", wrist_frame=None))
    assert FreeFloatingState.compute(robot, robot.neutral()).wrist is None


def test_straight_arm_is_a_coupling_singularity_and_p_rns_grows(inferred_robot):
    """theta = 0 on the first, inferred geometry (joints 1, 3, 5, 7 coaxial): det(M~ M~^T) = 0
    (second singularity type of section 4.3.1); P_RNS rank 5."""
    robot = inferred_robot
    state = FreeFloatingState.compute(robot, robot.neutral())
    assert state.determinants.coupling < 1e-9 * np.prod(
        FreeFloatingState.compute(
            robot, robot.configuration(np.deg2rad(SATELLITE_OBSERVATION_DEG))
        ).coupling_singular_values
        ** 2
    )
    assert state.reaction_null_space_rank == 5
    projector = state.reaction_null_space_projector
    assert np.allclose(state.coupling_angular_momentum_matrix @ projector, 0.0, atol=1e-9)


@SETTINGS
@given(configurations(), vectors(7, 0.05))
def test_state_with_moved_joints_is_the_state_computed_there(robot, config, step):
    """with_joint_angles (the hold midpoint) equals compute at the moved q, field by field."""
    state = _state(robot, config)
    theta = state.theta + step
    moved = state.with_joint_angles(theta)
    q = state.q.copy()
    q[7:] = theta
    direct = FreeFloatingState.compute(robot, q)
    for name in (
        "q",
        "base_position",
        "base_rotation",
        "coupling_angular_momentum_matrix",
        "base_rotational_inertia",
        "center_of_mass",
        "coupling_singular_values",
        "reaction_null_space_projector",
    ):
        np.testing.assert_allclose(getattr(moved, name), getattr(direct, name), atol=1e-12)
    for frame in ("camera", "wrist"):
        for name in ("position", "rotation", "jacobian"):
            np.testing.assert_allclose(
                getattr(getattr(moved, frame), name),
                getattr(getattr(direct, frame), name),
                atol=1e-12,
            )
    assert moved.reaction_null_space_rank == direct.reaction_null_space_rank
    assert not moved.q.flags.writeable
    assert not moved.reaction_null_space_projector.flags.writeable


@SETTINGS
@given(configurations())
def test_gram_projector_is_the_svd_kernel_projector(robot, config):
    """P_RNS from the 3 x 3 solve (eq. 2.34) equals V_k V_k^T of the SVD kernel basis."""
    coupling = _state(robot, config).coupling_angular_momentum_matrix
    projector, sigma, rank = reaction_null_space(coupling)
    kernel, sigma_svd, rank_svd = kernel_basis(coupling, 1e-9)
    if sigma_svd[-1] > GRAM_CONDITION_LIMIT * sigma_svd[0]:
        assert rank == rank_svd == 3
    np.testing.assert_allclose(projector, kernel @ kernel.T, atol=1e-10)
    np.testing.assert_allclose(sigma, sigma_svd, rtol=1e-9, atol=1e-9 * sigma_svd[0])


def test_near_a_coupling_singularity_the_projector_comes_from_the_svd():
    """Rank 2 up to 1e-12: the Gram matrix would lose all digits; the SVD decides rank 2."""
    rng = np.random.default_rng(3)
    coupling = rng.standard_normal((3, 2)) @ rng.standard_normal((2, 7))
    coupling[2] += 1e-12 * rng.standard_normal(7)
    projector, _, rank = reaction_null_space(coupling)
    assert rank == 2
    assert np.allclose(projector @ projector, projector, atol=1e-12)
    assert np.allclose(coupling @ projector, 0.0, atol=1e-10)
