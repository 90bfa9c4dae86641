"""Momentum conservation and the Reaction Null-Space (thesis chapter 2.2-2.3 and 3.1).

All functions take a :class:`~rns_ros.core.state.FreeFloatingState` computed once for the current
configuration. Twists and momenta are in world axes about the base frame origin (thesis convention).
"""

from __future__ import annotations

import numpy as np

from rns_ros.core.state import FrameKinematics, FreeFloatingState
from rns_ros.core.validation import as_vector


def spatial_momentum(state: FreeFloatingState, base_twist, theta_dot) -> np.ndarray:
    """L_B = M_b V_b + M_bm theta_dot, eq. (2.33).

    Args:
        base_twist: V_b = [v_b [m/s]; omega_b [rad/s]] in world axes, shape (6,).
        theta_dot: joint velocities [rad/s], shape (n,).

    Returns:
        [p [kg m/s]; l_B [kg m^2/s]], shape (6,): linear momentum and angular momentum about
        the base frame origin, world axes.
    """
    base_twist = as_vector(base_twist, 6, "base_twist")
    theta_dot = as_vector(theta_dot, state.n, "theta_dot")
    return state.inertia_base @ base_twist + state.coupling_inertia @ theta_dot


def base_twist_from_momentum(state: FreeFloatingState, theta_dot, momentum=None) -> np.ndarray:
    """Base twist that conserves the spatial momentum: V_b = M_b^-1 (L_B - M_bm theta_dot).

    Eq. (2.33) solved for V_b: this is how a free-floating base moves when the joints move.

    Args:
        theta_dot: joint velocities [rad/s], shape (n,).
        momentum: conserved L_B (world axes, about the base origin), shape (6,); default zero.

    Returns:
        V_b = [v_b [m/s]; omega_b [rad/s]], world axes, shape (6,).
    """
    theta_dot = as_vector(theta_dot, state.n, "theta_dot")
    rhs = -state.coupling_inertia @ theta_dot
    if momentum is not None:
        rhs = rhs + as_vector(momentum, 6, "momentum")
    return np.linalg.solve(state.inertia_base, rhs)


def coupling_angular_momentum(state: FreeFloatingState, theta_dot) -> np.ndarray:
    """Coupling angular momentum M~_omega_m theta_dot [kg m^2/s], shape (3,): eq. (3.2), (4.16).

    The base disturbance caused by a joint motion (linear momentum eliminated); zero for
    reactionless motion, eq. (3.4).
    """
    theta_dot = as_vector(theta_dot, state.n, "theta_dot")
    return state.coupling_angular_momentum_matrix @ theta_dot


def reactionless_joint_velocity(state: FreeFloatingState, theta_dot_arbitrary) -> np.ndarray:
    """theta_dot = P_RNS theta_dot_a, eq. (3.3): joint motion that leaves the base attitude alone.

    Args:
        theta_dot_arbitrary: any joint velocity theta_dot_a [rad/s], shape (n,).

    Returns:
        Its projection onto ker(M~_omega_m) [rad/s], shape (n,).
    """
    theta_dot_arbitrary = as_vector(theta_dot_arbitrary, state.n, "theta_dot_arbitrary")
    return state.reaction_null_space_projector @ theta_dot_arbitrary


def generalized_jacobian(state: FreeFloatingState, frame: FrameKinematics) -> np.ndarray:
    """Generalized Jacobian J* = J_m - J_b M_b^-1 M_bm of a frame, shape (6, n).

    With zero initial momentum the frame twist [v; omega] (world axes) is J* theta_dot: the
    fixed-base Jacobian corrected by the base motion that momentum conservation (2.33) imposes.
    """
    return frame.jacobian - frame.base_jacobian @ np.linalg.solve(
        state.inertia_base, state.coupling_inertia
    )


def shift_momentum(momentum, from_point, to_point) -> np.ndarray:
    """Re-express a spatial momentum [p; l] about another point: l' = l + (a - b) x p.

    Args:
        momentum: [p; l_a] with l_a about ``from_point`` a, world axes, shape (6,).
        from_point, to_point: a and b in world [m], shape (3,).

    Returns:
        [p; l_b], shape (6,). Linear momentum is unchanged.
    """
    momentum = as_vector(momentum, 6, "momentum")
    offset = as_vector(from_point, 3, "from_point") - as_vector(to_point, 3, "to_point")
    return np.concatenate((momentum[:3], momentum[3:] + np.cross(offset, momentum[:3])))
