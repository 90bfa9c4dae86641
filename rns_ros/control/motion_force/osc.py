"""OS-C: the operational-space motion/force controller, thesis section 6.1.1, (6.6)-(6.13)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rns_ros.control.motion_force.command import ControlCommand
from rns_ros.control.motion_force.projectors import DEFAULT_RCOND
from rns_ros.control.motion_force.task_space import TaskSpace
from rns_ros.core.errors import InputError
from rns_ros.core.fixed_base import FixedBaseState
from rns_ros.core.validation import Choice, as_vector


class OscVariant(Choice):
    """OS-C variants ([A-4.2]): ``literal`` = (6.13) at torque level with tau_a = 0;
    ``kinematic`` = theta_ddot = J^{M+} a', then computed torque."""

    __label__ = "OS-C variant"
    LITERAL = "literal"
    KINEMATIC = "kinematic"


@dataclass(frozen=True)
class OperationalSpace:
    """Operational-space quantities of eq. (6.6)-(6.8) in task coordinates.

    Attributes:
        mass: M_e = (J M^-1 J^T)^-1 [kg | kg m^2], (m, m), eq. (6.6).
        inverse: J^{M+} = M^-1 J^T M_e, the inertia-weighted generalized inverse, (n, m).
        coriolis: C_e = J^{M+T} c - M_e J_dot theta_dot, (m,), eq. (6.7).
        gravity: G_e = J^{M+T} g, (m,), eq. (6.8).
    """

    mass: np.ndarray
    inverse: np.ndarray
    coriolis: np.ndarray
    gravity: np.ndarray


def operational_space(state: FixedBaseState, task: TaskSpace) -> OperationalSpace:
    """M_e, J^{M+}, C_e, G_e of eq. (6.6)-(6.8) (solves with M, never inverts it).

    Raises:
        InputError: J M^-1 J^T is singular (a kinematic singularity of the task rows).
    """
    jac = task.jacobian(state)
    m_inv_jt = np.linalg.solve(state.mass_matrix, jac.T)  # M^-1 J^T, (n, m)
    lam = jac @ m_inv_jt
    lam = 0.5 * (lam + lam.T)
    sigma = np.linalg.svd(lam, compute_uv=False)
    if sigma[-1] <= DEFAULT_RCOND * sigma[0]:
        raise InputError(f"J M^-1 J^T is singular (sigma = {sigma.tolist()}): task singularity")
    mass = np.linalg.solve(lam, np.eye(task.m))
    mass = 0.5 * (mass + mass.T)
    inverse = m_inv_jt @ mass
    coriolis = inverse.T @ state.coriolis - mass @ task.drift(state)
    gravity = inverse.T @ state.gravity
    return OperationalSpace(mass, inverse, coriolis, gravity)


def os_control(
    state: FixedBaseState,
    task: TaskSpace,
    acceleration_ref,
    force_ref=None,
    *,
    variant: OscVariant | str = OscVariant.LITERAL,
    normal_acceleration=None,
    null_space_torque=None,
) -> ControlCommand:
    """The OS-C torque of eq. (6.10)-(6.13).

    F_m^ref = M_e S V_dot_ref + C_e + G_e (6.11), F_kappa^ref = S_perp F_c^ref = N f_ref (6.12),
    tau = J^T (F_m^ref + F_kappa^ref) + (E - J^T J^{M+T}) tau_a (6.13; the print's J^T J^{M+} is a
    transpose typo), tau_a = ``null_space_torque`` (default 0 as in every thesis experiment).

    ``kinematic`` instead applies theta_ddot = J^{M+} (S V_dot_ref - J_dot theta_dot) and
    tau = M theta_ddot + c + g + J^T N f_ref (null-space Coriolis compensated; tau_a ignored).

    Args:
        acceleration_ref: nu_dot_ref of (6.33), task coordinates (m,).
        force_ref: f_ref of (6.34) [N], (k,), force ON the environment [A-4.1]; default 0.
        normal_acceleration: a_n, see :meth:`TaskSpace.compose`.
    """
    variant = OscVariant.parse(variant)
    task_accel = task.compose(acceleration_ref, normal_acceleration)
    wrench = task.force_wrench(np.zeros(task.k) if force_ref is None else force_ref)
    os_ = operational_space(state, task)
    jac = task.jacobian(state)
    bias = state.coriolis + state.gravity
    if variant is OscVariant.LITERAL:
        motion_wrench = os_.mass @ task_accel + os_.coriolis + os_.gravity  # (6.11)
        torque = jac.T @ (motion_wrench + wrench)
        if null_space_torque is not None:
            tau_a = as_vector(null_space_torque, state.n, "null_space_torque")
            torque = torque + tau_a - jac.T @ (os_.inverse.T @ tau_a)
        accel = np.linalg.solve(state.mass_matrix, torque - jac.T @ wrench - bias)
    else:
        accel = os_.inverse @ (task_accel - task.drift(state))
        torque = state.mass_matrix @ accel + bias + jac.T @ wrench
    sigma = np.linalg.svd(np.linalg.solve(os_.mass, np.eye(task.m)), compute_uv=False)
    return ControlCommand(
        torque, accel, task_accel, wrench, f"os-c/{variant.value}", sigma[-1], sigma[0]
    )


__all__ = ["OperationalSpace", "OscVariant", "operational_space", "os_control"]
