r"""Motion/force control of fixed-base redundant arms: thesis Part II, chapters 6-7.

Two controllers put the end effector (EE) of a fixed-base arm in contact with its environment:
motion is controlled along the contact tangent(s), force along the contact normal.

* **OS-C** (section 6.1.1): the operational-space formulation, eqs. (6.6)-(6.13), in two labelled
  variants (:class:`OscVariant`): ``literal`` (torque level, tau_a = 0, the null-space share of the
  Coriolis torques is not compensated) and ``kinematic`` (theta_ddot = J^{M+} a').
* **RNS-C** (section 6.1.2): the Reaction Null-Space controller. The arm is reversed into a
  *control model* rooted at the EE link A, with the ground replaced by a heavy virtual link B
  (mass m_hat, inertia I_hat, length l_hat = 0) fixed by a constraint force.
  :class:`ReversedModel` builds the coupling inertia W = M_hat_Al of that model in REAL joint
  coordinates from the real Pinocchio bodies; :func:`rns_control` applies the closed form
  theta_ddot = W^T (J W^T)^{-1} (V_dot_ref - J_dot theta_dot) (shared/spec/thesis_rest.md
  section 4.2) and the real-model computed torque.
* **Chapter 7**: the resolved-acceleration reference J^+ (7.2), the null-space velocities
  ||P_hat_RNS theta_dot|| and ||P_J theta_dot|| (7.14), the velocity-level term (7.13) and the
  joint damper theta_ddot_a = -k_d theta_dot of section 7.2.2.

Conventions (docs/part2_controllers.md):

* Task coordinates: a selection of the rows of J_e (FixedBaseState.jacobian: V_e = [v; omega] in
  world axes at the EE point). The planar arm uses rows (0, 1) = (x, y), the LWR all six.
* Force [A-4.1]: ``f`` is the force the EE EXERTS ON the environment along the contact normal n
  (n points from the EE into the environment, f >= 0 pushes). The environment acts on the EE with
  -n f, so every torque here contains +J^T n f_ref.
* All functions take a :class:`rns_ros.core.fixed_base.FixedBaseState` computed once per step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ConfigError, InputError, ModelError
from rns_ros.core.fixed_base import FixedBaseModel, FixedBaseState
from rns_ros.core.validation import Choice, as_vector, positive

#: Names of the six rows of J_e / V_e (Pinocchio order: linear then angular, world axes).
ROW_NAMES = ("x", "y", "z", "wx", "wy", "wz")
#: Task rows of the planar 3-DoF arm: EE position x, y (orientation free, thesis x-z -> x-y).
PLANAR_ROWS = (0, 1)
#: Task rows of the 7-DoF arm: EE position and orientation (orientation held).
FULL_ROWS = (0, 1, 2, 3, 4, 5)
#: Default virtual-link mass m_hat [kg] (thesis section 6.2.1: 1e5 kg).
DEFAULT_VIRTUAL_MASS = 1.0e5
#: Default virtual-link inertia per unit mass I_hat / m_hat [m^2] ([A-4.9]: I_hat = m_hat/12).
DEFAULT_INERTIA_PER_MASS = 1.0 / 12.0
#: Damper gain of section 7.2.2 [1/s] (stable with RK4 at 1 ms; scale as 2.77 / step).
DEFAULT_DAMPER_GAIN = 2770.0
#: Relative rank threshold of the projectors and of the J W^T solve [-].
DEFAULT_RCOND = 1e-10


# --------------------------------------------------------------------------------------------
# Gains and the outer loops (6.33)-(6.34)


def _gain(value, name: str, unit: str, *, allow_zero: bool = False) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number {unit}, got {value!r}") from None
    if not np.isfinite(number) or number < 0.0 or (number == 0.0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ConfigError(f"{name} must be a finite number {bound} {unit}, got {value!r}")
    return number


@dataclass(frozen=True)
class MotionGains:
    """Gains of the motion loop (6.33).

    Attributes:
        k_p: position gain [1/s^2] (thesis: 100). k_d: velocity gain [1/s] (thesis: 10).
    """

    k_p: float = 100.0
    k_d: float = 10.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "k_p", _gain(self.k_p, "k_p", "[1/s^2]"))
        object.__setattr__(self, "k_d", _gain(self.k_d, "k_d", "[1/s]"))


@dataclass(frozen=True)
class ForceGains:
    """Gain of the force loop (6.34): k_f [-] (thesis: 5; 0 = pure feed-forward)."""

    k_f: float = 5.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "k_f", _gain(self.k_f, "k_f", "[-]", allow_zero=True))


def motion_loop(gains: MotionGains, nu_dot_des, nu_des, nu, pose_error) -> np.ndarray:
    """Task acceleration reference of eq. (6.33) (the print shows v on the left; it is an
    acceleration): nu_dot_ref = nu_dot_des + k_d (nu_des - nu) + k_p (x_des - x).

    Args:
        gains: :class:`MotionGains`.
        nu_dot_des [m/s^2 | rad/s^2], nu_des [m/s | rad/s], nu: desired acceleration and velocity,
            measured velocity, all in task coordinates, shape (m,).
        pose_error: x_des - x in task coordinates [m | rad], shape (m,)
            (:meth:`TaskSpace.pose_error`).

    Returns:
        nu_dot_ref, shape (m,). The controllers keep only its motion-direction part S nu_dot_ref.
    """
    nu_dot_des = np.asarray(nu_dot_des, dtype=float)
    size = nu_dot_des.shape[0] if nu_dot_des.ndim == 1 else -1
    if size < 1:
        raise InputError(f"nu_dot_des must be a vector, got shape {nu_dot_des.shape}")
    nu_dot_des = as_vector(nu_dot_des, size, "nu_dot_des")
    nu_des = as_vector(nu_des, size, "nu_des")
    nu = as_vector(nu, size, "nu")
    pose_error = as_vector(pose_error, size, "pose_error")
    return nu_dot_des + gains.k_d * (nu_des - nu) + gains.k_p * pose_error


def force_loop(gains: ForceGains, f_des, f) -> np.ndarray:
    """Force reference of eq. (6.34): f_ref = f_des + k_f (f_des - f) [N], shape (k,).

    f_des and the measured f are forces the EE exerts on the environment along the contact
    normal(s) [A-4.1], shape (k,).
    """
    f_des = np.atleast_1d(np.asarray(f_des, dtype=float))
    f_des = as_vector(f_des, f_des.shape[0], "f_des")
    f = as_vector(np.atleast_1d(np.asarray(f, dtype=float)), f_des.shape[0], "f")
    return f_des + gains.k_f * (f_des - f)


# --------------------------------------------------------------------------------------------
# Task description: rows, S, S_perp (6.10)-(6.12)


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


# --------------------------------------------------------------------------------------------
# OS-C (6.6)-(6.13)


class OscVariant(Choice):
    """OS-C variants ([A-4.2]): ``literal`` = (6.13) at torque level with tau_a = 0;
    ``kinematic`` = theta_ddot = J^{M+} a', then computed torque."""

    __label__ = "OS-C variant"
    LITERAL = "literal"
    KINEMATIC = "kinematic"


