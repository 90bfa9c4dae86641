"""RNS-C, the Reaction Null-Space motion/force law of section 6.1.2: closed form and as printed."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rns_ros.control.motion_force.command import ControlCommand, computed_torque
from rns_ros.control.motion_force.projectors import DEFAULT_RCOND, kernel_projector, svd_solve
from rns_ros.control.motion_force.reversed_model import ReversedModel, reduce_to_rows
from rns_ros.control.motion_force.task_space import TaskSpace
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.fixed_base import FixedBaseState
from rns_ros.core.validation import as_vector


def rns_control(
    state: FixedBaseState,
    task: TaskSpace,
    reversed_model: ReversedModel,
    acceleration_ref,
    force_ref=None,
    *,
    normal_acceleration=None,
    null_space_acceleration=None,
    w=None,
    rcond: float = DEFAULT_RCOND,
) -> ControlCommand:
    """RNS-C, closed form of (6.17) with the exact constraint force (6.22) (thesis_rest 4.2):

    theta_ddot = W^T (J W^T)^-1 (V_dot_ref - J_dot theta_dot) + O P_hat_RNS theta_ddot_a,
    O = E - W^T (J W^T)^-1 J,

    the unique acceleration in the row space of W (+ the null-space term) that meets the real
    task kinematics J theta_ddot + J_dot theta_dot = V_dot_ref; then the real computed torque
    tau = M theta_ddot + c + g + J^T N f_ref (equivalent to (6.18) mapped back by (6.29)).

    The null-space term follows (7.3): P_hat_RNS theta_ddot_a is the free part; the oblique
    projector O (onto ker J along row W) stands for the constraint force that keeps the task
    exact. Pass :func:`velocity_level_term` (7.13) or :func:`damper_term` as theta_ddot_a.
    ``sigma_min``/``sigma_max`` of the result are those of J W^T (watch sigma_min near
    singularities; it scales with m_hat).

    Args:
        reversed_model: built with the same rows as ``task``.
        w: W at state.q if already computed (else evaluated here).
    """
    if reversed_model.rows != task.rows:
        raise ConfigError(
            f"reversed model rows {reversed_model.rows} differ from task rows {task.rows}"
        )
    task_accel = task.compose(acceleration_ref, normal_acceleration)
    jac = task.jacobian(state)
    w = reversed_model.w(state.q) if w is None else np.asarray(w, dtype=float)
    if w.shape != (task.m, state.n) or not np.isfinite(w).all():
        raise InputError(f"W must be finite with shape ({task.m}, {state.n}), got {w.shape}")
    jwt = jac @ w.T
    y, s_min, s_max = svd_solve(jwt, task_accel - task.drift(state), rcond)
    accel = w.T @ y
    if null_space_acceleration is not None:
        extra = kernel_projector(w, rcond) @ as_vector(
            null_space_acceleration, state.n, "null_space_acceleration"
        )
        accel = accel + extra - w.T @ svd_solve(jwt, jac @ extra, rcond)[0]
    torque, wrench = computed_torque(state, task, accel, force_ref)
    return ControlCommand(torque, accel, task_accel, wrench, "rns-c/closed-form", s_min, s_max)


@dataclass(frozen=True)
class LiteralRnsStep:
    """One step of the literal RNS-C loop (6.22) + (6.17) + (6.18).

    Attributes:
        command: the :class:`ControlCommand` (method "rns-c/literal"); joint_acceleration is the
            theta_ddot_ref of (6.17), torque the tau of (6.18) for the next step.
        constraint_force: F_B of (6.22), B's wrench at the world origin [N, N m], (6,).
    """

    command: ControlCommand
    constraint_force: np.ndarray


def rns_literal_step(
    state: FixedBaseState,
    task: TaskSpace,
    reversed_model: ReversedModel,
    acceleration_ref,
    force_ref=None,
    *,
    previous_torque,
    normal_acceleration=None,
    momentum_approximation: bool = False,
    rcond: float = DEFAULT_RCOND,
) -> LiteralRnsStep:
    """RNS-C as printed ([A-4.3]): the algebraic loop broken by the previous step's torque.

    1. F_B of (6.22) with Q_hat = [F_A; tau_prev], F_A = -N f_ref the contact reaction on A.
    2. theta_ddot_ref of (6.17) (constraint force substituted, non-task root rows eliminated as
       in (6.24)-(6.25)): theta_ddot = W^+ (r_red - M_red V_dot_ref), r = F_A + T_hat F_B - c_A
       - g_A on the root rows (exact C_A, not the momentum approximation).
    3. tau of (6.16)/(6.18): M_Al^T V_dot_A + M_l theta_ddot + c_l + g_l - J_B^T F_B.

    The fixed point of tau_prev -> tau is the closed form of :func:`rns_control` (tested).
    ``momentum_approximation``: C_hat_A ~ M_hat_A_dot V_A + M_hat_Al_dot theta_dot instead of the
    exact C_hat_A (:meth:`ReversedModel.dynamics`), the variant section 6.1.2 rules out.
    """
    if reversed_model.rows != task.rows:
        raise ConfigError(
            f"reversed model rows {reversed_model.rows} differ from task rows {task.rows}"
        )
    n = state.n
    previous_torque = as_vector(previous_torque, n, "previous_torque")
    task_accel = task.compose(acceleration_ref, normal_acceleration)
    wrench = task.force_wrench(np.zeros(task.k) if force_ref is None else force_ref)
    dyn = reversed_model.dynamics(state, momentum_approximation=momentum_approximation)
    rows, free = list(task.rows), list(reversed_model.free_rows)
    root_force = np.zeros(6)
    root_force[rows] = -wrench  # the environment's reaction on A
    generalized = np.concatenate([root_force, previous_torque])
    nonlinear = dyn.bias + dyn.gravity
    jc = dyn.constraint
    m_inv = np.linalg.solve(dyn.mass, np.column_stack([jc.T, nonlinear - generalized]))
    f_b = np.linalg.solve(jc @ m_inv[:, :6], jc @ m_inv[:, 6] - dyn.constraint_drift)  # (6.22)
    residual = root_force + jc[:, :6].T @ f_b - nonlinear[:6]
    reduced_residual, reduced_mass, w = reduce_to_rows(dyn.mass, residual, rows, free)
    root, coupling = dyn.mass[:6, :6], dyn.mass[:6, 6:]
    accel = np.linalg.lstsq(w, reduced_residual - reduced_mass @ task_accel, rcond=rcond)[0]
    root_accel = np.zeros(6)
    root_accel[rows] = task_accel
    if free:
        root_accel[free] = np.linalg.solve(
            root[np.ix_(free, free)],
            residual[free] - root[np.ix_(free, rows)] @ task_accel - coupling[free] @ accel,
        )
    torque = coupling.T @ root_accel + dyn.mass[6:, 6:] @ accel + nonlinear[6:] - jc[:, 6:].T @ f_b
    sigma = np.linalg.svd(w, compute_uv=False)
    command = ControlCommand(
        torque, accel, task_accel, wrench, "rns-c/literal", sigma[-1], sigma[0]
    )
    return LiteralRnsStep(command, f_b)


__all__ = ["LiteralRnsStep", "rns_control", "rns_literal_step"]
