"""The rigid-contact force model of the force loop: lambda(tau) affine in the joint torque."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rns_ros.core.errors import InputError
from rns_ros.core.fixed_base import FixedBaseState


@dataclass(frozen=True)
class RigidContactModel:
    """The normal force of a rigid contact along n as an affine function of the joint torque.

    With the constraint n^T p_ddot = a_c (a_c torque-independent: curvature, stabilization),
    (C.1)-(C.2) of ``rns_ros.sim.contact`` give

        lambda(tau) = Lambda_n (n^T J_v M^-1 (tau - c - g) + n^T (J_dot v)_lin) + beta,
        Lambda_n = 1 / (n^T J_v M^-1 J_v^T n)  [kg],

    with beta torque-independent. lambda(tau + J_v^T n f) = lambda(tau) + f.

    Attributes:
        push: J_v^T n (n,) [m] (the torque per newton of f_ref).
        mobility: M^-1 J_v^T n (n,). inertia: Lambda_n [kg]. bias: c + g (n,) [N m].
        drift: n^T (J_dot v)_lin [m/s^2].
    """

    push: np.ndarray
    mobility: np.ndarray
    inertia: float
    bias: np.ndarray
    drift: float

    @classmethod
    def at(cls, state: FixedBaseState, normal) -> RigidContactModel:
        """The model at ``state`` along the unit ``normal`` (3,), world axes.

        Raises:
            InputError: the EE cannot move along n (n^T J_v M^-1 J_v^T n = 0).
        """
        n = np.asarray(normal, dtype=float)
        push = state.jacobian[:3].T @ n
        mobility = np.linalg.solve(state.mass_matrix, push)
        schur = float(push @ mobility)
        if not schur > 0.0:
            raise InputError(f"the end effector cannot move along the normal {n.tolist()}")
        return cls(
            push,
            mobility,
            1.0 / schur,
            state.coriolis + state.gravity,
            float(n @ state.jacobian_dot_v[:3]),
        )

    def force(self, torque) -> float:
        """lambda(tau) - beta [N] for the torque tau (n,) [N m]."""
        return self.inertia * (float(self.mobility @ (torque - self.bias)) + self.drift)


def predicted_contact_force(state: FixedBaseState, normal, torque, bias: float = 0.0) -> float:
    """lambda(tau) [N] of :class:`RigidContactModel` with the torque-independent part ``bias``."""
    return RigidContactModel.at(state, normal).force(np.asarray(torque, dtype=float)) + bias


def force_reference(f_des: float, lambda_0: float, k_f: float) -> float:
    """f_ref of (6.34) solved at the same instant: f = lambda_0 + f_ref gives
    f_ref = (f_des + k_f (f_des - lambda_0)) / (1 + k_f) [N] (then f - f_des = lambda_0/(1+k_f))."""
    return (f_des + k_f * (f_des - lambda_0)) / (1.0 + k_f)


def normal_acceleration(curvature: float, normal, ee_velocity) -> float:
    """a_n = curvature |v_t|^2 [m/s^2]: the normal acceleration that keeps the EE on a surface
    bending toward the environment with ``curvature`` [1/m], v_t = the EE velocity (3,) [m/s]
    tangent to the surface (world). Equals -kappa of ``ArcConstraint.curvature`` for motion
    across a cylinder of radius 1/curvature."""
    v = np.asarray(ee_velocity, dtype=float)
    n = np.asarray(normal, dtype=float)
    tangential = v - (n @ v) * n
    return float(curvature * (tangential @ tangential))


__all__ = [
    "RigidContactModel",
    "force_reference",
    "normal_acceleration",
    "predicted_contact_force",
]