@dataclass(frozen=True)
class OperationalSpace:
    """Operational-space quantities of eq. (6.6)-(6.8) in task coordinates.

    Attributes:
        mass: M_e = (J M^-1 J^T)^-1 [kg | kg m^2], (m, m), eq. (6.6).
        inverse: J^{M+} = M^-1 J^T M_e, the inertia-weighted generalized inverse, (n, m).
        coriolis: C_e = J^{M+T} c - M_e J_dot theta_dot, (m,), eq. (6.7).
        gravity: G_e = J^{M+T} g, (m,), eq. (6.8).
    """

    mass: np.ndarray
    inverse: np.ndarray
    coriolis: np.ndarray
    gravity: np.ndarray


def operational_space(state: FixedBaseState, task: TaskSpace) -> OperationalSpace:
    """M_e, J^{M+}, C_e, G_e of eq. (6.6)-(6.8) (solves with M, never inverts it).

    Raises:
        InputError: J M^-1 J^T is singular (a kinematic singularity of the task rows).
    """
    jac = task.jacobian(state)
    m_inv_jt = np.linalg.solve(state.mass_matrix, jac.T)  # M^-1 J^T, (n, m)
    lam = jac @ m_inv_jt
    lam = 0.5 * (lam + lam.T)
    sigma = np.linalg.svd(lam, compute_uv=False)
    if sigma[-1] <= DEFAULT_RCOND * sigma[0]:
        raise InputError(f"J M^-1 J^T is singular (sigma = {sigma.tolist()}): task singularity")
    mass = np.linalg.solve(lam, np.eye(task.m))
    mass = 0.5 * (mass + mass.T)
    inverse = m_inv_jt @ mass
    coriolis = inverse.T @ state.coriolis - mass @ task.drift(state)
    gravity = inverse.T @ state.gravity
    return OperationalSpace(mass, inverse, coriolis, gravity)


@dataclass(frozen=True)
class ControlCommand:
    """One controller output.

    Attributes:
        torque: tau [N m], (n,).
        joint_acceleration: theta_ddot the torque gives the FREE arm (no contact force), i.e.
            M^-1 (tau - J^T F_kappa^ref - c - g) [rad/s^2], (n,).
        task_acceleration: V_dot_ref used (S nu_dot_ref + N a_n), task coordinates, (m,).
        force_wrench: J^T is applied to this task-space force F_kappa^ref = N f_ref [N], (m,).
        method: "os-c/literal", "os-c/kinematic", "rns-c/closed-form" or "resolved/J+".
        sigma_min: smallest singular value of the matrix solved (J W^T for RNS-C, J M^-1 J^T
            for OS-C, J for J^+); compare with sigma_max.
        sigma_max: largest singular value of that matrix.
    """

    torque: np.ndarray
    joint_acceleration: np.ndarray
    task_acceleration: np.ndarray
    force_wrench: np.ndarray
    method: str
    sigma_min: float
    sigma_max: float


