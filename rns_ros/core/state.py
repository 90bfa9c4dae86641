"""One free-floating robot state: kinematics and dynamics computed once per configuration.

Like pink's ``Configuration``: build a :class:`FreeFloatingState` once per control or simulation
step with :meth:`FreeFloatingState.compute`, then pass it to every function that needs M_b, M_bm,
the coupling angular momentum matrix, P_RNS or Jacobians. Nothing is recomputed behind your back;
all arrays are read-only. All vectors are in world axes (the thesis convention, see
:mod:`rns_ros.core.conventions`) unless a name says otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import pinocchio as pin

from rns_ros.core.conventions import thesis_inertia_blocks
from rns_ros.core.inverses import kernel_basis
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.validation import as_vector

#: Relative singular-value threshold below which a direction of the coupling angular momentum
#: matrix counts as lost (rank decision for P_RNS), dimensionless.
DEFAULT_RANK_TOLERANCE = 1e-9


def _frozen(array: np.ndarray) -> np.ndarray:
    """A read-only copy (for arrays that may alias Pinocchio's data or the caller's)."""
    array = np.array(array, dtype=float)
    array.setflags(write=False)
    return array


def _sealed(array: np.ndarray) -> np.ndarray:
    """``array`` itself, made read-only (for arrays computed here and owned by nobody else)."""
    array.setflags(write=False)
    return array


def skew(vector: np.ndarray) -> np.ndarray:
    """[r^x] such that [r^x] a = r x a, shape (3, 3)."""
    x, y, z = vector
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


@dataclass(frozen=True)
class FrameKinematics:
    """Pose and Jacobians of one frame (camera or wrist) at a configuration.

    Attributes:
        position: frame origin in world [m], shape (3,).
        rotation: world <- frame rotation, shape (3, 3).
        jacobian: fixed-base Jacobian J_m = [J_v; J_omega] w.r.t. theta_dot, world axes,
            linear part of the frame origin, shape (6, n) [m/rad; -].
        base_position: base origin r_b in world [m], shape (3,).
    """

    position: np.ndarray
    rotation: np.ndarray
    jacobian: np.ndarray
    base_position: np.ndarray

    @property
    def base_jacobian(self) -> np.ndarray:
        """J_b mapping the thesis base twist V_b (world) to the frame twist,
        [[E, -[r_{b->e}^x]], [0, E]], shape (6, 6)."""
        base_jacobian = np.eye(6)
        base_jacobian[:3, 3:] = -skew(self.position - self.base_position)
        return base_jacobian


@dataclass(frozen=True)
class Determinants:
    """The three determinants of thesis section 4.3.1 (all dimensionless or in (kg m^2)^6).

    Attributes:
        kinematic: det(J_omega_e J_omega_e^T).
        coupling: det(M~_omega_m M~_omega_m^T) [(kg m^2)^6].
        algorithmic: det(J-bar J-bar^T) with J-bar = J_omega_e P_RNS (restricted Jacobian).
    """

    kinematic: float
    coupling: float
    algorithmic: float


@dataclass(frozen=True)
class FreeFloatingState:
    """Kinematic/dynamic quantities of the free-floating robot at one configuration q.

    Attributes (n = number of arm joints):
        q: Pinocchio configuration, shape (7 + n,).
        theta: joint angles [rad], shape (n,).
        base_position: r_b [m], shape (3,).
        base_rotation: R (world <- base), shape (3, 3).
        coupling_angular_momentum_matrix: M~_omega_m of eq. (3.2), shape (3, n) [kg m^2].
        base_rotational_inertia: M~_omega of eq. (3.2), shape (3, 3) [kg m^2].
        center_of_mass: system CoM r_C [m], shape (3,).
        coupling_singular_values: singular values of M~_omega_m, descending, shape (3,).
        reaction_null_space_projector: P_RNS = E - M~^+ M~ (eq. 2.34 / 3.3), shape (n, n).
        reaction_null_space_rank: rank of P_RNS (n - rank M~_omega_m).
        camera: :class:`FrameKinematics` of the end-effector frame.
        wrist: :class:`FrameKinematics` of the wrist frame, or None.

    The inertia blocks M_b, M_bm, M_m (properties ``inertia_base``, ``coupling_inertia``,
    ``manipulator_inertia``) are computed on first use (one CRBA) and cached: the control law only
    needs M~_omega_m and M~_omega, which come from the centroidal momentum matrix.
    """

    q: np.ndarray
    theta: np.ndarray
    base_position: np.ndarray
    base_rotation: np.ndarray
    coupling_angular_momentum_matrix: np.ndarray
    base_rotational_inertia: np.ndarray
    center_of_mass: np.ndarray
    coupling_singular_values: np.ndarray
    reaction_null_space_projector: np.ndarray
    reaction_null_space_rank: int
    camera: FrameKinematics
    wrist: FrameKinematics | None
    robot: FreeFloatingModel = field(repr=False, compare=False)

    @classmethod
    def compute(
        cls,
        robot: FreeFloatingModel,
        q,
        *,
        rank_tolerance: float = DEFAULT_RANK_TOLERANCE,
    ) -> FreeFloatingState:
        """Run Pinocchio once (centroidal map, joint Jacobians, frames) and derive the rest.

        M~_omega_m and M~_omega of eq. (3.2) are the angular rows of Pinocchio's centroidal
        momentum matrix A_G: with zero linear momentum the angular momentum is the same about
        every point, a base translation adds none about the CoM, and A_G's base columns act on
        the base twist in base axes (hence the R^T). A test checks them against eq. (3.2) built
        from M_b and M_bm.

        Args:
            robot: the model.
            q: configuration, shape (7 + n,); the quaternion must be unit.
            rank_tolerance: relative singular-value threshold for the rank of M~_omega_m [-].
        """
        model, data = robot.model, robot.data
        q = as_vector(q, model.nq, "q")
        centroidal = pin.computeCentroidalMap(model, data, q)  # also the CoM, data.com[0]
        com = data.com[0].copy()
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        rotation = data.oMi[1].rotation.copy()
        base_position = data.oMi[1].translation.copy()
        tilde_m_wm = centroidal[3:, 6:]
        tilde_m_w = centroidal[3:, 3:6] @ rotation.T

        # P_RNS from the SVD of M~_omega_m: projector onto its kernel (eq. 2.34, 3.3).
        kernel, sigma, rank = kernel_basis(tilde_m_wm, rank_tolerance, checked=True)
        projector = kernel @ kernel.T

        base_position = _sealed(base_position)
        camera = _frame_kinematics(robot, robot.camera_frame_id, base_position)
        wrist = (
            None
            if robot.wrist_frame_id is None
            else _frame_kinematics(robot, robot.wrist_frame_id, base_position)
        )
        q = _frozen(q)
        return cls(
            q=q,
            theta=q[7:],
            base_position=base_position,
            base_rotation=_sealed(rotation),
            coupling_angular_momentum_matrix=_sealed(tilde_m_wm),
            base_rotational_inertia=_sealed(tilde_m_w),
            center_of_mass=_sealed(com),
            coupling_singular_values=_sealed(sigma),
            reaction_null_space_projector=_sealed(projector),
            reaction_null_space_rank=robot.n - rank,
            camera=camera,
            wrist=wrist,
            robot=robot,
        )

    # --- inertia blocks of eq. (2.7), on first use -----------------------------------------------
    @cached_property
    def _inertia_blocks(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        model, data = self.robot.model, self.robot.data
        pin.crba(model, data, self.q)
        blocks = thesis_inertia_blocks(data.M, self.base_rotation)
        return tuple(_frozen(block) for block in blocks)

    @property
    def inertia_base(self) -> np.ndarray:
        """M_b of eq. (2.8), shape (6, 6) [kg, kg m, kg m^2]."""
        return self._inertia_blocks[0]

    @property
    def coupling_inertia(self) -> np.ndarray:
        """M_bm (= M_bl) of eq. (2.12), shape (6, n)."""
        return self._inertia_blocks[1]

    @property
    def manipulator_inertia(self) -> np.ndarray:
        """M_m (= M_l) of eq. (2.15), shape (n, n)."""
        return self._inertia_blocks[2]

    # --- derived quantities (cheap, from stored arrays) ----------------------------------------
    @property
    def n(self) -> int:
        """Number of arm joints."""
        return self.theta.shape[0]

    @property
    def inertia(self) -> np.ndarray:
        """Full inertia matrix M of eq. (2.7) in thesis coordinates, shape (6 + n, 6 + n)."""
        top = np.hstack((self.inertia_base, self.coupling_inertia))
        bottom = np.hstack((self.coupling_inertia.T, self.manipulator_inertia))
        return np.vstack((top, bottom))

    @property
    def restricted_jacobian(self) -> np.ndarray:
        """J-bar_omega_e = J_omega_e P_RNS of eq. (4.5), shape (3, n) [-]."""
        return self.camera.jacobian[3:] @ self.reaction_null_space_projector

    @property
    def determinants(self) -> Determinants:
        """The kinematic, coupling and algorithmic determinants of section 4.3.1."""
        return Determinants(
            kinematic=_gram_determinant(self.camera.jacobian[3:]),
            coupling=float(np.prod(self.coupling_singular_values**2)),
            algorithmic=_gram_determinant(self.restricted_jacobian),
        )


def _gram_determinant(matrix: np.ndarray) -> float:
    """det(A A^T) for a wide matrix A, via its singular values (accurate near zero)."""
    return float(np.prod(np.linalg.svd(matrix, compute_uv=False) ** 2))


def _frame_kinematics(robot: FreeFloatingModel, frame_id: int, base_position) -> FrameKinematics:
    model, data = robot.model, robot.data
    placement = data.oMf[frame_id]
    position = placement.translation.copy()
    jacobian = pin.getFrameJacobian(model, data, frame_id, pin.LOCAL_WORLD_ALIGNED)
    return FrameKinematics(
        position=_sealed(position),
        rotation=_frozen(placement.rotation),
        jacobian=_frozen(jacobian[:, 6:]),
        base_position=base_position,
    )
