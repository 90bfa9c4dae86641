"""OS-C (6.6)-(6.13) (rns_ros.control.motion_force.osc)."""

from __future__ import annotations

import numpy as np
import pytest
from motion_force_cases import (
    CASES,
    free_arm_acceleration,
    state_case,
)

from rns_ros.control.motion_force.osc import OscVariant, operational_space, os_control
from rns_ros.core import ConfigError, InputError


@pytest.mark.parametrize("name", sorted(CASES))
def test_operational_space_quantities_match_definitions(name):
    state, task, *_ = state_case(name, seed=1)
    os_ = operational_space(state, task)
    jac = task.jacobian(state)
    m_inv_jt = np.linalg.solve(state.mass_matrix, jac.T)
    assert np.allclose(os_.mass @ (jac @ m_inv_jt), np.eye(task.m), atol=1e-9)  # (6.6)
    assert np.allclose(jac @ os_.inverse, np.eye(task.m), atol=1e-9)  # generalized inverse
    assert np.allclose(os_.inverse, m_inv_jt @ os_.mass)
    expected_c = os_.inverse.T @ state.coriolis - os_.mass @ task.drift(state)  # (6.7)
    assert np.allclose(os_.coriolis, expected_c)
    assert np.allclose(os_.gravity, os_.inverse.T @ state.gravity)  # (6.8)


@pytest.mark.parametrize("variant", list(OscVariant))
@pytest.mark.parametrize("name", sorted(CASES))
def test_os_control_gives_commanded_task_acceleration_on_free_arm(name, variant):
    state, task, _, a_ref, f_ref = state_case(name, seed=2)
    jac = task.jacobian(state)
    free = os_control(state, task, a_ref, variant=variant)
    accel = free_arm_acceleration(state, free.torque)
    assert np.allclose(accel, free.joint_acceleration, atol=1e-9)
    assert np.allclose(jac @ accel + task.drift(state), task.selection @ a_ref, atol=1e-9)
    pushing = os_control(state, task, a_ref, f_ref, variant=variant)
    # the force reference enters as +J^T n f_ref
    assert np.allclose(pushing.torque - free.torque, jac.T @ task.force_basis @ f_ref)
    assert free.method == f"os-c/{OscVariant.parse(variant).value}"


def test_os_literal_and_kinematic_differ_by_null_space_coriolis():
    state, task, _, a_ref, _ = state_case("planar", seed=3, speed=2.0)
    literal = os_control(state, task, a_ref, variant="literal")
    kinematic = os_control(state, task, a_ref, variant="kinematic")
    os_ = operational_space(state, task)
    jac = task.jacobian(state)
    null = np.eye(state.n) - jac.T @ os_.inverse.T  # E - J^T J^{M+T}
    uncompensated = -np.linalg.solve(state.mass_matrix, null @ state.coriolis)
    diff = literal.joint_acceleration - kinematic.joint_acceleration
    assert np.allclose(diff, uncompensated, atol=1e-9)
    assert np.linalg.norm(diff) > 1e-3  # the term is not negligible at 2 rad/s


def test_os_null_space_torque_does_not_disturb_the_task():
    state, task, _, a_ref, _ = state_case("lwr", seed=4)
    base = os_control(state, task, a_ref)
    extra = os_control(state, task, a_ref, null_space_torque=np.arange(7.0))
    jac = task.jacobian(state)
    assert not np.allclose(base.torque, extra.torque)
    assert np.allclose(jac @ extra.joint_acceleration, jac @ base.joint_acceleration, atol=1e-9)


def test_bad_variant_and_force_reference_raise_typed_errors():
    with pytest.raises(ConfigError, match=r"literal.*kinematic.*inverse"):
        OscVariant.parse("inverse")
    state, task, *_ = state_case("planar")
    with pytest.raises(InputError, match=r"force_ref .*finite"):
        os_control(state, task, [0.0, 0.0], [float("inf")])
