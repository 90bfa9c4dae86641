"""Task coordinates and the selection of motion and force directions, eqs. (6.10)-(6.12)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.fixed_base import FixedBaseModel, FixedBaseState
from rns_ros.core.validation import as_vector

#: Names of the six rows of J_e / V_e (Pinocchio order: linear then angular, world axes).
ROW_NAMES = ("x", "y", "z", "wx", "wy", "wz")
#: Task rows of the planar 3-DoF arm: EE position x, y (orientation free, thesis x-z -> x-y).
PLANAR_ROWS = (0, 1)
#: Task rows of the 7-DoF arm: EE position and orientation (orientation held).
FULL_ROWS = (0, 1, 2, 3, 4, 5)


def contact_frame(normal, tangent=None) -> np.ndarray:
    """Rotation world <- {E} of the contact frame: columns [x_E, y_E, z_E] = [t, n x t, n].

    Args:
        normal: contact normal n in world axes, (3,), any length > 0; it points from the EE into
            the environment (the direction the EE pushes).
        tangent: first tangent t (3,), optional. Default: z_world x n (in-plane for a planar arm
            whose normal lies in x-y), or x_world projected if n is close to z_world.

    Raises:
        InputError: zero or non-finite normal/tangent, or a tangent parallel to the normal.
    """
    n = as_vector(normal, 3, "normal")
    norm = np.linalg.norm(n)
    if norm < 1e-12:
        raise InputError(f"normal must be non-zero, got {n.tolist()}")
    n = n / norm
    if tangent is None:
        t = np.cross([0.0, 0.0, 1.0], n)
        if np.linalg.norm(t) < 0.1:
            t = np.array([1.0, 0.0, 0.0])
    else:
        t = as_vector(tangent, 3, "tangent")
    t = t - (t @ n) * n
    if np.linalg.norm(t) < 1e-9:
        raise InputError(f"tangent {np.asarray(tangent).tolist()} is parallel to normal")
    t = t / np.linalg.norm(t)
    return np.column_stack([t, np.cross(n, t), n])


@dataclass(frozen=True)
class TaskSpace:
    """Which EE directions are motion- and which force-controlled, eq. (6.10)-(6.12).

    Attributes:
        rows: the rows of J_e used as task coordinates (0..5 = x, y, z, wx, wy, wz in world
            axes), m of them.
        force_basis: N, orthonormal columns in task coordinates spanning the force-controlled
            directions, shape (m, k), k >= 0.
        contact_rotation: world <- {E} (3, 3) of :func:`contact_frame`, or None without contact.

    S_perp = N N^T and S = E - S_perp (both (m, m), world axes) are the selection matrices of
    (6.11)-(6.12): planar arm with normal n, tangent t: S = t t^T, S_perp = n n^T.
    """

    rows: tuple[int, ...]
    force_basis: np.ndarray
    contact_rotation: np.ndarray | None = None

    def __post_init__(self) -> None:
        rows = tuple(int(r) for r in self.rows)
        if not rows or len(set(rows)) != len(rows) or any(r < 0 or r > 5 for r in rows):
            raise ConfigError(f"rows must be distinct indices in 0..5 (x..wz), got {self.rows!r}")
        basis = np.asarray(self.force_basis, dtype=float).reshape(len(rows), -1)
        if basis.shape[1] and not np.allclose(basis.T @ basis, np.eye(basis.shape[1]), atol=1e-9):
            raise ConfigError("force_basis must have orthonormal columns")
        object.__setattr__(self, "rows", rows)
        object.__setattr__(self, "force_basis", basis)

    @classmethod
    def free(cls, rows=FULL_ROWS) -> TaskSpace:
        """Motion control in every task row, no force direction (k = 0)."""
        return cls(tuple(rows), np.zeros((len(tuple(rows)), 0)))

    @classmethod
    def from_contact(cls, rows, normal, tangent=None) -> TaskSpace:
        """Point contact with force control along the normal n (world axes, (3,)).

        Raises:
            ConfigError: n has a component along a linear axis that is not a task row (the force
                could not be commanded).
        """
        rotation = contact_frame(normal, tangent)
        n = rotation[:, 2]
        rows = tuple(int(r) for r in rows)
        missing = [ROW_NAMES[i] for i in range(3) if i not in rows and abs(n[i]) > 1e-9]
        if missing:
            raise ConfigError(
                f"normal {n.tolist()} has components along {missing}, which are not task rows "
                f"{[ROW_NAMES[r] for r in rows if 0 <= r <= 5]}"
            )
        basis = np.array([n[r] if r < 3 else 0.0 for r in rows]).reshape(-1, 1)
        return cls(rows, basis, rotation)

    @property
    def m(self) -> int:
        """Number of task coordinates."""
        return len(self.rows)

    @property
    def k(self) -> int:
        """Number of force-controlled directions."""
        return self.force_basis.shape[1]

    @property
    def force_selection(self) -> np.ndarray:
        """S_perp = N N^T, (m, m), eq. (6.12)."""
        return self.force_basis @ self.force_basis.T

    @property
    def selection(self) -> np.ndarray:
        """S = E - S_perp, (m, m), eq. (6.11)."""
        return np.eye(self.m) - self.force_selection

    def jacobian(self, state: FixedBaseState) -> np.ndarray:
        """Task rows of J_e, (m, n)."""
        return state.jacobian[list(self.rows)]

    def drift(self, state: FixedBaseState) -> np.ndarray:
        """Task rows of J_e_dot theta_dot, (m,)."""
        return state.jacobian_dot_v[list(self.rows)]

    def velocity(self, state: FixedBaseState) -> np.ndarray:
        """nu = J_task theta_dot, (m,)."""
        return self.jacobian(state) @ state.v

    def pose_error(self, state: FixedBaseState, position, rotation=None) -> np.ndarray:
        """x_des - x in task coordinates, (m,): position rows p_des - p [m], orientation rows the
        rotation vector log(R_des R^T) in world axes [rad] (needs ``rotation`` then)."""
        position = as_vector(position, 3, "position")
        error = np.zeros(6)
        error[:3] = position - state.ee_position
        if any(r >= 3 for r in self.rows):
            if rotation is None:
                raise InputError("rotation (3, 3) is needed for the orientation rows")
            rotation = np.asarray(rotation, dtype=float).reshape(3, 3)
            error[3:] = pin.log3(rotation @ state.ee_rotation.T)
        return error[list(self.rows)]

    def compose(self, motion_acceleration, normal_acceleration=None) -> np.ndarray:
        """V_dot_ref = S nu_dot_ref + N a_n in task coordinates, (m,).

        ``normal_acceleration`` a_n (k,) [m/s^2] is a constraint-consistent acceleration along
        the force directions (e.g. the centripetal term on a curved surface, [A-4.8]); default 0,
        as in the thesis S V_dot.
        """
        a = as_vector(motion_acceleration, self.m, "motion acceleration reference")
        out = self.selection @ a
        if normal_acceleration is not None and self.k:
            out = out + self.force_basis @ as_vector(normal_acceleration, self.k, "a_n")
        return out

    def force_wrench(self, force_ref) -> np.ndarray:
        """F_kappa^ref = S_perp F_c^ref = N f_ref, (m,) [N], eq. (6.12) ([A-4.1] sign)."""
        if self.k == 0:
            return np.zeros(self.m)
        return self.force_basis @ as_vector(np.atleast_1d(force_ref), self.k, "force_ref")

    def check(self, robot: FixedBaseModel) -> None:
        """ConfigError unless the task fits the arm (m <= n)."""
        if self.m > robot.n:
            raise ConfigError(f"{self.m} task rows exceed the {robot.n} joints of {robot.name}")


__all__ = ["FULL_ROWS", "PLANAR_ROWS", "ROW_NAMES", "TaskSpace", "contact_frame"]
