"""Chapter 7 (rns_ros.control.motion_force.null_space and .projectors): J^+ (7.2), the
null-space projectors and velocities (7.3), (7.14), the velocity-level term (7.13), the damper."""

from __future__ import annotations

import numpy as np
import pytest
from motion_force_cases import (
    CASES,
    PLANAR,
    PLANAR_START,
    state_case,
)

from rns_ros.control.motion_force.null_space import (
    damper_term,
    free_floating_acceleration,
    null_space_velocity,
    resolved_acceleration,
    velocity_level_term,
)
from rns_ros.control.motion_force.projectors import kernel_projector
from rns_ros.control.motion_force.reversed_model import ReversedModel
from rns_ros.control.motion_force.rnsc import rns_control
from rns_ros.control.motion_force.task_space import PLANAR_ROWS, TaskSpace
from rns_ros.core import ConfigError, InputError
from rns_ros.core.fixed_base import FixedBaseState


@pytest.mark.parametrize("name", sorted(CASES))
def test_rns_tends_to_resolved_acceleration_as_one_over_virtual_mass(name):
    """Spec 4.6: RNS-C -> J^+ (7.2) as m_hat -> inf, the difference proportional to 1/m_hat."""
    state, task, _, a_ref, _ = state_case(name, seed=7)
    robot = CASES[name][0]
    reference = resolved_acceleration(state, task, a_ref).joint_acceleration
    masses = np.array([1e3, 1e4, 1e5, 1e6])
    diffs = np.array(
        [
            np.linalg.norm(
                rns_control(
                    state, task, ReversedModel(robot, task.rows, virtual_mass=mass), a_ref
                ).joint_acceleration
                - reference
            )
            for mass in masses
        ]
    )
    slope = np.polyfit(np.log10(masses), np.log10(diffs), 1)[0]
    assert -1.02 < slope < -0.98, (slope, diffs)
    assert np.all(diffs * masses < 1.03 * diffs[-1] * masses[-1])


@pytest.mark.parametrize("name", sorted(CASES))
def test_free_floating_solution_tends_to_resolved_acceleration_as_one_over_virtual_mass(name):
    """(7.4)-(7.6): without F_B the control model floats, and B's velocity ~ 1/m_hat, so the
    Q_M_Al particular solution misses the real task kinematics by ~1/m_hat and tends to J^+."""
    state, task, _, a_ref, _ = state_case(name, seed=7)
    robot = CASES[name][0]
    reference = resolved_acceleration(state, task, a_ref).joint_acceleration
    rhs = task.selection @ a_ref - task.drift(state)
    masses = np.array([1e3, 1e4, 1e5, 1e6])
    diffs, misses = [], []
    for mass in masses:
        model = ReversedModel(robot, task.rows, virtual_mass=mass)
        accel = free_floating_acceleration(state, task, model, a_ref).joint_acceleration
        diffs.append(np.linalg.norm(accel - reference))
        misses.append(np.linalg.norm(task.jacobian(state) @ accel - rhs))
    for values in (diffs, misses):
        slope = np.polyfit(np.log10(masses), np.log10(values), 1)[0]
        assert -1.02 < slope < -0.98, (slope, values)
    assert misses[0] > 1e-3 * np.linalg.norm(rhs)  # a real miss at finite m_hat, not round-off


@pytest.mark.parametrize("name", sorted(CASES))
def test_free_floating_solution_keeps_every_root_row_of_the_unheld_control_model(name):
    """M_hat_A V_dot_A + M_hat_Al theta_ddot + C_hat_A = 0 on all six root rows (no F_A, no F_B,
    zero gravity), with the non-task root accelerations those the free rows give."""
    state, task, rns, a_ref, _ = state_case(name, seed=3)
    command = free_floating_acceleration(state, task, rns, a_ref)
    dyn = rns.dynamics(state)
    rows, free = list(rns.rows), list(rns.free_rows)
    root, coupling, bias = dyn.mass[:6, :6], dyn.mass[:6, 6:], dyn.bias[:6]
    root_accel = np.zeros(6)
    root_accel[rows] = command.task_acceleration
    if free:
        rest = -bias[free] - root[np.ix_(free, rows)] @ command.task_acceleration
        rest -= coupling[free] @ command.joint_acceleration
        root_accel[free] = np.linalg.solve(root[np.ix_(free, free)], rest)
    residual = root @ root_accel + coupling @ command.joint_acceleration + bias
    assert np.abs(residual).max() < 1e-8 * np.abs(bias).max() + 1e-9
    # and the minimum-norm solution: in the row space of W
    w = rns.w(state.q)
    assert np.allclose(kernel_projector(w) @ command.joint_acceleration, 0.0, atol=1e-9)


