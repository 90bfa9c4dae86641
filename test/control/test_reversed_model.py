"""The RNS-C control model (rns_ros.control.motion_force.reversed_model), (6.14)-(6.32)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from motion_force_cases import (
    CASES,
    LWR,
    LWR_RNS,
    PLANAR,
    PLANAR_START,
    free_arm_acceleration,
    state_case,
)

from rns_ros.control.motion_force.reversed_model import ReversedModel
from rns_ros.control.motion_force.task_space import PLANAR_ROWS
from rns_ros.core import ConfigError, ModelError


def _planar_spec_w(q, virtual_mass):
    """Independent planar construction of thesis_rest 4.4: body Jacobians in [v_A, w_A, theta],
    column of real joint j (between body k and A) -perp(c_k - p_j) / -1, then reduce w_A."""
    angles = np.cumsum(q)
    joints = [np.zeros(2)]
    for angle in angles:
        joints.append(joints[-1] + [np.cos(angle), np.sin(angle)])
    tip = joints[3]

    def perp(v):
        return np.array([-v[1], v[0]])

    bodies = [(10.0, 0.833333, joints[k] + 0.5 * (joints[k + 1] - joints[k]), k) for k in range(3)]
    bodies.append((virtual_mass, virtual_mass / 12.0, joints[0], -1))
    mass = np.zeros((6, 6))
    for m, inertia, com, k in bodies:
        jv, jw = np.zeros((2, 6)), np.zeros(6)
        jv[:, :2], jv[:, 2], jw[2] = np.eye(2), perp(com - tip), 1.0
        for j in range(k + 1, 3):
            jv[:, 3 + j], jw[3 + j] = -perp(com - joints[j]), -1.0
        mass += m * jv.T @ jv + inertia * np.outer(jw, jw)
    m_vw, m_w = mass[:2, 2:3], mass[2, 2]
    return mass[:2, 3:] - m_vw @ mass[2:3, 3:] / m_w, mass[:2, :2] - m_vw @ m_vw.T / m_w


@pytest.mark.parametrize("virtual_mass", [10.0, 1e5])
def test_reversed_model_matches_planar_construction(virtual_mass):
    q = PLANAR_START + np.array([0.1, -0.2, 0.3])
    quantities = ReversedModel(PLANAR, PLANAR_ROWS, virtual_mass=virtual_mass).evaluate(q)
    w, reduced = _planar_spec_w(q, virtual_mass)
    scale = np.abs(w).max()
    assert np.allclose(quantities.w, w, atol=1e-9 * scale + 1e-6)
    assert np.allclose(quantities.reduced_mass, reduced, atol=1e-9 * scale + 1e-6)
    assert np.linalg.eigvalsh(quantities.mass)[0] > 0.0  # M_hat is SPD


def test_reversed_model_momentum_equals_real_arm_momentum_about_a():
    """With B at rest (the real motion: V_A = J_e theta_dot), the control model's momentum
    [M_A M_Al] [V_A; theta_dot] is the real links' momentum about A: a 3-D check."""
    state, *_ = state_case("lwr", seed=5)
    quantities = LWR_RNS.evaluate(state.q)
    hat = quantities.root_mass @ (state.jacobian @ state.v) + quantities.coupling @ state.v
    data = LWR.model.createData()
    centroidal = pin.computeCentroidalMomentum(LWR.model, data, state.q, state.v)
    linear, angular_com = centroidal.linear, centroidal.angular
    angular_a = angular_com + np.cross(data.com[0] - state.ee_position, linear)
    assert np.allclose(hat, np.concatenate([linear, angular_a]), atol=1e-8)


@pytest.mark.parametrize("name", sorted(CASES))
def test_constrained_control_model_reproduces_real_arm_dynamics(name):
    """(6.19)-(6.22): the control model with B held by F_B IS the real arm (any m_hat)."""
    state, task, *_ = state_case(name, seed=12)
    robot = CASES[name][0]
    dyn = ReversedModel(robot, task.rows, virtual_mass=100.0).dynamics(state)
    torque = np.random.default_rng(12).standard_normal(robot.n)
    generalized = np.concatenate([np.zeros(6), torque])
    jc = dyn.constraint
    assert np.allclose(jc @ dyn.velocity, 0.0, atol=1e-12)  # B at rest in the real motion
    rhs = np.column_stack([jc.T, generalized - dyn.bias - dyn.gravity])
    m_inv = np.linalg.solve(dyn.mass, rhs)
    f_b = np.linalg.solve(jc @ m_inv[:, :6], -jc @ m_inv[:, 6] - dyn.constraint_drift)
    accel = m_inv[:, 6] + m_inv[:, :6] @ f_b
    real = free_arm_acceleration(state, torque)
    assert np.allclose(accel[6:], real, atol=1e-6)
    assert np.allclose(accel[:6], state.jacobian @ real + state.jacobian_dot_v, atol=1e-6)


def test_control_model_coriolis_power_identity():
    """q_hat_dot^T c_hat = 1/2 q_hat_dot^T M_hat_dot q_hat_dot (M_hat_dot by central difference)."""
    state, _, rns, *_ = state_case("lwr", seed=13)
    dyn = rns.dynamics(state)
    step = 1e-6
    mass_dot = (
        rns.evaluate(state.q + step * state.v).mass - rns.evaluate(state.q - step * state.v).mass
    ) / (2 * step)
    power = 0.5 * dyn.velocity @ mass_dot @ dyn.velocity
    assert np.isclose(dyn.velocity @ dyn.bias, power, rtol=1e-6, atol=1e-6)


def test_w_rate_finite_difference_is_consistent():
    state, _, rns, *_ = state_case("lwr", seed=11)
    fine, coarse = rns.w_rate(state.q, state.v, 1e-6), rns.w_rate(state.q, state.v, 1e-4)
    assert np.allclose(fine, coarse, rtol=1e-5, atol=1e-6 * np.abs(fine).max())


def test_non_serial_or_misplaced_ee_model_is_rejected():
    model = PLANAR.model
    robot = type(PLANAR)(model.copy(), "link_2")  # EE frame on link 2, not the last link
    with pytest.raises(ModelError, match="last link"):
        ReversedModel(robot, PLANAR_ROWS)


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: ReversedModel(PLANAR, PLANAR_ROWS, virtual_mass=0.0), r"m_hat.*0.0"),
        (
            lambda: ReversedModel(PLANAR, PLANAR_ROWS, virtual_inertia=-np.eye(3)),
            "positive definite",
        ),
    ],
)
def test_bad_virtual_link_raises_config_errors(build, match):
    with pytest.raises(ConfigError, match=match):
        build()
