"""Kinematic free-floating integration: joints follow theta_dot(t, q), the base follows momentum.

This is the resolved-rate setting of thesis chapter 4: the joint velocities are prescribed and the
base twist follows from momentum conservation, V_b = M_b^-1 (L_B - M_bm theta_dot) (eq. 2.33).
The step is classical RK4 written on the configuration manifold in Runge-Kutta-Munthe-Kaas form:
each stage velocity is pulled back to the tangent space at the step start through the inverse of
``pin.dIntegrate`` (the dexp^-1 correction), so the scheme keeps fourth order on the SE(3) base and
the quaternion stays unit by construction (``pin.integrate``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin

from rns_ros.core.conventions import pinocchio_velocity
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.momentum import base_twist_from_momentum, shift_momentum
from rns_ros.core.state import FreeFloatingState

#: theta_dot = joint_velocity(t [s], state) [rad/s], shape (n,).
JointVelocityFunction = Callable[[float, FreeFloatingState], np.ndarray]

_ORIGIN = np.zeros(3)


def free_floating_velocity(
    state: FreeFloatingState, theta_dot: np.ndarray, momentum_world: np.ndarray | None = None
) -> np.ndarray:
    """Pinocchio generalized velocity v (6 + n,) of the free-floating robot.

    Args:
        state: current state.
        theta_dot: joint velocities [rad/s], shape (n,).
        momentum_world: conserved spatial momentum [p; l_O] about the world origin, world axes,
            shape (6,); None means zero.
    """
    momentum = None
    if momentum_world is not None:
        momentum = shift_momentum(momentum_world, _ORIGIN, state.base_position)
    base_twist = base_twist_from_momentum(state, theta_dot, momentum)
    return pinocchio_velocity(state.base_rotation, base_twist, theta_dot)


def rk4_step(
    robot: FreeFloatingModel,
    q: np.ndarray,
    t: float,
    dt: float,
    joint_velocity: JointVelocityFunction,
    momentum_world: np.ndarray | None = None,
) -> np.ndarray:
    """One RK4 (Munthe-Kaas) step of the kinematic free-floating system; returns q(t + dt)."""
    model = robot.model

    def stage_velocity(increment: np.ndarray, time: float) -> np.ndarray:
        q_stage = pin.integrate(model, q, increment)
        state = FreeFloatingState.compute(robot, q_stage)
        v = free_floating_velocity(state, joint_velocity(time, state), momentum_world)
        if not increment.any():
            return v
        # Pull the stage velocity back to the tangent space at q (dexp^-1 of RKMK).
        jacobian = pin.dIntegrate(model, q, increment, pin.ArgumentPosition.ARG1)
        return np.linalg.solve(jacobian, v)

    k1 = stage_velocity(np.zeros(model.nv), t)
    k2 = stage_velocity(0.5 * dt * k1, t + 0.5 * dt)
    k3 = stage_velocity(0.5 * dt * k2, t + 0.5 * dt)
    k4 = stage_velocity(dt * k3, t + dt)
    return pin.integrate(model, q, dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4))


def attitude_deviation(rotation_initial: np.ndarray, rotation: np.ndarray) -> float:
    """Angle of R_0^T R [rad]: how far the base attitude has turned from its initial value."""
    return float(np.linalg.norm(pin.log3(rotation_initial.T @ rotation)))
