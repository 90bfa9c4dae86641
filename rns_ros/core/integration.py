"""Free-floating velocity and attitude helpers shared by the simulator, demo and tests.

The fixed-step integrator itself lives in :mod:`rns_ros.sim.free_floating`.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from rns_ros.core.conventions import pinocchio_velocity
from rns_ros.core.momentum import base_twist_from_momentum, shift_momentum
from rns_ros.core.state import FreeFloatingState

_ORIGIN = np.zeros(3)


def free_floating_velocity(
    state: FreeFloatingState, theta_dot: np.ndarray, momentum_world: np.ndarray | None = None
) -> np.ndarray:
    """Pinocchio generalized velocity v (6 + n,) of the free-floating robot, eq. (2.33).

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


def attitude_deviation(rotation_initial: np.ndarray, rotation: np.ndarray) -> float:
    """Angle of R_0^T R [rad]: how far the base attitude has turned from its initial value."""
    return float(np.linalg.norm(pin.log3(rotation_initial.T @ rotation)))