def os_control(
    state: FixedBaseState,
    task: TaskSpace,
    acceleration_ref,
    force_ref=None,
    *,
    variant: OscVariant | str = OscVariant.LITERAL,
    normal_acceleration=None,
    null_space_torque=None,
) -> ControlCommand:
    """The OS-C torque of eq. (6.10)-(6.13).

    F_m^ref = M_e S V_dot_ref + C_e + G_e (6.11), F_kappa^ref = S_perp F_c^ref = N f_ref (6.12),
    tau = J^T (F_m^ref + F_kappa^ref) + (E - J^T J^{M+T}) tau_a (6.13; the print's J^T J^{M+} is a
    transpose typo), tau_a = ``null_space_torque`` (default 0 as in every thesis experiment).

    ``kinematic`` instead applies theta_ddot = J^{M+} (S V_dot_ref - J_dot theta_dot) and
    tau = M theta_ddot + c + g + J^T N f_ref (null-space Coriolis compensated; tau_a ignored).

    Args:
        acceleration_ref: nu_dot_ref of (6.33), task coordinates (m,).
        force_ref: f_ref of (6.34) [N], (k,), force ON the environment [A-4.1]; default 0.
        normal_acceleration: a_n, see :meth:`TaskSpace.compose`.
    """
    variant = OscVariant.parse(variant)
    task_accel = task.compose(acceleration_ref, normal_acceleration)
    wrench = task.force_wrench(np.zeros(task.k) if force_ref is None else force_ref)
    os_ = operational_space(state, task)
    jac = task.jacobian(state)
    bias = state.coriolis + state.gravity
    if variant is OscVariant.LITERAL:
        motion_wrench = os_.mass @ task_accel + os_.coriolis + os_.gravity  # (6.11)
        torque = jac.T @ (motion_wrench + wrench)
        if null_space_torque is not None:
            tau_a = as_vector(null_space_torque, state.n, "null_space_torque")
            torque = torque + tau_a - jac.T @ (os_.inverse.T @ tau_a)
        accel = np.linalg.solve(state.mass_matrix, torque - jac.T @ wrench - bias)
    else:
        accel = os_.inverse @ (task_accel - task.drift(state))
        torque = state.mass_matrix @ accel + bias + jac.T @ wrench
    sigma = np.linalg.svd(np.linalg.solve(os_.mass, np.eye(task.m)), compute_uv=False)
    return ControlCommand(
        torque, accel, task_accel, wrench, f"os-c/{variant.value}", sigma[-1], sigma[0]
    )


# --------------------------------------------------------------------------------------------
# RNS-C: the reversed control model (6.14)-(6.32)


def _skew(p: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -p[2], p[1]], [p[2], 0.0, -p[0]], [-p[1], p[0], 0.0]])


@dataclass(frozen=True)
class ReversedQuantities:
    """The control model's inertia at one configuration, in REAL joint coordinates.

    Coordinates q_hat_dot = [V_A; theta_dot] with V_A = [v_A; omega_A] the twist of the EE point
    A in world axes (same as V_e) and theta the REAL joints (the thesis' reversed, sign-flipped
    theta_hat of (6.28) is a signed permutation of them; row spaces and projectors carry over).

    Attributes:
        mass: M_hat (6 + n, 6 + n): rows/cols [V_A; theta]; momentum rows = [linear momentum;
            angular momentum about A] in world axes.
        root_mass: M_hat_A (6, 6). coupling: M_hat_Al (6, n).
        reduced_mass: M_red (m, m) = M_hat_A with the non-task root coordinates eliminated
            (eq. 6.24-6.25 generalized); = M_hat_A when all six rows are tasks.
        w: W = M_lred (m, n): M_hat_Al reduced the same way (the planar 2x3 of 6.25; the LWR 6x7).
    """

    mass: np.ndarray
    root_mass: np.ndarray
    coupling: np.ndarray
    reduced_mass: np.ndarray
    w: np.ndarray


def _cross_motion(twist: np.ndarray, motion: np.ndarray) -> np.ndarray:
    """Spatial motion cross product V x m, Pinocchio order [linear; angular]."""
    v, w = twist[:3], twist[3:]
    return np.concatenate(
        [np.cross(w, motion[:3]) + np.cross(v, motion[3:]), np.cross(w, motion[3:])]
    )


