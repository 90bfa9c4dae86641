"""The output record of every motion/force law and the real computed torque."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rns_ros.control.motion_force.task_space import TaskSpace
from rns_ros.core.fixed_base import FixedBaseState


@dataclass(frozen=True)
class ControlCommand:
    """One controller output.

    Attributes:
        torque: tau [N m], (n,).
        joint_acceleration: theta_ddot the torque gives the FREE arm (no contact force), i.e.
            M^-1 (tau - J^T F_kappa^ref - c - g) [rad/s^2], (n,).
        task_acceleration: V_dot_ref used (S nu_dot_ref + N a_n), task coordinates, (m,).
        force_wrench: J^T is applied to this task-space force F_kappa^ref = N f_ref [N], (m,).
        method: "os-c/literal", "os-c/kinematic", "rns-c/closed-form" or "resolved/J+".
        sigma_min: smallest singular value of the matrix solved (J W^T for RNS-C, J M^-1 J^T
            for OS-C, J for J^+); compare with sigma_max.
        sigma_max: largest singular value of that matrix.
    """

    torque: np.ndarray
    joint_acceleration: np.ndarray
    task_acceleration: np.ndarray
    force_wrench: np.ndarray
    method: str
    sigma_min: float
    sigma_max: float


def computed_torque(state: FixedBaseState, task: TaskSpace, accel, force_ref):
    """(tau, N f_ref): tau = M theta_ddot + c + g + J^T N f_ref [N m] (n,) for the joint
    acceleration ``accel`` (n,) and f_ref [N] (k,) (None: 0)."""
    wrench = task.force_wrench(np.zeros(task.k) if force_ref is None else force_ref)
    torque = (
        state.mass_matrix @ accel + state.coriolis + state.gravity + task.jacobian(state).T @ wrench
    )
    return torque, wrench


__all__ = ["ControlCommand", "computed_torque"]
