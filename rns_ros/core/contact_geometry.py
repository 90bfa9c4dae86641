r"""Rigid surfaces of thesis chapter 6 that hold the end-effector point, and the projection of a
configuration onto them.

A surface is one scalar holonomic constraint phi(p_e) = 0 on the EE point p_e [m]. Its gradient n
gives the constraint Jacobian J_c = n^T J_v (n,) of the velocity constraint (6.19), and its
curvature kappa = p_dot^T (d^2 phi / d p^2) p_dot the drift term of the acceleration constraint
(6.20): phi_ddot = J_c q_ddot + n^T J_v_dot q_dot + kappa. Signs and tolerances: docs/part2.md.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.fixed_base import FixedBaseModel
from rns_ros.core.validation import as_vector, positive

#: Norm below which a direction vector (axis, normal) cannot be normalized.
_TINY_NORM = 1e-9


def _point(value, name: str) -> np.ndarray:
    """A finite (3,) vector [m] or ConfigError naming the value."""
    array = np.asarray(value, dtype=float) if is_numeric(value) else None
    if array is None or array.shape != (3,) or not np.isfinite(array).all():
        raise ConfigError(f"{name} must be 3 finite numbers, got {value!r}")
    return array


def _direction(value, name: str) -> np.ndarray:
    """``value`` normalized to a unit (3,) vector, or ConfigError (zero or non-finite)."""
    array = _point(value, name)
    norm = float(np.linalg.norm(array))
    if norm < _TINY_NORM:
        raise ConfigError(
            f"{name} must be a non-zero direction (norm > {_TINY_NORM:g}), got {value!r}"
        )
    return array / norm


def is_numeric(value) -> bool:
    """True when ``value`` converts to a float array."""
    try:
        np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return False
    return True


class ArcConstraint:
    r"""The end effector on the circle of radius R about ``center`` in the plane normal to
    ``axis``: the surface of a rigid cylinder (thesis_rest A-4.8: R = 0.707 m, centre
    (1.91, 1.91) m for the planar arm of section 6.2.1).

    With P = E - a a^T (projection on the plane normal to the unit axis a) and d = P (p - c):

        phi(p)      = R - |d|                 [m], > 0 inside the cylinder
        n(p)        = -d / |d|                (3,), unit, towards the axis (into the cylinder)
        kappa(p, v) = -|P v - (u . v) u|^2 / |d|   [m/s^2], u = d / |d|

    kappa is the centripetal term of the acceleration constraint (6.20): moving along the circle
    at tangential speed s needs the normal acceleration s^2 / R toward the centre. The end
    effector is outside the cylinder and pushes toward its axis. Motion along the axis is free.

    Args:
        center: a point of the axis c [m], (3,).
        radius: R [m], finite and > 0.
        axis: the cylinder axis (3,), any non-zero length; default +z (the planar arms' normal).

    Raises:
        ConfigError: a non-finite or wrongly shaped centre/axis, a zero axis, radius <= 0.
    """

    def __init__(self, center, radius: float, axis=(0.0, 0.0, 1.0)) -> None:
        self.center = _point(center, "arc center")
        if not is_numeric(radius) or np.ndim(radius) != 0:
            raise ConfigError(f"arc radius must be a finite number > 0 m, got {radius!r}")
        self.radius = positive(radius, "arc radius", "[m]")
        self.axis = _direction(axis, "arc axis")
        self._projector = np.eye(3) - np.outer(self.axis, self.axis)

    def __repr__(self) -> str:
        return (
            f"ArcConstraint(center={self.center.tolist()}, radius={self.radius}, "
            f"axis={self.axis.tolist()})"
        )

    def _offset(self, p) -> tuple[np.ndarray, float]:
        d = self._projector @ (np.asarray(p, dtype=float) - self.center)
        return d, float(np.linalg.norm(d))

    def phi(self, p) -> float:
        """phi = R - |P (p - c)| [m] (> 0: penetration)."""
        return self.radius - self._offset(p)[1]

    def gradient(self, p) -> np.ndarray:
        """n = d phi / d p = -d / |d|, unit, into the cylinder (3,).

        Raises:
            InputError: p on the axis, where the normal is undefined.
        """
        d, distance = self._offset(p)
        if not distance > _TINY_NORM * self.radius:
            raise InputError(f"point {np.asarray(p).tolist()} is on the arc axis: no normal")
        return -d / distance

    def curvature(self, p, p_dot) -> float:
        """kappa = p_dot^T (d^2 phi / d p^2) p_dot = -|tangential in-plane velocity|^2 / |d|
        [m/s^2]."""
        d, distance = self._offset(p)
        planar = self._projector @ np.asarray(p_dot, dtype=float)
        u = d / distance
        tangential = planar - (u @ planar) * u
        return -float(tangential @ tangential) / distance

    def evaluate(self, p, p_dot) -> tuple[float, np.ndarray, float]:
        """(phi [m], n (3,), kappa [m/s^2]) in one pass (the simulator's inner loop)."""
        d = self._projector @ (p - self.center)
        distance = math.sqrt(d @ d)
        u = d / distance
        planar = self._projector @ p_dot
        tangential = planar - (u @ planar) * u
        return self.radius - distance, -u, -float(tangential @ tangential) / distance


class PlaneConstraint:
    """The end effector on the plane through ``point`` with normal ``normal``: a rigid wall
    (thesis section 6.2.2, the 7-DoF arm; the wall is z of the task frame {E}).

        phi(p) = n . (p - p0) [m] (> 0 behind the wall surface), gradient n, kappa = 0,

    so (6.19)-(6.20) read n^T J_v q_dot = 0 and n^T (J_v q_ddot + J_v_dot q_dot) = 0.

    Args:
        point: a point of the wall surface p0 [m], (3,).
        normal: the wall normal n (3,), any non-zero length, pointing INTO the wall (the
            direction in which the end effector pushes); normalized here.

    Raises:
        ConfigError: non-finite or wrongly shaped vectors, a zero normal.
    """

    def __init__(self, point, normal) -> None:
        self.point = _point(point, "plane point")
        self.normal = _direction(normal, "plane normal")

    def __repr__(self) -> str:
        return f"PlaneConstraint(point={self.point.tolist()}, normal={self.normal.tolist()})"

    def phi(self, p) -> float:
        """phi = n . (p - p0) [m]."""
        return float(self.normal @ (np.asarray(p, dtype=float) - self.point))

    def gradient(self, p) -> np.ndarray:
        """n (3,), unit, into the wall (constant)."""
        return self.normal.copy()

    def curvature(self, p, p_dot) -> float:
        """0: a plane has no curvature [m/s^2]."""
        return 0.0

    def evaluate(self, p, p_dot) -> tuple[float, np.ndarray, float]:
        """(phi [m], n (3,), kappa = 0) in one pass (the simulator's inner loop)."""
        return float(self.normal @ (p - self.point)), self.normal, 0.0


#: Any object with phi(p) [m], gradient(p) (3,) and curvature(p, p_dot) [m/s^2].
Constraint = ArcConstraint | PlaneConstraint


def project_onto_constraint(
    robot: FixedBaseModel,
    constraint: Constraint,
    q,
    v=None,
    *,
    tolerance: float = 1e-13,
    max_iterations: int = 50,
) -> tuple[np.ndarray, np.ndarray]:
    """The nearest configuration on the constraint (Gauss-Newton, minimum-norm steps
    dq = -J_c^+ phi) and the velocity with its normal part removed (v - J_c^+ J_c v), so that the
    start satisfies phi = 0 and the velocity constraint (6.19), J_c q_dot = 0.

    Use it to put a rounded start configuration (e.g. the planar [106.4, -45.7, -56.2] deg, about
    1 mm off the arc) exactly on the surface.

    Args:
        q: start configuration [rad] (n,). v: start velocity [rad/s] (n,), default zero.
        tolerance: |phi| [m] to reach. max_iterations: Gauss-Newton iterations.

    Returns:
        (q (n,) with |phi| <= tolerance, v (n,) with phi_dot = 0 to round-off).

    Raises:
        InputError: bad q/v. ConfigError: no convergence (e.g. the surface is out of reach).
    """
    n = robot.n
    q = as_vector(q, n, "q").copy()
    v = np.zeros(n) if v is None else as_vector(v, n, "v").copy()
    data = robot.model.createData()
    phi = math.inf
    for _ in range(max_iterations + 1):
        p, J_v = ee_point_jacobian(robot, data, q)
        phi = constraint.phi(p)
        J_c = constraint.gradient(p) @ J_v
        if abs(phi) <= tolerance:
            return q, v - J_c * (J_c @ v) / (J_c @ J_c)
        q = q - J_c * phi / (J_c @ J_c)
    raise ConfigError(
        f"could not project q onto {constraint!r}: |phi| = {abs(phi):.3g} m after "
        f"{max_iterations} iterations (is the surface within reach?)"
    )


def ee_point_jacobian(
    robot: FixedBaseModel, data: pin.Data, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """EE position [m] (3,) and linear Jacobian J_v (3, n), world axes."""
    J = pin.computeFrameJacobian(robot.model, data, q, robot.ee_frame_id, pin.LOCAL_WORLD_ALIGNED)
    return data.oMf[robot.ee_frame_id].translation.copy(), J[:3]