def _cross_force(twist: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Spatial force cross product V x* f, Pinocchio order [force; moment]."""
    v, w = twist[:3], twist[3:]
    return np.concatenate([np.cross(w, force[:3]), np.cross(w, force[3:]) + np.cross(v, force[:3])])


@dataclass(frozen=True)
class ReversedDynamics:
    """The control model's dynamics (6.21) M_hat q_hat_ddot + c_hat + g_hat = Q_hat +
    J_const^T F_B at the real state, real joint coordinates, q_hat = [V_A (6); theta (n)].

    Attributes:
        mass: M_hat (6 + n, 6 + n). bias: c_hat (6 + n,). gravity: g_hat (6 + n,) (B's weight
            included; zero with gravity off).
        constraint: J_const (6, 6 + n), maps q_hat_dot to B's spatial twist at the world origin
            (6.19); its root block is T_hat^T = X_A, its joint block J_B = -J_world.
        constraint_drift: J_const_dot q_hat_dot (6,) of (6.20).
        velocity: q_hat_dot = [J_e theta_dot; theta_dot].
    """

    mass: np.ndarray
    bias: np.ndarray
    gravity: np.ndarray
    constraint: np.ndarray
    constraint_drift: np.ndarray
    velocity: np.ndarray


class ReversedModel:
    """The RNS-C control model (Fig. 6.2 b) of a real fixed-base serial arm, section 6.1.2.

    The real arm is re-rooted at its EE link A (6-DoF virtual joint to the inertial frame); the
    ground becomes the virtual constrained link B at the real base: mass m_hat, rotational inertia
    I_hat about its CoM, length l_hat = 0, i.e. its CoM at the origin of real joint 1.

    Construction (thesis_rest 4.4 generalized to 3-D): with A as root, body k (real link k) moves
    with the twist V_k = X_A V_A - sum_{j > k} S_j theta_dot_j (spatial twists at the world origin;
    S_j the world Jacobian column of joint j, X_A shifts V_A from the EE point to the origin):
    increasing theta_j turns the base side of joint j by -theta_j. B moves with
    X_A V_A - sum_{all j} S_j theta_dot_j. Then M_hat = sum_k J_k^T I_k J_k with I_k the spatial
    inertia of body k in world axes. The real ground body (Pinocchio's universe inertia) is
    replaced by B.

    Args:
        robot: the real :class:`FixedBaseModel` (a serial chain; the EE frame on the last link).
        rows: task rows (non-task root coordinates are eliminated, [A-4.9]-style reduction).
        virtual_mass: m_hat [kg] > 0 (default 1e5).
        virtual_inertia: I_hat [kg m^2]: None -> m_hat/12 E ([A-4.9]), a number -> that times E,
            or an SPD (3, 3) matrix in world axes.

    Raises:
        ConfigError: m_hat not > 0, I_hat not SPD, bad rows. ModelError: not a serial chain or
            the EE is not on the last link.
    """

    def __init__(
        self,
        robot: FixedBaseModel,
        rows=FULL_ROWS,
        *,
        virtual_mass: float = DEFAULT_VIRTUAL_MASS,
        virtual_inertia=None,
    ) -> None:
        self.robot = robot
        self.rows = TaskSpace.free(rows).rows
        self.free_rows = tuple(i for i in range(6) if i not in self.rows)
        self.virtual_mass = positive(virtual_mass, "virtual_mass m_hat", "[kg]")
        if virtual_inertia is None:
            inertia = DEFAULT_INERTIA_PER_MASS * self.virtual_mass * np.eye(3)
        elif np.ndim(virtual_inertia) == 0:
            inertia = positive(virtual_inertia, "virtual_inertia I_hat", "[kg m^2]") * np.eye(3)
        else:
            inertia = np.asarray(virtual_inertia, dtype=float)
            if inertia.shape != (3, 3) or not np.isfinite(inertia).all():
                raise ConfigError(f"virtual_inertia must be a number or (3, 3), got {inertia!r}")
            if not np.allclose(inertia, inertia.T) or np.linalg.eigvalsh(inertia)[0] <= 0.0:
                raise ConfigError(
                    f"virtual_inertia must be symmetric positive definite, got {inertia.tolist()}"
                )
        self.virtual_inertia = inertia
        model = robot.model
        for j in range(1, model.njoints):
            if model.parents[j] != j - 1:
                raise ModelError(f"{robot.name}: RNS-C needs a serial chain (joint {j})")
        if model.frames[robot.ee_frame_id].parentJoint != model.njoints - 1:
            raise ModelError(f"{robot.name}: the EE frame must be on the last link")
        self._data = model.createData()
        base = model.jointPlacements[1].translation.copy()  # l_hat = 0: B's CoM at joint 1
        self._b_inertia = pin.Inertia(self.virtual_mass, base, inertia).matrix()

    def evaluate(self, q) -> ReversedQuantities:
        """M_hat, M_hat_A, M_hat_Al, M_red and W at the real configuration q [rad], (n,)."""
        robot, model, data = self.robot, self.robot.model, self._data
        n = robot.n
        q = as_vector(q, n, "q")
        pin.computeJointJacobians(model, data, q)  # also forward kinematics
        pin.updateFramePlacements(model, data)
        joint_twists = data.J  # (6, n) spatial axes at the world origin
        p_a = data.oMf[robot.ee_frame_id].translation
        shift = np.eye(6)
        shift[:3, 3:] = _skew(p_a)  # V^O = X_A V_A: v_O = v_A + p_A x omega
        mass = np.zeros((6 + n, 6 + n))
        for k in range(n + 1):  # real links 1..n (k = 1..n), then B (k = 0 slot)
            jac = np.zeros((6, 6 + n))
            jac[:, :6] = shift
            if k == 0:
                jac[:, 6:] = -joint_twists
                inertia = self._b_inertia
            else:
                jac[:, 6 + k :] = -joint_twists[:, k:]  # joints k+1..n lie between A and body k
                inertia = data.oMi[k].act(model.inertias[k]).matrix()
            mass += jac.T @ inertia @ jac
        mass = 0.5 * (mass + mass.T)
        root, coupling = mass[:6, :6], mass[:6, 6:]
        rows, free = list(self.rows), list(self.free_rows)
        reduced, w = root[np.ix_(rows, rows)], coupling[rows]
        if free:
            solve = np.linalg.solve(
                root[np.ix_(free, free)], np.hstack([root[free][:, rows], coupling[free]])
            )
            reduced = reduced - root[np.ix_(rows, free)] @ solve[:, : len(rows)]
            w = w - root[np.ix_(rows, free)] @ solve[:, len(rows) :]
        return ReversedQuantities(mass, root, coupling, 0.5 * (reduced + reduced.T), w)

    def dynamics(self, state: FixedBaseState) -> ReversedDynamics:
        """The control model's equation of motion (6.21) at the REAL state (B at rest).

        Coordinates q_hat_dot = [V_A; theta_dot] with V_A = J_e theta_dot. With spatial twists
        V_k = J_k q_hat_dot at the world origin and world-axes spatial inertias I_k (Featherstone):
        c_hat = sum_k J_k^T (I_k J_k_dot q_hat_dot + V_k x* I_k V_k), g_hat = -sum_k J_k^T I_k a_g,
        J_k_dot q_hat_dot = [v_A x omega_A; 0] - sum_{j>k} (V_j x S_j) theta_dot_j. The constraint
        of (6.19) is V_B = J_const q_hat_dot = 0 with J_const = [X_A, -J_world] (= [T_hat^T J_B]).
        """
        robot, model, data = self.robot, self.robot.model, self._data
        n = robot.n
        if state.n != n:
            raise InputError(f"state has {state.n} joints, the model {n}")
        pin.computeJointJacobians(model, data, state.q)
        pin.updateFramePlacements(model, data)
        joint_twists = data.J.copy()
        p_a = data.oMf[robot.ee_frame_id].translation.copy()
        v_a = state.jacobian @ state.v  # (6,) [v_A; omega_A] at the EE point
        velocity = np.concatenate([v_a, state.v])
        shift = np.eye(6)
        shift[:3, 3:] = _skew(p_a)
        root_drift = np.concatenate([np.cross(v_a[:3], v_a[3:]), np.zeros(3)])
        twist_a = shift @ v_a
        # body twists V_j (j = 1..n), spatial at the origin, of the hat model at the real state
        tail = np.cumsum((joint_twists * state.v)[:, ::-1], axis=1)[:, ::-1]  # sum_{i>=j}
        tail = np.hstack([tail, np.zeros((6, 1))])  # tail[:, j] = sum_{i>j} (0-based j+1..)
        gravity_acc = np.concatenate([np.asarray(model.gravity.linear, float), np.zeros(3)])
        mass = np.zeros((6 + n, 6 + n))
        bias, weight = np.zeros(6 + n), np.zeros(6 + n)
        constraint = drift_b = None
        for k in range(n + 1):
            jac = np.zeros((6, 6 + n))
            jac[:, :6] = shift
            first = 0 if k == 0 else k  # 0-based index of the first joint between k and A
            jac[:, 6 + first :] = -joint_twists[:, first:]
            drift = root_drift.copy()
            for j in range(first, n):  # 0-based joint j, child body twist V = X_A V_A - tail
                body_twist = twist_a - tail[:, j + 1]
                drift -= _cross_motion(body_twist, joint_twists[:, j]) * state.v[j]
            twist = twist_a - tail[:, first]
            inertia = self._b_inertia if k == 0 else data.oMi[k].act(model.inertias[k]).matrix()
            mass += jac.T @ inertia @ jac
            bias += jac.T @ (inertia @ drift + _cross_force(twist, inertia @ twist))
            weight -= jac.T @ (inertia @ gravity_acc)
            if k == 0:
                constraint, drift_b = jac, drift
        return ReversedDynamics(0.5 * (mass + mass.T), bias, weight, constraint, drift_b, velocity)

    def w(self, q) -> np.ndarray:
        """W (m, n) at q."""
        return self.evaluate(q).w

    def w_rate(self, q, v, step: float = 1e-6) -> np.ndarray:
        """W_dot = dW/dq theta_dot by a central difference along theta_dot.

        Args:
            step: time step h of W(q +- h theta_dot) [s] (> 0; error O(h^2)).
        """
        step = positive(step, "step", "[s]")
        q = as_vector(q, self.robot.n, "q")
        v = as_vector(v, self.robot.n, "v")
        return (self.w(q + step * v) - self.w(q - step * v)) / (2.0 * step)


# --------------------------------------------------------------------------------------------
# Projectors, null-space velocity, chapter 7


def _svd_solve(matrix: np.ndarray, rhs: np.ndarray, rcond: float):
    """x with matrix x = rhs (square solve; minimum-norm least squares when rank-deficient),
    plus (sigma_min, sigma_max)."""
    sigma = np.linalg.svd(matrix, compute_uv=False)
    if sigma[-1] > rcond * sigma[0]:
        return np.linalg.solve(matrix, rhs), sigma[-1], sigma[0]
    return np.linalg.lstsq(matrix, rhs, rcond=rcond)[0], sigma[-1], sigma[0]


def kernel_projector(matrix, rcond: float = DEFAULT_RCOND) -> np.ndarray:
    """Orthogonal projector onto ker(A): E - A^+ A from the SVD, (n, n).

    With A = W it is P_hat_RNS of (7.3)/(7.14); with A = J it is P_J of (7.2).
    Singular values <= rcond * sigma_max [-] count as zero.
    """
    matrix = np.asarray(matrix, dtype=float)
    _, sigma, vt = np.linalg.svd(matrix, full_matrices=True)
    rank = int((sigma > rcond * max(sigma[0], 1e-300)).sum())
    row_space = vt[:rank]
    return np.eye(matrix.shape[1]) - row_space.T @ row_space


@dataclass(frozen=True)
class NullSpaceVelocity:
    """Null-space velocity measures of (7.14) [A-4.14] [rad/s].

    Attributes:
        rns: ||P_hat_RNS theta_dot|| (P_hat_RNS onto ker W). jacobian: ||P_J theta_dot||.
    """

    rns: float
    jacobian: float


def null_space_velocity(
    state: FixedBaseState, task: TaskSpace, w, rcond: float = DEFAULT_RCOND
) -> NullSpaceVelocity:
    """||P_hat_RNS theta_dot|| and ||P_J theta_dot|| at ``state`` (W from ReversedModel.w)."""
    return NullSpaceVelocity(
        float(np.linalg.norm(kernel_projector(w, rcond) @ state.v)),
        float(np.linalg.norm(kernel_projector(task.jacobian(state), rcond) @ state.v)),
    )


def _computed_torque(state, task, accel, force_ref):
    wrench = task.force_wrench(np.zeros(task.k) if force_ref is None else force_ref)
    torque = (
        state.mass_matrix @ accel + state.coriolis + state.gravity + task.jacobian(state).T @ wrench
    )
    return torque, wrench


def resolved_acceleration(
    state: FixedBaseState,
    task: TaskSpace,
    acceleration_ref,
    force_ref=None,
    *,
    normal_acceleration=None,
    null_space_acceleration=None,
    rcond: float = DEFAULT_RCOND,
) -> ControlCommand:
    """Resolved acceleration, eq. (7.2): theta_ddot = J^+ (V_dot_ref - J_dot theta_dot)
    + P_J theta_ddot_a (minimum acceleration norm for theta_ddot_a = 0), then the real computed
    torque tau = M theta_ddot + c + g + J^T N f_ref. J^+ via least squares (SVD)."""
    task_accel = task.compose(acceleration_ref, normal_acceleration)
    jac = task.jacobian(state)
    rhs = task_accel - task.drift(state)
    accel = np.linalg.lstsq(jac, rhs, rcond=rcond)[0]
    if null_space_acceleration is not None:
        extra = as_vector(null_space_acceleration, state.n, "null_space_acceleration")
        accel = accel + kernel_projector(jac, rcond) @ extra
    torque, wrench = _computed_torque(state, task, accel, force_ref)
    sigma = np.linalg.svd(jac, compute_uv=False)
    return ControlCommand(torque, accel, task_accel, wrench, "resolved/J+", sigma[-1], sigma[0])


def rns_control(
    state: FixedBaseState,
    task: TaskSpace,
    reversed_model: ReversedModel,
    acceleration_ref,
    force_ref=None,
    *,
    normal_acceleration=None,
    null_space_acceleration=None,
    w=None,
    rcond: float = DEFAULT_RCOND,
) -> ControlCommand:
    """RNS-C, closed form of (6.17) with the exact constraint force (6.22) (thesis_rest 4.2):

    theta_ddot = W^T (J W^T)^-1 (V_dot_ref - J_dot theta_dot) + O P_hat_RNS theta_ddot_a,
    O = E - W^T (J W^T)^-1 J,

    the unique acceleration in the row space of W (+ the null-space term) that meets the real
    task kinematics J theta_ddot + J_dot theta_dot = V_dot_ref; then the real computed torque
    tau = M theta_ddot + c + g + J^T N f_ref (equivalent to (6.18) mapped back by (6.29)).

    The null-space term follows (7.3): P_hat_RNS theta_ddot_a is the free part; the oblique
    projector O (onto ker J along row W) stands for the constraint force that keeps the task
    exact. Pass :func:`velocity_level_term` (7.13) or :func:`damper_term` as theta_ddot_a.
    ``sigma_min``/``sigma_max`` of the result are those of J W^T (watch sigma_min near
    singularities; it scales with m_hat).

    Args:
        reversed_model: built with the same rows as ``task``.
        w: W at state.q if already computed (else evaluated here).
    """
    if reversed_model.rows != task.rows:
        raise ConfigError(
            f"reversed model rows {reversed_model.rows} differ from task rows {task.rows}"
        )
    task_accel = task.compose(acceleration_ref, normal_acceleration)
    jac = task.jacobian(state)
    w = reversed_model.w(state.q) if w is None else np.asarray(w, dtype=float)
    if w.shape != (task.m, state.n) or not np.isfinite(w).all():
        raise InputError(f"W must be finite with shape ({task.m}, {state.n}), got {w.shape}")
    jwt = jac @ w.T
    y, s_min, s_max = _svd_solve(jwt, task_accel - task.drift(state), rcond)
    accel = w.T @ y
    if null_space_acceleration is not None:
        extra = kernel_projector(w, rcond) @ as_vector(
            null_space_acceleration, state.n, "null_space_acceleration"
        )
        accel = accel + extra - w.T @ _svd_solve(jwt, jac @ extra, rcond)[0]
    torque, wrench = _computed_torque(state, task, accel, force_ref)
    return ControlCommand(torque, accel, task_accel, wrench, "rns-c/closed-form", s_min, s_max)


@dataclass(frozen=True)
class LiteralRnsStep:
    """One step of the literal RNS-C loop (6.22) + (6.17) + (6.18).

    Attributes:
        command: the :class:`ControlCommand` (method "rns-c/literal"); joint_acceleration is the
            theta_ddot_ref of (6.17), torque the tau of (6.18) for the next step.
        constraint_force: F_B of (6.22), B's wrench at the world origin [N, N m], (6,).
    """

    command: ControlCommand
    constraint_force: np.ndarray


def rns_literal_step(
    state: FixedBaseState,
    task: TaskSpace,
    reversed_model: ReversedModel,
    acceleration_ref,
    force_ref=None,
    *,
    previous_torque,
    normal_acceleration=None,
    rcond: float = DEFAULT_RCOND,
) -> LiteralRnsStep:
    """RNS-C as printed ([A-4.3]): the algebraic loop broken by the previous step's torque.

    1. F_B of (6.22) with Q_hat = [F_A; tau_prev], F_A = -N f_ref the contact reaction on A.
    2. theta_ddot_ref of (6.17) (constraint force substituted, non-task root rows eliminated as
       in (6.24)-(6.25)): theta_ddot = W^+ (r_red - M_red V_dot_ref), r = F_A + T_hat F_B - c_A
       - g_A on the root rows (exact C_A, not the momentum approximation).
    3. tau of (6.16)/(6.18): M_Al^T V_dot_A + M_l theta_ddot + c_l + g_l - J_B^T F_B.

    The fixed point of tau_prev -> tau is the closed form of :func:`rns_control` (tested).
    """
    if reversed_model.rows != task.rows:
        raise ConfigError(
            f"reversed model rows {reversed_model.rows} differ from task rows {task.rows}"
        )
    n = state.n
    previous_torque = as_vector(previous_torque, n, "previous_torque")
    task_accel = task.compose(acceleration_ref, normal_acceleration)
    wrench = task.force_wrench(np.zeros(task.k) if force_ref is None else force_ref)
    dyn = reversed_model.dynamics(state)
    rows, free = list(task.rows), list(reversed_model.free_rows)
    root_force = np.zeros(6)
    root_force[rows] = -wrench  # the environment's reaction on A
    generalized = np.concatenate([root_force, previous_torque])
    nonlinear = dyn.bias + dyn.gravity
    jc = dyn.constraint
    m_inv = np.linalg.solve(dyn.mass, np.column_stack([jc.T, nonlinear - generalized]))
    f_b = np.linalg.solve(jc @ m_inv[:, :6], jc @ m_inv[:, 6] - dyn.constraint_drift)  # (6.22)
    residual = root_force + jc[:, :6].T @ f_b - nonlinear[:6]
    root, coupling = dyn.mass[:6, :6], dyn.mass[:6, 6:]
    reduced_residual, reduced_mass, w = residual[rows], root[np.ix_(rows, rows)], coupling[rows]
    if free:
        solve = np.linalg.solve(
            root[np.ix_(free, free)],
            np.column_stack([residual[free], root[free][:, rows], coupling[free]]),
        )
        cross = root[np.ix_(rows, free)]
        reduced_residual = reduced_residual - cross @ solve[:, 0]
        reduced_mass = reduced_mass - cross @ solve[:, 1 : 1 + len(rows)]
        w = w - cross @ solve[:, 1 + len(rows) :]
    accel = np.linalg.lstsq(w, reduced_residual - reduced_mass @ task_accel, rcond=rcond)[0]
    root_accel = np.zeros(6)
    root_accel[rows] = task_accel
    if free:
        root_accel[free] = np.linalg.solve(
            root[np.ix_(free, free)],
            residual[free] - root[np.ix_(free, rows)] @ task_accel - coupling[free] @ accel,
        )
    torque = coupling.T @ root_accel + dyn.mass[6:, 6:] @ accel + nonlinear[6:] - jc[:, 6:].T @ f_b
    sigma = np.linalg.svd(w, compute_uv=False)
    command = ControlCommand(
        torque, accel, task_accel, wrench, "rns-c/literal", sigma[-1], sigma[0]
    )
    return LiteralRnsStep(command, f_b)


class VelocityTermForm(Choice):
    """Forms of (7.13): ``momentum`` = -P Wdot^T (W W^T)^-1 M_red V_A with V_A = J theta_dot
    (the printed form); ``velocity`` = +P Wdot^T W^{+T} theta_dot (equal under the zero-momentum
    condition (7.9); exact for keeping P_hat_RNS theta_dot = 0 on the real arm)."""

    __label__ = "velocity-level term form"
    MOMENTUM = "momentum"
    VELOCITY = "velocity"


def velocity_level_term(
    state: FixedBaseState,
    task: TaskSpace,
    reversed_model: ReversedModel,
    *,
    form: VelocityTermForm | str = VelocityTermForm.VELOCITY,
    step: float = 1e-6,
    rcond: float = DEFAULT_RCOND,
) -> np.ndarray:
    """theta_ddot_add of eq. (7.13) [rad/s^2], (n,), in ker W.

    W_dot by a central difference along theta_dot (``step`` [s], :meth:`ReversedModel.w_rate`).
    """
    form = VelocityTermForm.parse(form)
    quantities = reversed_model.evaluate(state.q)
    w = quantities.w
    w_dot = reversed_model.w_rate(state.q, state.v, step)
    if form is VelocityTermForm.MOMENTUM:
        momentum = quantities.reduced_mass @ task.velocity(state)  # M_hat_A V_hat_A, reduced
        y = -_svd_solve(w @ w.T, momentum, rcond)[0]
    else:
        y = _svd_solve(w @ w.T, w @ state.v, rcond)[0]  # W^{+T} theta_dot = (W W^T)^-1 W th_dot
    return kernel_projector(w, rcond) @ (w_dot.T @ y)


def damper_term(v, gain: float = DEFAULT_DAMPER_GAIN) -> np.ndarray:
    """theta_ddot_a = -k_d theta_dot (section 7.2.2), k_d = ``gain`` [1/s] > 0 (2770 at RK4,
    1 ms; the RK4 limit is about 2.785 / step)."""
    gain = _gain(gain, "damper gain k_d", "[1/s]")
    v = np.asarray(v, dtype=float)
    if v.ndim != 1:
        raise InputError(f"theta_dot must be a vector, got shape {v.shape}")
    return -gain * as_vector(v, v.shape[0], "theta_dot")


__all__ = [
    "DEFAULT_DAMPER_GAIN",
    "DEFAULT_INERTIA_PER_MASS",
    "DEFAULT_VIRTUAL_MASS",
    "FULL_ROWS",
    "PLANAR_ROWS",
    "ControlCommand",
    "ForceGains",
    "LiteralRnsStep",
    "MotionGains",
    "NullSpaceVelocity",
    "OperationalSpace",
    "OscVariant",
    "ReversedDynamics",
    "ReversedModel",
    "ReversedQuantities",
    "TaskSpace",
    "VelocityTermForm",
    "contact_frame",
    "damper_term",
    "force_loop",
    "kernel_projector",
    "motion_loop",
    "null_space_velocity",
    "operational_space",
    "os_control",
    "resolved_acceleration",
    "rns_control",
    "rns_literal_step",
    "velocity_level_term",
]