def test_resolved_acceleration_is_minimum_norm():
    state, task, _, a_ref, _ = state_case("lwr", seed=8)
    command = resolved_acceleration(state, task, a_ref)
    jac = task.jacobian(state)
    rhs = task.selection @ a_ref - task.drift(state)
    assert np.allclose(command.joint_acceleration, np.linalg.pinv(jac) @ rhs)
    extra = resolved_acceleration(state, task, a_ref, null_space_acceleration=np.ones(7))
    assert np.allclose(jac @ extra.joint_acceleration, rhs, atol=1e-9)


@pytest.mark.parametrize("name", sorted(CASES))
def test_rns_projector_is_orthogonal_projector_onto_kernel_of_w(name):
    state, task, rns, *_ = state_case(name, seed=9)
    w = rns.w(state.q)
    projector = kernel_projector(w)
    assert np.allclose(projector @ projector, projector, atol=1e-12)
    assert np.allclose(projector, projector.T, atol=1e-12)
    assert np.allclose(w @ projector, 0.0, atol=1e-9 * np.abs(w).max())
    assert round(np.trace(projector)) == state.n - task.m  # one redundant DoF in both arms
    measure = null_space_velocity(state, task, w)
    assert np.isclose(measure.rns, np.linalg.norm(projector @ state.v))
    assert np.isclose(
        measure.jacobian, np.linalg.norm(kernel_projector(task.jacobian(state)) @ state.v)
    )


@pytest.mark.parametrize("form", ["velocity", "momentum"])
def test_velocity_level_term_lies_in_kernel_of_w(form):
    state, task, rns, *_ = state_case("lwr", seed=10)
    term = velocity_level_term(state, task, rns, form=form)
    w = rns.w(state.q)
    assert np.allclose(kernel_projector(w) @ term, term, atol=1e-9 * (1 + np.abs(term).max()))
    assert np.linalg.norm(term) > 0.0


def _null_space_velocity_run(mode: str, duration: float = 0.1, step: float = 1e-3) -> float:
    """Planar arm, m_hat = 1e4, no contact, RK4 at 1 ms from rest; peak ||P_RNS theta_dot||."""
    task = TaskSpace.free(PLANAR_ROWS)
    rns = ReversedModel(PLANAR, PLANAR_ROWS, virtual_mass=1e4)

    def accel(q, v, t):
        state = FixedBaseState.compute(PLANAR, q, v)
        extra = {
            "none": None,
            "velocity": lambda: velocity_level_term(state, task, rns),
            "damper": lambda: damper_term(v),
        }[mode]
        a_ref = 2.0 * np.array([np.sin(5 * t), np.cos(5 * t)])
        return rns_control(
            state, task, rns, a_ref, null_space_acceleration=extra and extra()
        ).joint_acceleration

    q, v, peak = PLANAR_START.copy(), np.zeros(3), 0.0
    for i in range(round(duration / step)):
        t = i * step
        k1 = (v, accel(q, v, t))
        k2 = (v + step / 2 * k1[1], accel(q + step / 2 * k1[0], v + step / 2 * k1[1], t + step / 2))
        k3 = (v + step / 2 * k2[1], accel(q + step / 2 * k2[0], v + step / 2 * k2[1], t + step / 2))
        k4 = (v + step * k3[1], accel(q + step * k3[0], v + step * k3[1], t + step))
        q = q + step / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        v = v + step / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        state = FixedBaseState.compute(PLANAR, q, v)
        peak = max(peak, null_space_velocity(state, task, rns.w(q)).rns)
    return peak


def test_velocity_level_term_keeps_null_space_velocity_zero():
    """(7.13) keeps ||P_RNS theta_dot|| at round-off; without it the null-space velocity grows,
    the damper (7.3, k_d = 2770 1/s) holds it small but not at zero."""
    plain = _null_space_velocity_run("none")
    velocity = _null_space_velocity_run("velocity")
    damper = _null_space_velocity_run("damper")
    assert plain > 1e-5
    assert velocity < 1e-10
    assert velocity < damper < plain


def test_damper_term():
    assert np.allclose(damper_term([1.0, -2.0, 0.5]), [-2770.0, 5540.0, -1385.0])
    assert np.allclose(damper_term([1.0], gain=10.0), [-10.0])


def test_bad_damper_arguments_raise_typed_errors():
    with pytest.raises(ConfigError, match=r"k_d .*> 0.*0.0"):
        damper_term([1.0], gain=0.0)
    with pytest.raises(InputError, match="theta_dot must be a vector"):
        damper_term(np.zeros((2, 2)))
