"""Motion/force controllers of thesis Part II (rns_ros.control.motion_force): OS-C (6.6)-(6.13),
RNS-C closed form with the reversed control model, the J^+ limit (7.2), chapter-7 terms."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rns_ros.control.motion_force.null_space import (
    damper_term,
    null_space_velocity,
    resolved_acceleration,
    velocity_level_term,
)
from rns_ros.control.motion_force.osc import OscVariant, operational_space, os_control
from rns_ros.control.motion_force.outer_loops import (
    ForceGains,
    MotionGains,
    force_loop,
    motion_loop,
)
from rns_ros.control.motion_force.projectors import kernel_projector
from rns_ros.control.motion_force.reversed_model import ReversedModel
from rns_ros.control.motion_force.rnsc import rns_control, rns_literal_step
from rns_ros.control.motion_force.task_space import FULL_ROWS, PLANAR_ROWS, TaskSpace, contact_frame
from rns_ros.core import ConfigError, InputError, ModelError
from rns_ros.core.fixed_base import FixedBaseState, load_fixed_base_model

CONFIG = Path(__file__).resolve().parents[2] / "config"
PLANAR_START = np.deg2rad([106.4, -45.7, -56.2])
LWR_START = np.deg2rad([20.0, -20.0, 0.0, 100.0, 0.0, 10.0, 0.0])
PLANAR = load_fixed_base_model(CONFIG / "planar_3dof.yaml")
LWR = load_fixed_base_model(CONFIG / "lwr_7dof.yaml", gravity=True)  # gravity on: G_e, g_l used
PLANAR_TASK = TaskSpace.from_contact(PLANAR_ROWS, [1.0, 0.0, 0.0])  # normal +x, tangent +y
WALL_TASK = TaskSpace.from_contact(FULL_ROWS, [0.0, 0.0, 1.0])  # wall: force along z
PLANAR_RNS = ReversedModel(PLANAR, PLANAR_ROWS)
LWR_RNS = ReversedModel(LWR, FULL_ROWS)
CASES = {
    "planar": (PLANAR, PLANAR_TASK, PLANAR_RNS, PLANAR_START),
    "lwr": (LWR, WALL_TASK, LWR_RNS, LWR_START),
}


def _state(name: str, seed: int = 0, speed: float = 0.5):
    robot, task, rns, q0 = CASES[name]
    rng = np.random.default_rng(seed)
    state = FixedBaseState.compute(robot, q0, speed * rng.standard_normal(robot.n))
    return state, task, rns, rng.standard_normal(task.m), np.array([7.0])


def _free_arm_acceleration(state, torque):
    """theta_ddot of the free arm (no contact force) under ``torque``, from M directly."""
    return np.linalg.solve(state.mass_matrix, torque - state.coriolis - state.gravity)


# ----------------------------------------------------------------------------- task space, loops


def test_task_space_selection_matrices():
    assert np.allclose(PLANAR_TASK.force_selection, np.diag([1.0, 0.0]))
    assert np.allclose(PLANAR_TASK.selection, np.diag([0.0, 1.0]))  # S = t t^T, t = +y
    assert np.allclose(WALL_TASK.selection, np.diag([1, 1, 0, 1, 1, 1]))
    frame = contact_frame([1.0, 1.0, 0.0])
    assert np.allclose(frame.T @ frame, np.eye(3))
    assert np.isclose(np.linalg.det(frame), 1.0)
    assert np.allclose(frame[:, 2], np.array([1, 1, 0]) / np.sqrt(2))
    assert abs(frame[2, 0]) < 1e-12  # planar default tangent stays in x-y
    free = TaskSpace.free(PLANAR_ROWS)
    assert free.k == 0
    assert np.allclose(free.selection, np.eye(2))


def test_outer_loops_6_33_and_6_34():
    gains = MotionGains()
    assert (gains.k_p, gains.k_d) == (100.0, 10.0)
    out = motion_loop(gains, [1.0, 0.0], [0.5, 0.0], [0.4, 0.1], [0.01, -0.02])
    assert np.allclose(out, [1.0 + 10 * 0.1 + 100 * 0.01, 10 * -0.1 + 100 * -0.02])
    assert np.allclose(force_loop(ForceGains(), [10.0], [8.0]), [20.0])  # 10 + 5 (10 - 8)


def test_pose_error_orientation_rows():
    state, *_ = _state("lwr")
    rotation = pin.exp3(np.array([0.0, 0.0, 0.1])) @ state.ee_rotation
    error = WALL_TASK.pose_error(state, state.ee_position + np.array([0.01, 0, 0]), rotation)
    assert np.allclose(error, [0.01, 0, 0, 0, 0, 0.1])
    with pytest.raises(InputError, match="rotation"):
        WALL_TASK.pose_error(state, state.ee_position)


# ------------------------------------------------------------------------------------------ OS-C


@pytest.mark.parametrize("name", sorted(CASES))
def test_operational_space_quantities_match_definitions(name):
    state, task, *_ = _state(name, seed=1)
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
    state, task, _, a_ref, f_ref = _state(name, seed=2)
    jac = task.jacobian(state)
    free = os_control(state, task, a_ref, variant=variant)
    accel = _free_arm_acceleration(state, free.torque)
    assert np.allclose(accel, free.joint_acceleration, atol=1e-9)
    assert np.allclose(jac @ accel + task.drift(state), task.selection @ a_ref, atol=1e-9)
    pushing = os_control(state, task, a_ref, f_ref, variant=variant)
    # the force reference enters as +J^T n f_ref
    assert np.allclose(pushing.torque - free.torque, jac.T @ task.force_basis @ f_ref)
    assert free.method == f"os-c/{OscVariant.parse(variant).value}"


def test_os_literal_and_kinematic_differ_by_null_space_coriolis():
    state, task, _, a_ref, _ = _state("planar", seed=3, speed=2.0)
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
    state, task, _, a_ref, _ = _state("lwr", seed=4)
    base = os_control(state, task, a_ref)
    extra = os_control(state, task, a_ref, null_space_torque=np.arange(7.0))
    jac = task.jacobian(state)
    assert not np.allclose(base.torque, extra.torque)
    assert np.allclose(jac @ extra.joint_acceleration, jac @ base.joint_acceleration, atol=1e-9)


# ------------------------------------------------------------------------ reversed control model


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
    state, *_ = _state("lwr", seed=5)
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
    state, task, *_ = _state(name, seed=12)
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
    real = _free_arm_acceleration(state, torque)
    assert np.allclose(accel[6:], real, atol=1e-6)
    assert np.allclose(accel[:6], state.jacobian @ real + state.jacobian_dot_v, atol=1e-6)


def test_control_model_coriolis_power_identity():
    """q_hat_dot^T c_hat = 1/2 q_hat_dot^T M_hat_dot q_hat_dot (M_hat_dot by central difference)."""
    state, _, rns, *_ = _state("lwr", seed=13)
    dyn = rns.dynamics(state)
    step = 1e-6
    mass_dot = (
        rns.evaluate(state.q + step * state.v).mass - rns.evaluate(state.q - step * state.v).mass
    ) / (2 * step)
    power = 0.5 * dyn.velocity @ mass_dot @ dyn.velocity
    assert np.isclose(dyn.velocity @ dyn.bias, power, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize(("virtual_mass", "contraction"), [(100.0, 0.3), (1e5, 1e-3)])
@pytest.mark.parametrize("name", sorted(CASES))
def test_literal_rns_loop_converges_to_closed_form(name, virtual_mass, contraction):
    """[A-4.3]: (6.22)+(6.17) with tau from the previous step converges to the closed form; the
    error shrinks by about 1/m_hat per step."""
    state, task, _, a_ref, f_ref = _state(name, seed=14)
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


# ------------------------------------------------------------------------------------------ RNS-C


def _check_rns(state, task, rns, a_ref, f_ref):
    command = rns_control(state, task, rns, a_ref, f_ref)
    jac, w = task.jacobian(state), rns.w(state.q)
    accel = command.joint_acceleration
    achieved = jac @ accel + task.drift(state)
    scale = 1.0 + np.abs(a_ref).max() + np.abs(task.drift(state)).max()
    assert np.allclose(achieved, task.selection @ a_ref, atol=1e-9 * scale)
    assert np.linalg.norm(kernel_projector(w) @ accel) <= 1e-9 * (1 + np.linalg.norm(accel))
    torque = command.torque - jac.T @ task.force_wrench(f_ref)
    assert np.allclose(_free_arm_acceleration(state, torque), accel, atol=1e-8 * scale)
    return command


@pytest.mark.parametrize("name", sorted(CASES))
def test_rns_closed_form_meets_task_in_row_space_of_w(name):
    command = _check_rns(*_state(name, seed=6))
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


@pytest.mark.parametrize("name", sorted(CASES))
def test_rns_tends_to_resolved_acceleration_as_one_over_virtual_mass(name):
    """Spec 4.6: RNS-C -> J^+ (7.2) as m_hat -> inf, the difference proportional to 1/m_hat."""
    state, task, _, a_ref, _ = _state(name, seed=7)
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


def test_resolved_acceleration_is_minimum_norm():
    state, task, _, a_ref, _ = _state("lwr", seed=8)
    command = resolved_acceleration(state, task, a_ref)
    jac = task.jacobian(state)
    rhs = task.selection @ a_ref - task.drift(state)
    assert np.allclose(command.joint_acceleration, np.linalg.pinv(jac) @ rhs)
    extra = resolved_acceleration(state, task, a_ref, null_space_acceleration=np.ones(7))
    assert np.allclose(jac @ extra.joint_acceleration, rhs, atol=1e-9)


# -------------------------------------------------------------------- projectors and chapter 7


@pytest.mark.parametrize("name", sorted(CASES))
def test_rns_projector_is_orthogonal_projector_onto_kernel_of_w(name):
    state, task, rns, *_ = _state(name, seed=9)
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
    state, task, rns, *_ = _state("lwr", seed=10)
    term = velocity_level_term(state, task, rns, form=form)
    w = rns.w(state.q)
    assert np.allclose(kernel_projector(w) @ term, term, atol=1e-9 * (1 + np.abs(term).max()))
    assert np.linalg.norm(term) > 0.0


def test_w_rate_finite_difference_is_consistent():
    state, _, rns, *_ = _state("lwr", seed=11)
    fine, coarse = rns.w_rate(state.q, state.v, 1e-6), rns.w_rate(state.q, state.v, 1e-4)
    assert np.allclose(fine, coarse, rtol=1e-5, atol=1e-6 * np.abs(fine).max())


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


# -------------------------------------------------------------------------------------- errors


@pytest.mark.parametrize(
    ("build", "error", "match"),
    [
        (lambda: MotionGains(k_p=-1.0), ConfigError, r"k_p .*1/s\^2.*-1"),
        (lambda: MotionGains(k_d=float("nan")), ConfigError, r"k_d .*nan"),
        (lambda: ForceGains(k_f=-0.5), ConfigError, r"k_f .*>= 0.*-0.5"),
        (lambda: damper_term([1.0], gain=0.0), ConfigError, r"k_d .*> 0.*0.0"),
        (lambda: ReversedModel(PLANAR, PLANAR_ROWS, virtual_mass=0.0), ConfigError, r"m_hat.*0.0"),
        (
            lambda: ReversedModel(PLANAR, PLANAR_ROWS, virtual_inertia=-np.eye(3)),
            ConfigError,
            "positive definite",
        ),
        (lambda: TaskSpace.free((0, 0)), ConfigError, r"distinct indices in 0\.\.5"),
        (lambda: TaskSpace.free((0, 6)), ConfigError, r"0\.\.5.*6"),
        (lambda: TaskSpace.from_contact(PLANAR_ROWS, [0, 1, 1]), ConfigError, r"\['z'\]"),
        (lambda: contact_frame([0.0, 0.0, 0.0]), InputError, "non-zero"),
        (lambda: OscVariant.parse("inverse"), ConfigError, r"literal.*kinematic.*inverse"),
        (lambda: TaskSpace.free(FULL_ROWS).check(PLANAR), ConfigError, "6 task rows exceed"),
    ],
)
def test_bad_parameters_raise_typed_errors(build, error, match):
    with pytest.raises(error, match=match):
        build()


def test_bad_references_raise_typed_errors():
    state, task, rns, *_ = _state("planar")
    with pytest.raises(InputError, match=r"shape \(2,\)"):
        rns_control(state, task, rns, [0.0, 0.0, 0.0])
    with pytest.raises(InputError, match=r"force_ref .*finite"):
        os_control(state, task, [0.0, 0.0], [float("inf")])
    with pytest.raises(ConfigError, match="rows"):
        rns_control(state, task, LWR_RNS, [0.0, 0.0])
    with pytest.raises(InputError, match=r"W must be finite with shape \(2, 3\)"):
        rns_control(state, task, rns, [0.0, 0.0], w=np.zeros((3, 3)))
    with pytest.raises(InputError, match="theta_dot must be a vector"):
        damper_term(np.zeros((2, 2)))
    with pytest.raises(InputError, match="pose_error"):
        motion_loop(MotionGains(), [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0])


def test_non_serial_or_misplaced_ee_model_is_rejected():
    model = PLANAR.model
    robot = type(PLANAR)(model.copy(), "link_2")  # EE frame on link 2, not the last link
    with pytest.raises(ModelError, match="last link"):
        ReversedModel(robot, PLANAR_ROWS)


def test_docs_example_runs(monkeypatch, capsys):
    """The python block of docs/part2_controllers.md runs as written (from the repository root)."""
    text = (CONFIG.parent / "docs" / "part2_controllers.md").read_text()
    block = text.split("```python\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(CONFIG.parent)
    exec(compile(block, "part2_controllers.md", "exec"), {})  # our own documentation
    assert "NullSpaceVelocity" in capsys.readouterr().out
