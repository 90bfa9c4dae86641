"""Chapter 7: resolved acceleration (7.2), the free-floating RNS particular solution (7.4),
null-space velocities (7.14), the velocity-level term (7.13) and the joint damper of section
7.2.2."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rns_ros.control.motion_force.command import ControlCommand, computed_torque
from rns_ros.control.motion_force.outer_loops import parse_gain
from rns_ros.control.motion_force.projectors import DEFAULT_RCOND, kernel_projector, svd_solve
from rns_ros.control.motion_force.reversed_model import ReversedModel, reduce_to_rows
from rns_ros.control.motion_force.task_space import TaskSpace
from rns_ros.core.errors import InputError
from rns_ros.core.fixed_base import FixedBaseState
from rns_ros.core.validation import Choice, as_vector

#: Damper gain of section 7.2.2 [1/s] (stable with RK4 at 1 ms; scale as 2.77 / step).
DEFAULT_DAMPER_GAIN = 2770.0


@dataclass(frozen=True)
class NullSpaceVelocity:
    """Null-space velocity measures of (7.14) [A-4.14] [rad/s].

    Attributes:
        rns: ||P_hat_RNS theta_dot|| (P_hat_RNS onto ker W). jacobian: ||P_J theta_dot||.
    """

    rns: float
    jacobian: float


def null_space_velocity(
    state: FixedBaseState, task: TaskSpace, w, rcond: float = DEFAULT_RCOND
) -> NullSpaceVelocity:
    """||P_hat_RNS theta_dot|| and ||P_J theta_dot|| at ``state`` (W from ReversedModel.w)."""
    return NullSpaceVelocity(
        float(np.linalg.norm(kernel_projector(w, rcond) @ state.v)),
        float(np.linalg.norm(kernel_projector(task.jacobian(state), rcond) @ state.v)),
    )


def resolved_acceleration(
    state: FixedBaseState,
    task: TaskSpace,
    acceleration_ref,
    force_ref=None,
    *,
    normal_acceleration=None,
    null_space_acceleration=None,
    rcond: float = DEFAULT_RCOND,
) -> ControlCommand:
    """Resolved acceleration, eq. (7.2): theta_ddot = J^+ (V_dot_ref - J_dot theta_dot)
    + P_J theta_ddot_a (minimum acceleration norm for theta_ddot_a = 0), then the real computed
    torque tau = M theta_ddot + c + g + J^T N f_ref. J^+ via least squares (SVD)."""
    task_accel = task.compose(acceleration_ref, normal_acceleration)
    jac = task.jacobian(state)
    rhs = task_accel - task.drift(state)
    accel = np.linalg.lstsq(jac, rhs, rcond=rcond)[0]
    if null_space_acceleration is not None:
        extra = as_vector(null_space_acceleration, state.n, "null_space_acceleration")
        accel = accel + kernel_projector(jac, rcond) @ extra
    torque, wrench = computed_torque(state, task, accel, force_ref)
    sigma = np.linalg.svd(jac, compute_uv=False)
    return ControlCommand(torque, accel, task_accel, wrench, "resolved/J+", sigma[-1], sigma[0])


def free_floating_acceleration(
    state: FixedBaseState,
    task: TaskSpace,
    reversed_model: ReversedModel,
    acceleration_ref,
    *,
    normal_acceleration=None,
    rcond: float = DEFAULT_RCOND,
) -> ControlCommand:
    """The particular solution of Q_M_Al, eq. (7.4) with theta_ddot_a = 0 (thesis_rest A-4.15
    variant (b)): theta_ddot = -M_hat_Al^+ (M_hat_A V_dot_A + C_hat_A) [rad/s^2], (n,).

    The constraint-force term M_hat_Al^+ T_hat F_B of (7.3) is left out: the control model is
    free floating (B not held), so theta_ddot keeps the control model's root rows with no
    external wrench, M_red V_dot_A + W theta_ddot + C_red = 0, with V_dot_A = the task rows of
    V_dot_ref and the non-task root coordinates eliminated as in (6.24)-(6.25). It meets the REAL
    task kinematics J theta_ddot + J_dot theta_dot = V_dot_ref only as m_hat -> inf ((7.5)-(7.6):
    B's velocity ~ 1/m_hat); C_hat_A is the control model's at the real state
    (:meth:`ReversedModel.dynamics`). (7.4) is written for zero gravity and G_hat_A is left out:
    unheld, B's weight m_hat g would pull the model away at any m_hat. Then the real computed
    torque tau = M theta_ddot + c + g. ``sigma_min``/``sigma_max`` are those of W.
    """
    task_accel = task.compose(acceleration_ref, normal_acceleration)
    dyn = reversed_model.dynamics(state)
    rows, free = list(reversed_model.rows), list(reversed_model.free_rows)
    residual = -dyn.bias[:6]  # no F_A (no interaction), no F_B, no G_hat_A (zero gravity)
    reduced_residual, reduced_mass, w = reduce_to_rows(dyn.mass, residual, rows, free)
    accel, s_min, s_max = _min_norm(w, reduced_residual - reduced_mass @ task_accel, rcond)
    torque, wrench = computed_torque(state, task, accel, None)
    return ControlCommand(torque, accel, task_accel, wrench, "rns/free-floating", s_min, s_max)


def _min_norm(matrix: np.ndarray, rhs: np.ndarray, rcond: float):
    """(x, sigma_min, sigma_max): the minimum-norm least-squares x of matrix x = rhs (SVD)."""
    x, _, _, sigma = np.linalg.lstsq(matrix, rhs, rcond=rcond)
    return x, float(sigma[-1]), float(sigma[0])


class VelocityTermForm(Choice):
    """Forms of (7.13): ``momentum`` = -P Wdot^T (W W^T)^-1 M_red V_A with V_A = J theta_dot
    (the printed form); ``velocity`` = +P Wdot^T W^{+T} theta_dot (equal under the zero-momentum
    condition (7.9); exact for keeping P_hat_RNS theta_dot = 0 on the real arm)."""

    __label__ = "velocity-level term form"
    MOMENTUM = "momentum"
    VELOCITY = "velocity"


def velocity_level_term(
    state: FixedBaseState,
    task: TaskSpace,
    reversed_model: ReversedModel,
    *,
    form: VelocityTermForm | str = VelocityTermForm.VELOCITY,
    step: float = 1e-6,
    rcond: float = DEFAULT_RCOND,
) -> np.ndarray:
    """theta_ddot_add of eq. (7.13) [rad/s^2], (n,), in ker W.

    W_dot by a central difference along theta_dot (``step`` [s], :meth:`ReversedModel.w_rate`).
    """
    form = VelocityTermForm.parse(form)
    quantities = reversed_model.evaluate(state.q)
    w = quantities.w
    w_dot = reversed_model.w_rate(state.q, state.v, step)
    if form is VelocityTermForm.MOMENTUM:
        momentum = quantities.reduced_mass @ task.velocity(state)  # M_hat_A V_hat_A, reduced
        y = -svd_solve(w @ w.T, momentum, rcond)[0]
    else:
        y = svd_solve(w @ w.T, w @ state.v, rcond)[0]  # W^{+T} theta_dot = (W W^T)^-1 W th_dot
    return kernel_projector(w, rcond) @ (w_dot.T @ y)


def damper_term(v, gain: float = DEFAULT_DAMPER_GAIN) -> np.ndarray:
    """theta_ddot_a = -k_d theta_dot (section 7.2.2), k_d = ``gain`` [1/s] > 0 (2770 at RK4,
    1 ms; the RK4 limit is about 2.785 / step)."""
    gain = parse_gain(gain, "damper gain k_d", "[1/s]")
    v = np.asarray(v, dtype=float)
    if v.ndim != 1:
        raise InputError(f"theta_dot must be a vector, got shape {v.shape}")
    return -gain * as_vector(v, v.shape[0], "theta_dot")


__all__ = [
    "DEFAULT_DAMPER_GAIN",
    "NullSpaceVelocity",
    "VelocityTermForm",
    "damper_term",
    "free_floating_acceleration",
    "null_space_velocity",
    "resolved_acceleration",
    "velocity_level_term",
]
