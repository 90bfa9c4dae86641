"""RNS-C (rns_ros.control.motion_force.rnsc): the closed form and the literal loop."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from motion_force_cases import (
    CASES,
    CONFIG,
    LWR_RNS,
    PLANAR,
    PLANAR_RNS,
    free_arm_acceleration,
    state_case,
)

from rns_ros.control.motion_force.osc import os_control
from rns_ros.control.motion_force.projectors import kernel_projector
from rns_ros.control.motion_force.reversed_model import ReversedModel
from rns_ros.control.motion_force.rnsc import rns_control, rns_literal_step
from rns_ros.control.motion_force.task_space import PLANAR_ROWS, TaskSpace
from rns_ros.core import ConfigError, InputError
from rns_ros.core.fixed_base import FixedBaseState


@pytest.mark.parametrize(("virtual_mass", "contraction"), [(100.0, 0.3), (1e5, 1e-3)])
@pytest.mark.parametrize("name", sorted(CASES))
def test_literal_rns_loop_converges_to_closed_form(name, virtual_mass, contraction):
    """[A-4.3]: (6.22)+(6.17) with tau from the previous step converges to the closed form; the
    error shrinks by about 1/m_hat per step."""
    state, task, _, a_ref, f_ref = state_case(name, seed=14)
    robot = CASES[name][0]
    rns = ReversedModel(robot, task.rows, virtual_mass=virtual_mass)
    closed = rns_control(state, task, rns, a_ref, f_ref)
    torque, errors = np.zeros(robot.n), []
    for _ in range(12):
        step = rns_literal_step(state, task, rns, a_ref, f_ref, previous_torque=torque)
        torque = step.command.torque
        errors.append(np.abs(step.command.joint_acceleration - closed.joint_acceleration).max())
    assert step.command.method == "rns-c/literal"
    assert errors[-1] < 1e-8
    assert np.allclose(torque, closed.torque, atol=1e-6 * (1 + np.abs(closed.torque).max()))
    assert errors[2] < contraction * errors[1]


def _check_rns(state, task, rns, a_ref, f_ref):
    command = rns_control(state, task, rns, a_ref, f_ref)
    jac, w = task.jacobian(state), rns.w(state.q)
    accel = command.joint_acceleration
    achieved = jac @ accel + task.drift(state)
    scale = 1.0 + np.abs(a_ref).max() + np.abs(task.drift(state)).max()
    assert np.allclose(achieved, task.selection @ a_ref, atol=1e-9 * scale)
    assert np.linalg.norm(kernel_projector(w) @ accel) <= 1e-9 * (1 + np.linalg.norm(accel))
    torque = command.torque - jac.T @ task.force_wrench(f_ref)
    assert np.allclose(free_arm_acceleration(state, torque), accel, atol=1e-8 * scale)
    return command


@pytest.mark.parametrize("name", sorted(CASES))
def test_rns_closed_form_meets_task_in_row_space_of_w(name):
    command = _check_rns(*state_case(name, seed=6))
    assert command.method == "rns-c/closed-form"
    assert command.sigma_min > 0.0


@settings(max_examples=40, deadline=None)
@given(
    q=st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3),
    v=st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3),
    a=st.lists(st.floats(-5.0, 5.0), min_size=2, max_size=2),
    normal_angle=st.floats(0.0, 2 * np.pi),
)
def test_rns_closed_form_random_planar_configurations(q, v, a, normal_angle):
    state = FixedBaseState.compute(PLANAR, q, v)
    task = TaskSpace.from_contact(PLANAR_ROWS, [np.cos(normal_angle), np.sin(normal_angle), 0])
    jac = task.jacobian(state)
    if np.linalg.svd(jac @ PLANAR_RNS.w(state.q).T, compute_uv=False)[-1] < 1e-6 * 1e5:
        return  # J W^T near-singular: covered by the singular test below
    _check_rns(state, task, PLANAR_RNS, np.array(a), np.array([3.0]))


@settings(max_examples=25, deadline=None)
@given(
    q2=st.floats(1e-3, 2e-2),
    q3=st.floats(-2e-2, 2e-2),
    v=st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
)
def test_rns_near_singular_planar_stays_exact_and_finite(q2, q3, v):
    """Near the stretched arm (a kinematic singularity of x, y) J W^T is ill-conditioned but the
    commanded task acceleration is still met; sigma_min reports it."""
    state = FixedBaseState.compute(PLANAR, [0.3, q2, q3], v)
    task = TaskSpace.free(PLANAR_ROWS)
    command = rns_control(state, task, PLANAR_RNS, [0.0, 0.1])
    assert np.isfinite(command.joint_acceleration).all()
    assert command.sigma_min < 1e-2 * command.sigma_max
    achieved = task.jacobian(state) @ command.joint_acceleration + task.drift(state)
    assert np.allclose(achieved, [0.0, 0.1], atol=1e-6 * (1 + np.abs(task.drift(state)).max()))


def test_singular_task_reports_sigma_and_os_raises():
    state = FixedBaseState.compute(PLANAR, [0.3, 0.0, 0.0], [0.0, 0.0, 0.0])
    task = TaskSpace.free(PLANAR_ROWS)
    command = rns_control(state, task, PLANAR_RNS, [0.0, 0.1])
    assert np.isfinite(command.torque).all()
    assert command.sigma_min <= 1e-9 * command.sigma_max
    with pytest.raises(InputError, match="singular"):
        os_control(state, task, [0.0, 0.1])


def test_bad_references_raise_typed_errors():
    state, task, rns, *_ = state_case("planar")
    with pytest.raises(InputError, match=r"shape \(2,\)"):
        rns_control(state, task, rns, [0.0, 0.0, 0.0])
    with pytest.raises(ConfigError, match="rows"):
        rns_control(state, task, LWR_RNS, [0.0, 0.0])
    with pytest.raises(InputError, match=r"W must be finite with shape \(2, 3\)"):
        rns_control(state, task, rns, [0.0, 0.0], w=np.zeros((3, 3)))


def test_docs_example_runs(monkeypatch, capsys):
    """The python block of docs/part2_controllers.md runs as written (from the repository root)."""
    text = (CONFIG.parent / "docs" / "part2_controllers.md").read_text()
    block = text.split("```python\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(CONFIG.parent)
    exec(compile(block, "part2_controllers.md", "exec"), {})  # our own documentation
    assert "NullSpaceVelocity" in capsys.readouterr().out
