"""Can this arm do reactionless camera pointing on its satellite? The numbers ``rns_model check``
prints, at the model's initial configuration.

With n controlled joints, the coupling angular momentum matrix M~_omega_m (3, n) of eq. (3.2)
leaves a reaction null space of dimension d = n - rank M~_omega_m (eq. 2.34). Reactionless camera
pointing (eq. 4.5) asks three camera angular velocity rows J_omega_e (3, n) of it: possible at a
configuration iff the restricted Jacobian J-bar = J_omega_e P_RNS has rank 3, i.e. iff the stacked
matrix [M~_omega_m; J_omega_e] (6, n) has rank rank M~_omega_m + 3 (= 6 away from a coupling
singularity), which needs n >= 6. What is left, n - rank [M~_omega_m; J_omega_e], is the null space
the wrist term of eq. (4.5) moves in (thesis section 4.1.2: 1 for the 7-joint arm); with none
left, a wrist frame has no effect.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from rns_ros.core.inverses import kernel_basis
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import DEFAULT_RANK_TOLERANCE, FreeFloatingState

#: Rows of the camera task: the camera's angular velocity (eq. 4.5) [-].
POINTING_ROWS = 3
#: Rows of the reactionless constraint: the base's angular momentum (eq. 3.2) [-].
CONSTRAINT_ROWS = 3
#: sigma_min of the restricted Jacobian below which the initial configuration is reported as
#: near an algorithmic singularity [-]: the DLS singular region of the thesis (epsilon = 0.2,
#: section 4.3.2) starts there, so the commanded camera velocity is no longer followed exactly.
NEAR_SINGULAR = 0.2


@dataclass(frozen=True)
class ArmFeasibility:
    """What ``rns_model check`` reports about a model at its initial configuration.

    Attributes:
        controlled_joints: joints the controller drives (theta order), length n.
        held_joints: joint name -> held position [rad or m] (not driven; their mass counts).
        total_mass: m_C [kg]; base_mass: the free-flyer's body (satellite plus the links fixed
            to it) [kg]; arm_mass: total_mass - base_mass [kg].
        theta: the initial configuration [rad], shape (n,).
        coupling_rank: rank of M~_omega_m (3 away from a coupling singularity).
        null_space_dimension: d = n - coupling_rank.
        stacked_rank: rank of [M~_omega_m; J_omega_e] (6, n).
        restricted_singular_values: singular values of J-bar = J_omega_e P_RNS, descending (3,).
        wrist_frame: the wrist frame's name, or None (no wrist term).
        warnings: one sentence per problem, with its reason and what to do.
    """

    controlled_joints: tuple[str, ...]
    held_joints: dict[str, float]
    total_mass: float
    base_mass: float
    theta: np.ndarray = field(repr=False)
    coupling_rank: int
    stacked_rank: int
    restricted_singular_values: np.ndarray = field(repr=False)
    wrist_frame: str | None
    warnings: tuple[str, ...] = ()

    @property
    def n(self) -> int:
        """Number of controlled joints."""
        return len(self.controlled_joints)

    @property
    def arm_mass(self) -> float:
        """Mass of everything but the base body [kg]."""
        return self.total_mass - self.base_mass

    @property
    def mass_ratio(self) -> float:
        """Base-to-arm mass ratio [-] (the thesis' ETS-VII-class satellite: ~10 and more)."""
        return self.base_mass / self.arm_mass if self.arm_mass > 0.0 else float("inf")

    @property
    def null_space_dimension(self) -> int:
        """d = n - rank M~_omega_m: joint motions that leave the base attitude alone."""
        return self.n - self.coupling_rank

    @property
    def pointing_feasible(self) -> bool:
        """Reactionless camera pointing: J-bar of full rank 3 (the stacked matrix one of rank
        rank M~_omega_m + 3)."""
        return self.stacked_rank == self.coupling_rank + POINTING_ROWS

    @property
    def wrist_null_space_dimension(self) -> int:
        """Null space left after the constraint and the camera rows: n - rank of the stack."""
        return self.n - self.stacked_rank

    @property
    def wrist_feasible(self) -> bool:
        """The wrist term has room: pointing is feasible and a null space is left after it."""
        return self.pointing_feasible and self.wrist_null_space_dimension > 0

    @property
    def restricted_sigma_min(self) -> float:
        """Smallest singular value of J-bar [-]."""
        return float(self.restricted_singular_values[-1])


def arm_feasibility(
    robot: FreeFloatingModel, theta=None, *, rank_tolerance: float = DEFAULT_RANK_TOLERANCE
) -> ArmFeasibility:
    """:class:`ArmFeasibility` of ``robot`` at ``theta`` [rad] (n,) (default: the model's
    initial configuration, zeros when it has none).

    Ranks are decided as :class:`FreeFloatingState` decides the rank of M~_omega_m: singular
    values below ``rank_tolerance`` times the largest count as zero.
    """
    if theta is None:
        theta = robot.initial_theta
    state = FreeFloatingState.compute(
        robot, robot.configuration(theta), rank_tolerance=rank_tolerance
    )
    coupling = state.coupling_angular_momentum_matrix
    # rows scaled to one: M~_omega_m [kg m^2] and J_omega_e [-] have different units
    stacked = np.vstack((_unit_scale(coupling), _unit_scale(state.camera.jacobian[3:])))
    _, _, stacked_rank = kernel_basis(stacked, rank_tolerance, checked=True)
    restricted = np.linalg.svd(state.restricted_jacobian, compute_uv=False)
    wrist = None if robot.wrist_frame_id is None else robot.model.frames[robot.wrist_frame_id].name
    result = ArmFeasibility(
        controlled_joints=tuple(robot.joint_names),
        held_joints=dict(robot.held_joints),
        total_mass=float(robot.total_mass),
        base_mass=robot.base_mass,
        theta=np.array(state.theta),
        coupling_rank=robot.n - state.reaction_null_space_rank,
        stacked_rank=stacked_rank,
        restricted_singular_values=restricted,
        wrist_frame=wrist,
    )
    return _with_warnings(result)


def _unit_scale(matrix: np.ndarray) -> np.ndarray:
    """``matrix`` divided by its largest singular value (unchanged when it is zero)."""
    largest = np.linalg.norm(matrix, 2)
    return matrix / largest if largest > 0.0 else matrix


def _with_warnings(result: ArmFeasibility) -> ArmFeasibility:
    """``result`` with one warning per task that cannot be reactionless, and why."""
    warnings = []
    n, d = result.n, result.null_space_dimension
    if result.coupling_rank < CONSTRAINT_ROWS:
        warnings.append(
            f"M~_omega_m has rank {result.coupling_rank} < 3 at the initial configuration (a "
            "coupling singularity, thesis section 4.3.1): choose other initial_joint_positions"
        )
    if not result.pointing_feasible:
        if n < CONSTRAINT_ROWS + POINTING_ROWS:
            reason = (
                f"{n} controlled joints leave a {d}-dimensional reaction null space, fewer than "
                f"the {POINTING_ROWS} camera rows: control at least 6 joints"
            )
        else:
            reason = (
                f"the restricted Jacobian J_omega_e P_RNS has rank "
                f"{result.stacked_rank - result.coupling_rank} < 3 at the initial configuration "
                "(an algorithmic singularity, thesis section 4.3.1): choose other "
                "initial_joint_positions"
            )
        warnings.append(f"reactionless camera pointing is not possible: {reason}")
    elif result.restricted_sigma_min < NEAR_SINGULAR:
        warnings.append(
            f"sigma_min of the restricted Jacobian is {result.restricted_sigma_min:.3g} < "
            f"{NEAR_SINGULAR:g} (the DLS singular region, section 4.3.2): the camera will not "
            "follow the commanded rate exactly near the start; choose initial_joint_positions "
            "further from the singularity"
        )
    if result.wrist_frame is not None and result.pointing_feasible and not result.wrist_feasible:
        warnings.append(
            f"wrist holding cannot be reactionless: {n} controlled joints leave a {d}-dimensional "
            f"reaction null space, all of it taken by the {POINTING_ROWS} camera rows; no "
            f"redundancy is left for the wrist term (wrist_frame '{result.wrist_frame}' has no "
            "effect): set wrist_frame: null, or control a seventh joint"
        )
    return replace(result, warnings=tuple(warnings))
