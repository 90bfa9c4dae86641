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
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from rns_ros.core.conventions import thesis_inertia_blocks
from rns_ros.core.fastmath import solve_small_many, symmetric_eigenvalues
from rns_ros.core.inverses import kernel_basis
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.validation import as_vector

#: Relative singular-value threshold below which a direction of the coupling angular momentum
#: matrix counts as lost (rank decision for P_RNS), dimensionless.
DEFAULT_RANK_TOLERANCE = 1e-9
#: P_RNS comes from the 3 x 3 Gram matrix M~ M~^T (a solve) while sigma_min / sigma_max of
#: M~_omega_m stays above this [-]; closer to a coupling singularity from the SVD, with the rank
#: decision of ``rank_tolerance``. (The Gram matrix squares the condition number: at 1e-2 P_RNS
#: is idempotent to ~1e-13, at 3e-3 only to 1e-12; our arm has sigma_min / sigma_max ~ 0.04.)
GRAM_CONDITION_LIMIT = 1e-2


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


class ArmKinematics(NamedTuple):
    """What the reactionless law (4.5) reads at a configuration, without P_RNS: the partial state
    the hold correction evaluates the law on (:meth:`FreeFloatingState.arm_kinematics`).

    Attributes (n = number of arm joints; world axes; all read-only):
        theta: joint angles [rad], shape (n,).
        coupling_angular_momentum_matrix: M~_omega_m of eq. (3.2), shape (3, n) [kg m^2].
        camera_angular_jacobian: J_omega_e, shape (3, n) [-].
        wrist_linear_jacobian: J_vw, shape (3, n) [m/rad], or None without a wrist frame.
        wrist_offset: wrist position minus the base origin [m], shape (3,), or None.
    """

    theta: np.ndarray
    coupling_angular_momentum_matrix: np.ndarray
    camera_angular_jacobian: np.ndarray
    wrist_linear_jacobian: np.ndarray | None
    wrist_offset: np.ndarray | None


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
        q = _frozen(as_vector(q, model.nq, "q"))
        pin.computeCentroidalMap(model, data, q)  # also the CoM and the joint placements
        rotation = _frozen(data.oMi[1].rotation)
        base_position = _frozen(data.oMi[1].translation)
        return cls._from_centroidal_map(robot, q, base_position, rotation, rank_tolerance)

    def with_joint_angles(
        self, theta, *, rank_tolerance: float = DEFAULT_RANK_TOLERANCE
    ) -> FreeFloatingState:
        """The state with the arm at ``theta`` [rad], shape (n,), and the base pose unchanged.

        What a held joint velocity reaches within a control period while the base stands still
        (reactionless motion): the hold correction evaluates the law there. Same quantities as
        :meth:`compute` at the moved q, without re-checking q or recomputing the base pose (the
        base arrays are shared with this state; all are read-only).
        """
        q = self.q.copy()
        q[7:] = theta
        q.setflags(write=False)
        pin.computeCentroidalMap(self.robot.model, self.robot.data, q)
        return type(self)._from_centroidal_map(
            self.robot, q, self.base_position, self.base_rotation, rank_tolerance
        )

    def arm_kinematics(self, theta) -> ArmKinematics:
        """:class:`ArmKinematics` with the arm at ``theta`` [rad], shape (n,), base pose unchanged.

        The part of :meth:`with_joint_angles` the law needs, at a fraction of its cost: one
        centroidal map and the joint Jacobians (Pinocchio, ~3 us), no SVD, no P_RNS, no frame
        rotations. The hold midpoint: the law there has a closed form in these matrices.
        """
        robot = self.robot
        model, data = robot.model, robot.data
        q = self.q.copy()
        q[7:] = theta
        pin.computeCentroidalMap(model, data, q)
        pin.computeJointJacobians(model, data)
        reference = pin.LOCAL_WORLD_ALIGNED
        camera = pin.getFrameJacobian(model, data, robot.camera_frame_id, reference)[3:, 6:]
        jacobian = offset = None
        if robot.wrist_frame_id is not None:
            placement = pin.updateFramePlacement(model, data, robot.wrist_frame_id)  # a copy
            offset = _sealed(placement.translation - self.base_position)
            jacobian = pin.getFrameJacobian(model, data, robot.wrist_frame_id, reference)
            jacobian = _sealed(jacobian[:3, 6:])
        return ArmKinematics(
            theta=_sealed(q[7:]),
            coupling_angular_momentum_matrix=_sealed(data.Ag[3:, 6:].copy()),
            camera_angular_jacobian=_sealed(camera),
            wrist_linear_jacobian=jacobian,
            wrist_offset=offset,
        )

    @classmethod
    def _from_centroidal_map(
        cls, robot, q, base_position, rotation, rank_tolerance
    ) -> FreeFloatingState:
        """The rest of :meth:`compute` once ``pin.computeCentroidalMap`` ran at ``q``."""
        model, data = robot.model, robot.data
        centroidal = data.Ag
        com = data.com[0].copy()
        pin.computeJointJacobians(model, data)  # at the placements of the centroidal map
        tilde_m_wm = centroidal[3:, 6:].copy()
        tilde_m_w = centroidal[3:, 3:6] @ rotation.T
        projector, sigma, rank = reaction_null_space(tilde_m_wm, rank_tolerance)
        camera = _frame_kinematics(robot, robot.camera_frame_id, base_position)
        wrist = (
            None
            if robot.wrist_frame_id is None
            else _frame_kinematics(robot, robot.wrist_frame_id, base_position)
        )
        return cls(
            q=q,
            theta=q[7:],
            base_position=base_position,
            base_rotation=rotation,
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


def reaction_null_space(
    coupling: np.ndarray, rank_tolerance: float = DEFAULT_RANK_TOLERANCE
) -> tuple[np.ndarray, np.ndarray, int]:
    """P_RNS = E - M~^+ M~ of eq. (2.34) / (3.3) for M~_omega_m (3, n), n > 3 or not.

    Returns (P_RNS (n, n), singular values of M~ descending (min(3, n),), rank of M~). Away from
    a coupling singularity (sigma_min / sigma_max > GRAM_CONDITION_LIMIT) M~^+ M~ =
    M~^T (M~ M~^T)^-1 M~ with one 3 x 3 solve and the singular values from the eigenvalues of
    M~ M~^T; otherwise the kernel basis of the SVD (rank decision by ``rank_tolerance``).
    """
    rows, columns = coupling.shape
    if rows < columns:
        gram = coupling @ coupling.T
        eigenvalues = symmetric_eigenvalues(gram)
        if eigenvalues[0] > GRAM_CONDITION_LIMIT**2 * eigenvalues[-1]:
            projector = np.eye(columns) - coupling.T @ solve_small_many(gram, coupling)
            return projector, np.sqrt(eigenvalues[::-1]), rows
    kernel, sigma, rank = kernel_basis(coupling, rank_tolerance, checked=True)
    return kernel @ kernel.T, sigma, rank


def _gram_determinant(matrix: np.ndarray) -> float:
    """det(A A^T) for a wide matrix A, via its singular values (accurate near zero)."""
    return float(np.prod(np.linalg.svd(matrix, compute_uv=False) ** 2))


def _frame_kinematics(robot: FreeFloatingModel, frame_id: int, base_position) -> FrameKinematics:
    model, data = robot.model, robot.data
    pin.updateFramePlacement(model, data, frame_id)
    placement = data.oMf[frame_id]
    position = placement.translation.copy()
    jacobian = pin.getFrameJacobian(model, data, frame_id, pin.LOCAL_WORLD_ALIGNED)
    return FrameKinematics(
        position=_sealed(position),
        rotation=_frozen(placement.rotation),
        jacobian=_frozen(jacobian[:, 6:]),
        base_position=base_position,
    )
