"""The one place where Pinocchio's free-flyer conventions meet the thesis' conventions.

Pinocchio (free-flyer root joint):
    q = [r_b (3) [m], quaternion x y z w (4), theta (n) [rad]]
    v = [R^T v_b (3) [m/s], R^T omega_b (3) [rad/s], theta_dot (n) [rad/s]]
    i.e. the base twist is expressed in the *base* frame.
Thesis (chapter 2, eq. 2.1-2.4, 2.33):
    V_b = [v_b; omega_b] (6,) expressed in the inertial frame ``world``; v_b is the velocity of the
    base frame origin (= base CoM for the default model).

With S = blkdiag(R, R), V_b = S v[:6]. The inertia matrix in thesis coordinates is
M_thesis = T^T M_pin T with T = blkdiag(S^T, E_n): see :func:`thesis_inertia_blocks`.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import InputError
from rns_ros.core.validation import as_vector


def rotation_from_quaternion(quaternion_xyzw) -> np.ndarray:
    """Rotation matrix (3, 3) of a quaternion (x, y, z, w), normalized first.

    Raises:
        InputError: the quaternion is not finite or has norm < 1e-9.
    """
    x, y, z, w = as_vector(quaternion_xyzw, 4, "quaternion (x, y, z, w)")
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if norm < 1e-9:
        raise InputError("quaternion (x, y, z, w) must be non-zero, got [0, 0, 0, 0]")
    return pin.Quaternion(w / norm, x / norm, y / norm, z / norm).toRotationMatrix()


def base_rotation_blocks(rotation: np.ndarray) -> np.ndarray:
    """S = blkdiag(R, R), shape (6, 6): maps a base-frame twist to world axes."""
    block = np.zeros((6, 6))
    block[:3, :3] = rotation
    block[3:, 3:] = rotation
    return block


def base_twist_to_world(rotation: np.ndarray, twist_in_base: np.ndarray) -> np.ndarray:
    """Pinocchio base twist ``v[:6]`` (base axes) -> thesis V_b (world axes), shape (6,)."""
    return np.concatenate((rotation @ twist_in_base[:3], rotation @ twist_in_base[3:6]))


def base_twist_to_base(rotation: np.ndarray, twist_in_world: np.ndarray) -> np.ndarray:
    """Thesis V_b (world axes) -> Pinocchio base twist ``v[:6]`` (base axes), shape (6,)."""
    return np.concatenate((rotation.T @ twist_in_world[:3], rotation.T @ twist_in_world[3:6]))


def pinocchio_velocity(
    rotation: np.ndarray, base_twist_world: np.ndarray, theta_dot: np.ndarray
) -> np.ndarray:
    """Pinocchio generalized velocity v (6 + n,) from thesis V_b (world, (6,)) and theta_dot."""
    return np.concatenate((base_twist_to_base(rotation, base_twist_world), theta_dot))


def thesis_inertia_blocks(
    inertia_pin: np.ndarray, rotation: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split Pinocchio's joint-space inertia into the thesis blocks of eq. (2.7).

    Args:
        inertia_pin: M from ``pin.crba``, shape (6 + n, 6 + n), base twist in base axes.
        rotation: base attitude R (world <- base), shape (3, 3).

    Returns:
        (M_b (6, 6), M_bm (6, n), M_m (n, n)) with the base twist in world axes.
    """
    blocks = base_rotation_blocks(rotation)
    inertia_base = blocks @ inertia_pin[:6, :6] @ blocks.T
    coupling = blocks @ inertia_pin[:6, 6:]
    manipulator = inertia_pin[6:, 6:]
    return inertia_base, coupling, manipulator
