"""Uniform scaling of a joint velocity to the joint speed and position limits.

Scaling the whole theta_dot by one factor keeps it in the reaction null space and keeps its
direction; clipping joints one by one would do neither.
"""

from __future__ import annotations

import numpy as np

from rns_ros.core.model import FreeFloatingModel


def uniform_speed_scale(theta_dot: np.ndarray, velocity_limits: np.ndarray) -> float:
    """Largest s in (0, 1] with |s theta_dot_i| <= limit_i for every joint."""
    ratios = np.abs(theta_dot) / velocity_limits
    worst = float(ratios.max(initial=0.0))
    return 1.0 if worst <= 1.0 else 1.0 / worst


def position_limit_scale(
    theta: np.ndarray,
    theta_dot: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    horizon: float,
) -> float:
    """Largest s in [0, 1] such that theta + s theta_dot horizon stays within [lower, upper].

    Joints moving away from their limit never restrict s; a joint at (or past) its limit and
    moving into it gives s = 0, i.e. the whole motion halts (uniformly, so it stays reactionless).

    Args:
        theta, theta_dot, lower, upper: [rad], [rad/s], [rad], [rad], shape (n,).
        horizon: look-ahead time [s], > 0 (one control period).
    """
    step = theta_dot * horizon
    room = np.maximum(np.where(step > 0.0, upper - theta, theta - lower), 0.0)
    moving = np.abs(step)
    # s = room / |step| for moving joints; scale only where the step would use up the room
    binding = moving > room
    if not binding.any():
        return 1.0
    return float((room[binding] / moving[binding]).min())


def scale_to_joint_limits(
    robot: FreeFloatingModel,
    theta: np.ndarray,
    theta_dot: np.ndarray,
    limit_horizon: float | None,
) -> tuple[np.ndarray, float, bool]:
    """theta_dot scaled uniformly to ``robot``'s speed limits, then to its position limits.

    Args:
        theta: joint angles [rad], shape (n,).
        theta_dot: joint velocity [rad/s], shape (n,).
        limit_horizon: look-ahead for the position limits [s]; None ignores them.

    Returns:
        (scaled theta_dot [rad/s] (n,), overall scale in [0, 1] [-], True when a position limit
        reduced the scale).
    """
    limit_scale = uniform_speed_scale(theta_dot, robot.velocity_limits)
    if limit_scale < 1.0:
        theta_dot = limit_scale * theta_dot
    position_limited = False
    if limit_horizon is not None:
        position_scale = position_limit_scale(
            theta, theta_dot, robot.lower_limits, robot.upper_limits, limit_horizon
        )
        if position_scale < 1.0:
            position_limited = True
            limit_scale *= position_scale
            theta_dot = position_scale * theta_dot
    return theta_dot, limit_scale, position_limited
